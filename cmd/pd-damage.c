/*
 * pd-damage -- damage per particle for every frame of a run.
 *
 * phi_i = 1 - sum_{j intact} V_j / sum_{j in reference family} V_j
 * (seed 000 eq. 10, as LAMMPS compute damage/atom), stored as the frame
 * field `damage`, and a table on stdout per frame: step, time, broken bonds,
 * mean and max damage, and the number of particles with damage > 0.3;
 * with --fragments the number of fragments and the largest one's share of
 * the body's volume (pd_fragments).
 *
 * Pre-cracked bonds (/bonds/precrack, pd-bonds --crack) are broken bonds and
 * count in phi.  With --no-precrack they are left out of both sums
 * (pd_damage_no_precrack): the damage of what broke during the run, stored
 * as the frame field `damage_run`.
 *
 * pd-run writes `damage` into every frame itself; updating a run in place
 * then finds it there, and the file is read, not copied, and left as it is.
 */
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pd.h"

#define PROG "pd-damage"
#include "cli.h"

struct options {
    const char *input;
    const char *output;  /* NULL: update INPUT in place (through a copy) */
    double threshold;
    int no_precrack;     /* damage without the pre-crack, field damage_run */
    int fragments;       /* the table's fragments columns (pd_fragments) */
    int no_write, quiet, debug;
};

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: " PROG " [OPTION]... RUN.h5 [-o OUT.h5]\n"
            "Damage per particle for every frame of a run (seed 000 eq. 10), stored as the\n"
            "frame field 'damage', and a table on stdout (stderr with -o -).  Without -o,\n"
            "RUN.h5 is updated (through a temporary copy renamed over it), unless every\n"
            "frame already holds this very damage (pd-run writes it): then it is left as is.\n"
            "\n"
            "Options:\n"
            "  -o, --output FILE   write the run with damage to FILE ('-' for stdout)\n"
            "  -n, --no-write      only print the table\n"
            "  -q, --quiet         no table\n"
            "  --threshold D       count particles with damage above D (default %g)\n"
            "  --no-precrack       leave the pre-crack (pd-bonds --crack) out: damage and\n"
            "                      broken bonds of the run alone, stored as 'damage_run'\n"
            "  --fragments         add the number of fragments (the pieces the intact bonds\n"
            "                      hold together) and the largest one's share of the volume\n"
            "      --debug         print HDF5's own error stack\n"
            "  -h, --help          show this help\n"
            "  -V, --version       show the version\n",
            PD_DAMAGE_THRESHOLD);
}

static int parse_options(int argc, char **argv, struct options *o)
{
    enum { OPT_THRESHOLD = 256, OPT_NO_PRECRACK, OPT_FRAGMENTS };
    static const struct option longopts[] = {
        {"output", required_argument, 0, 'o'},
        {"no-write", no_argument, 0, 'n'},
        {"quiet", no_argument, 0, 'q'},
        {"threshold", required_argument, 0, OPT_THRESHOLD},
        {"no-precrack", no_argument, 0, OPT_NO_PRECRACK},
        {"fragments", no_argument, 0, OPT_FRAGMENTS},
        COMMON_LONGOPTS,
        {0, 0, 0, 0}};
    memset(o, 0, sizeof *o);
    o->threshold = PD_DAMAGE_THRESHOLD;
    int c, status = 0;
    while ((c = next_option(argc, argv, "o:nqhV", longopts, usage, &o->debug, &status)) != -1) {
        switch (c) {
        case 'o':
            o->output = optarg;
            break;
        case 'n':
            o->no_write = 1;
            break;
        case 'q':
            o->quiet = 1;
            break;
        case OPT_THRESHOLD:
            if (!pd_parse_double(optarg, &o->threshold) || o->threshold < 0 || o->threshold > 1)
                return usage_error("--threshold must be a number in [0,1], not", optarg);
            break;
        case OPT_NO_PRECRACK:
            o->no_precrack = 1;
            break;
        case OPT_FRAGMENTS:
            o->fragments = 1;
            break;
        default:
            return option_error(argv, longopts);
        }
    }
    if (status)
        return status;
    if ((status = one_input(argc, argv, "RUN.h5", &o->input)) != 0)
        return status;
    if (o->no_write && o->output)
        return usage_error("--no-write and -o exclude each other", NULL);
    if (!o->no_write && !o->output && strcmp(o->input, "-") == 0)
        o->output = "-";
    if (o->output && strcmp(o->output, "-") == 0)
        o->no_write = 0;
    return 0;
}

/* One pass over the frames of f: the damage of each, its table line into
 * `table` (NULL: none) and, by `mode`, written as the frame field
 * (WRITE), compared with the field the frame holds (COMPARE: *same = 0
 * when one differs or is missing), or neither (READ). */
enum pass_mode { READ, WRITE, COMPARE };

