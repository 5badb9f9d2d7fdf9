/*
 * sets_io.c -- the particle sets in a file: /sets/NAME, int64 (k),
 * ascending ids (man 5 pd-h5), checked against the particles on reading.
 */
#include <stdlib.h>
#include <string.h>

#include "base/comm.h"
#include "base/sets.h"
#include "io/h5util.h"

typedef struct {
    const pd_file *f;
    const pd_id_row *ix;
    const pd_particles *p;
    pd_sets *sets;
    pd_status st;
} read_ctx;

/* The first of a set's n ids that is no particle's: -1 for none.  A window
 * of a body on MPI ranks (collective) finds each id among the rows some
 * rank owns. */
static int64_t missing_id(const read_ctx *c, const int64_t *ids, int64_t n)
{
    const pd_particles *p = c->p;
    if (!p->window) {
        for (int64_t k = 0; k < n; k++)
            if (pd_row_of_id(c->ix, p->n, ids[k]) < 0)
                return k;
        return -1;
    }
    double *found = calloc((size_t)(n > 0 ? n : 1), sizeof(double));
    if (found)
        for (int64_t k = 0; k < n; k++) {
            const int64_t i = pd_row_of_id(c->ix, p->n, ids[k]);
            found[k] = i >= p->own_lo && i < p->own_hi;
        }
    if (pd_comm_agree(found ? PD_OK : PD_ERR_NOMEM) != PD_OK) {
        free(found);
        return -2;
    }
    pd_comm_add(found, n); /* one owner a row: 1 or 0, exact */
    int64_t k = 0;
    while (k < n && found[k] != 0)
        k++;
    free(found);
    return k < n ? k : -1;
}

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
    for (int64_t k = 1; k < n && c->st == PD_OK; k++)
        if (!(ids[k] > ids[k - 1]))
            c->st = pd_fail(PD_ERR_FORMAT, "'%s': set '%s': ids are not strictly ascending", fn,
                            name);
    const int64_t miss = c->st == PD_OK ? missing_id(c, ids, n) : -1;
    if (miss == -2)
        c->st = pd_fail(PD_ERR_NOMEM, "out of memory checking set '%s'", name);
    else if (miss >= 0)
        c->st = pd_fail(PD_ERR_FORMAT, "'%s': set '%s': id %lld is no particle's", fn, name,
                        (long long)ids[miss]);
    if (c->st != PD_OK) {
        free(ids);
        return 1;
    }
    c->st = pd_sets_append(c->sets, name, n, ids);
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
    pd_id_row *ix = pd_id_index(p);
    if (ix == NULL) {
        H5Gclose(g);
        pd_sets_free(s);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    read_ctx c = {f, ix, p, s, PD_OK};
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
