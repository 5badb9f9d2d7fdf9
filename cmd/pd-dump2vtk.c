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
 * The arrays are compressed by zlib (--compress LEVEL, 0 for raw).  A run
 * with an indenter or a projectile also gets DIR/NAME_indenter_STEP.vtu and
 * DIR/NAME_projectile_STEP.vtu, the sphere's surface at that frame, listed
 * in the .pvd at the frame's time as parts 1 and on (the particles are
 * part 0), each named.
 *
 * With --xdmf it copies nothing: it writes an XDMF file that describes the
 * frames of RUN.h5 where they are (pd_xdmf_write), which ParaView's XDMF
 * Reader opens as the same time series.
 */
#define _XOPEN_SOURCE 700 /* realpath (XSI) */
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
    int level;         /* --compress: zlib level, 0 raw                 */
    int has_level;
    int xdmf;          /* --xdmf: -o names the XDMF file (optional)     */
    int quiet, debug;
};

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: " PROG " [OPTION]... RUN.h5 -o DIR\n"
            "  or:  " PROG " --xdmf RUN.h5 [-o FILE.xdmf]\n"
            "Write every frame of a run as DIR/NAME_STEP.vtu (VTK XML, points at the current\n"
            "positions with displacement, velocity, damage, material and id) and the\n"
            "ParaView collection DIR/NAME.pvd of all frames with their times.  NAME is the\n"
            "file name of RUN.h5 without '.h5' ('run' when RUN.h5 is '-', stdin).  A run\n"
            "with a pre-crack (pd-bonds --crack) also gets damage_run, the damage without\n"
            "the pre-crack.  The optional fields of pd-run --fields go along when the frames\n"
            "have them: strain_energy_density, stress (a tensor) and von_mises.  A run with\n"
            "an indenter or a projectile also gets its sphere at every frame,\n"
            "DIR/NAME_indenter_STEP.vtu and DIR/NAME_projectile_STEP.vtu, in the .pvd.\n"
            "With --xdmf nothing is copied: FILE.xdmf (default RUN.xdmf beside RUN.h5)\n"
            "describes the frames where they are in RUN.h5, for ParaView's XDMF Reader.\n"
            "\n"
            "Options:\n"
            "  -o, --output DIR    directory of the output, created when missing (required);\n"
            "                      with --xdmf the XDMF file\n"
            "      --xdmf          describe the frames in XDMF instead of copying them\n"
            "      --name NAME     base name of the output files\n"
            "      --compress LEVEL  zlib level of the arrays, 1 (fast, the default) to 9\n"
            "                      (small); 0 writes them raw\n"
            "  -q, --quiet         no summary on stderr\n"
            "      --debug         print HDF5's own error stack\n"
            "  -h, --help          show this help\n"
            "  -V, --version       show the version\n");
}

