/*
 * sets.c -- named particle sets (pd-lattice --set), the particles a
 * boundary condition acts on.  A set is stored by global id, not by row:
 * pd-bonds reorders rows, ids travel with the particles.  In the file:
 * /sets/NAME, int64 (k), ascending ids (man 5 pd-h5; lib/io/sets_io.c).
 */
#include <stdlib.h>
#include <string.h>

#include "base/sets.h"

pd_sets *pd_sets_new(void)
{
    return calloc(1, sizeof(pd_sets));
}

void pd_sets_free(pd_sets *s)
{
    if (s == NULL)
        return;
    for (int k = 0; k < s->count; k++)
        free(s->set[k].id);
    free(s->set);
    free(s);
}

int pd_set_name_ok(const char *name)
{
    size_t len = strlen(name);
    if (len == 0 || len >= PD_SET_NAME_MAX || strcmp(name, ".") == 0 || strcmp(name, "..") == 0)
        return 0;
    return strspn(name, "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_.-") ==
           len;
}

const pd_set *pd_sets_find(const pd_sets *s, const char *name)
{
    for (int k = 0; s && k < s->count; k++)
        if (strcmp(s->set[k].name, name) == 0)
            return &s->set[k];
    return NULL;
}

static int cmp_id(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

pd_status pd_sets_append(pd_sets *s, const char *name, int64_t n, int64_t *ids)
{
    pd_set *nv = realloc(s->set, (size_t)(s->count + 1) * sizeof *nv);
    if (nv == NULL) {
        free(ids);
        return pd_fail(PD_ERR_NOMEM, "out of memory for set '%s'", name);
    }
    s->set = nv;
    pd_set *t = &s->set[s->count++];
    memset(t, 0, sizeof *t);
    snprintf(t->name, sizeof t->name, "%s", name);
    t->n = n;
    t->id = ids;
    return PD_OK;
}

pd_status pd_sets_add_region(pd_sets *s, const char *name, const pd_region *r,
                             const pd_particles *p)
{
    if (!pd_set_name_ok(name))
        return pd_fail(PD_ERR_INVALID,
                       "set name '%s': expected 1 to %d of A-Z a-z 0-9 _ . - (not . or ..)", name,
                       PD_SET_NAME_MAX - 1);
    if (pd_sets_find(s, name))
        return pd_fail(PD_ERR_INVALID, "set '%s' is given twice", name);
    int64_t *ids = malloc((size_t)(p->n > 0 ? p->n : 1) * sizeof(int64_t)), n = 0;
    if (ids == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for set '%s'", name);
    for (int64_t i = 0; i < p->n; i++) {
        double x[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
        if (pd_region_inside(r, x))
            ids[n++] = p->id[i];
    }
    if (n == 0) {
        free(ids);
        return pd_fail(PD_ERR_INVALID, "set '%s' holds no particle (its region misses the body)",
                       name);
    }
    qsort(ids, (size_t)n, sizeof *ids, cmp_id);
    return pd_sets_append(s, name, n, ids);
}

static int cmp_id_row(const void *a, const void *b)
{
    return cmp_id(a, b); /* id first */
}

pd_id_row *pd_id_index(const pd_particles *p)
{
    pd_id_row *ix = malloc((size_t)(p->n > 0 ? p->n : 1) * sizeof *ix);
    if (ix == NULL)
        return NULL;
    for (int64_t i = 0; i < p->n; i++)
        ix[i] = (pd_id_row){p->id[i], i};
    qsort(ix, (size_t)p->n, sizeof *ix, cmp_id_row);
    return ix;
}

int64_t pd_row_of_id(const pd_id_row *ix, int64_t n, int64_t id)
{
    const pd_id_row key = {id, 0};
    const pd_id_row *hit = bsearch(&key, ix, (size_t)n, sizeof *ix, cmp_id_row);
    return hit ? hit->row : -1;
}

pd_status pd_set_rows_present(const pd_set *set, const pd_particles *p, int64_t **rows)
{
    pd_id_row *ix = pd_id_index(p);
    int64_t *r = malloc((size_t)(set->n > 0 ? set->n : 1) * sizeof(int64_t));
    if (ix == NULL || r == NULL) {
        free(ix);
        free(r);
        return pd_fail(PD_ERR_NOMEM, "out of memory for set '%s'", set->name);
    }
    for (int64_t k = 0; k < set->n; k++)
        r[k] = pd_row_of_id(ix, p->n, set->id[k]);
    free(ix);
    *rows = r;
    return PD_OK;
}

pd_status pd_set_rows(const pd_set *set, const pd_particles *p, int64_t **rows)
{
    pd_id_row *ix = pd_id_index(p);
    int64_t *r = malloc((size_t)set->n * sizeof(int64_t));
    if (ix == NULL || r == NULL) {
        free(ix);
        free(r);
        return pd_fail(PD_ERR_NOMEM, "out of memory for set '%s'", set->name);
    }
    for (int64_t k = 0; k < set->n; k++)
        if ((r[k] = pd_row_of_id(ix, p->n, set->id[k])) < 0) {
            free(ix);
            free(r);
            return pd_fail(PD_ERR_INVALID, "set '%s': id %lld is no particle's", set->name,
                           (long long)set->id[k]);
        }
    free(ix);
    *rows = r;
    return PD_OK;
}