static pd_status frames_pass(pd_file *f, const struct options *o, enum pass_mode mode,
                             FILE *table, int *same)
{
    pd_particles *p = NULL;
    pd_bonds *b = NULL;
    int64_t nframes = 0;
    char **names = NULL;
    pd_status s;
    if ((s = pd_read_particles(f, &p)) == PD_OK && (s = pd_read_bonds(f, p, &b)) == PD_OK)
        s = pd_list_frames(f, &nframes, &names);
    double *damage = NULL, *stored = NULL;
    uint64_t *intact = NULL;
    if (s == PD_OK) {
        damage = malloc((size_t)(p->n > 0 ? p->n : 1) * sizeof(double));
        stored = malloc((size_t)(p->n > 0 ? p->n : 1) * sizeof(double));
        intact = malloc((size_t)(pd_bits_words(b->count) + 1) * sizeof(uint64_t));
        if (damage == NULL || stored == NULL || intact == NULL)
            s = pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    const char *field = o->no_precrack ? "damage_run" : "damage";
    double volume = 0; /* the body's, for the largest fragment's share */
    for (int64_t i = 0; s == PD_OK && o->fragments && i < p->n; i++)
        volume += p->volume[i];
    for (int64_t k = 0; k < nframes && s == PD_OK; k++) {
        pd_frame_info fi;
        if ((s = pd_read_frame_info(f, names[k], &fi)) != PD_OK ||
            (s = pd_read_frame_state(f, names[k], b->count, intact)) != PD_OK)
            break;
        if (k == 0 && table) /* only once a frame is known to be readable */
            fprintf(table, "# step time_s broken_bonds mean_damage max_damage n_damage_gt_%g%s\n",
                    o->threshold, o->fragments ? " fragments largest_fraction" : "");
        if (o->no_precrack)
            pd_damage_no_precrack(p, b, intact, damage);
        else
            pd_damage(p, b, intact, damage);
        /* with --no-precrack only the bonds the run broke */
        int64_t broken =
            pd_bits_count_broken_except(intact, o->no_precrack ? b->precrack : NULL, b->count) / 2;
        double sum = 0, max = 0;
        int64_t above = 0;
        for (int64_t i = 0; i < p->n; i++) {
            sum += damage[i];
            max = damage[i] > max ? damage[i] : max;
            above += damage[i] > o->threshold;
        }
        int64_t pieces = 0;
        double largest = 0;
        if (o->fragments && table &&
            (s = pd_fragments(p, b, intact, &pieces, &largest)) != PD_OK)
            break;
        if (table) {
            fprintf(table, "%lld %.9e %lld %.9f %.9f %lld", (long long)fi.step, fi.time,
                    (long long)broken, sum / (double)p->n, max, (long long)above);
            if (o->fragments)
                fprintf(table, " %lld %.9f", (long long)pieces,
                        volume > 0 ? largest / volume : 0.0);
            fputc('\n', table);
        }
        if (mode == WRITE)
            s = pd_write_frame_scalar(f, names[k], field, p->n, damage);
        else if (mode == COMPARE && *same) {
            int present = 0; /* one unreadable is one to write */
            *same = pd_read_frame_scalar(f, names[k], field, p->n, stored, &present) == PD_OK &&
                    present && memcmp(stored, damage, (size_t)p->n * sizeof(double)) == 0;
        }
    }
    free(damage);
    free(stored);
    free(intact);
    pd_frames_free_list(nframes, names);
    pd_bonds_free(b);
    pd_particles_free(p);
    return s;
}

/* Updating RUN.h5 in place when every frame already holds this very
 * damage (pd-run writes `damage` into each frame): the file is left as it
 * is, read and never copied, and the table printed.  1 when so (or when
 * the run cannot be read: *s says), 0 when the file is to be updated. */
static int unchanged(const struct options *o, FILE *table, pd_status *s)
{
    pd_file *f = NULL;
    if ((*s = pd_file_open(o->input, &f)) != PD_OK)
        return 1;
    char *lines = NULL;
    size_t len = 0;
    FILE *mem = table ? open_memstream(&lines, &len) : NULL;
    int same = 1;
    *s = frames_pass(f, o, COMPARE, mem, &same);
    if (mem)
        fclose(mem);
    pd_file_close(f);
    if (*s == PD_OK && same && lines)
        fputs(lines, table);
    free(lines);
    return *s != PD_OK || same;
}

int main(int argc, char **argv)
{
    /* before getopt_long permutes argv */
    char *cmdline = pd_join_argv(argc, argv);
    struct options o;
    int rc = parse_options(argc, argv, &o);
    if (rc) {
        free(cmdline);
        return rc;
    }
    pd_h5_debug(o.debug);
    remove_temps_on_signal();

    /* a table goes to stdout unless stdout carries the file */
    FILE *table = (o.output && strcmp(o.output, "-") == 0) ? stderr : stdout;
    if (o.quiet)
        table = NULL;
    pd_status s = PD_OK;
    const int in_place = !o.no_write && (o.output == NULL || strcmp(o.output, o.input) == 0) &&
                         strcmp(o.input, "-") != 0;
    if (in_place && unchanged(&o, table, &s)) {
        free(cmdline);
        return s == PD_OK ? 0 : fail();
    }
    pd_file *f = NULL;
    s = o.no_write ? pd_file_open(o.input, &f)
                   : pd_file_update(o.input, o.output ? o.output : o.input, &f);
    if (s != PD_OK) {
        free(cmdline);
        return fail();
    }
    s = frames_pass(f, &o, o.no_write ? READ : WRITE, table, NULL);
    if (s == PD_OK && !o.no_write)
        s = pd_append_history(f, cmdline ? cmdline : PROG);
    free(cmdline);
    if (s == PD_OK)
        s = pd_file_close(f);
    else
        pd_file_abort(f);
    return s == PD_OK ? 0 : fail();
}
