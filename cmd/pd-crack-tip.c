/*
 * pd-crack-tip -- crack tips, crack extension and crack speed in every frame
 * of a run; or the crack front of a 3-D body.
 *
 * Seed 004 (Silling & Askari 2005) §5: the tip is the largest coordinate
 * along an axis among the particles whose damage phi exceeds phi_0 = 0.3,
 * here at the current positions y = x + u; the crack growth distance
 * Delta a(t) (Fig. 7) has the crack speed as its slope.  Both tips of a
 * centre crack are followed, the lower (smallest coordinate) and the upper
 * (largest), each Delta a counted from the first frame with damage so that
 * both grow positive, and each speed the slope of a least-squares line
 * through a window of frames (pd_crack_extension, pd_crack_speed).  With
 * --front the table describes the outline of the damaged zone instead
 * (pd_crack_front): its size, its largest and mean distance from an axis or
 * a point, its extent along the axis.  Damage is the frame's `damage` field
 * when pd-damage stored it, otherwise it is computed from the frame's bond
 * state (seed 000 eq. 10, pd_damage), pre-crack included: the ends of a
 * pre-crack are where growth starts.  --plot draws Delta a(t) with gnuplot,
 * --path writes the damaged zone of every frame for ParaView.
 */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "pd.h"

#define PROG "pd-crack-tip"
#include "cli.h"

#define MAX_WINDOW 100000 /* frames on each side of a speed's window */
#define MAX_REGIONS 16    /* --region, at most                       */

