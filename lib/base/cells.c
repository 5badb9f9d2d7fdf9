/*
 * cells.c -- cell lists: particles binned into cubes of edge >= cutoff, so
 * that every pair closer than the cutoff lies in the same or adjacent cells.
 * Building is a counting sort, O(N); each particle's partners are then found
 * among 27 cells, never among all pairs.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "pd.h"

void pd_cells_locate(const pd_cells *c, const double x[3], int64_t cell[3])
{
    for (int d = 0; d < 3; d++) {
        double t = floor((x[d] - c->lo[d]) / c->size);
        const double top = (double)(c->dim[d] - 1); /* clamped, without calls */
        int64_t k = isfinite(t) ? (int64_t)(t < 0.0 ? 0.0 : t < top ? t : top) : 0;
        cell[d] = k;
    }
}

int pd_cells_adjacent(const pd_cells *c, const double x[3], int64_t cells[27])
{
    int64_t k[3];
    pd_cells_locate(c, x, k);
    int m = 0;
    for (int64_t cz = k[2] - 1; cz <= k[2] + 1; cz++)
        for (int64_t cy = k[1] - 1; cy <= k[1] + 1; cy++)
            for (int64_t cx = k[0] - 1; cx <= k[0] + 1; cx++)
                if (cz >= 0 && cz < c->dim[2] && cy >= 0 && cy < c->dim[1] && cx >= 0 &&
                    cx < c->dim[0])
                    cells[m++] = (cz * c->dim[1] + cy) * c->dim[0] + cx;
    return m;
}

int pd_cells_adjacent_runs(const pd_cells *c, const double x[3], int64_t first[9], int *width,
                           int around[9], int *dx0)
{
    int64_t k[3];
    pd_cells_locate(c, x, k);
    const int64_t x0 = k[0] > 0 ? k[0] - 1 : 0, x1 = k[0] + 1 < c->dim[0] ? k[0] + 1 : k[0];
    int m = 0;
    for (int64_t cz = k[2] - 1; cz <= k[2] + 1; cz++)
        for (int64_t cy = k[1] - 1; cy <= k[1] + 1; cy++)
            if (cz >= 0 && cz < c->dim[2] && cy >= 0 && cy < c->dim[1]) {
                around[m] = (int)(3 * (cz - k[2] + 1) + (cy - k[1] + 1));
                first[m++] = (cz * c->dim[1] + cy) * c->dim[0] + x0;
            }
    *width = (int)(x1 - x0 + 1);
    *dx0 = (int)(x0 - k[0]);
    return m;
}

int pd_cells_adjacent_rows(const pd_cells *c, const double x[3], int64_t lo[9], int64_t hi[9])
{
    int64_t first[9];
    int width, around[9], dx0;
    const int m = pd_cells_adjacent_runs(c, x, first, &width, around, &dx0);
    for (int r = 0; r < m; r++) {
        lo[r] = c->start[first[r]];
        hi[r] = c->start[first[r] + width];
    }
    return m;
}

static int64_t cell_of(const pd_cells *c, const double x[3])
{
    int64_t k[3];
    pd_cells_locate(c, x, k);
    return (k[2] * c->dim[1] + k[1]) * c->dim[0] + k[0];
}

pd_status pd_cells_build(pd_cells *c, int64_t n, double *const x[3], double cutoff)
{
    return pd_cells_build_except(c, n, x, cutoff, NULL);
}

void pd_cells_geometry(pd_cells *c, const double box_lo[3], const double box_hi[3], int64_t n,
                       double cutoff)
{
    double lo[3], hi[3];
    for (int d = 0; d < 3; d++) {
        lo[d] = box_lo[d] <= box_hi[d] ? box_lo[d] : 0;
        hi[d] = box_lo[d] <= box_hi[d] ? box_hi[d] : 0;
    }
    /* Keep the grid near the particle count: particles flying far away must
     * not make the grid (and the build) huge. */
    double size = cutoff;
    double limit = fmax(8.0 * (double)n, 4096.0);
    for (;;) {
        double cells = 1;
        for (int d = 0; d < 3; d++)
            cells *= floor((hi[d] - lo[d]) / size) + 1;
        if (cells <= limit)
            break;
        size *= 1.25;
    }
    c->size = size;
    for (int d = 0; d < 3; d++) {
        c->lo[d] = lo[d];
        c->dim[d] = (int64_t)floor((hi[d] - lo[d]) / size) + 1;
    }
}

