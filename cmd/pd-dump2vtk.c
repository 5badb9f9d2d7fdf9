/*
 * pd-dump2vtk -- the frames of a run as VTK files for ParaView.
 *
 * Each frame becomes DIR/NAME_<step, 8 digits>.vtu, a VTK XML unstructured
 * grid of vertex cells at the current positions y = x + u (x the reference
 * /particles position, u the frame's displacement) with point data
 * displacement, velocity, damage, material and id; DIR/NAME.pvd lists them
 * with their times, so ParaView opens the whole run as one time series.
 * Damage is the frame's `damage` field when pd-damage stored it, otherwise
 * it is computed from the frame's bond state (seed 000 eq. 10, pd_damage).
 * A run from a pre-cracked model (/bonds/precrack) also gets damage_run, the
 * damage without the pre-crack (pd_damage_no_precrack, or the frame's
 * `damage_run` field), which shows only what broke during the run.
 * Every optional field a frame holds (pd-run --fields) goes along:
 * strain_energy_density, stress (a 9-component tensor) and von_mises.
 */
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pd.h"

#define PROG "pd-dump2vtk"
#include "cli.h"

struct options {
    const char *input;
    const char *dir;   /* -o DIR                                       */
    const char *name;  /* --name; NULL: from the input's file name      */
    int quiet, debug;
};

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: " PROG " [OPTION]... RUN.h5 -o DIR\n"
            "Write every frame of a run as DIR/NAME_STEP.vtu (VTK XML, points at the current\n"
            "positions with displacement, velocity, damage, material and id) and the\n"
            "ParaView collection DIR/NAME.pvd of all frames with their times.  NAME is the\n"
            "file name of RUN.h5 without '.h5' ('run' when RUN.h5 is '-', stdin).  A run\n"
            "with a pre-crack (pd-bonds --crack) also gets damage_run, the damage without\n"
            "the pre-crack.  The optional fields of pd-run --fields go along when the frames\n"
            "have them: strain_energy_density, stress (a tensor) and von_mises.\n"
            "\n"
            "Options:\n"
            "  -o, --output DIR    directory of the output, created when missing (required)\n"
            "      --name NAME     base name of the output files\n"
            "  -q, --quiet         no summary on stderr\n"
            "      --debug         print HDF5's own error stack\n"
            "  -h, --help          show this help\n"
            "  -V, --version       show the version\n");
}

static int parse_options(int argc, char **argv, struct options *o)
{
    enum { OPT_NAME = 256 };
    static const struct option longopts[] = {
        {"output", required_argument, 0, 'o'},
        {"name", required_argument, 0, OPT_NAME},
        {"quiet", no_argument, 0, 'q'},
        COMMON_LONGOPTS,
        {0, 0, 0, 0}};
    memset(o, 0, sizeof *o);
    int c, status = 0;
    while ((c = next_option(argc, argv, "o:qhV", longopts, usage, &o->debug, &status)) != -1) {
        switch (c) {
        case 'o':
            o->dir = optarg;
            break;
        case OPT_NAME:
            o->name = optarg;
            break;
        case 'q':
            o->quiet = 1;
            break;
        default:
            return option_error(argv, longopts);
        }
    }
    if (status)
        return status;
    if ((status = one_input(argc, argv, "RUN.h5", &o->input)) != 0)
        return status;
    if (o->dir == NULL)
        return usage_error("missing -o DIR", NULL);
    if (o->dir[0] == '\0')
        return usage_error("-o needs a directory name", NULL);
    if (o->name && (o->name[0] == '\0' || strchr(o->name, '/') != NULL))
        return usage_error("--name must be a file name without '/', not", o->name);
    return 0;
}

/* The base name of the output: --name, else the input's file name without
 * a final ".h5", else "run".  Caller frees. */
static char *output_name(const struct options *o)
{
    if (o->name)
        return strdup(o->name);
    if (strcmp(o->input, "-") == 0)
        return strdup("run");
    const char *slash = strrchr(o->input, '/');
    char *name = strdup(slash ? slash + 1 : o->input);
    if (name == NULL)
        return NULL;
    size_t len = strlen(name);
    if (len > 3 && strcmp(name + len - 3, ".h5") == 0)
        name[len - 3] = '\0';
    if (name[0] == '\0' || strcmp(name, ".") == 0 || strcmp(name, "..") == 0) {
        free(name);
        return strdup("run");
    }
    return name;
}



/* Per-particle work arrays of one frame. */
struct frame_data {
    double *disp[3], *vel[3], *pos[3], *damage, *damage_run;
    double *energy, *stress, *mises; /* the optional fields pd-run --fields wrote */
};

static pd_status frame_data_alloc(struct frame_data *d, int64_t n)
{
    memset(d, 0, sizeof *d);
    size_t bytes = (size_t)n * sizeof(double);
    int ok = (d->damage = malloc(bytes)) != NULL && (d->damage_run = malloc(bytes)) != NULL &&
             (d->energy = malloc(bytes)) != NULL && (d->stress = malloc(9 * bytes)) != NULL &&
             (d->mises = malloc(bytes)) != NULL;
    for (int k = 0; k < 3; k++)
        ok &= (d->disp[k] = malloc(bytes)) != NULL && (d->vel[k] = malloc(bytes)) != NULL &&
              (d->pos[k] = malloc(bytes)) != NULL;
    return ok ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory for %lld particles", (long long)n);
}

