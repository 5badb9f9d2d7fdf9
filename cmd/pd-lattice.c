/*
 * pd-lattice -- make particles on a simple cubic lattice inside regions.
 *
 * Sites n*spacing (integer n per axis, anchored at the origin like LAMMPS
 * `lattice sc`) inside the union of the given regions, minus the subtracted
 * ones; each particle gets volume spacing^3 and node radius spacing/2 (seed
 * 000, "Spatial Discretization", eq. 15).  Writes /particles of a pd-h5 file,
 * and /sets: named sets of the particles made inside a region (--set), by
 * global id, for the boundary conditions of pd-run.
 * With --dimension 2 it makes a plate: the square lattice of sites
 * (i spacing, j spacing, 0) where the regions, cut at z = 0, hold the point;
 * volume spacing^2 H for the thickness H of --thickness.
 * --material-region ID=REGION paints the particles inside a region with a
 * material id (the last such region wins), for pd-run --material and
 * --interface.
 * --inside MESH (and mesh,MESH wherever a region is named) is the inside of
 * a closed surface mesh: read by pd-mesh --surface (meshio), unless MESH is
 * already such a pd-h5 /surface file, and tested by libpd's exact winding
 * number (lib/base/surface.c).
 */
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "pd.h"

#define PROG "pd-lattice"
#include "cli.h"
#define MAX_REGIONS 64
#define MAX_SETS 64
#define MAX_PAINTS 64
#define MAX_SURFACES 16

extern char **environ;

struct options {
    pd_region regions[MAX_REGIONS];
    int nregions;
    char *set_names[MAX_SETS]; /* --set NAME=REGION, in order */
    pd_region set_regions[MAX_SETS];
    int nsets;
    int32_t paint_ids[MAX_PAINTS]; /* --material-region ID=REGION, in order */
    pd_region paint_regions[MAX_PAINTS];
    int npaints;
    pd_lattice_params lp;
    int has_spacing, has_density;
    int dimension;    /* 3, or 2 for a plate                          */
    double thickness; /* --thickness H of a plate, m                  */
    int has_thickness;
    const char *output;
    int quiet, debug;
};

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: " PROG " --spacing DX --density RHO REGION... [OPTION]... [-o FILE]\n"
            "Make particles on a simple cubic lattice (a square one for a plate) inside\n"
            "regions (pd-h5 /particles).\n"
            "\n"
            "Regions (several form a union):\n"
            "  --box XLO,XHI,YLO,YHI,ZLO,ZHI\n"
            "  --cylinder AXIS,C1,C2,R,LO,HI   axis x|y|z; C1,C2 locate the axis in the\n"
            "                                  other two dimensions (LAMMPS region cylinder)\n"
            "  --sphere X,Y,Z,R\n"
            "  --inside MESH                   the inside of a closed surface mesh (STL, OBJ,\n"
            "                                  PLY, or the boundary of any mesh meshio reads;\n"
            "                                  or a pd-mesh --surface file)\n"
            "  --subtract KIND,...             cut a region out; KIND is box, cylinder,\n"
            "                                  sphere or mesh: --subtract sphere,0,0,0,1e-3,\n"
            "                                  --subtract mesh,hole.stl\n"
            "\n"
            "Options:\n"
            "  --spacing DX      lattice spacing, m (> 0)\n"
            "  --density RHO     mass density, kg/m^3 (> 0)\n"
            "  --material ID     material id (default 1)\n"
            "  --material-region ID=KIND,...\n"
            "                    the particles inside a region (KIND box, cylinder,\n"
            "                    sphere or mesh, as --subtract) get material ID; repeatable,\n"
            "                    the last region holding a particle wins:\n"
            "                    --material-region 2=box,0,1,0.5,1,0,1\n"
            "  --origin FX,FY,FZ the sites are ((i+FX) DX, (j+FY) DY, (k+FZ) DX): the lattice\n"
            "                    shifted by fractions of the spacing in [0, 1) (default 0,0,0;\n"
            "                    LAMMPS lattice sc DX origin FX FY FZ); 0.5,0.5,0.5 keeps\n"
            "                    faces on multiples of DX half a spacing from every site\n"
            "  --perturb A       move each site by uniform noise in [-A,A] per axis, m\n"
            "  --seed N          seed of the perturbation (default 1)\n"
            "  --dimension D     3 (default) or 2: a plate, the square lattice of sites\n"
            "                    (i DX, j DX, 0) where the regions cut at z = 0 hold\n"
            "                    the point (x, y, 0); needs --thickness\n"
            "  --thickness H     the plate's thickness, m (> 0; volume DX^2 H)\n"
            "  --set NAME=KIND,...\n"
            "                    name the set of the particles made inside a region\n"
            "                    (KIND box, cylinder, sphere or mesh, as --subtract), for\n"
            "                    pd-run's boundary conditions; NAME of A-Z a-z 0-9 _ . -;\n"
            "                    repeatable: --set top=box,0,1,0.9,1,0,1\n"
            "  -o, --output FILE output file, '-' for stdout (default '-')\n"
            "  -q, --quiet       no summary on stderr\n"
            "      --debug       print HDF5's own error stack\n"
            "  -h, --help        show this help\n"
            "  -V, --version     show the version\n");
}