struct options {
    const char *input;
    int axis;          /* 0, 1, 2 for x, y, z                          */
    double threshold;  /* phi_0: damage strictly above it              */
    int window;        /* K: the speed fits frames k-K..k+K            */
    int front;         /* --front: the outline of the damaged zone     */
    int has_center;
    double center[3];  /* --center, m                                  */
    int from_point;    /* --distance point (else from the axis line)   */
    const char *plot;  /* --plot FILE.png, or NULL                     */
    const char *path;  /* --path PREFIX, or NULL                       */
    pd_region regions[MAX_REGIONS]; /* --region: damage only inside their union */
    int nregions;
    int connected;     /* --connected: only the pre-crack's damaged cluster */
    int debug;
};

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: " PROG " [OPTION]... RUN.h5\n"
            "Crack tips per frame of a run (seed 004 section 5): the smallest (lower) and\n"
            "largest (upper) current coordinate along an axis among particles with damage\n"
            "above a threshold, pre-crack included; the crack extension of each tip since\n"
            "the first frame with damage (both grow positive) and its speed, the slope of a\n"
            "least-squares line through the frames within a window.  Prints on stdout:\n"
            "  # step time_s lower_m upper_m da_lower_m da_upper_m speed_lower_m_s\n"
            "    speed_upper_m_s n_damaged\n"
            "With --front, the crack front of a 3-D body instead: the damaged particles\n"
            "with an undamaged family member, and their distance r from an axis or point:\n"
            "  # step time_s n_damaged n_front r_max_m r_mean_m lo_m hi_m da_m speed_m_s\n"
            "\n"
            "Options:\n"
            "  -a, --axis x|y|z    direction of crack growth; with --front, the axis of the\n"
            "                      front's distances and extent (default x)\n"
            "  -t, --threshold D   damage threshold phi_0 in [0,1] (default %g)\n"
            "  -w, --window K      speed from frames k-K..k+K (default 2)\n"
            "      --front         the crack front (outline of the damaged zone)\n"
            "      --center X,Y,Z  with --front: the centre of the distances, m (default\n"
            "                      the centroid of the reference positions)\n"
            "      --distance axis|point  with --front: r from the line through the centre\n"
            "                      along the axis (default) or from the centre point\n"
            "      --plot FILE.png draw the crack extension against time (gnuplot)\n"
            "      --path PREFIX   the damaged zone of each frame as PREFIX_STEP.vtu and\n"
            "                      PREFIX.pvd for ParaView (with --front, a front flag)\n"
            "      --region KIND,...  only the damage inside a region of the reference\n"
            "                      body: box,XLO,XHI,YLO,YHI,ZLO,ZHI, cylinder,AXIS,C1,C2,\n"
            "                      R,LO,HI or sphere,X,Y,Z,R, m, as pd-lattice's (several:\n"
            "                      their union)\n"
            "      --connected     only the damaged cluster of the pre-crack: particles\n"
            "                      reached from it through damaged neighbours within the\n"
            "                      horizon (needs pd-bonds --crack)\n"
            "      --debug         print HDF5's own error stack (and gnuplot's messages)\n"
            "  -h, --help          show this help\n"
            "  -V, --version       show the version\n",
            PD_DAMAGE_THRESHOLD);
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
    enum { OPT_FRONT = 256, OPT_CENTER, OPT_DISTANCE, OPT_PLOT, OPT_PATH, OPT_REGION,
           OPT_CONNECTED };
    static const struct option longopts[] = {
        {"axis", required_argument, 0, 'a'},
        {"threshold", required_argument, 0, 't'},
        {"window", required_argument, 0, 'w'},
        {"front", no_argument, 0, OPT_FRONT},
        {"center", required_argument, 0, OPT_CENTER},
        {"distance", required_argument, 0, OPT_DISTANCE},
        {"plot", required_argument, 0, OPT_PLOT},
        {"path", required_argument, 0, OPT_PATH},
        {"region", required_argument, 0, OPT_REGION},
        {"connected", no_argument, 0, OPT_CONNECTED},
        COMMON_LONGOPTS,
        {0, 0, 0, 0}};
    memset(o, 0, sizeof *o);
    o->threshold = PD_DAMAGE_THRESHOLD;
    o->window = 2;
    int c, status = 0, has_distance = 0;
    int64_t k;
    while ((c = next_option(argc, argv, "a:t:w:hV", longopts, usage, &o->debug, &status)) !=
           -1) {
        switch (c) {
        case 'a':
            if (!parse_axis(optarg, &o->axis))
                return usage_error("--axis must be x, y or z, not", optarg);
            break;
        case 't':
            if (!pd_parse_double(optarg, &o->threshold) || o->threshold < 0 || o->threshold > 1)
                return usage_error("--threshold must be a number in [0,1], not", optarg);
            break;
        case 'w':
            if (!pd_parse_int64(optarg, &k) || k < 1 || k > MAX_WINDOW)
                return usage_error("--window must be a whole number of frames >= 1, not",
                                   optarg);
            o->window = (int)k;
            break;
        case OPT_FRONT:
            o->front = 1;
            break;
        case OPT_CENTER:
            if (!pd_parse_doubles(optarg, o->center, 3))
                return usage_error("--center must be X,Y,Z in m, not", optarg);
            o->has_center = 1;
            break;
        case OPT_DISTANCE:
            if (strcmp(optarg, "axis") != 0 && strcmp(optarg, "point") != 0)
                return usage_error("--distance must be axis or point, not", optarg);
            o->from_point = strcmp(optarg, "point") == 0;
            has_distance = 1;
            break;
        case OPT_PLOT:
            if (optarg[0] == '\0' || strchr(optarg, '\n') != NULL)
                return usage_error("--plot needs a file name, not", optarg);
            o->plot = optarg;
            break;
        case OPT_PATH:
            if (optarg[0] == '\0' || optarg[strlen(optarg) - 1] == '/')
                return usage_error("--path needs a file name prefix, not", optarg);
            o->path = optarg;
            break;
        case OPT_REGION:
            if (o->nregions == MAX_REGIONS)
                return usage_error("--region is given at most 16 times; one more:", optarg);
            if (pd_region_parse_tagged(optarg, &o->regions[o->nregions]) != PD_OK ||
                o->regions[o->nregions].subtract)
                return usage_error("--region needs box,..., cylinder,... or sphere,... as "
                                   "pd-lattice's regions, not",
                                   optarg);
            o->nregions++;
            break;
        case OPT_CONNECTED:
            o->connected = 1;
            break;
        default:
            return option_error(argv, longopts);
        }
    }
    if (status)
        return status;
    if ((status = one_input(argc, argv, "RUN.h5", &o->input)) != 0)
        return status;
    if (!o->front && o->has_center)
        return usage_error("--center needs --front", NULL);
    if (!o->front && has_distance)
        return usage_error("--distance needs --front", NULL);
    return 0;
}

/* ------------------------------------------------------------ the series */