static void frame_data_free(struct frame_data *d)
{
    for (int k = 0; k < 3; k++) {
        free(d->disp[k]);
        free(d->vel[k]);
        free(d->pos[k]);
    }
    free(d->damage);
    free(d->damage_run);
    free(d->energy);
    free(d->stress);
    free(d->mises);
}

/* Write frame `frame` as DIR/file; file and time are filled in. */
static pd_status dump_frame(const pd_file *f, const pd_particles *p, const char *frame,
                            const char *dir, const char *name, struct frame_data *d,
                            pd_bonds **b, uint64_t **intact, char **file, double *time)
{
    pd_frame_info fi;
    pd_status s;
    int has_run = 0, has_energy = 0, has_stress = 0, has_mises = 0;
    if ((s = pd_read_frame_info(f, frame, &fi)) != PD_OK ||
        (s = pd_read_frame_scalar(f, frame, "strain_energy_density", p->n, d->energy,
                                  &has_energy)) != PD_OK ||
        (s = pd_read_frame_stress(f, frame, p->n, d->stress, &has_stress)) != PD_OK ||
        (s = pd_read_frame_scalar(f, frame, "von_mises", p->n, d->mises, &has_mises)) != PD_OK ||
        (s = pd_read_frame_vectors(f, frame, p->n, d->disp, d->vel)) != PD_OK ||
        (s = pd_read_frame_damage(f, p, frame, b, intact, d->damage)) != PD_OK ||
        (s = pd_read_frame_damage_run(f, p, frame, b, intact, d->damage_run, &has_run)) != PD_OK)
        return s;
    for (int k = 0; k < 3; k++)
        for (int64_t i = 0; i < p->n; i++)
            d->pos[k][i] = p->x[k][i] + d->disp[k][i];
    size_t len = strlen(dir) + strlen(name) + 48;
    char *path = malloc(len);
    *file = malloc(len);
    if (path == NULL || *file == NULL) {
        free(path);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    snprintf(*file, len, "%s_%08lld.vtu", name, (long long)fi.step);
    snprintf(path, len, "%s/%s", dir, *file);
    *time = fi.time;
    /* every optional field the frame has */
    pd_vtk_field extra[3];
    int nextra = 0;
    if (has_energy)
        extra[nextra++] = (pd_vtk_field){"strain_energy_density", 1, d->energy};
    if (has_stress)
        extra[nextra++] = (pd_vtk_field){"stress", 9, d->stress};
    if (has_mises)
        extra[nextra++] = (pd_vtk_field){"von_mises", 1, d->mises};
    pd_vtk_frame fr = {p->n, d->pos, d->disp, d->vel, d->damage, p->material, p->id,
                       has_run ? d->damage_run : NULL, NULL, 0, NULL, nextra, extra};
    s = pd_vtk_write(path, &fr);
    free(path);
    return s;
}

int main(int argc, char **argv)
{
    struct options o;
    int rc = parse_options(argc, argv, &o);
    if (rc)
        return rc;
    pd_h5_debug(o.debug);
    remove_temps_on_signal();

    char *name = output_name(&o);
    if (name == NULL) {
        pd_fail(PD_ERR_NOMEM, "out of memory");
        return fail();
    }
    pd_file *f = NULL;
    pd_particles *p = NULL;
    pd_bonds *b = NULL;
    uint64_t *intact = NULL;
    int64_t nframes = 0;
    char **frames = NULL, **files = NULL;
    double *times = NULL;
    struct frame_data d = {0};
    pd_status s = pd_file_open(o.input, &f);
    if (s == PD_OK && (s = pd_read_particles(f, &p)) == PD_OK &&
        (s = pd_list_frames(f, &nframes, &frames)) == PD_OK &&
        (s = frame_data_alloc(&d, p->n)) == PD_OK) {
        files = calloc((size_t)(nframes ? nframes : 1), sizeof *files);
        times = calloc((size_t)(nframes ? nframes : 1), sizeof *times);
        if (files == NULL || times == NULL)
            s = pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    if (s == PD_OK)
        s = pd_make_dirs(o.dir);
    for (int64_t k = 0; k < nframes && s == PD_OK; k++)
        s = dump_frame(f, p, frames[k], o.dir, name, &d, &b, &intact, &files[k], &times[k]);
    size_t len = strlen(o.dir) + strlen(name) + 8;
    char *pvd = malloc(len);
    if (s == PD_OK && pvd == NULL)
        s = pd_fail(PD_ERR_NOMEM, "out of memory");
    if (s == PD_OK) {
        snprintf(pvd, len, "%s/%s.pvd", o.dir, name);
        s = pd_pvd_write(pvd, nframes, files, times);
    }
    if (s == PD_OK && !o.quiet)
        fprintf(stderr, PROG ": %lld frames of %lld particles, %s\n", (long long)nframes,
                (long long)p->n, pvd);
    for (int64_t k = 0; files && k < nframes; k++)
        free(files[k]);
    free(files);
    free(times);
    free(pvd);
    free(name);
    free(intact);
    frame_data_free(&d);
    pd_frames_free_list(nframes, frames);
    pd_bonds_free(b);
    pd_particles_free(p);
    pd_file_close(f);
    return s == PD_OK ? 0 : fail();
}
