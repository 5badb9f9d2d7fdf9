/*
 * build.c -- the families within the horizon (seed 000 eq. 11): on a
 * lattice by its sites (stencil.c, pd_bonds_build_lattice), otherwise by
 * cell lists of edge delta; linear in N, the same bonds either way.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "pd.h"

/* Visit the partners of i within the horizon: count them (out == NULL) or
 * write them (unsorted) into out[]. */
static int64_t family(const pd_particles *p, const pd_cells *c, int64_t i, double horizon,
                      int32_t *out)
{
    const double cut2 = horizon * horizon;
    double xi[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
    int64_t cells[27];
    int ncells = pd_cells_adjacent(c, xi, cells);
    int64_t m = 0;
    for (int q = 0; q < ncells; q++)
        for (int64_t e = c->start[cells[q]]; e < c->start[cells[q] + 1]; e++) {
            int32_t j = c->index[e];
            if (j == i)
                continue;
            /* the same arithmetic as LAMMPS fix PERI_NEIGH, so that pairs at
             * exactly the horizon are decided alike */
            double dx = xi[0] - p->x[0][j], dy = xi[1] - p->x[1][j], dz = xi[2] - p->x[2][j];
            double rsq = dx * dx + dy * dy + dz * dz;
            if (rsq <= cut2) {
                if (out)
                    out[m] = j;
                m++;
            }
        }
    return m;
}

static int cmp_int32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

pd_status pd_bonds_build(const pd_particles *p, double horizon, pd_bonds **out)
{
    if (!(horizon > 0) || !isfinite(horizon))
        return pd_fail(PD_ERR_INVALID, "horizon must be a positive number");
    if (p->n >= INT32_MAX)
        return pd_fail(PD_ERR_INVALID, "too many particles for one process (%lld)",
                       (long long)p->n);
    pd_status ls = pd_bonds_build_lattice(p, horizon, 1, out);
    if (ls != PD_OK || *out)
        return ls;
    return pd_bonds_build_rows(p, horizon, 0, p->n, out);
}

pd_status pd_bonds_build_rows(const pd_particles *p, double horizon, int64_t lo, int64_t hi,
                              pd_bonds **out)
{
    if (!(horizon > 0) || !isfinite(horizon))
        return pd_fail(PD_ERR_INVALID, "horizon must be a positive number");
    if (p->n >= INT32_MAX)
        return pd_fail(PD_ERR_INVALID, "too many particles for one process (%lld)",
                       (long long)p->n);
    pd_cells c;
    pd_status st = pd_cells_build(&c, p->n, p->x, horizon);
    if (st != PD_OK)
        return st;
    int64_t n = p->n;
    int64_t *count = calloc((size_t)(n + 1), sizeof(int64_t));
    if (count == NULL) {
        pd_cells_free(&c);
        return pd_fail(PD_ERR_NOMEM, "out of memory for bond counts");
    }
#pragma omp parallel for schedule(dynamic, 1024)
    for (int64_t i = lo; i < hi; i++)
        count[i] = family(p, &c, i, horizon, NULL);
    int64_t total = 0;
    for (int64_t i = lo; i < hi; i++)
        total += count[i];
    pd_bonds *b = pd_bonds_alloc(n, total);
    if (b == NULL) {
        free(count);
        pd_cells_free(&c);
        return pd_fail(PD_ERR_NOMEM, "out of memory for %lld bonds", (long long)total);
    }
    b->horizon = horizon;
    for (int64_t i = 0; i < n; i++) /* the rows beyond [lo, hi): no family */
        b->offset[i + 1] = b->offset[i] + count[i];
    free(count);
#pragma omp parallel for schedule(dynamic, 1024)
    for (int64_t i = lo; i < hi; i++) {
        int32_t *nb = b->neighbor + b->offset[i];
        int64_t m = family(p, &c, i, horizon, nb);
        qsort(nb, (size_t)m, sizeof *nb, cmp_int32);
        for (int64_t q = 0; q < m; q++) {
            int64_t k = b->offset[i] + q, j = nb[q];
            double dx = p->x[0][i] - p->x[0][j], dy = p->x[1][i] - p->x[1][j],
                   dz = p->x[2][i] - p->x[2][j];
            b->length[k] = sqrt(dx * dx + dy * dy + dz * dz);
            b->vfactor[k] = pd_partial_volume(b->length[k], horizon, p->radius[j]);
        }
    }
    pd_cells_free(&c);
    /* two particles at one place: no bond direction, no stretch */
    for (int64_t i = lo; i < hi; i++)
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++)
            if (b->length[k] == 0) {
                int64_t j = b->neighbor[k];
                pd_bonds_free(b);
                return pd_fail(PD_ERR_INVALID,
                               "particles %lld and %lld (ids %lld and %lld) are at the same "
                               "position (%g, %g, %g) m",
                               (long long)(i < j ? i : j), (long long)(i < j ? j : i),
                               (long long)p->id[i < j ? i : j], (long long)p->id[i < j ? j : i],
                               p->x[0][i], p->x[1][i], p->x[2][i]);
            }
    memset(b->intact, 0xff, (size_t)pd_bits_words(total) * sizeof(uint64_t));
    *out = b;
    return PD_OK;
}
