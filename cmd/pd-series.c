/*
 * pd-series -- print or draw the time series of one or more runs.
 *
 * pd-run records a row of the run's figures every --series N steps and at
 * the last (pd_sim_series_row): the step, the time, the energies of the
 * balance, the damage counts, the momentum, each named set's mean
 * displacement and reaction force, the projectile's and the indenter's
 * motion and force.  The run file holds them as (man 5 pd-h5)
 *
 *   /series          attributes columns (the names, separated by single
 *                    spaces, `step` first) and rows (the complete rows)
 *   /series/values   float64, capacity x columns: only the first `rows`
 *                    rows count
 *
 * read through pd_read_series.  This program only chooses and formats:
 * an aligned table for reading, CSV exact to the bit (%.17g round-trips
 * every double) for another tool, some columns, the last row of each run
 * (the summary of a sweep), or curves of columns against another drawn by
 * gnuplot into a PNG that appears only once it is whole.
 */
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <math.h>
#include <signal.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "pd.h"

#define PROG "pd-series"
#include "cli.h"

extern char **environ;

#define MIN_WIDTH 12            /* characters of a table column, at least   */
#define WHOLE_MAX 9007199254740992.0 /* 2^53: every integer below is a double */
#define TEMP_MAX 4096           /* bytes of a temporary's path              */

/* A comma list of column names (--columns, --y), split in place. */
struct names {
    char *text;         /* the copy the names point into */
    const char **name;
    int n;
};

struct options {
    char **inputs;      /* RUN.h5..., as given ("-": stdin) */
    int ninputs;
    int csv;            /* --csv: comma-separated, %.17g */
    int last;           /* --last: the last row of each run */
    int has_columns;
    struct names columns; /* --columns LIST */
    const char *plot;   /* --plot FILE.png, or NULL */
    const char *x;      /* --x NAME (default time); has_x: given */
    int has_x;
    struct names y;     /* --y LIST: the curves of --plot */
    int debug;
};

/* One run as read, and where its columns are. */
struct run {
    const char *path;   /* as given on the command line */
    pd_series s;
    int *col;           /* per column printed: its index in s */
};

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: " PROG " [OPTION]... RUN.h5...\n"
            "Print the time series pd-run records in a run (/series; pd-run --series): a\n"
            "header line of the column names, then one line per recorded step.  With several\n"
            "runs, a first column 'run' names the file of each row.  RUN.h5 '-' reads\n"
            "standard input (once).\n"
            "\n"
            "Options:\n"
            "      --csv            comma-separated values, exact (%%.17g)\n"
            "      --columns LIST   only these columns (a comma list of names), in this order\n"
            "      --last           only the last row of each run, with the 'run' column\n"
            "      --plot FILE.png  draw --y against --x with gnuplot; print nothing\n"
            "      --x NAME         with --plot: the abscissa (default time)\n"
            "      --y LIST         with --plot: the curves, a comma list of column names\n"
            "      --debug          print HDF5's own error stack (and gnuplot's messages)\n"
            "  -h, --help           show this help\n"
            "  -V, --version        show the version\n");
}

/* Split a comma list of names into *l: 1, or 0 when a name is empty. */
static int split_names(const char *list, struct names *l)
{
    free(l->text);
    free(l->name);
    memset(l, 0, sizeof *l);
    int n = 1;
    for (const char *p = list; *p; p++)
        n += *p == ',';
    l->text = strdup(list);
    l->name = malloc((size_t)n * sizeof *l->name);
    if (l->text == NULL || l->name == NULL) {
        fprintf(stderr, PROG ": error: out of memory\n");
        exit(1);
    }
    for (char *p = l->text;; p++) {
        l->name[l->n++] = p;
        p += strcspn(p, ",");
        if (*p == '\0')
            break;
        *p = '\0';
    }
    for (int k = 0; k < l->n; k++)
        if (l->name[k][0] == '\0')
            return 0;
    return 1;
}

static void names_free(struct names *l)
{
    free(l->text);
    free(l->name);
    memset(l, 0, sizeof *l);
}