/* The surfaces of mesh regions, read once per file. */
static struct {
    char *path;
    pd_surface *surface;
} surfaces[MAX_SURFACES];
static int nsurfaces;

static void free_surfaces(void)
{
    for (int k = 0; k < nsurfaces; k++) {
        free(surfaces[k].path);
        pd_surface_free(surfaces[k].surface);
    }
    nsurfaces = 0;
}

/* pd-mesh: beside this program (an installed or a built tree), else on PATH. */
static int find_pd_mesh(char *path, size_t len)
{
    ssize_t n = readlink("/proc/self/exe", path, len - 1);
    if (n > 0) {
        path[n] = '\0';
        char *slash = strrchr(path, '/');
        if (slash && (size_t)(slash - path) + sizeof "/pd-mesh" <= len) {
            strcpy(slash, "/pd-mesh");
            if (access(path, X_OK) == 0)
                return 1;
        }
    }
    snprintf(path, len, "pd-mesh");
    return 0;
}

/* Run `pd-mesh --surface MESH -o -` and open what it writes; its error
 * line, if it fails, becomes this program's. */
static pd_status surface_by_pd_mesh(const char *mesh, pd_file **out)
{
    char exe[PATH_MAX];
    int beside = find_pd_mesh(exe, sizeof exe);
    FILE *err = tmpfile();
    int fd[2];
    if (err == NULL || pipe(fd) != 0) {
        if (err)
            fclose(err);
        return pd_fail(PD_ERR_IO, "--inside '%s': cannot run pd-mesh: %s", mesh, strerror(errno));
    }
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_adddup2(&fa, fd[1], 1);
    posix_spawn_file_actions_adddup2(&fa, fileno(err), 2);
    posix_spawn_file_actions_addclose(&fa, fd[0]);
    posix_spawn_file_actions_addclose(&fa, fd[1]);
    char *argv[] = {"pd-mesh", "--surface", "-q", "-o", "-", "--", (char *)mesh, NULL};
    pid_t pid;
    fflush(NULL);
    int e = beside ? posix_spawn(&pid, exe, &fa, NULL, argv, environ)
                   : posix_spawnp(&pid, exe, &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    close(fd[1]);
    if (e != 0) {
        close(fd[0]);
        fclose(err);
        return pd_fail(PD_ERR_IO, "--inside '%s': cannot run pd-mesh: %s", mesh, strerror(e));
    }
    /* all it writes, then its status: a failed pd-mesh writes nothing */
    FILE *in = fdopen(fd[0], "rb");
    pd_file *f = NULL;
    pd_status s = in ? pd_file_open_stream(in, mesh, &f)
                     : pd_fail(PD_ERR_IO, "--inside '%s': %s", mesh, strerror(errno));
    if (in)
        fclose(in);
    else
        close(fd[0]);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
        ;
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        pd_file_abort(f);
        f = NULL;
        char line[400] = "";
        rewind(err);
        if (fgets(line, sizeof line, err) == NULL)
            snprintf(line, sizeof line, "pd-mesh failed");
        line[strcspn(line, "\n")] = '\0';
        const char *why = strstr(line, "error: ") ? strstr(line, "error: ") + 7 : line;
        s = pd_fail(PD_ERR_IO, "--inside '%s': %s", mesh, why);
    }
    fclose(err);
    *out = f;
    return s;
}

