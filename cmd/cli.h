/*
 * cli.h -- the lines of glue every program shares: one-line errors and the
 * exit status (1 runtime or data error, 2 usage error).  Include it after
 * defining PROG.  Library code never prints; these are the only printers of
 * pd_errmsg().
 */
#ifndef PD_CLI_H
#define PD_CLI_H

#include <getopt.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "pd.h"

/* A usage error: one line on stderr, exit status 2. */
static inline int usage_error(const char *msg, const char *arg)
{
    fprintf(stderr, PROG ": error: %s%s%s%s (see '" PROG " --help')\n", msg, arg ? " '" : "",
            arg ? arg : "", arg ? "'" : "");
    return 2;
}

/* getopt_long's '?' (its own message is switched off by opterr = 0). */
static inline int option_error(char **argv)
{
    return usage_error("unknown option or missing value in", argv[optind - 1]);
}

/* The long options every program has, with codes above any program's own. */
enum { OPT_DEBUG = 1000 };
#define COMMON_LONGOPTS                                                                            \
    {"debug", no_argument, 0, OPT_DEBUG}, {"help", no_argument, 0, 'h'},                           \
        {"version", no_argument, 0, 'V'}

/* --help and --version (both exit 0), --debug, and what getopt_long could
 * not parse (exit status 2); -1 when `c` is one of the program's own. */
static inline int common_option(int c, char **argv, void (*usage)(FILE *), int *debug)
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
        return option_error(argv);
    }
    return -1;
}

/* On SIGINT, SIGTERM, SIGHUP or SIGPIPE: remove the temporary output, then
 * die of the signal as before.  A signal ignored at start (nohup, a
 * background job's SIGINT) stays ignored. */
static void remove_temps_and_die(int sig)
{
    pd_remove_temps();
    signal(sig, SIG_DFL);
    raise(sig);
}

static inline void remove_temps_on_signal(void)
{
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
        if (c == -1)
            return -1;
        int rc = common_option(c, argv, usage, debug);
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

#endif