static int parse_options(int argc, char **argv, struct options *o)
{
    enum { OPT_CSV = 256, OPT_COLUMNS, OPT_LAST, OPT_PLOT, OPT_X, OPT_Y };
    static const struct option longopts[] = {
        {"csv", no_argument, 0, OPT_CSV},
        {"columns", required_argument, 0, OPT_COLUMNS},
        {"last", no_argument, 0, OPT_LAST},
        {"plot", required_argument, 0, OPT_PLOT},
        {"x", required_argument, 0, OPT_X},
        {"y", required_argument, 0, OPT_Y},
        COMMON_LONGOPTS,
        {0, 0, 0, 0}};
    memset(o, 0, sizeof *o);
    o->x = "time";
    int c, status = 0;
    while ((c = next_option(argc, argv, "hV", longopts, usage, &o->debug, &status)) != -1) {
        switch (c) {
        case OPT_CSV:
            o->csv = 1;
            break;
        case OPT_COLUMNS:
            if (!split_names(optarg, &o->columns))
                return usage_error("--columns needs a comma list of column names, not", optarg);
            o->has_columns = 1;
            break;
        case OPT_LAST:
            o->last = 1;
            break;
        case OPT_PLOT:
            if (optarg[0] == '\0' || strcmp(optarg, "-") == 0 ||
                optarg[strlen(optarg) - 1] == '/')
                return usage_error("--plot needs the name of a PNG file, not", optarg);
            o->plot = optarg;
            break;
        case OPT_X:
            if (optarg[0] == '\0' || strchr(optarg, ',') != NULL)
                return usage_error("--x needs one column name, not", optarg);
            o->x = optarg;
            o->has_x = 1;
            break;
        case OPT_Y:
            if (!split_names(optarg, &o->y))
                return usage_error("--y needs a comma list of column names, not", optarg);
            break;
        default:
            return option_error(argv, longopts);
        }
    }
    if (status)
        return status;
    if (optind == argc)
        return usage_error("missing RUN.h5", NULL);
    o->inputs = argv + optind;
    o->ninputs = argc - optind;
    for (int a = 0, stdin_seen = 0; a < o->ninputs; a++)
        if (strcmp(o->inputs[a], "-") == 0 && stdin_seen++)
            return usage_error("standard input '-' is given more than once", NULL);
    if (o->has_x && !o->plot)
        return usage_error("--x needs --plot", NULL);
    if (o->y.n && !o->plot)
        return usage_error("--y needs --plot", NULL);
    if (o->plot && o->y.n == 0)
        return usage_error("--plot needs --y, the columns to draw", NULL);
    if (o->plot && o->csv)
        return usage_error("--csv and --plot exclude each other", NULL);
    if (o->plot && (o->has_columns || o->last))
        return usage_error(o->last ? "--last and --plot exclude each other"
                                   : "--columns and --plot exclude each other (--plot draws "
                                     "--x and --y)",
                           NULL);
    return 0;
}

/* ------------------------------------------------------------ the runs */

/* The series of every input, each file closed once read. */
static pd_status read_runs(const struct options *o, struct run *runs)
{
    for (int k = 0; k < o->ninputs; k++) {
        pd_file *f = NULL;
        runs[k].path = o->inputs[k];
        pd_status s = pd_file_open(o->inputs[k], &f);
        if (s == PD_OK)
            s = pd_read_series(f, &runs[k].s);
        if (f != NULL) {
            pd_status sc = pd_file_close(f);
            if (s == PD_OK)
                s = sc;
        }
        if (s != PD_OK)
            return s;
    }
    return PD_OK;
}

/* The index of column `name` in r, or a data error naming the file and,
 * when one is near (a typo), the nearest of its columns. */
