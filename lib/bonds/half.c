/*
 * half.c -- the bonds of a run, each stored once (i < j): the half bonds
 * every kernel walks (lib/models/pmb.c's bond list, lib/stencil/ and
 * lib/models/lps.c through their state bits), built from the file's
 * directed families, and their state kept in step with the directed bits.
 */
#include <math.h>
#include <stdlib.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "bonds/half.h"
#include "base/comm.h"

static int64_t lower_bound(const int32_t *v, int64_t lo, int64_t hi, int32_t key)
{
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (v[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

void pd_half_free(pd_half_bonds *h)
{
    if (h == NULL)
        return;
    free(h->offset);
    free(h->neighbor);
    free(h->length);
    if (h->w_ji != h->w_ij)
        free(h->w_ji);
    free(h->w_ij);
    free(h->intact);
    free(h->released);
    free(h->cursor);
    free(h->kfail);
    free(h->pack);
    free(h->eb);
    free(h->ec);
    pd_half_lanes_free(h);
}

void pd_half_lanes_free(pd_half_bonds *h)
{
    pd_half_lanes *L = h->lanes;
    if (L == NULL)
        return;
    free(L->first);
    free(L->col);
    free(L->row);
    free(L->at);
    free(L->length);
    free(L->w);
    free(L->wji);
    free(L->kfail);
    free(L->act);
    free(L->bits);
    free(L);
    h->lanes = NULL;
}

/* The state bits of row i's half bonds (i-j, j > i: the bit of its copy
 * in i's family), or-ed into h->intact a word at a time, atomically as a
 * row ends or the word does (words are shared at the rows' ends); with
 * `partners`, their partners into h->neighbor on the way. */
static void row_state(pd_half_bonds *h, const pd_bonds *b, const uint64_t *intact, int64_t i,
                      int partners)
{
    int64_t q = h->offset[i];
    uint64_t word = 0;
    pd_bond_iter it;
    for (pd_family_start_partners(b, NULL, i, &it); pd_family_next(&it);)
        if (it.j > i) {
            if (partners)
                h->neighbor[q] = it.j;
            if (pd_bond_intact(intact, it.q))
                word |= UINT64_C(1) << (q & 63);
            if ((++q & 63) == 0) {
                if (word)
                    __atomic_fetch_or(&h->intact[(q - 1) >> 6], word, __ATOMIC_RELAXED);
                word = 0;
            }
        }
    if (word)
        __atomic_fetch_or(&h->intact[(q - 1) >> 6], word, __ATOMIC_RELAXED);
}

int64_t pd_half_block_of(int64_t n, int64_t span, int64_t *nblocks)
{
    /* blocks of at least `span` rows (a block writes only to itself and
     * the next), as many as fit rounded down to a multiple of 4, so that
     * each of the two phases has an even count: two threads share a phase
     * evenly (a rule of the body alone: the sums' order, hence every bit,
     * is the same at any thread count) */
    int64_t nb = span > 0 ? n / span : n;
    nb = nb >= 4 ? nb - nb % 4 : nb > 0 ? nb : 1;
    int64_t block = (n + nb - 1) / nb;
    block = block > span ? block : span;
    *nblocks = block > 0 ? (n + block - 1) / block : 0;
    return block;
}

int64_t pd_half_span(const pd_bonds *b)
{
    int64_t span = 1;
#pragma omp parallel for schedule(static) reduction(max : span)
    for (int64_t i = 0; i < b->n; i++) {
        pd_bond_iter it;
        for (pd_family_start_partners(b, NULL, i, &it); pd_family_next(&it);)
            span = it.j - i > span ? it.j - i : span;
    }
    return span;
}

pd_status pd_half_build(const pd_bonds *b, pd_half_bonds *h)
{
    int64_t n = b->n, count = 0;
    h->n = n;
    h->offset = malloc((size_t)(n + 1) * sizeof(int64_t));
    h->cursor = malloc((size_t)(n > 0 ? n : 1) * sizeof(int64_t));
    if (h->offset == NULL || h->cursor == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the bonds of the run");
    h->offset[0] = 0;
    int64_t span = 1;
    /* the families in either form (pd_family_start: lists or compact) */
#pragma omp parallel for schedule(static) reduction(max : span)
    for (int64_t i = 0; i < n; i++) {
        int64_t c = 0;
        pd_bond_iter it;
        for (pd_family_start_partners(b, NULL, i, &it); pd_family_next(&it);)
            if (it.j > i) {
                c++;
                span = it.j - i > span ? it.j - i : span;
            }
        h->offset[i + 1] = c;
    }
    for (int64_t i = 0; i < n; i++)
        h->offset[i + 1] = count += h->offset[i + 1];
    h->count = count;
    size_t m = (size_t)(count > 0 ? count : 1);
    h->neighbor = malloc(m * sizeof(int32_t));
    h->intact = calloc((size_t)pd_bits_words(count) + 1, sizeof(uint64_t));
    if (!h->neighbor || !h->intact)
        return pd_fail(PD_ERR_NOMEM, "out of memory for %lld bonds", (long long)count);
    /* the partners and, on the same walk, their state bits */
    h->epoch++;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++)
        row_state(h, b, b->intact, i, 1);
    h->block = pd_half_block_of(n, span, &h->nblocks);
    h->walk = h->nblocks;
    h->walk_lo = h->clip = h->blk0 = 0;
    h->released = calloc((size_t)(h->nblocks > 0 ? h->nblocks : 1), sizeof(double));
    if (h->released == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the bonds of the run");
    return PD_OK;
}

pd_status pd_half_set_block(pd_half_bonds *h, int64_t block)
{
    int64_t span = 0;
    for (int64_t i = 0; i < h->n; i++)
        if (h->offset[i + 1] > h->offset[i])
            span = h->neighbor[h->offset[i + 1] - 1] - i > span ? h->neighbor[h->offset[i + 1] - 1] - i : span;
    if (block < span || block < 1)
        return pd_fail(PD_ERR_INVALID, "blocks of %lld rows are shorter than a bond's span, %lld",
                       (long long)block, (long long)span);
    h->block = block;
    h->nblocks = h->walk = (h->n + block - 1) / block;
    h->walk_lo = h->clip = h->blk0 = 0;
    free(h->released);
    h->released = calloc((size_t)(h->nblocks > 0 ? h->nblocks : 1), sizeof(double));
    return h->released ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory for the bonds of the run");
}

void pd_half_set_state(pd_half_bonds *h, const pd_bonds *b, const uint64_t *intact)
{
    h->epoch++;
    for (int64_t w = 0; w < pd_bits_words(h->count); w++)
        h->intact[w] = 0;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < h->n; i++)
        row_state(h, b, intact, i, 0);
}

int64_t pd_half_find(const pd_half_bonds *h, int64_t i, int64_t j)
{
    int64_t q = lower_bound(h->neighbor, h->offset[i], h->offset[i + 1], (int32_t)j);
    return q < h->offset[i + 1] && h->neighbor[q] == j ? q : -1;
}

/* Particles j != i with |x_i - x_j|^2 <= cut2, by pd-bonds's arithmetic
 * (lib/bonds/build.c), among the points of i's 27 cells. */
static int64_t within(const pd_cells *c, const pd_particles *p, int64_t i, double cut2)
{
    const double xi[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
    int64_t lo[9], hi[9], m = 0;
    const int rows = pd_cells_adjacent_rows(c, xi, lo, hi);
    for (int q = 0; q < rows; q++)
        for (int64_t e = lo[q]; e < hi[q]; e++) {
            const int32_t j = c->index[e];
            const double dx = xi[0] - p->x[0][j], dy = xi[1] - p->x[1][j], dz = xi[2] - p->x[2][j];
            m += (dx * dx + dy * dy + dz * dz <= cut2) & (j != i);
        }
    return m;
}

/* The closest pair that is not a half bond, searched pair by pair. */
static double closest_unbonded(const pd_cells *c, const pd_half_bonds *h, const pd_particles *p,
                               double radius, int64_t lo_row, int64_t hi_row)
{
    double best = radius; /* a min in any order is exact */
#pragma omp parallel for schedule(static) reduction(min : best)
    for (int64_t i = lo_row; i < hi_row; i++) {
        const double xi[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
        int64_t lo[9], hi[9];
        const int rows = pd_cells_adjacent_rows(c, xi, lo, hi);
        for (int q = 0; q < rows; q++)
            for (int64_t e = lo[q]; e < hi[q]; e++) {
                const int32_t j = c->index[e];
                const double dx = p->x[0][j] - xi[0], dy = p->x[1][j] - xi[1],
                             dz = p->x[2][j] - xi[2];
                const double d2 = dx * dx + dy * dy + dz * dz;
                if (j > i && d2 < best * best && pd_half_find(h, i, j) < 0)
                    best = sqrt(d2) < best ? sqrt(d2) : best;
            }
    }
    return best;
}

pd_status pd_half_gap(const pd_half_bonds *h, const pd_bonds *b, const pd_particles *p,
                      double *gap)
{
    return pd_half_gap_rows(h, b, p, 0, p->n, 0, gap);
}

pd_status pd_half_gap_rows(const pd_half_bonds *h, const pd_bonds *b, const pd_particles *p,
                           int64_t lo, int64_t hi, int ranks, double *gap)
{
    const double radius = b->horizon, cut2 = radius * radius;
    pd_cells c;
    pd_status s = pd_cells_build(&c, p->n, p->x, radius);
    if (s != PD_OK)
        return s;
    /* the families of pd-bonds: every bond within the horizon and every
     * pair within it a bond (as many as the family holds), so no pair
     * that is not a bond is closer than the horizon */
    int64_t odd = 0;
#pragma omp parallel for schedule(static) reduction(+ : odd)
    for (int64_t i = lo; i < hi; i++) {
        for (int64_t q = h->offset[i]; q < h->offset[i + 1]; q++) {
            const int32_t j = h->neighbor[q];
            const double dx = p->x[0][i] - p->x[0][j], dy = p->x[1][i] - p->x[1][j],
                         dz = p->x[2][i] - p->x[2][j];
            odd += !(dx * dx + dy * dy + dz * dz <= cut2);
        }
        odd += within(&c, p, i, cut2) != b->offset[i + 1] - b->offset[i];
    }
    if (ranks) /* a piece's rows: the whole body's answer */
        odd = pd_comm_total(odd);
    *gap = odd == 0 ? radius : closest_unbonded(&c, h, p, radius, lo, hi);
    if (ranks && odd != 0)
        *gap = -pd_comm_max(-*gap);
    pd_cells_free(&c);
    return PD_OK;
}

void pd_half_break_all(pd_half_bonds *h, const pd_bonds *b, int64_t i)
{
    h->epoch++;
    pd_bond_iter it;
    for (pd_family_start_partners(b, NULL, i, &it); pd_family_next(&it);) {
        const int32_t j = it.j;
        int64_t q = pd_half_find(h, j < i ? j : i, j < i ? i : j);
        if (q >= 0)
            pd_bond_break(h->intact, q);
    }
}

/* The row holding directed bond k: the last i with offset[i] <= k. */
static int64_t row_of(const int64_t *offset, int64_t n, int64_t k)
{
    int64_t lo = 0, hi = n; /* offset[lo] <= k < offset[hi] */
    while (hi - lo > 1) {
        int64_t mid = lo + (hi - lo) / 2;
        if (offset[mid] <= k)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* The directed bits of rows [i0, i1), whose bonds are [k0, k1): row i
 * meets its bonds to j < i in ascending i for each j, so a cursor per row
 * walks the half bonds of j in order.  The cursors of rows j >= i0 start
 * at their rows' heads (h->cursor, used by this range alone); those of the
 * rows before i0 (at most h->block of them) in `before`, at the first half
 * bond of j to a row >= i0.  The first and last words may be shared with
 * the neighbouring ranges, and are or-ed in atomically. */
static void expand_rows(const pd_half_bonds *h, const pd_bonds *b, int64_t i0, int64_t i1,
                        int64_t *before, uint64_t *intact)
{
    const int64_t k0 = b->offset[i0], k1 = b->offset[i1];
    if (k1 == k0)
        return;
    const int64_t j0 = i0 - h->block > 0 ? i0 - h->block : 0;
    for (int64_t j = j0; j < i0; j++) {
        int64_t q = h->offset[j];
        while (q < h->offset[j + 1] && h->neighbor[q] < i0)
            q++;
        before[j - j0] = q;
    }
    for (int64_t i = i0; i < i1; i++)
        h->cursor[i] = h->offset[i];
    const int64_t w0 = k0 >> 6, w1 = (k1 - 1) >> 6;
    uint64_t word = 0;
    int64_t w = w0;
    for (int64_t i = i0; i < i1; i++) {
        int64_t own = h->offset[i];
        pd_bond_iter it;
        for (pd_family_start_partners(b, NULL, i, &it); pd_family_next(&it);) {
            const int64_t k = it.q;
            if ((k >> 6) != w) { /* a word done */
                if (w == w0)
                    __atomic_fetch_or(&intact[w], word, __ATOMIC_RELAXED);
                else
                    intact[w] = word;
                word = 0;
                w = k >> 6;
            }
            const int32_t j = it.j;
            const int64_t q = j > i ? own++ : j >= i0 ? h->cursor[j]++ : before[j - j0]++;
            if (pd_bond_intact(h->intact, q))
                word |= UINT64_C(1) << (k & 63);
        }
    }
    if (w == w0 || w == w1)
        __atomic_fetch_or(&intact[w], word, __ATOMIC_RELAXED);
    else
        intact[w] = word;
}

void pd_half_expand(const pd_half_bonds *h, const pd_bonds *b, uint64_t *intact)
{
    /* rows split among the threads by their bonds; each range walks its
     * rows as one serial walk would, so the bits are the same for every
     * thread count */
    const int64_t words = pd_bits_words(b->count);
    for (int64_t w = 0; w < words; w++)
        intact[w] = 0;
    int failed = 0;
#pragma omp parallel reduction(| : failed)
    {
        int T = 1, t = 0;
#ifdef _OPENMP
        T = omp_get_num_threads();
        t = omp_get_thread_num();
#endif
        const int64_t i0 = t == 0 ? 0 : row_of(b->offset, b->n, b->count * t / T) + 1;
        const int64_t i1 = t == T - 1 ? b->n : row_of(b->offset, b->n, b->count * (t + 1) / T) + 1;
        int64_t *before = malloc((size_t)(h->block > 0 ? h->block : 1) * sizeof(int64_t));
        if (before == NULL)
            failed = 1;
        else if (i0 < i1)
            expand_rows(h, b, i0, i1, before, intact);
        free(before);
    }
    if (failed) /* out of memory for a few cursors: all rows as one range
                   (no row before the first: no cursor of `before`) */
        expand_rows(h, b, 0, b->n, NULL, intact);
}

