/*
 * check.h -- the few lines every C unit test of lib/ shares: CHECK records
 * a failure with its place, proved() reports one proved statement, die()
 * stops on a library error that makes the rest meaningless, shuffle_rows()
 * puts a body's rows in a fixed other order.
 */
#ifndef PD_TEST_CHECK_H
#define PD_TEST_CHECK_H

#include <stdio.h>
#include <stdlib.h>

#include "pd.h"

static int failures;

#define CHECK(cond, ...)                                                                           \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            failures++;                                                                            \
            fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__);                                   \
            fprintf(stderr, __VA_ARGS__);                                                          \
            fputc('\n', stderr);                                                                   \
        }                                                                                          \
    } while (0)

static inline void proved(int before, const char *what)
{
    printf("%s: %s\n", failures == before ? "ok" : "FAILED", what);
}

static inline void die(const char *what)
{
    fprintf(stderr, "%s: %s\n", what, pd_errmsg());
    exit(1);
}

/* A fixed shuffle of the particles' rows (positions and ids), for tests
 * of what holds in any row order. */
static inline void shuffle_rows(pd_particles *p)
{
    for (int64_t i = p->n - 1; i > 0; i--) {
        int64_t j = (i * 7919) % (i + 1);
        for (int d = 0; d < 3; d++) {
            double t = p->x[d][i];
            p->x[d][i] = p->x[d][j];
            p->x[d][j] = t;
        }
        int64_t t = p->id[i];
        p->id[i] = p->id[j];
        p->id[j] = t;
    }
}

#endif