static int parse_options(int argc, char **argv, struct options *o)
{
    enum { OPT_NAME = 256, OPT_COMPRESS, OPT_XDMF };
    static const struct option longopts[] = {
        {"output", required_argument, 0, 'o'},
        {"name", required_argument, 0, OPT_NAME},
        {"compress", required_argument, 0, OPT_COMPRESS},
        {"xdmf", no_argument, 0, OPT_XDMF},
        {"quiet", no_argument, 0, 'q'},
        COMMON_LONGOPTS,
        {0, 0, 0, 0}};
    memset(o, 0, sizeof *o);
    o->level = PD_VTK_ZLIB_LEVEL;
    int c, status = 0;
    int64_t level;
    while ((c = next_option(argc, argv, "o:qhV", longopts, usage, &o->debug, &status)) != -1) {
        switch (c) {
        case 'o':
            o->dir = optarg;
            break;
        case OPT_NAME:
            o->name = optarg;
            break;
        case OPT_COMPRESS:
            if (!pd_parse_int64(optarg, &level) || level < 0 || level > 9)
                return usage_error("--compress needs a zlib level 0 to 9, not", optarg);
            o->level = (int)level;
            o->has_level = 1;
            break;
        case OPT_XDMF:
            o->xdmf = 1;
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
    if (o->xdmf) {
        if (strcmp(o->input, "-") == 0)
            return usage_error("--xdmf describes a run file in place: give its name, not", "-");
        if (o->name || o->has_level)
            return usage_error("--xdmf copies nothing: it takes no --name or --compress", NULL);
        if (o->dir && o->dir[0] == '\0')
            return usage_error("-o needs a file name", NULL);
        return 0;
    }
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

/* The entries of the .pvd: a file, its time, its part and the part's name. */
struct collection {
    int64_t n;
    char **files;
    double *times;
    int *parts;
    const char **names;
};

/* Add DIR/NAME_WHAT_STEP.vtu (WHAT "" for the particles) to c; *path
 * gets its path (caller frees). */
static pd_status add_entry(struct collection *c, const char *dir, const char *name,
                           const char *what, const pd_frame_info *fi, int part, char **path)
{
    size_t len = strlen(dir) + strlen(name) + strlen(what) + 48;
    char *file = malloc(len);
    *path = malloc(len);
    if (file == NULL || *path == NULL) {
        free(file);
        free(*path);
        *path = NULL;
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    snprintf(file, len, "%s%s%s_%08lld.vtu", name, what[0] ? "_" : "", what, (long long)fi->step);
    snprintf(*path, len, "%s/%s", dir, file);
    c->files[c->n] = file;
    c->times[c->n] = fi->time;
    c->parts[c->n] = part;
    c->names[c->n] = what[0] ? what : "particles";
    c->n++;
    return PD_OK;
}

/* The indenter's and the projectile's spheres at a frame, parts 1 and on. */
static pd_status dump_spheres(const pd_file *f, const pd_frame_info *fi, const struct options *o,
                              const char *name, struct collection *c)
{
    pd_frame_sphere sp[2];
    int n;
    pd_status s = pd_frame_spheres(f, fi, sp, &n);
    for (int k = 0; k < n && s == PD_OK; k++) {
        char *path;
        if ((s = add_entry(c, o->dir, name, sp[k].name, fi, 1 + k, &path)) != PD_OK)
            break;
        s = pd_vtk_write_sphere(path, &sp[k], o->level);
        free(path);
    }
    return s;
}

/* Write frame `frame` as DIR/NAME_STEP.vtu and its spheres, listed in c. */
static pd_status dump_frame(const pd_file *f, const pd_particles *p, const char *frame,
                            const struct options *o, const char *name, struct frame_data *d,
                            pd_bonds **b, uint64_t **intact, struct collection *c)
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
    char *path;
    if ((s = add_entry(c, o->dir, name, "", &fi, 0, &path)) != PD_OK)
        return s;
    /* every optional field the frame has */
    pd_vtk_field extra[3];
    int nextra = 0;
    if (has_energy)
        extra[nextra++] = (pd_vtk_field){"strain_energy_density", 1, d->energy};
    if (has_stress)
        extra[nextra++] = (pd_vtk_field){"stress", 9, d->stress};
    if (has_mises)
        extra[nextra++] = (pd_vtk_field){"von_mises", 1, d->mises};
    pd_vtk_frame fr = {.n = p->n,
                       .position = d->pos,
                       .displacement = d->disp,
                       .velocity = d->vel,
                       .damage = d->damage,
                       .material = p->material,
                       .id = p->id,
                       .damage_run = has_run ? d->damage_run : NULL,
                       .nextra = nextra,
                       .extra = extra,
                       .zlib_level = o->level};
    s = pd_vtk_write(path, &fr);
    free(path);
    return s == PD_OK ? dump_spheres(f, &fi, o, name, c) : s;
}

/* The folder of `path` as an absolute path without links, or NULL (caller
 * frees). */
static char *real_dir(const char *path)
{
    char *copy = strdup(path);
    if (copy == NULL)
        return NULL;
    char *slash = strrchr(copy, '/');
    char *dir = realpath(slash == NULL ? "." : slash == copy ? "/" : (*slash = '\0', copy), NULL);
    free(copy);
    return dir;
}

/* --xdmf: OUT.xdmf (default: RUN.h5 less '.h5', plus '.xdmf') describing
 * the frames of RUN.h5 in place.  The run file is named in it by its file
 * name when both are in one folder (the pair can then move together), else
 * by its absolute path. */
static int describe(const struct options *o)
{
    size_t len = strlen(o->input);
    char *out = NULL, *h5dir = NULL, *outdir = NULL, *h5ref = NULL;
    if (o->dir)
        out = strdup(o->dir);
    else if ((out = malloc(len + 6)) != NULL) {
        memcpy(out, o->input, len + 1);
        if (len > 3 && strcmp(out + len - 3, ".h5") == 0)
            out[len - 3] = '\0';
        strcat(out, ".xdmf");
    }
    pd_status s = out ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory");
    if (s == PD_OK && (h5dir = real_dir(o->input)) == NULL)
        s = pd_fail(PD_ERR_IO, "cannot find the folder of '%s'", o->input);
    if (s == PD_OK && (outdir = real_dir(out)) == NULL)
        s = pd_fail(PD_ERR_IO, "cannot write '%s': no such folder", out);
    if (s == PD_OK) {
        const char *slash = strrchr(o->input, '/');
        h5ref = strcmp(h5dir, outdir) == 0 ? strdup(slash ? slash + 1 : o->input)
                                           : realpath(o->input, NULL);
        if (h5ref == NULL)
            s = pd_fail(PD_ERR_IO, "cannot find '%s'", o->input);
    }
    pd_file *f = NULL;
    pd_particles *p = NULL;
    int64_t nframes = 0;
    if (s == PD_OK && (s = pd_file_open(o->input, &f)) == PD_OK &&
        (s = pd_read_particles(f, &p)) == PD_OK)
        s = pd_xdmf_write(f, h5ref, out, &nframes);
    if (s == PD_OK && !o->quiet)
        fprintf(stderr, PROG ": %lld frames of %lld particles described in place, %s (ParaView: XDMF Reader)\n",
                (long long)nframes, (long long)p->n, out);
    pd_particles_free(p);
    pd_file_close(f);
    free(out);
    free(h5dir);
    free(outdir);
    free(h5ref);
    return s == PD_OK ? 0 : fail();
}

int main(int argc, char **argv)
{
    struct options o;
    int rc = parse_options(argc, argv, &o);
    if (rc)
        return rc;
    pd_h5_debug(o.debug);
    remove_temps_on_signal();
    if (o.xdmf)
        return describe(&o);

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
    char **frames = NULL;
    struct collection c = {0};
    struct frame_data d = {0};
    pd_status s = pd_file_open(o.input, &f);
    if (s == PD_OK && (s = pd_read_particles(f, &p)) == PD_OK &&
        (s = pd_list_frames(f, &nframes, &frames)) == PD_OK &&
        (s = frame_data_alloc(&d, p->n)) == PD_OK) {
        /* the particles and at most two spheres a frame */
        size_t most = 3 * (size_t)(nframes ? nframes : 1);
        c.files = calloc(most, sizeof *c.files);
        c.times = calloc(most, sizeof *c.times);
        c.parts = calloc(most, sizeof *c.parts);
        c.names = calloc(most, sizeof *c.names);
        if (c.files == NULL || c.times == NULL || c.parts == NULL || c.names == NULL)
            s = pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    if (s == PD_OK)
        s = pd_make_dirs(o.dir);
    for (int64_t k = 0; k < nframes && s == PD_OK; k++)
        s = dump_frame(f, p, frames[k], &o, name, &d, &b, &intact, &c);
    size_t len = strlen(o.dir) + strlen(name) + 8;
    char *pvd = malloc(len);
    if (s == PD_OK && pvd == NULL)
        s = pd_fail(PD_ERR_NOMEM, "out of memory");
    if (s == PD_OK) {
        snprintf(pvd, len, "%s/%s.pvd", o.dir, name);
        s = pd_pvd_write(pvd, c.n, c.files, c.times, c.parts, c.names);
    }
    if (s == PD_OK && !o.quiet) {
        fprintf(stderr, PROG ": %lld frames of %lld particles, ", (long long)nframes,
                (long long)p->n);
        const char *kinds[2] = {"indenter", "projectile"};
        for (int k = 0; k < 2; k++) {
            int64_t count = 0;
            for (int64_t e = 0; e < c.n; e++)
                count += strcmp(c.names[e], kinds[k]) == 0;
            if (count)
                fprintf(stderr, "%lld %s spheres, ", (long long)count, kinds[k]);
        }
        fprintf(stderr, "%s\n", pvd);
    }
    for (int64_t k = 0; k < c.n; k++)
        free(c.files[k]);
    free(c.files);
    free(c.times);
    free(c.parts);
    free(c.names);
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
