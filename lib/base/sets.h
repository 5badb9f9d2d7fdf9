/*
 * sets.h -- internal (lib/base/sets.c): what the sets' file code
 * (lib/io/sets_io.c) shares with their logic.
 */
#ifndef PD_SETS_H
#define PD_SETS_H

#include "pd.h"

/* Append a set that takes ownership of ids (n of them, sorted). */
pd_status pd_sets_append(pd_sets *s, const char *name, int64_t n, int64_t *ids);

/* (id, row) pairs sorted by id, to map ids to rows. */
typedef struct {
    int64_t id, row;
} pd_id_row;

/* The index of p's ids (malloc'd; NULL when out of memory), and the row of
 * an id in it (-1: none). */
pd_id_row *pd_id_index(const pd_particles *p);
int64_t pd_row_of_id(const pd_id_row *ix, int64_t n, int64_t id);

#endif
