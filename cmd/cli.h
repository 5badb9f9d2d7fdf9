/*
 * cli.h -- the lines of glue every program shares: one-line errors and the
 * exit status (1 runtime or data error, 2 usage error).  Include it after
 * defining PROG.  Library code never prints; these are the only printers of
 * pd_errmsg().
 */
#ifndef PD_CLI_H
#define PD_CLI_H

#include <getopt.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "pd.h"

/* Where the option being read came from, "FILE:LINE: " of a scene file
 * (pd-run --scene), or NULL: the command line. */
static const char *cli_where;
/* The arguments a scene file gave (pd-run: pd_scene_args), each with its
 * line, for cli_where. */
static struct {
    const char *file;
    char *const *args;
    const int *line;
    int count;
    char where[512];
} cli_scene;


/* A usage error: one line on stderr, exit status 2. */
static inline int usage_error(const char *msg, const char *arg)
{
    fprintf(stderr, PROG ": error: %s%s%s%s%s (see '" PROG " --help')\n",
            cli_where ? cli_where : "", msg, arg ? " '" : "", arg ? arg : "", arg ? "'" : "");
    return 2;
}

/* cli_where of argv[k]: a scene's argument is found by its address, which
 * getopt's permutation of argv keeps.  Returns 0, or 2 after a usage
 * error when a scene's option took its value from past its own line. */
static inline int cli_locate(char **argv, int k, const char *value)
{
    cli_where = NULL;
    for (int m = 0; k >= 1 && m < cli_scene.count; m++)
        if (cli_scene.args[m] == argv[k]) {
            snprintf(cli_scene.where, sizeof cli_scene.where, "%s:%d: ", cli_scene.file,
                     cli_scene.line[m]);
            cli_where = cli_scene.where;
            if (value && !(m + 1 < cli_scene.count && cli_scene.args[m + 1] == value &&
                           cli_scene.line[m + 1] == cli_scene.line[m]))
                return usage_error("missing value for", argv[k]);
            return 0;
        }
    return 0;
}

/* getopt_long's '?' (its own message is switched off by opterr = 0): a
 * known option without its value, or an unknown one, with the nearest
 * long option when one is near (a typo). */
static inline int option_error(char **argv, const struct option *longopts)
{
    const char *arg = argv[optind - 1];
    if (strncmp(arg, "--", 2) != 0 || arg[2] == '\0')
        return usage_error("unknown option or missing value in", arg);
    const size_t len = strcspn(arg + 2, "=");
    const char *best = NULL;
    size_t best_d = (size_t)-1;
    char msg[256];
    for (const struct option *o = longopts; o->name; o++) {
        if (strlen(o->name) == len && strncmp(o->name, arg + 2, len) == 0) {
            if (arg[2 + len] != '=')
                return usage_error("missing value for", arg);
            snprintf(msg, sizeof msg, "--%s takes no value, not '%s'", o->name, arg);
            return usage_error(msg, NULL);
        }
        size_t d = pd_edit_distance(arg + 2, len, o->name, strlen(o->name));
        if (d < best_d) {
            best_d = d;
            best = o->name;
        }
    }
    if (best == NULL || best_d > 1 + len / 4)
        return usage_error("unknown option", arg);
    snprintf(msg, sizeof msg, "unknown option '%.*s'; did you mean '--%s'?", (int)(len + 2) > 200 ? 200 : (int)len + 2, arg, best);
    return usage_error(msg, NULL);
}

/* The long options every program has, with codes above any program's own. */
enum { OPT_DEBUG = 1000 };
#define COMMON_LONGOPTS                                                                            \
    {"debug", no_argument, 0, OPT_DEBUG}, {"help", no_argument, 0, 'h'},                           \
        {"version", no_argument, 0, 'V'}

/* --help and --version (both exit 0), --debug, and what getopt_long could
 * not parse (exit status 2); -1 when `c` is one of the program's own. */
