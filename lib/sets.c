/*
 * sets.c -- named particle sets (pd-lattice --set), the particles a
 * boundary condition acts on.  A set is stored by global id, not by row:
 * pd-bonds reorders rows, ids travel with the particles.  In the file:
 * /sets/NAME, int64 (k), ascending ids (man 5 pd-h5).
 */
#include <stdlib.h>
#include <string.h>

#include "h5util.h"

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

/* Append a set that takes ownership of ids (n of them, sorted). */
static pd_status append(pd_sets *s, const char *name, int64_t n, int64_t *ids)
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
    return append(s, name, n, ids);
}

/* (id, row) pairs sorted by id, to map ids to rows. */
typedef struct {
    int64_t id, row;
} id_row;

static int cmp_id_row(const void *a, const void *b)
{
    return cmp_id(a, b); /* id first */
}

static id_row *id_index(const pd_particles *p)
{
    id_row *ix = malloc((size_t)(p->n > 0 ? p->n : 1) * sizeof *ix);
    if (ix == NULL)
        return NULL;
    for (int64_t i = 0; i < p->n; i++)
        ix[i] = (id_row){p->id[i], i};
    qsort(ix, (size_t)p->n, sizeof *ix, cmp_id_row);
    return ix;
}

static int64_t row_of_id(const id_row *ix, int64_t n, int64_t id)
{
    const id_row key = {id, 0};
    const id_row *hit = bsearch(&key, ix, (size_t)n, sizeof *ix, cmp_id_row);
    return hit ? hit->row : -1;
}

pd_status pd_set_rows(const pd_set *set, const pd_particles *p, int64_t **rows)
{
    id_row *ix = id_index(p);
    int64_t *r = malloc((size_t)set->n * sizeof(int64_t));
    if (ix == NULL || r == NULL) {
        free(ix);
        free(r);
        return pd_fail(PD_ERR_NOMEM, "out of memory for set '%s'", set->name);
    }
    for (int64_t k = 0; k < set->n; k++)
        if ((r[k] = row_of_id(ix, p->n, set->id[k])) < 0) {
            free(ix);
            free(r);
            return pd_fail(PD_ERR_INVALID, "set '%s': id %lld is no particle's", set->name,
                           (long long)set->id[k]);
        }
    free(ix);
    *rows = r;
    return PD_OK;
}

/* ------------------------------------------------------------ the file */

typedef struct {
    const pd_file *f;
    const id_row *ix;
    int64_t n;
    pd_sets *sets;
    pd_status st;
} read_ctx;

static herr_t read_one(hid_t g, const char *name, const H5L_info_t *info, void *data)
{
    (void)info;
    read_ctx *c = data;
    const char *fn = c->f->name;
    if (!pd_set_name_ok(name)) {
        c->st = pd_fail(PD_ERR_FORMAT, "'%s': /sets has a member with a bad name '%s'", fn, name);
        return 1;
    }
    char path[PD_SET_NAME_MAX + 8];
    snprintf(path, sizeof path, "/sets/%s", name);
    pd_h5_form form = {H5T_INTEGER, 8, 1, {0, 0}};
    int64_t *ids = NULL;
    hsize_t dims[1] = {0};
    (void)g;
    c->st = pd_h5_read_data(c->f->fid, fn, path, &form, H5T_NATIVE_INT64, sizeof(int64_t),
                            (void **)&ids, dims);
    if (c->st != PD_OK)
        return 1;
    int64_t n = (int64_t)dims[0];
    if (n == 0)
        c->st = pd_fail(PD_ERR_FORMAT, "'%s': set '%s' is empty", fn, name);
    for (int64_t k = 0; k < n && c->st == PD_OK; k++)
        if (k > 0 && !(ids[k] > ids[k - 1]))
            c->st = pd_fail(PD_ERR_FORMAT, "'%s': set '%s': ids are not strictly ascending", fn,
                            name);
        else if (row_of_id(c->ix, c->n, ids[k]) < 0)
            c->st = pd_fail(PD_ERR_FORMAT, "'%s': set '%s': id %lld is no particle's", fn, name,
                            (long long)ids[k]);
    if (c->st != PD_OK) {
        free(ids);
        return 1;
    }
    c->st = append(c->sets, name, n, ids);
    return c->st != PD_OK;
}

pd_status pd_read_sets(const pd_file *f, const pd_particles *p, pd_sets **out)
{
    pd_sets *s = pd_sets_new();
    if (s == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    if (!pd_h5_has_link(f->fid, "/sets")) {
        *out = s;
        return PD_OK;
    }
    hid_t g = H5Gopen2(f->fid, "/sets", H5P_DEFAULT);
    if (g < 0) {
        pd_sets_free(s);
        return pd_fail(PD_ERR_FORMAT, "'%s': /sets is not a group", f->name);
    }
    id_row *ix = id_index(p);
    if (ix == NULL) {
        H5Gclose(g);
        pd_sets_free(s);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    read_ctx c = {f, ix, p->n, s, PD_OK};
    hsize_t idx = 0;
    herr_t e = H5Literate(g, H5_INDEX_NAME, H5_ITER_INC, &idx, read_one, &c);
    H5Gclose(g);
    free(ix);
    if (c.st == PD_OK && e < 0)
        c.st = pd_fail(PD_ERR_FORMAT, "'%s': cannot read /sets", f->name);
    if (c.st != PD_OK) {
        pd_sets_free(s);
        return c.st;
    }
    *out = s;
    return PD_OK;
}

pd_status pd_write_sets(pd_file *f, const pd_sets *s)
{
    if (s == NULL || s->count == 0)
        return PD_OK;
    if (pd_h5_has_link(f->fid, "/sets"))
        return PD_OK; /* a file updated in place keeps its own */
    hid_t g = pd_h5_create_group(f->fid, "/sets");
    if (g < 0)
        return pd_fail(PD_ERR_IO, "cannot create /sets");
    pd_status st = PD_OK;
    for (int k = 0; k < s->count && st == PD_OK; k++) {
        hsize_t d1[1] = {(hsize_t)s->set[k].n};
        st = pd_h5_write_data(g, s->set[k].name, H5T_STD_I64LE, H5T_NATIVE_INT64, 1, d1,
                              s->set[k].id);
    }
    H5Gclose(g);
    return st;
}
