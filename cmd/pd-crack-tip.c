/*
 * pd-crack-tip -- the crack tip position in every frame of a run.
 *
 * Seed 004 (Silling & Askari 2005) §5: the tip is the largest coordinate
 * along an axis among the particles whose damage phi exceeds phi_0 = 0.3,
 * here at the current positions y = x + u.  Damage is the frame's `damage`
 * field when pd-damage stored it, otherwise it is computed from the frame's
 * bond state (seed 000 eq. 10, pd_damage).  A table on stdout, one row per
 * frame: step, time, tip (nan when no particle is damaged enough) and the
 * number of particles above the threshold.
 */
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pd.h"

#define PROG "pd-crack-tip"
#include "cli.h"

struct options {
    const char *input;
    int axis;          /* 0, 1, 2 for x, y, z              */
    double threshold;  /* phi_0: damage strictly above it  */
    int debug;
};

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: " PROG " [OPTION]... RUN.h5\n"
            "Crack tip per frame of a run (seed 004 section 5): the largest current\n"
            "coordinate along an axis among particles with damage above a threshold.\n"
            "Prints a table on stdout: step, time (s), tip (m, nan when no particle is\n"
            "above the threshold), number of particles above the threshold.\n"
            "\n"
            "Options:\n"
            "  -a, --axis x|y|z    direction of crack growth (default x)\n"
            "  -t, --threshold D   damage threshold phi_0 in [0,1] (default 0.3)\n"
            "      --debug         print HDF5's own error stack\n"
            "  -h, --help          show this help\n"
            "  -V, --version       show the version\n");
}

static int parse_axis(const char *s, int *axis)
{
    static const char *names[3] = {"x", "y", "z"};
    for (int d = 0; d < 3; d++)
        if (strcmp(s, names[d]) == 0) {
            *axis = d;
            return 1;
        }
    return 0;
}

static int parse_options(int argc, char **argv, struct options *o)
{
    static const struct option longopts[] = {
        {"axis", required_argument, 0, 'a'},
        {"threshold", required_argument, 0, 't'},
        COMMON_LONGOPTS,
        {0, 0, 0, 0}};
    memset(o, 0, sizeof *o);
    o->threshold = 0.3;
    int c, status = 0;
    while ((c = next_option(argc, argv, "a:t:hV", longopts, usage, &o->debug, &status)) != -1) {
        switch (c) {
        case 'a':
            if (!parse_axis(optarg, &o->axis))
                return usage_error("--axis must be x, y or z, not", optarg);
            break;
        case 't':
            if (!pd_parse_double(optarg, &o->threshold) || o->threshold < 0 || o->threshold > 1)
                return usage_error("--threshold must be a number in [0,1], not", optarg);
            break;
        default:
            return option_error(argv);
        }
    }
    if (status)
        return status;
    if (optind != argc - 1)
        return usage_error(optind < argc ? "give exactly one RUN.h5" : "missing RUN.h5", NULL);
    o->input = argv[optind];
    return 0;
}

int main(int argc, char **argv)
{
    struct options o;
    int rc = parse_options(argc, argv, &o);
    if (rc)
        return rc;
    pd_h5_debug(o.debug);
    remove_temps_on_signal();

    pd_file *f = NULL;
    pd_particles *p = NULL;
    pd_bonds *b = NULL;
    uint64_t *intact = NULL;
    int64_t nframes = 0;
    char **frames = NULL;
    double *damage = NULL, *disp[3] = {NULL, NULL, NULL};
    pd_status s = pd_file_open(o.input, &f);
    if (s == PD_OK && (s = pd_read_particles(f, &p)) == PD_OK &&
        (s = pd_list_frames(f, &nframes, &frames)) == PD_OK) {
        size_t bytes = (size_t)p->n * sizeof(double);
        damage = malloc(bytes);
        for (int d = 0; d < 3; d++)
            disp[d] = malloc(bytes);
        if (damage == NULL || disp[0] == NULL || disp[1] == NULL || disp[2] == NULL)
            s = pd_fail(PD_ERR_NOMEM, "out of memory for %lld particles", (long long)p->n);
    }
    for (int64_t k = 0; k < nframes && s == PD_OK; k++) {
        pd_frame_info fi;
        double tip;
        int64_t ndamaged;
        if ((s = pd_read_frame_info(f, frames[k], &fi)) != PD_OK ||
            (s = pd_read_frame_vectors(f, frames[k], p->n, disp, NULL)) != PD_OK ||
            (s = pd_read_frame_damage(f, p, frames[k], &b, &intact, damage)) != PD_OK ||
            (s = pd_crack_tip(p, disp, damage, o.axis, o.threshold, &tip, &ndamaged)) != PD_OK)
            break;
        if (k == 0) /* only once the first frame is known to be readable */
            printf("# step time_s tip_m n_damaged\n");
        printf("%lld %.9e %.9e %lld\n", (long long)fi.step, fi.time, tip, (long long)ndamaged);
    }
    if (s == PD_OK && fflush(stdout) != 0)
        s = pd_fail(PD_ERR_IO, "cannot write to stdout");
    free(damage);
    for (int d = 0; d < 3; d++)
        free(disp[d]);
    free(intact);
    pd_frames_free_list(nframes, frames);
    pd_bonds_free(b);
    pd_particles_free(p);
    pd_file_close(f);
    return s == PD_OK ? 0 : fail();
}