static inline int common_option(int c, char **argv, const struct option *longopts,
                                void (*usage)(FILE *), int *debug)
{
    switch (c) {
    case 'h':
        usage(stdout);
        exit(0);
    case 'V':
        printf(PROG " (pd) " PD_VERSION "\n");
        exit(0);
    case OPT_DEBUG:
        *debug = 1;
        return 0;
    case '?':
    case ':':
        return option_error(argv, longopts);
    }
    return -1;
}

/* The thread that opens and closes the files (main's). */
static pthread_t cli_main_thread;

/* On SIGINT, SIGTERM, SIGHUP or SIGPIPE: remove the temporary output, then
 * die of the signal as before.  A signal ignored at start (nohup, a
 * background job's SIGINT) stays ignored.  The kernel may hand a signal to
 * any thread, an OpenMP worker too: that one passes it on to the main
 * thread and goes on, so that the main thread cannot create or reopen a
 * temporary file after the handler removed it, in the moment before the
 * process dies. */
static void remove_temps_and_die(int sig)
{
    if (!pthread_equal(pthread_self(), cli_main_thread)) {
        pthread_kill(cli_main_thread, sig);
        return;
    }
    pd_remove_temps();
    signal(sig, SIG_DFL);
    raise(sig);
}

static inline void remove_temps_on_signal(void)
{
    cli_main_thread = pthread_self();
    /* past a file-size limit (ulimit -f) a write fails with EFBIG and is
     * reported like a full disk, instead of killing the program */
    signal(SIGXFSZ, SIG_IGN);
    const int sigs[] = {SIGINT, SIGTERM, SIGHUP, SIGPIPE};
    for (size_t k = 0; k < sizeof sigs / sizeof sigs[0]; k++) {
        struct sigaction old, sa;
        if (sigaction(sigs[k], NULL, &old) == 0 && old.sa_handler == SIG_IGN)
            continue;
        sa.sa_handler = remove_temps_and_die;
        sigemptyset(&sa.sa_mask);
        sa.sa_flags = 0;
        sigaction(sigs[k], &sa, NULL);
    }
}

/* The next of the program's own options: getopt_long with the common ones
 * handled here.  Returns -1 at the end of the options, or when an option
 * was wrong, with *status set to the exit status (2). */
static inline int next_option(int argc, char **argv, const char *shortopts,
                              const struct option *longopts, void (*usage)(FILE *), int *debug,
                              int *status)
{
    opterr = 0;
    for (;;) {
        int c = getopt_long(argc, argv, shortopts, longopts, NULL);
        if (c == -1) {
            cli_where = NULL; /* what follows is about the whole command */
            return -1;
        }
        /* the option's argument (its value may be the next one) */
        const int apart = optarg && optind >= 2 && optarg == argv[optind - 1] && c != '?';
        int rc = cli_locate(argv, apart ? optind - 2 : optind - 1, apart ? optarg : NULL);
        if (rc) {
            *status = rc;
            return -1;
        }
        rc = common_option(c, argv, longopts, usage, debug);
        if (rc < 0)
            return c;
        if (rc > 0) {
            *status = rc;
            return -1;
        }
    }
}

/* The one operand of a program that reads one file, named `what` in the
 * usage (e.g. "RUN.h5"), after the options: *input = argv[optind] and 0,
 * or a usage error (exit status 2) "missing WHAT" when there is none and
 * "give exactly one WHAT" when there are more. */
static inline int one_input(int argc, char **argv, const char *what, const char **input)
{
    if (optind == argc - 1) {
        *input = argv[optind];
        return 0;
    }
    char msg[128];
    snprintf(msg, sizeof msg, "%s %s", optind < argc ? "give exactly one" : "missing", what);
    return usage_error(msg, NULL);
}

/* Threads that share the cores.  An OpenMP thread waiting for work spins
 * before it sleeps, by default (libgomp) for 300,000 rounds: a run alone
 * loses nothing by it, but two runs on the same cores (`make -j` of a
 * sweep, two shells) spin on cores the other one needs, and each waits at
 * every barrier for a partner thread that is not running.  Measured on 2
 * cores, the crack-convergence plate at 0.5 mm (800 steps): 1.5 s alone,
 * 20.7 s each for two at once; with 1000 rounds 1.5 s alone and 3.1 s each
 * for two at once, half the machine each (OMP_WAIT_POLICY=passive: 1.8 s
 * alone).  libgomp reads its setting from the environment as the program
 * is loaded, before main, so a program that finds neither OMP_WAIT_POLICY
 * nor GOMP_SPINCOUNT set sets GOMP_SPINCOUNT to PD_SPINCOUNT and runs
 * itself again, once (the variable is set then); the user's own setting
 * wins.  Call it first thing in main, with main's argv. */