/* What is kept of every frame for the table and the plot. */
struct series {
    int64_t n;
    int64_t *step, *ndamaged, *nfront;
    double *time, *lower, *upper, *r_max, *r_mean, *lo, *hi;
    double *da_lower, *da_upper, *v_lower, *v_upper; /* front: *_upper only */
};

static pd_status series_alloc(struct series *s, int64_t n)
{
    memset(s, 0, sizeof *s);
    s->n = n;
    size_t m = (size_t)(n > 0 ? n : 1);
    int ok = (s->step = calloc(m, sizeof(int64_t))) != NULL &&
             (s->ndamaged = calloc(m, sizeof(int64_t))) != NULL &&
             (s->nfront = calloc(m, sizeof(int64_t))) != NULL;
    double **d[] = {&s->time,   &s->lower,    &s->upper,    &s->r_max,   &s->r_mean,
                    &s->lo,     &s->hi,       &s->da_lower, &s->da_upper, &s->v_lower,
                    &s->v_upper};
    for (size_t k = 0; k < sizeof d / sizeof d[0]; k++)
        ok &= (*d[k] = calloc(m, sizeof(double))) != NULL;
    return ok ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory for %lld frames", (long long)n);
}

static void series_free(struct series *s)
{
    void *v[] = {s->step,   s->ndamaged, s->nfront,   s->time,     s->lower,   s->upper,
                 s->r_max,  s->r_mean,   s->lo,       s->hi,       s->da_lower, s->da_upper,
                 s->v_lower, s->v_upper};
    for (size_t k = 0; k < sizeof v / sizeof v[0]; k++)
        free(v[k]);
}

/* Extension and speed of the tips, or of the front's r_max. */
static pd_status series_growth(struct series *s, const struct options *o)
{
    pd_status st;
    if (o->front) {
        pd_crack_extension(s->n, s->r_max, +1, s->da_upper);
        return pd_crack_speed(s->n, s->time, s->da_upper, o->window, s->v_upper);
    }
    pd_crack_extension(s->n, s->lower, -1, s->da_lower);
    pd_crack_extension(s->n, s->upper, +1, s->da_upper);
    if ((st = pd_crack_speed(s->n, s->time, s->da_lower, o->window, s->v_lower)) != PD_OK)
        return st;
    return pd_crack_speed(s->n, s->time, s->da_upper, o->window, s->v_upper);
}

static void series_print(const struct series *s, const struct options *o)
{
    if (o->front)
        printf("# step time_s n_damaged n_front r_max_m r_mean_m lo_m hi_m da_m speed_m_s\n");
    else
        printf("# step time_s lower_m upper_m da_lower_m da_upper_m speed_lower_m_s "
               "speed_upper_m_s n_damaged\n");
    for (int64_t k = 0; k < s->n; k++) {
        if (o->front)
            printf("%lld %.9e %lld %lld %.9e %.9e %.9e %.9e %.9e %.9e\n", (long long)s->step[k],
                   s->time[k], (long long)s->ndamaged[k], (long long)s->nfront[k], s->r_max[k],
                   s->r_mean[k], s->lo[k], s->hi[k], s->da_upper[k], s->v_upper[k]);
        else
            printf("%lld %.9e %.9e %.9e %.9e %.9e %.9e %.9e %lld\n", (long long)s->step[k],
                   s->time[k], s->lower[k], s->upper[k], s->da_lower[k], s->da_upper[k],
                   s->v_lower[k], s->v_upper[k], (long long)s->ndamaged[k]);
    }
}

/* ------------------------------------------------------------ the plot */

/* Whether `prog` is an executable file in a directory of $PATH. */
static int on_path(const char *prog)
{
    const char *path = getenv("PATH");
    if (path == NULL || *path == '\0')
        return 0;
    char *copy = strdup(path), *save = NULL;
    int found = 0;
    for (char *dir = copy ? strtok_r(copy, ":", &save) : NULL; dir && !found;
         dir = strtok_r(NULL, ":", &save)) {
        size_t len = strlen(dir) + strlen(prog) + 2;
        char *file = malloc(len);
        if (file == NULL)
            break;
        snprintf(file, len, "%s/%s", dir, prog);
        found = access(file, X_OK) == 0;
        free(file);
    }
    free(copy);
    return found;
}