static pd_status find_column(const struct run *r, const char *name, int *col)
{
    if ((*col = pd_series_column(&r->s, name)) >= 0)
        return PD_OK;
    const size_t len = strlen(name);
    size_t best_d = (size_t)-1;
    int best = -1;
    for (int k = 0; k < r->s.ncols; k++) {
        size_t d = pd_edit_distance(name, len, r->s.name[k], strlen(r->s.name[k]));
        if (d < best_d) {
            best_d = d;
            best = k;
        }
    }
    if (best >= 0 && best_d <= 1 + len / 3)
        return pd_fail(PD_ERR_INVALID, "'%s' has no column '%s'; did you mean '%s'?", r->path,
                       name, r->s.name[best]);
    return pd_fail(PD_ERR_INVALID, "'%s' has no column '%s'", r->path, name);
}

/* The columns to print or draw, in order: --x and --y with --plot, else
 * --columns, else those of the first run (which every other run must
 * have); each looked up in every run. */
static pd_status choose_columns(const struct options *o, struct run *runs, const char ***names,
                                int *n)
{
    if (o->plot)
        *n = 1 + o->y.n;
    else
        *n = o->has_columns ? o->columns.n : runs[0].s.ncols;
    *names = malloc((size_t)*n * sizeof **names);
    if (*names == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    for (int k = 0; k < *n; k++)
        if (o->plot)
            (*names)[k] = k == 0 ? o->x : o->y.name[k - 1];
        else
            (*names)[k] = o->has_columns ? o->columns.name[k] : runs[0].s.name[k];
    for (int r = 0; r < o->ninputs; r++) {
        if ((runs[r].col = malloc((size_t)*n * sizeof(int))) == NULL)
            return pd_fail(PD_ERR_NOMEM, "out of memory");
        for (int k = 0; k < *n; k++) {
            pd_status s = find_column(&runs[r], (*names)[k], &runs[r].col[k]);
            if (s != PD_OK)
                return s;
        }
    }
    return PD_OK;
}

/* The first row of r to print: its last with --last, else 0. */
static int64_t first_row(const struct options *o, const struct run *r)
{
    return o->last && r->s.nrows > 0 ? r->s.nrows - 1 : 0;
}

/* Column k (of those printed) of row i of r. */
static double value(const struct run *r, int64_t i, int k)
{
    return r->s.value[i * r->s.ncols + r->col[k]];
}

/* ------------------------------------------------------------ printing */

/* A field of CSV, quoted when it holds a comma, a quote or a line end. */
static void csv_field(const char *s)
{
    if (strpbrk(s, ",\"\r\n") == NULL) {
        fputs(s, stdout);
        return;
    }
    putchar('"');
    for (; *s; s++) {
        if (*s == '"')
            putchar('"');
        putchar(*s);
    }
    putchar('"');
}

/* The table's layout of column k over the rows printed: whole (every
 * value a whole number below 2^53, as steps and counts: printed as such,
 * step 1000000 not 1e+06) and its width (its name's, MIN_WIDTH at least,
 * or a whole number's digits). */
static void layout(const struct options *o, const struct run *runs, const char *name, int k,
                   int *whole, int *width)
{
    double lo = 0, hi = 0;
    *whole = 1;
    for (int r = 0; r < o->ninputs && *whole; r++)
        for (int64_t i = first_row(o, &runs[r]); i < runs[r].s.nrows && *whole; i++) {
            double v = value(&runs[r], i, k);
            *whole = isfinite(v) && fabs(v) < WHOLE_MAX && v == floor(v);
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
    *width = (int)strlen(name);
    *width = *width > MIN_WIDTH ? *width : MIN_WIDTH;
    if (*whole) {
        int digits = snprintf(NULL, 0, "%.0f", lo), d = snprintf(NULL, 0, "%.0f", hi);
        digits = d > digits ? d : digits;
        *width = digits > *width ? digits : *width;
    }
}

/* The rows of every run on stdout: the table or, with --csv, CSV; the
 * 'run' column first with several runs or --last. */
static pd_status print_series(const struct options *o, const struct run *runs,
                              const char **names, int n)
{
    const int with_run = o->ninputs > 1 || o->last;
    int *whole = malloc((size_t)n * sizeof(int)), *width = malloc((size_t)n * sizeof(int));
    if (whole == NULL || width == NULL) {
        free(whole);
        free(width);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    int run_width = 3; /* "run" */
    for (int r = 0; r < o->ninputs; r++) {
        int len = (int)strlen(runs[r].path);
        run_width = len > run_width ? len : run_width;
    }
    for (int k = 0; k < n && !o->csv; k++)
        layout(o, runs, names[k], k, &whole[k], &width[k]);

    if (with_run && o->csv)
        fputs("run", stdout);
    else if (with_run)
        printf("%-*s", run_width, "run");
    for (int k = 0; k < n; k++) {
        if (o->csv) {
            if (with_run || k > 0)
                putchar(',');
            csv_field(names[k]);
        } else
            printf("%s%*s", with_run || k > 0 ? " " : "", width[k], names[k]);
    }
    putchar('\n');
    for (int r = 0; r < o->ninputs; r++)
        for (int64_t i = first_row(o, &runs[r]); i < runs[r].s.nrows; i++) {
            if (with_run && o->csv)
                csv_field(runs[r].path);
            else if (with_run)
                printf("%-*s", run_width, runs[r].path);
            for (int k = 0; k < n; k++) {
                const double v = value(&runs[r], i, k);
                const char *sep = with_run || k > 0 ? (o->csv ? "," : " ") : "";
                if (o->csv)
                    printf("%s%.17g", sep, v);
                else if (whole[k])
                    printf("%s%*.0f", sep, width[k], v + 0.0); /* -0 as 0 */
                else
                    printf("%s%*.6g", sep, width[k], v);
            }
            putchar('\n');
        }
    free(whole);
    free(width);
    const int bad = ferror(stdout);
    if (fflush(stdout) != 0)
        return pd_fail(PD_ERR_IO, "cannot write to standard output: %s", strerror(errno));
    if (bad)
        return pd_fail(PD_ERR_IO, "cannot write to standard output");
    return PD_OK;
}

/* ------------------------------------------------------------ drawing */

/* The temporaries of --plot and gnuplot's process, for a signal: a killed
 * pd-series leaves neither behind (as the library's outputs, cli.h). */
static char temp_script[TEMP_MAX], temp_png[TEMP_MAX];
static volatile pid_t gnuplot_pid;

static void remove_plot_temps(void)
{
    if (temp_script[0])
        unlink(temp_script);
    if (temp_png[0])
        unlink(temp_png);
    temp_script[0] = temp_png[0] = '\0';
}

static void plot_die(int sig)
{
    if (gnuplot_pid > 0)
        kill(gnuplot_pid, SIGTERM);
    remove_plot_temps();
    signal(sig, SIG_DFL);
    raise(sig);
}

/* plot_die on SIGINT, SIGTERM, SIGHUP and SIGPIPE, unless one was ignored
 * at start (nohup). */
static void remove_plot_temps_on_signal(void)
{
    const int sigs[] = {SIGINT, SIGTERM, SIGHUP, SIGPIPE};
    for (size_t k = 0; k < sizeof sigs / sizeof sigs[0]; k++) {
        struct sigaction old, sa;
        if (sigaction(sigs[k], NULL, &old) == 0 && old.sa_handler == SIG_IGN)
            continue;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = plot_die;
        sigemptyset(&sa.sa_mask);
        sigaction(sigs[k], &sa, NULL);
    }
}

/* A new empty file from `path`'s template (...XXXXXX, replaced), with the
 * mode a new file gets (mkstemp's is 0600): PD_OK, or an error naming
 * `what`. */
static pd_status make_temp(char *path, const char *what, FILE **out)
{
    int fd = mkstemp(path);
    if (fd < 0) {
        path[0] = '\0';
        return pd_fail(PD_ERR_IO, "cannot write '%s': %s", what, strerror(errno));
    }
    mode_t mask = umask(0);
    umask(mask);
    fchmod(fd, 0666 & ~mask);
    if ((*out = fdopen(fd, "w")) == NULL) {
        close(fd);
        return pd_fail(PD_ERR_IO, "cannot write '%s': %s", what, strerror(errno));
    }
    return PD_OK;
}

/* A string as a gnuplot single-quoted string ('' is a quote inside; a
 * control character, which would end the line, as '?'). */
static void gp_string(FILE *gp, const char *s)
{
    fputc('\'', gp);
    for (; *s; s++) {
        if (*s == '\'')
            fputc('\'', gp);
        fputc((unsigned char)*s < ' ' ? '?' : *s, gp);
    }
    fputc('\'', gp);
}

/* The gnuplot script of the plot, its data inline: one datablock per run
 * with rows (x, y1, y2, ...), exact, a non-finite value as NaN (no point). */
static void write_script(FILE *gp, const struct options *o, const struct run *runs,
                         const char **names, int n)
{
    fprintf(gp, "set encoding utf8\n"
                "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
                "    set terminal pngcairo size 900,600\n"
                "} else {\n"
                "    set terminal png size 900,600\n"
                "}\n"
                "set termoption noenhanced\n"
                "set output ");
    gp_string(gp, temp_png);
    fprintf(gp, "\nset grid\nset key top left\nset xlabel ");
    gp_string(gp, names[0]);
    fprintf(gp, "\nset ylabel ");
    size_t len = 1;
    for (int k = 1; k < n; k++)
        len += strlen(names[k]) + 2;
    char *ylabel = malloc(len);
    if (ylabel) {
        ylabel[0] = '\0';
        for (int k = 1; k < n; k++)
            strcat(strcat(ylabel, k > 1 ? ", " : ""), names[k]);
        gp_string(gp, ylabel);
        free(ylabel);
    } else
        gp_string(gp, names[1]);
    fputc('\n', gp);
    for (int r = 0; r < o->ninputs; r++) {
        if (runs[r].s.nrows == 0)
            continue;
        fprintf(gp, "$run%d << EOD\n", r);
        for (int64_t i = 0; i < runs[r].s.nrows; i++)
            for (int k = 0; k < n; k++) {
                const double v = value(&runs[r], i, k);
                if (isfinite(v))
                    fprintf(gp, "%.17g%c", v, k + 1 < n ? ' ' : '\n');
                else
                    fprintf(gp, "NaN%c", k + 1 < n ? ' ' : '\n');
            }
        fprintf(gp, "EOD\n");
    }
    fprintf(gp, "plot");
    for (int r = 0, curves = 0; r < o->ninputs; r++)
        for (int k = 1; k < n && runs[r].s.nrows > 0; k++) {
            fprintf(gp, "%s $run%d using 1:%d with lines linewidth 2 title ",
                    curves++ ? "," : "", r, k + 1);
            if (o->ninputs > 1) {
                size_t tl = strlen(runs[r].path) + strlen(names[k]) + 3;
                char *title = malloc(tl);
                if (title) {
                    snprintf(title, tl, "%s: %s", runs[r].path, names[k]);
                    gp_string(gp, title);
                    free(title);
                } else
                    gp_string(gp, names[k]);
            } else
                gp_string(gp, names[k]);
        }
    fprintf(gp, "\nunset output\n");
}

/* gnuplot on `script`, its output to /dev/null (and its messages, unless
 * --debug): PD_OK when it ran and exited 0. */
static pd_status run_gnuplot(const struct options *o, const char *script)
{
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
    if (!o->debug)
        posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
    char *argv[] = {"gnuplot", (char *)script, NULL};
    pid_t pid;
    fflush(NULL);
    int err = posix_spawnp(&pid, "gnuplot", &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    if (err == ENOENT)
        return pd_fail(PD_ERR_IO, "cannot draw '%s': gnuplot is not on PATH", o->plot);
    if (err != 0)
        return pd_fail(PD_ERR_IO, "cannot draw '%s': cannot run gnuplot: %s", o->plot,
                       strerror(err));
    gnuplot_pid = pid;
    int status = 0;
    pid_t w;
    while ((w = waitpid(pid, &status, 0)) < 0 && errno == EINTR)
        ;
    gnuplot_pid = 0;
    if (w < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
        return pd_fail(PD_ERR_IO, "cannot draw '%s': gnuplot failed%s", o->plot,
                       o->debug ? "" : " (see --debug)");
    return PD_OK;
}

/* The curves of --y against --x, one per run and column, drawn by gnuplot
 * into a temporary beside FILE.png and renamed to it only when gnuplot
 * succeeded: never a half-drawn FILE.png. */
static pd_status plot(const struct options *o, const struct run *runs, const char **names,
                      int n)
{
    int any = 0;
    for (int r = 0; r < o->ninputs; r++)
        any |= runs[r].s.nrows > 0;
    if (!any)
        return pd_fail(PD_ERR_INVALID, "cannot draw '%s': %s", o->plot,
                       o->ninputs > 1 ? "no run has a row yet" : "the run has no row yet");
    const char *tmpdir = getenv("TMPDIR");
    const char *slash = strrchr(o->plot, '/');
    int dirlen = slash ? (int)(slash - o->plot + 1) : 0;
    if (snprintf(temp_script, sizeof temp_script, "%s/" PROG ".XXXXXX",
                 tmpdir && *tmpdir ? tmpdir : "/tmp") >= (int)sizeof temp_script ||
        snprintf(temp_png, sizeof temp_png, "%.*s.%s.tmp.XXXXXX", dirlen, o->plot,
                 o->plot + dirlen) >= (int)sizeof temp_png) {
        temp_script[0] = temp_png[0] = '\0';
        return pd_fail(PD_ERR_IO, "cannot write '%s': name too long", o->plot);
    }
    remove_plot_temps_on_signal();
    FILE *gp = NULL, *png = NULL;
    pd_status s = make_temp(temp_png, o->plot, &png);
    if (s == PD_OK && fclose(png) != 0)
        s = pd_fail(PD_ERR_IO, "cannot write '%s': %s", o->plot, strerror(errno));
    if (s == PD_OK)
        s = make_temp(temp_script, "the gnuplot script", &gp);
    if (s == PD_OK) {
        write_script(gp, o, runs, names, n);
        const int bad = ferror(gp);
        if (fclose(gp) != 0 || bad)
            s = pd_fail(PD_ERR_IO, "cannot write the gnuplot script '%s' (disk full?)",
                        temp_script);
    }
    if (s == PD_OK)
        s = run_gnuplot(o, temp_script);
    struct stat st;
    if (s == PD_OK && (stat(temp_png, &st) != 0 || st.st_size == 0))
        s = pd_fail(PD_ERR_IO, "cannot draw '%s': gnuplot wrote nothing", o->plot);
    if (s == PD_OK && rename(temp_png, o->plot) != 0)
        s = pd_fail(PD_ERR_IO, "cannot write '%s': %s", o->plot, strerror(errno));
    if (s == PD_OK)
        temp_png[0] = '\0';
    remove_plot_temps();
    return s;
}

/* ------------------------------------------------------------ main */

int main(int argc, char **argv)
{
    struct options o;
    int rc = parse_options(argc, argv, &o);
    if (rc) {
        names_free(&o.columns);
        names_free(&o.y);
        return rc;
    }
    pd_h5_debug(o.debug);
    struct run *runs = calloc((size_t)o.ninputs, sizeof *runs);
    const char **names = NULL;
    int n = 0;
    pd_status s = runs ? read_runs(&o, runs) : pd_fail(PD_ERR_NOMEM, "out of memory");
    if (s == PD_OK)
        s = choose_columns(&o, runs, &names, &n);
    if (s == PD_OK)
        s = o.plot ? plot(&o, runs, names, n) : print_series(&o, runs, names, n);
    for (int r = 0; runs && r < o.ninputs; r++) {
        pd_series_free(&runs[r].s);
        free(runs[r].col);
    }
    free(runs);
    free(names);
    names_free(&o.columns);
    names_free(&o.y);
    return s == PD_OK ? 0 : fail();
}