/* The surface of MESH: its /surface when it is a pd-h5 file, else read by
 * pd-mesh. */
static pd_status load_surface(const char *mesh, const pd_surface **out)
{
    for (int k = 0; k < nsurfaces; k++)
        if (strcmp(surfaces[k].path, mesh) == 0) {
            *out = surfaces[k].surface;
            return PD_OK;
        }
    if (nsurfaces == MAX_SURFACES)
        return pd_fail(PD_ERR_INVALID, "too many meshes (at most %d)", MAX_SURFACES);
    const int hdf5 = pd_file_is_hdf5(mesh);
    if (hdf5 < 0)
        return pd_fail(PD_ERR_IO, "--inside: %s", pd_errmsg());
    pd_file *f = NULL;
    pd_status s = hdf5 ? pd_file_open(mesh, &f) : surface_by_pd_mesh(mesh, &f);
    pd_surface *surface = NULL;
    if (s == PD_OK)
        s = pd_read_surface(f, &surface);
    pd_file_abort(f);
    if (s != PD_OK)
        return s;
    if ((surfaces[nsurfaces].path = strdup(mesh)) == NULL) {
        pd_surface_free(surface);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    surfaces[nsurfaces++].surface = surface;
    *out = surface;
    return PD_OK;
}

/* A region KIND,... of --subtract, --set or --material-region: the
 * library's kinds, or mesh,FILE.  Returns 0, 2 (usage) or 1 (a mesh that
 * cannot be read). */
static int parse_region(const char *spec, pd_region *r)
{
    if (strncmp(spec, "mesh,", 5) == 0) {
        memset(r, 0, sizeof *r);
        r->kind = PD_REGION_SURFACE;
        return load_surface(spec + 5, &r->surface) == PD_OK ? 0 : fail();
    }
    return pd_region_parse_tagged(spec, r) == PD_OK ? 0 : usage_error(pd_errmsg(), NULL);
}

static int add_region(struct options *o, pd_region_kind kind, const char *spec, int tagged)
{
    if (o->nregions == MAX_REGIONS)
        return usage_error("too many regions", NULL);
    pd_region *r = &o->regions[o->nregions];
    int rc;
    if (tagged) {
        if ((rc = parse_region(spec, r)))
            return rc;
    } else if (kind == PD_REGION_SURFACE) {
        memset(r, 0, sizeof *r);
        r->kind = kind;
        if (load_surface(spec, &r->surface) != PD_OK)
            return fail();
    } else if (pd_region_parse(kind, spec, r) != PD_OK)
        return usage_error(pd_errmsg(), NULL);
    r->subtract = tagged;
    o->nregions++;
    return 0;
}

/* --set NAME=KIND,...: a name and a region. */
static int add_set(struct options *o, const char *arg)
{
    if (o->nsets == MAX_SETS)
        return usage_error("too many sets", NULL);
    const char *eq = strchr(arg, '=');
    if (eq == NULL)
        return usage_error("--set needs NAME=KIND,... (KIND box, cylinder, sphere or mesh), not", arg);
    char name[PD_SET_NAME_MAX];
    size_t len = (size_t)(eq - arg);
    snprintf(name, sizeof name, "%.*s", (int)len, arg);
    if (len >= sizeof name || !pd_set_name_ok(name))
        return usage_error("--set NAME must be 1 to 63 of A-Z a-z 0-9 _ . - (not . or ..), not",
                           arg);
    for (int k = 0; k < o->nsets; k++)
        if (strcmp(o->set_names[k], name) == 0)
            return usage_error("--set: a name given twice:", name);
    pd_region *r = &o->set_regions[o->nsets];
    int rc = parse_region(eq + 1, r);
    if (rc)
        return rc;
    if ((o->set_names[o->nsets] = strdup(name)) == NULL)
        return usage_error("out of memory", NULL);
    o->nsets++;
    return 0;
}

/* --material-region ID=KIND,...: a material id and a region. */
static int add_paint(struct options *o, const char *arg)
{
    if (o->npaints == MAX_PAINTS)
        return usage_error("too many --material-region", NULL);
    const char *eq = strchr(arg, '=');
    char id[32];
    int64_t iv;
    if (eq == NULL || (size_t)(eq - arg) >= sizeof id)
        return usage_error("--material-region needs ID=KIND,... (KIND box, cylinder, "
                           "sphere or mesh), not",
                           arg);
    snprintf(id, sizeof id, "%.*s", (int)(eq - arg), arg);
    if (!pd_parse_int64(id, &iv) || iv < 0 || iv > INT32_MAX)
        return usage_error("--material-region ID must be a non-negative integer, not", arg);
    int rc = parse_region(eq + 1, &o->paint_regions[o->npaints]);
    if (rc)
        return rc;
    o->paint_ids[o->npaints++] = (int32_t)iv;
    return 0;
}

static int parse_options(int argc, char **argv, struct options *o)
{
    enum { OPT_BOX = 256, OPT_CYL, OPT_SPHERE, OPT_INSIDE, OPT_SUB, OPT_ORIGIN, OPT_SPACING, OPT_DENSITY, OPT_MATERIAL,
           OPT_PERTURB, OPT_SEED, OPT_DIMENSION, OPT_THICKNESS, OPT_SET, OPT_PAINT };
    static const struct option longopts[] = {
        {"box", required_argument, 0, OPT_BOX},
        {"cylinder", required_argument, 0, OPT_CYL},
        {"sphere", required_argument, 0, OPT_SPHERE},
        {"inside", required_argument, 0, OPT_INSIDE},
        {"subtract", required_argument, 0, OPT_SUB},
        {"origin", required_argument, 0, OPT_ORIGIN},
        {"spacing", required_argument, 0, OPT_SPACING},
        {"density", required_argument, 0, OPT_DENSITY},
        {"material", required_argument, 0, OPT_MATERIAL},
        {"perturb", required_argument, 0, OPT_PERTURB},
        {"seed", required_argument, 0, OPT_SEED},
        {"dimension", required_argument, 0, OPT_DIMENSION},
        {"thickness", required_argument, 0, OPT_THICKNESS},
        {"set", required_argument, 0, OPT_SET},
        {"material-region", required_argument, 0, OPT_PAINT},
        {"output", required_argument, 0, 'o'},
        {"quiet", no_argument, 0, 'q'},
        COMMON_LONGOPTS,
        {0, 0, 0, 0}};
    memset(o, 0, sizeof *o);
    o->lp.material = 1;
    o->lp.seed = 1;
    o->dimension = 3;
    o->output = "-";
    int c, rc, status = 0;
    int64_t iv;
    while ((c = next_option(argc, argv, "o:qhV", longopts, usage, &o->debug, &status)) != -1) {
        switch (c) {
        case OPT_BOX:
            if ((rc = add_region(o, PD_REGION_BOX, optarg, 0)))
                return rc;
            break;
        case OPT_CYL:
            if ((rc = add_region(o, PD_REGION_CYLINDER, optarg, 0)))
                return rc;
            break;
        case OPT_SPHERE:
            if ((rc = add_region(o, PD_REGION_SPHERE, optarg, 0)))
                return rc;
            break;
        case OPT_INSIDE:
            if ((rc = add_region(o, PD_REGION_SURFACE, optarg, 0)))
                return rc;
            break;
        case OPT_SUB:
            if ((rc = add_region(o, PD_REGION_BOX, optarg, 1)))
                return rc;
            break;
        case OPT_ORIGIN:
            if (!pd_parse_doubles(optarg, o->lp.origin, 3) || !(o->lp.origin[0] >= 0) ||
                !(o->lp.origin[0] < 1) || !(o->lp.origin[1] >= 0) || !(o->lp.origin[1] < 1) ||
                !(o->lp.origin[2] >= 0) || !(o->lp.origin[2] < 1))
                return usage_error("--origin needs FX,FY,FZ, fractions of the spacing in [0, 1), "
                                   "not",
                                   optarg);
            break;
        case OPT_SPACING:
            if (!pd_parse_double(optarg, &o->lp.spacing) || !(o->lp.spacing > 0))
                return usage_error("--spacing must be a positive number, not", optarg);
            o->has_spacing = 1;
            break;
        case OPT_DENSITY:
            if (!pd_parse_double(optarg, &o->lp.density) || !(o->lp.density > 0))
                return usage_error("--density must be a positive number, not", optarg);
            o->has_density = 1;
            break;
        case OPT_MATERIAL:
            if (!pd_parse_int64(optarg, &iv) || iv < 0 || iv > INT32_MAX)
                return usage_error("--material must be a non-negative integer, not", optarg);
            o->lp.material = (int32_t)iv;
            break;
        case OPT_PERTURB:
            if (!pd_parse_double(optarg, &o->lp.perturb) || !(o->lp.perturb >= 0))
                return usage_error("--perturb must be zero or a positive number, not", optarg);
            break;
        case OPT_SEED:
            if (!pd_parse_int64(optarg, &iv) || iv < 0)
                return usage_error("--seed must be a non-negative integer, not", optarg);
            o->lp.seed = (unsigned long)iv;
            break;
        case OPT_DIMENSION:
            if (!pd_parse_int64(optarg, &iv) || (iv != 2 && iv != 3))
                return usage_error("--dimension must be 2 or 3, not", optarg);
            o->dimension = (int)iv;
            break;
        case OPT_THICKNESS:
            if (!pd_parse_double(optarg, &o->thickness) || !(o->thickness > 0))
                return usage_error("--thickness must be a positive number, not", optarg);
            o->has_thickness = 1;
            break;
        case OPT_SET:
            if ((rc = add_set(o, optarg)))
                return rc;
            break;
        case OPT_PAINT:
            if ((rc = add_paint(o, optarg)))
                return rc;
            break;
        case 'o':
            o->output = optarg;
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
    if (optind < argc)
        return usage_error("unexpected argument", argv[optind]);
    if (!o->has_spacing)
        return usage_error("--spacing is required", NULL);
    if (!o->has_density)
        return usage_error("--density is required", NULL);
    if (o->dimension == 2 && !o->has_thickness)
        return usage_error("--dimension 2 needs --thickness", NULL);
    if (o->dimension == 2 && o->lp.origin[2] != 0)
        return usage_error("a plate's sites are at z = 0: give --origin FX,FY,0", NULL);
    if (o->has_thickness && o->dimension != 2)
        return usage_error("--thickness is for a plate: give --dimension 2", NULL);
    int adds = 0;
    for (int r = 0; r < o->nregions; r++)
        adds += !o->regions[r].subtract;
    if (adds == 0)
        return usage_error("give at least one region (--box, --cylinder, --sphere or --inside)",
                           NULL);
    return 0;
}

static void free_set_names(struct options *o)
{
    for (int k = 0; k < o->nsets; k++)
        free(o->set_names[k]);
}

/* One warning per region with a face on a lattice plane to rounding. */
static void warn_rounding(const struct options *o)
{
    static const char *kind[] = {"--box", "--cylinder", "--sphere", "--inside"};
    char what[PD_SET_NAME_MAX + 32], text[512];
    for (int k = 0; k < o->nregions; k++)
        if (pd_region_rounding(&o->regions[k], o->lp.spacing, o->lp.origin,
                               o->regions[k].subtract ? "--subtract" : kind[o->regions[k].kind],
                               text, sizeof text))
            fprintf(stderr, PROG ": warning: %s\n", text);
    for (int k = 0; k < o->nsets; k++) {
        snprintf(what, sizeof what, "--set %s", o->set_names[k]);
        if (pd_region_rounding(&o->set_regions[k], o->lp.spacing, o->lp.origin, what, text,
                               sizeof text))
            fprintf(stderr, PROG ": warning: %s\n", text);
    }
    for (int k = 0; k < o->npaints; k++) {
        snprintf(what, sizeof what, "--material-region %d", (int)o->paint_ids[k]);
        if (pd_region_rounding(&o->paint_regions[k], o->lp.spacing, o->lp.origin, what, text,
                               sizeof text))
            fprintf(stderr, PROG ": warning: %s\n", text);
    }
}

int main(int argc, char **argv)
{
    /* before getopt_long permutes argv */
    char *cmdline = pd_join_argv(argc, argv);
    struct options o;
    int rc = parse_options(argc, argv, &o);
    if (rc) {
        free_set_names(&o);
        free_surfaces();
        free(cmdline);
        return rc;
    }
    pd_h5_debug(o.debug);
    remove_temps_on_signal();

    pd_particles *p = NULL;
    pd_sets *sets = NULL;
    pd_status s = o.dimension == 2
                      ? pd_plate_make(o.regions, o.nregions, &o.lp, o.thickness, &p)
                      : pd_lattice_make(o.regions, o.nregions, &o.lp, &p);
    if (s == PD_OK && !o.quiet)
        warn_rounding(&o);
    for (int k = 0; k < o.npaints && s == PD_OK; k++)
        pd_material_paint(p, &o.paint_regions[k], o.paint_ids[k]);
    if (s == PD_OK && (sets = pd_sets_new()) == NULL)
        s = pd_fail(PD_ERR_NOMEM, "out of memory");
    for (int k = 0; k < o.nsets && s == PD_OK; k++)
        s = pd_sets_add_region(sets, o.set_names[k], &o.set_regions[k], p);
    pd_file *out = NULL;
    if (s == PD_OK)
        s = pd_file_create(o.output, &out);
    if (s == PD_OK)
        s = pd_write_model(out, NULL, cmdline ? cmdline : PROG, p, NULL, sets);
    if (s == PD_OK)
        s = pd_file_close(out);
    else
        pd_file_abort(out);
    free(cmdline);
    free_set_names(&o);
    if (s != PD_OK) {
        pd_sets_free(sets);
        pd_particles_free(p);
        free_surfaces();
        return fail();
    }
    if (!o.quiet) {
        for (int k = 0; k < nsurfaces; k++)
            fprintf(stderr, PROG ": mesh '%s': a closed surface of %lld triangles, volume %.10g m^3\n",
                    surfaces[k].path, (long long)pd_surface_triangles(surfaces[k].surface),
                    fabs(pd_surface_volume(surfaces[k].surface)));
        fprintf(stderr, PROG ": %lld particles, spacing %g m%s\n", (long long)p->n, p->spacing,
                p->dimension == 2 ? ", a 2-D plate" : "");
        for (int k = 0; k < sets->count; k++)
            fprintf(stderr, PROG ": set '%s': %lld particles\n", sets->set[k].name,
                    (long long)sets->set[k].n);
    }
    pd_sets_free(sets);
    pd_particles_free(p);
    free_surfaces();
    return 0;
}