/* A string as a gnuplot single-quoted string ('' is a quote inside). */
static void gp_quoted(FILE *gp, const char *s)
{
    fputc('\'', gp);
    for (; *s; s++) {
        if (*s == '\'')
            fputc('\'', gp);
        fputc(*s, gp);
    }
    fputc('\'', gp);
}

/* Delta a (mm) against time (us) as a PNG, drawn by gnuplot into a
 * temporary beside `png` and renamed over it when gnuplot succeeded. */
static pd_status plot(const struct series *s, const struct options *o)
{
    if (s->n == 0)
        return pd_fail(PD_ERR_INVALID, "cannot draw '%s': the run has no complete frame yet",
                       o->plot);
    if (!on_path("gnuplot"))
        return pd_fail(PD_ERR_IO, "cannot draw '%s': gnuplot is not on PATH", o->plot);
    size_t len = strlen(o->plot) + 64;
    char *tmp = malloc(len);
    if (tmp == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    const char *slash = strrchr(o->plot, '/');
    int dirlen = slash ? (int)(slash - o->plot + 1) : 0;
    snprintf(tmp, len, "%.*s.%s.tmp.%ld", dirlen, o->plot, slash ? slash + 1 : o->plot,
             (long)getpid());
    FILE *probe = fopen(tmp, "wx");
    if (probe == NULL) {
        pd_status st = pd_fail(PD_ERR_IO, "cannot write '%s': %s", o->plot, strerror(errno));
        free(tmp);
        return st;
    }
    fclose(probe);
    /* a gnuplot that dies early must not kill this program with SIGPIPE */
    struct sigaction ign, old;
    memset(&ign, 0, sizeof ign);
    ign.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &ign, &old);
    fflush(NULL);
    FILE *gp = popen(o->debug ? "exec gnuplot" : "exec gnuplot 2>/dev/null", "w");
    pd_status st = PD_OK;
    if (gp == NULL) {
        st = pd_fail(PD_ERR_IO, "cannot run gnuplot: %s", strerror(errno));
    } else {
        static const char *axes = "xyz";
        fprintf(gp, "set encoding utf8\nset terminal pngcairo size 900,560\nset output ");
        gp_quoted(gp, tmp);
        fprintf(gp, "\nset xlabel 'time (µs)'\nset grid\nset key top left\n");
        if (o->front)
            fprintf(gp, "set ylabel 'front growth Δr_{max} (mm)'\n"
                        "set title 'crack front (%s from the %s)'\n",
                    "largest distance", o->from_point ? "centre" : "axis");
        else
            fprintf(gp, "set ylabel 'crack extension Δa (mm)'\n"
                        "set title 'crack tips along %c'\n",
                    axes[o->axis]);
        fprintf(gp, "$d << EOD\n");
        for (int64_t k = 0; k < s->n; k++)
            fprintf(gp, "%.9g %.9g %.9g\n", s->time[k] * 1e6, s->da_lower[k] * 1e3,
                    s->da_upper[k] * 1e3);
        fprintf(gp, "EOD\n");
        if (o->front)
            fprintf(gp, "plot $d using 1:3 with linespoints title 'front'\n");
        else
            fprintf(gp, "plot $d using 1:2 with linespoints title 'lower tip', "
                        "$d using 1:3 with linespoints title 'upper tip'\n");
        int bad = ferror(gp);
        int rc = pclose(gp);
        if (bad || rc == -1 || !WIFEXITED(rc) || WEXITSTATUS(rc) != 0)
            st = pd_fail(PD_ERR_IO, "cannot draw '%s': gnuplot failed%s", o->plot,
                         o->debug ? "" : " (see --debug)");
    }
    sigaction(SIGPIPE, &old, NULL);
    if (st == PD_OK && rename(tmp, o->plot) != 0)
        st = pd_fail(PD_ERR_IO, "cannot rename the plot to '%s': %s", o->plot, strerror(errno));
    if (st != PD_OK)
        unlink(tmp);
    free(tmp);
    return st;
}

/* ------------------------------------------------------------ the path */

/* The damaged zone of one frame (rows with damage > threshold) as
 * PREFIX_STEP.vtu; *file gets its name relative to the .pvd. */