#define PD_SPINCOUNT "1000"
static inline void settle_threads(char **argv)
{
    if (getenv("OMP_WAIT_POLICY") || getenv("GOMP_SPINCOUNT"))
        return;
    if (setenv("GOMP_SPINCOUNT", PD_SPINCOUNT, 1) == 0)
        execv("/proc/self/exe", argv);
    /* no /proc: go on as loaded */
}

/* A runtime or data error from libpd: one line on stderr, exit status 1. */
static inline int fail(void)
{
    fprintf(stderr, PROG ": error: %s\n", pd_errmsg());
    return 1;
}

/* On several MPI ranks (the MPI builds of pd-run and pd-bonds) rank 0
 * speaks for the program: the other ranks' stderr is /dev/null, and a
 * failure of any rank is told by rank 0 (cli_agreed, cli_failed). */
static int cli_agreed_failure; /* 1: every rank holds the failure rank 0 tells */

/* MPI started (one rank without it), the other ranks' stderr silenced.
 * Returns 0, or 1 after the error line. */
static inline int cli_ranks_start(int *argc, char ***argv)
{
    if (pd_comm_init(argc, argv) != PD_OK)
        return fail();
    if (pd_comm_rank() > 0 && freopen("/dev/null", "w", stderr) == NULL)
        return 1;
    return 0;
}

/* A failure of any rank is every rank's (collective on several ranks):
 * the one of the lowest rank that failed of its own (not for another,
 * pd_comm_agree), its message on every rank. */
static inline pd_status cli_agreed(pd_status s)
{
    if (pd_comm_size() == 1 || !pd_comm_or(s != PD_OK))
        return s;
    const int64_t me = pd_comm_rank(), own = s != PD_OK && !pd_comm_echo();
    int64_t first = pd_comm_min(own ? me : INT64_MAX);
    if (first == INT64_MAX)
        first = pd_comm_min(s != PD_OK ? me : INT64_MAX);
    cli_agreed_failure = 1;
    return pd_comm_error_from((int)first, s);
}

/* The exit status of a failure: 1, with its line on stderr (rank 0's on
 * several ranks, once agreed). */
static inline int cli_failed(void)
{
    if (cli_agreed_failure && pd_comm_rank() > 0)
        return 1;
    return fail();
}

/* The end of a program on MPI ranks: one that failed (every rank, for a
 * usage error or an agreed failure) waits until every rank has said what
 * it says, so that mpirun, stopping the job at the first rank's exit,
 * cuts no line short.  Returns code. */
static inline int cli_ranks_end(int code)
{
    if (code != 0 && pd_comm_size() > 1) {
        fflush(stderr);
        pd_comm_barrier();
    }
    pd_comm_finalize();
    return code;
}

/* On several MPI ranks every rank reads the input and all write the
 * output together (parallel HDF5): both must be files, the output a
 * regular one.  Returns 0, or 2 after a usage error. */
static inline int cli_ranks_files(const char *input, const char *in_what, const char *output,
                                  const char *out_what)
{
    char msg[256];
    struct stat st;
    if (pd_comm_size() == 1)
        return 0;
    if (strcmp(input, "-") == 0) {
        snprintf(msg, sizeof msg, "on several MPI ranks %s must be a file, not", in_what);
        return usage_error(msg, "-");
    }
    if (strcmp(output, "-") == 0 ||
        (stat(output, &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode))) {
        snprintf(msg, sizeof msg,
                 "on several MPI ranks %s must be a regular file, which the ranks write "
                 "together (parallel HDF5), not",
                 out_what);
        return usage_error(msg, output);
    }
    return 0;
}

#endif
