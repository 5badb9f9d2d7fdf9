/*
 * check.h -- the few lines every C unit test of lib/ shares: CHECK records
 * a failure with its place, proved() reports one proved statement, die()
 * stops on a library error that makes the rest meaningless.
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

#endif