static pd_status write_path(const struct options *o, const pd_particles *p, double *const pos[3],
                            double *const disp[3], const double *damage, const uint8_t *front,
                            int64_t *rows, int64_t step, char **file)
{
    int64_t m = 0;
    for (int64_t i = 0; i < p->n; i++)
        if (damage[i] > o->threshold)
            rows[m++] = i;
    const char *slash = strrchr(o->path, '/');
    size_t len = strlen(o->path) + 32;
    char *path = malloc(len);
    *file = malloc(len);
    if (path == NULL || *file == NULL) {
        free(path);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    if (slash && slash != o->path) { /* PREFIX's folder, as pd-dump2vtk -o makes its own */
        snprintf(path, len, "%.*s", (int)(slash - o->path), o->path);
        pd_status s = pd_make_dirs(path);
        if (s != PD_OK) {
            free(path);
            return s;
        }
    }
    snprintf(path, len, "%s_%08lld.vtu", o->path, (long long)step);
    snprintf(*file, len, "%s", slash ? path + (slash - o->path) + 1 : path);
    pd_vtk_frame fr = {.n = p->n, .position = pos, .displacement = disp, .damage = damage,
                       .material = p->material, .id = p->id, .select = rows, .nselect = m,
                       .front = front, .zlib_level = PD_VTK_ZLIB_LEVEL};
    pd_status s = pd_vtk_write(path, &fr);
    free(path);
    return s;
}

/* ------------------------------------------------------------ main */

/* Per-particle work arrays of one frame. */
struct frame_data {
    double *disp[3], *pos[3], *damage;
    uint8_t *front, *keep;
    int64_t *rows;
};

static pd_status frame_data_alloc(struct frame_data *d, int64_t n)
{
    memset(d, 0, sizeof *d);
    size_t m = (size_t)(n > 0 ? n : 1);
    int ok = (d->damage = malloc(m * sizeof(double))) != NULL &&
             (d->front = calloc(m, 1)) != NULL && (d->keep = calloc(m, 1)) != NULL &&
             (d->rows = malloc(m * sizeof(int64_t))) != NULL;
    for (int k = 0; k < 3; k++)
        ok &= (d->disp[k] = malloc(m * sizeof(double))) != NULL &&
              (d->pos[k] = malloc(m * sizeof(double))) != NULL;
    return ok ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory for %lld particles", (long long)n);
}

static void frame_data_free(struct frame_data *d)
{
    for (int k = 0; k < 3; k++) {
        free(d->disp[k]);
        free(d->pos[k]);
    }
    free(d->damage);
    free(d->front);
    free(d->keep);
    free(d->rows);
}

/* A run has damage data when it has bonds and /frames; a model (pd-lattice,
 * pd-bonds) has none.  A run killed before its first frame has /frames but
 * no complete frame yet: not an error, a table of no rows (as for every pd
 * reader). */
static pd_status check_damage_data(const pd_file *f, const char *name, int64_t *nframes,
                                   char ***frames)
{
    if (!pd_file_has_frames(f))
        return pd_fail(PD_ERR_FORMAT, "'%s' has no damage data: no /frames (not a run of pd-run)",
                       name);
    if (!pd_file_has_bonds(f))
        return pd_fail(PD_ERR_FORMAT, "'%s' has no damage data: no /bonds (run pd-bonds first)",
                       name);
    return pd_list_frames(f, nframes, frames);
}

/* --region and --connected: the damage of the particles they leave out is
 * set to 0, below any threshold, for the tips, the front and the path. */
static pd_status only_chosen(const struct options *o, const pd_file *f, const pd_particles *p,
                             pd_bonds **b, struct frame_data *d)
{
    for (int64_t i = 0; i < p->n; i++) {
        const double x[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
        int in = o->nregions == 0;
        for (int r = 0; r < o->nregions && !in; r++)
            in = pd_region_inside(&o->regions[r], x);
        d->keep[i] = (uint8_t)in;
    }
    pd_status st = PD_OK;
    int64_t nkept;
    if (o->connected && *b == NULL)
        st = pd_read_bonds(f, p, b);
    if (st == PD_OK && o->connected)
        st = pd_crack_connected(p, *b, d->damage, o->threshold, d->keep, &nkept);
    if (st != PD_OK)
        return st;
    for (int64_t i = 0; i < p->n; i++)
        if (!d->keep[i])
            d->damage[i] = 0;
    return PD_OK;
}

/* Read frame k and put its tips or front into the series. */
static pd_status one_frame(const struct options *o, const pd_file *f, const pd_particles *p,
                           const char *frame, int64_t k, struct frame_data *d, pd_bonds **b,
                           uint64_t **intact, struct series *s, char **file)
{
    pd_frame_info fi;
    pd_status st;
    if ((st = pd_read_frame_info(f, frame, &fi)) != PD_OK ||
        (st = pd_read_frame_vectors(f, frame, p->n, d->disp, NULL)) != PD_OK ||
        (st = pd_read_frame_damage(f, p, frame, b, intact, d->damage)) != PD_OK)
        return st;
    if ((o->nregions > 0 || o->connected) && (st = only_chosen(o, f, p, b, d)) != PD_OK)
        return st;
    s->step[k] = fi.step;
    s->time[k] = fi.time;
    if ((st = pd_crack_tips(p, d->disp, d->damage, o->axis, o->threshold, &s->lower[k],
                            &s->upper[k], &s->ndamaged[k])) != PD_OK)
        return st;
    if (o->front) {
        pd_crack_front_info fr;
        if ((*b == NULL && (st = pd_read_bonds(f, p, b)) != PD_OK) ||
            (st = pd_crack_front(p, *b, d->damage, o->threshold, d->front, &s->nfront[k])) !=
                PD_OK ||
            (st = pd_crack_front_stats(p, d->disp, d->front, o->center, o->axis, !o->from_point,
                                       &fr)) != PD_OK)
            return st;
        s->r_max[k] = fr.r_max;
        s->r_mean[k] = fr.r_mean;
        s->lo[k] = fr.lo;
        s->hi[k] = fr.hi;
    }
    if (o->path == NULL)
        return PD_OK;
    for (int c = 0; c < 3; c++)
        for (int64_t i = 0; i < p->n; i++)
            d->pos[c][i] = p->x[c][i] + d->disp[c][i];
    return write_path(o, p, d->pos, d->disp, d->damage, o->front ? d->front : NULL, d->rows,
                      fi.step, file);
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
    char **frames = NULL, **files = NULL;
    struct frame_data d = {0};
    struct series s = {0};
    pd_status st = pd_file_open(o.input, &f);
    if (st == PD_OK && (st = pd_read_particles(f, &p)) == PD_OK &&
        (st = check_damage_data(f, o.input, &nframes, &frames)) == PD_OK &&
        (st = frame_data_alloc(&d, p->n)) == PD_OK && (st = series_alloc(&s, nframes)) == PD_OK &&
        (files = calloc((size_t)(nframes ? nframes : 1), sizeof *files)) == NULL)
        st = pd_fail(PD_ERR_NOMEM, "out of memory");
    if (st == PD_OK && o.front && !o.has_center) /* the centroid of the body */
        for (int c = 0; c < 3; c++) {
            double sum = 0;
            for (int64_t i = 0; i < p->n; i++)
                sum += p->x[c][i];
            o.center[c] = p->n ? sum / (double)p->n : 0.0;
        }
    for (int64_t k = 0; k < nframes && st == PD_OK; k++)
        st = one_frame(&o, f, p, frames[k], k, &d, &b, &intact, &s, &files[k]);
    if (st == PD_OK)
        st = series_growth(&s, &o);
    if (st == PD_OK && o.path) {
        size_t len = strlen(o.path) + 8;
        char *pvd = malloc(len);
        if (pvd == NULL)
            st = pd_fail(PD_ERR_NOMEM, "out of memory");
        else {
            snprintf(pvd, len, "%s.pvd", o.path);
            st = pd_pvd_write(pvd, nframes, files, s.time, NULL, NULL);
        }
        free(pvd);
    }
    if (st == PD_OK && o.plot)
        st = plot(&s, &o);
    if (st == PD_OK) {
        series_print(&s, &o);
        if (fflush(stdout) != 0)
            st = pd_fail(PD_ERR_IO, "cannot write to stdout");
    }
    for (int64_t k = 0; files && k < nframes; k++)
        free(files[k]);
    free(files);
    series_free(&s);
    frame_data_free(&d);
    free(intact);
    pd_frames_free_list(nframes, frames);
    pd_bonds_free(b);
    pd_particles_free(p);
    pd_file_close(f);
    return st == PD_OK ? 0 : fail();
}