pd_status pd_cells_build_except(pd_cells *c, int64_t n, double *const x[3], double cutoff,
                                const uint8_t *skip)
{
    memset(c, 0, sizeof *c);
    return pd_cells_rebuild_except(c, n, x, cutoff, skip);
}

pd_status pd_cells_rebuild_except(pd_cells *c, int64_t n, double *const x[3], double cutoff,
                                  const uint8_t *skip)
{
    double lo0 = INFINITY, lo1 = INFINITY, lo2 = INFINITY;
    double hi0 = -INFINITY, hi1 = -INFINITY, hi2 = -INFINITY;
#pragma omp parallel for schedule(static) reduction(min : lo0, lo1, lo2) \
    reduction(max : hi0, hi1, hi2)
    for (int64_t i = 0; i < n; i++)
        if (!(skip && skip[i])) { /* fmin, fmax inlined */
            const double a = x[0][i], b = x[1][i], d = x[2][i];
            if (isfinite(a)) {
                lo0 = a < lo0 ? a : lo0;
                hi0 = a > hi0 ? a : hi0;
            }
            if (isfinite(b)) {
                lo1 = b < lo1 ? b : lo1;
                hi1 = b > hi1 ? b : hi1;
            }
            if (isfinite(d)) {
                lo2 = d < lo2 ? d : lo2;
                hi2 = d > hi2 ? d : hi2;
            }
        }
    if (!(cutoff > 0))
        return pd_fail(PD_ERR_INVALID, "cell size must be positive");
    const double lo[3] = {lo0, lo1, lo2}, hi[3] = {hi0, hi1, hi2};
    pd_cells_geometry(c, lo, hi, n, cutoff);
    const int64_t ncell = c->dim[0] * c->dim[1] * c->dim[2], m = n > 0 ? n : 1;
    c->nfull = 0;
    if (!pd_grow((void **)&c->start, &c->start_room, ncell + 1, sizeof(int64_t)) ||
        !pd_grow((void **)&c->index, &c->index_room, m, sizeof(int32_t)) ||
        !pd_grow((void **)&c->cellof, &c->cellof_room, m, sizeof(int64_t)) ||
        !pd_grow((void **)&c->full, &c->full_room, m < ncell ? m : ncell, sizeof(int64_t))) {
        pd_cells_free(c);
        return pd_fail(PD_ERR_NOMEM, "out of memory for a cell list");
    }
    int64_t *start = c->start, *cellof = c->cellof;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++)
        if (!(skip && skip[i])) {
            const double p[3] = {x[0][i], x[1][i], x[2][i]};
            cellof[i] = cell_of(c, p);
        }
    /* a counting sort: each cell's count, then its end (and the cells that
     * hold points, in order), then its points placed from the last down,
     * each cell's end its cursor, so that it ends at the cell's start */
    memset(start, 0, (size_t)(ncell + 1) * sizeof(int64_t));
    for (int64_t i = 0; i < n; i++)
        if (!(skip && skip[i]))
            start[cellof[i]]++;
    int64_t end = 0;
    for (int64_t k = 0; k < ncell; k++) {
        if (start[k] > 0)
            c->full[c->nfull++] = k;
        end += start[k];
        start[k] = end;
    }
    start[ncell] = end;
    for (int64_t i = n - 1; i >= 0; i--)
        if (!(skip && skip[i]))
            c->index[--start[cellof[i]]] = (int32_t)i;
    return PD_OK;
}

void pd_cells_free(pd_cells *c)
{
    if (c == NULL)
        return;
    free(c->start);
    free(c->index);
    free(c->cellof);
    free(c->full);
    memset(c, 0, sizeof *c);
}
