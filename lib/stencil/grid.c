/*
 * grid.c -- the bonds of a body on a lattice, walked as a stencil (PMB, and
 * LPS without ellipsoids): building the stencil (its offsets, runs,
 * segments and blocks), keeping its masks in step with the half bonds,
 * and the small queries.  The kernels that walk it are in grid_pmb.c
 * (PMB), grid_energy.c (energies, damage) and grid_lps.c (LPS); the data
 * in grid_impl.h.
 *
 * A body made by pd-lattice sits on a simple cubic (or, for a plate,
 * square) lattice of spacing h, and pd-bonds gives every particle a bond to
 * each particle at a lattice offset d with |d| h <= delta.  Such a bond is
 * named by its first particle and its offset: no neighbour index, length or
 * weight needs to be stored per bond, only one bit of state.  When pd-run
 * finds a PMB scene, or an LPS one whose influence depends on |xi| alone,
 * on such a body (pd_grid_new checks every condition below; any other
 * scene keeps the bond lists of lib/models/pmb.c and lib/models/lps.c), it walks the
 * bonds as a stencil:
 *
 *   - Lattice coordinates.  Particle i sits at lo + h c_i with integer c_i
 *     (to 1e-6 h).  The axes are taken in the order inner (the longest
 *     extent), mid (the shortest), outer (the other one), and "grid order"
 *     sorts the particles by (outer, mid, inner): a row (fixed outer and
 *     mid) is then made of runs of particles consecutive along the inner
 *     axis and in memory.  pd-bonds writes its particles in grid order
 *     (pd_particles_sort_spatial), so a run needs no copies; otherwise the
 *     positions and forces are gathered and scattered every step.
 *   - The half stencil.  Of the offsets d and -d the kernel keeps the one
 *     that is lexicographically positive in (outer, mid, inner), so the
 *     partner j of a bond comes later in grid order; bond i-j is stored
 *     once, as bit k of i's mask.  Per offset k the table holds the
 *     reference length |xi_k|, c V nu_k (volumes and radii must be equal
 *     over the body, and nu the same for every bond of an offset) and the
 *     contact distance d_k = min(0.9 |xi_k|, 1.35 (r + r)).
 *   - Segments.  For a run A and an offset k the partners of A's particles
 *     lie in one or more runs of the row at (mid, outer) + d; each overlap
 *     is a segment: particles g in [lo, hi) with partner g + shift.  A
 *     segment is a loop over consecutive particles with consecutive
 *     partners: the loads and the force updates of both ends are
 *     contiguous, and the loop vectorizes without gathers or scatters.
 *   - Tiles (AVX-512; PMB's force pass, LPS's dilatation and force
 *     passes).  A run at least GRID_TILE long is walked 16 particles at a
 *     time: the tile keeps its own positions, forces and new s0 (LPS: and
 *     theta/m, 1/m, or the dilatation sums) in registers over all its
 *     segments, so that a bond loads and stores only its partner's (a
 *     segment loop stores both ends, and the stores bound it).  The
 *     segments of a run are in tile order (by inner offset first), so
 *     that the partner windows of consecutive offsets do not overlap: a
 *     load that overlaps a store still in flight would wait for it.
 *     Contacts (and PMB's breaks) are only flagged in the vector loop and
 *     found by a scalar pass over the segment (bit for bit the same
 *     arithmetic); LPS's breaks are taken lane by lane from the vector
 *     test, after the segment.  Other processors, and PD_NO_AVX512 set in
 *     the environment, walk the segments alone.
 *   - Threads.  Outer planes are cut into blocks at least as thick as the
 *     stencil's reach, so a block's bonds write only to the block and the
 *     next one; even blocks run in parallel, then odd blocks (lib/models/pmb.c's
 *     scheme).  Every sum is taken in an order fixed by the blocks: the
 *     result does not depend on the thread count.
 *
 * The arithmetic of a bond is lib/models/pmb.c's (the stretch, the eps_machine
 * guard, the failure test against min(s0_i, s0_j) of the previous step and
 * the new s0 of both ends), with one division by r per bond and the
 * reciprocal of |xi| from the table.  The contact forces of seed 000 eqs.
 * 13-15 between the two ends of every stencil pair, bonded or not, are
 * added in the same pass (their d_ij is d_k); lib/effects/contact.c leaves these
 * pairs out of its list, which then holds only pairs that were farther
 * than the horizon apart in the reference configuration.  Sums are rounded
 * in another order than the bond list's, so the two kernels agree to
 * rounding, not bit for bit.
 *
 * The bond state lives in both places: the masks (walked every step) and
 * the half bonds' bits (lib/models/pmb.c), which the rest of pd-run reads.  A bond
 * the kernel breaks is cleared in both (and its energy booked as
 * released); a change made to the half bonds from outside (a restart, a
 * lost particle) bumps their epoch and the masks are rebuilt from them.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/comm.h"
#include "stencil/grid_impl.h"

void pd_grid_free(pd_grid *G)
{
    if (G == NULL)
        return;
    free(G->off);
    free(G->len);
    free(G->inv_len);
    free(G->w);
    free(G->dc);
    free(G->nu);
    free(G->omega);
    free(G->theta_m);
    free(G->inv_m);
    free(G->lookup);
    for (int d = 0; d < 3; d++) {
        free(G->lc[d]);
        free(G->y[d]);
        free(G->f[d]);
    }
    free(G->perm);
    free(G->nofail);
    free(G->mask);
    free(G->cmask);
    free(G->seg);
    free(G->run);
    free(G->block_run);
    free(G->block_at);
    if (G->breaks)
        for (int64_t b = 0; b < G->nblocks; b++) {
            free(G->breaks[b].g);
            free(G->breaks[b].k);
            free(G->breaks[b].j);
        }
    free(G->breaks);
    free(G->released);
    free(G->s0);
    free(G->s0n);
    free(G->eb);
    free(G->ec);
    free(G->pos);
    free(G->neg);
    free(G->mirror);
    free(G->vsum);
    free(G);
}

/* --------------------------------------------------------------- building */

static inline int lookup_index(const pd_grid *G, const int d[3])
{
    const int r = G->reach, w = 2 * r + 1;
    for (int a = 0; a < 3; a++)
        if (d[a] < -r || d[a] > r)
            return -1;
    return ((d[2] + r) * w + (d[1] + r)) * w + (d[0] + r);
}

/* The half-stencil offset of d: k >= 0 for d itself, -1 - k for -d, or
 * INT16_MIN when d is not in the stencil. */
static inline int offset_of(const pd_grid *G, const int d[3])
{
    int q = lookup_index(G, d);
    return q < 0 ? INT16_MIN : G->lookup[q];
}

static inline int positive(const int d[3])
{
    return d[2] > 0 || (d[2] == 0 && (d[1] > 0 || (d[1] == 0 && d[0] > 0)));
}

static inline int64_t gidx_of(const int64_t *inv, int64_t i)
{
    return inv ? inv[i] : i;
}

/* Is every bond of each of the nk offsets d (x, y, z, with their first
 * bonds' length and nu, NaN: no bond, and spread, pd_family_offsets)
 * bound to have its first bond's nu within half of GRID_NU_TOL?  Then the
 * walk of build_stencil would find the same values and pass its check.
 * dg gets the offsets in grid axes. */
static int table_bound(const pd_grid *G, double r, double horizon, int nk, int32_t (*d)[3],
                       const double *len, const double *nu, const double *spread,
                       int32_t (*dg)[3])
{
    int ok = 1;
    for (int k = 0; k < nk && ok; k++) {
        for (int a = 0; a < 3; a++)
            dg[k][a] = d[k][G->axis[a]];
        if (isnan(len[k]))
            continue;
        const double lo = pd_partial_volume(len[k] + spread[k], horizon, r),
                     hi = pd_partial_volume(len[k] - spread[k], horizon, r);
        ok = fabs(lo - nu[k]) <= 0.5 * GRID_NU_TOL * nu[k] &&
             fabs(hi - nu[k]) <= 0.5 * GRID_NU_TOL * nu[k];
    }
    return ok;
}

/* Compact families' offsets in grid axes (dg, in b->stencil's count)
 * with their first bonds' length and nu (NaN: no bond), when table_bound
 * settles them.  Returns the number of offsets, 0 when a bound does not
 * settle it (then the walk decides), -1 when out of memory. */
static int table_offsets(const pd_grid *G, const pd_particles *p, const pd_bonds *b,
                         int32_t (*dg)[3], double *len, double *nu)
{
    const int nk = b->stencil->nk;
    int32_t(*d)[3] = malloc((size_t)nk * sizeof *d);
    double *spread = malloc((size_t)nk * sizeof(double));
    if (d == NULL || spread == NULL) {
        free(d);
        free(spread);
        return -1;
    }
    /* equal radii (pd_grid_new) */
    const int ok = pd_family_offsets(b, p, d, len, nu, spread) == nk &&
                   table_bound(G, p->radius[0], b->horizon, nk, d, len, nu, spread, dg);
    free(d);
    free(spread);
    return ok ? nk : 0;
}

/* The stencil from the table of nt offsets tg (grid axes) with their
 * lengths tl and factors tn (NaN: no bond), or with nt = 0 from the walk
 * of the file's bonds: every offset a bond has, with its length and nu
 * from the first bond of it (and nu checked on all).  Returns 0 when the
 * bonds are not a stencil. */
static int build_stencil(pd_grid *G, const pd_particles *p, const pd_bonds *b, int nt,
                         int32_t (*tg)[3], const double *tl, const double *tn)
{
    int reach = 0;
    for (int k = 0; k < nt; k++)
        for (int a = 0; a < 3 && !isnan(tl[k]); a++)
            reach = abs(tg[k][a]) > reach ? abs(tg[k][a]) : reach;
    for (int64_t i = 0; i < b->n && nt == 0; i++) {
        pd_bond_iter it;
        for (pd_family_start_partners(b, p, i, &it); pd_family_next(&it);)
            for (int a = 0; a < 3; a++) {
                int d = abs(G->lc[a][it.j] - G->lc[a][i]);
                reach = d > reach ? d : reach;
            }
    }
    if (reach > GRID_REACH_MAX)
        return 0;
    G->reach = reach;
    const int w = 2 * reach + 1;
    G->lookup = malloc((size_t)w * w * w * sizeof(int16_t));
    double *nu = malloc((size_t)w * w * w * sizeof(double));
    double *len = malloc((size_t)w * w * w * sizeof(double));
    if (!G->lookup || !nu || !len) {
        free(nu);
        free(len);
        return -1;
    }
    for (int q = 0; q < w * w * w; q++) {
        G->lookup[q] = INT16_MIN;
        nu[q] = NAN;
    }
    int ok = 1;
    for (int k = 0; k < nt; k++)
        if (!isnan(tl[k])) {
            const int dk[3] = {tg[k][0], tg[k][1], tg[k][2]};
            const int at = lookup_index(G, dk);
            nu[at] = tn[k];
            len[at] = tl[k];
        }
    for (int64_t i = 0; i < b->n && ok && nt == 0; i++) {
        pd_bond_iter it;
        for (pd_family_start(b, p, i, &it); ok && pd_family_next(&it);) {
            const int32_t j = it.j;
            int d[3] = {G->lc[0][j] - G->lc[0][i], G->lc[1][j] - G->lc[1][i],
                        G->lc[2][j] - G->lc[2][i]};
            int at = lookup_index(G, d);
            if (d[0] == 0 && d[1] == 0 && d[2] == 0)
                ok = 0;
            else if (isnan(nu[at])) {
                nu[at] = it.vfactor;
                len[at] = it.length;
            } else
                ok = fabs(it.vfactor - nu[at]) <= GRID_NU_TOL * nu[at];
        }
    }
    /* the half stencil, in lookup order (outer, mid, inner ascending) */
    int nk = 0;
    for (int q = 0; q < w * w * w && ok; q++) {
        int d[3] = {q % w - reach, (q / w) % w - reach, q / (w * w) - reach};
        int m[3] = {-d[0], -d[1], -d[2]};
        int mq = lookup_index(G, m);
        if (isnan(nu[q]) != isnan(nu[mq]) ||
            (!isnan(nu[q]) && fabs(nu[q] - nu[mq]) > GRID_NU_TOL * nu[q]))
            ok = 0; /* the family of d and -d must match */
        nk += !isnan(nu[q]) && positive(d);
    }
    if (ok && nk > 0) {
        G->nk = nk;
        G->words = (nk + 63) / 64;
        G->off = malloc((size_t)nk * sizeof *G->off);
        G->len = malloc((size_t)nk * sizeof(double));
        G->inv_len = malloc((size_t)nk * sizeof(double));
        G->w = malloc((size_t)nk * sizeof(double));
        G->dc = malloc((size_t)nk * sizeof(double));
        G->nu = malloc((size_t)nk * sizeof(double));
        if (!G->off || !G->len || !G->inv_len || !G->w || !G->dc || !G->nu) {
            free(nu);
            free(len);
            return -1;
        }
        int k = 0;
        for (int q = 0; q < w * w * w; q++) {
            int d[3] = {q % w - reach, (q / w) % w - reach, q / (w * w) - reach};
            if (isnan(nu[q]) || !positive(d))
                continue;
            int m[3] = {-d[0], -d[1], -d[2]};
            G->lookup[q] = (int16_t)k;
            G->lookup[lookup_index(G, m)] = (int16_t)(-1 - k);
            for (int a = 0; a < 3; a++)
                G->off[k][a] = d[a];
            G->len[k] = len[q];
            G->inv_len[k] = 1.0 / len[q];
            G->nu[k] = nu[q]; /* w = c V nu below, with the volume */
            G->dc[k] = fmin(PD_CONTACT_REF_FRAC * len[q], PD_CONTACT_RADIUS_FAC * 2.0 * p->radius[0]);
            k++;
        }
    }
    free(nu);
    free(len);
    return ok && nk > 0;
}

/* build_stencil of the file's bonds b: from their table (of compact
 * families, table_offsets) where it settles them, else from the walk. */
static int stencil_of_bonds(pd_grid *G, const pd_particles *p, const pd_bonds *b)
{
    int nt = 0; /* offsets from the table, or 0: the walk */
    int32_t(*tg)[3] = NULL;
    double *tl = NULL, *tn = NULL;
    if (!pd_bonds_has_lists(b) && b->stencil) {
        const size_t nk = (size_t)b->stencil->nk;
        tg = malloc(nk * sizeof *tg);
        tl = malloc(nk * sizeof(double));
        tn = malloc(nk * sizeof(double));
        nt = tg && tl && tn ? table_offsets(G, p, b, tg, tl, tn) : -1;
    }
    const int ok = nt < 0 ? -1 : build_stencil(G, p, b, nt, tg, tl, tn);
    free(tg);
    free(tl);
    free(tn);
    return ok;
}

typedef struct {
    int64_t start;   /* grid index of the first particle */
    int32_t a0, a1;  /* inner coordinates [a0, a1)       */
} row_run;

/* The offsets in the order a tile walks them: by inner offset, then outer,
 * then mid.  Consecutive offsets then differ in mid or outer, so their
 * partner windows are a row or more apart: the partner stores of one
 * offset never overlap the partner loads of the next (a load that
 * overlaps a store still in flight waits for it). */
static int *tile_order(const pd_grid *G)
{
    int *o = malloc((size_t)G->nk * sizeof *o);
    if (o == NULL)
        return NULL;
    int n = 0;
    for (int di = -G->reach; di <= G->reach; di++)
        for (int dout = -G->reach; dout <= G->reach; dout++)
            for (int dm = -G->reach; dm <= G->reach; dm++)
                for (int k = 0; k < G->nk; k++)
                    if (G->off[k][0] == di && G->off[k][2] == dout && G->off[k][1] == dm)
                        o[n++] = k;
    return o;
}

/* The runs and the segments; blocks of outer planes. */
static int build_segments(pd_grid *G, const int64_t *inv)
{
    const int64_t n = G->n;
    int32_t lo[3] = {INT32_MAX, INT32_MAX, INT32_MAX}, hi[3] = {INT32_MIN, INT32_MIN, INT32_MIN};
    for (int a = 0; a < 3; a++)
        for (int64_t i = 0; i < n; i++) {
            lo[a] = G->lc[a][i] < lo[a] ? G->lc[a][i] : lo[a];
            hi[a] = G->lc[a][i] > hi[a] ? G->lc[a][i] : hi[a];
        }
    const int64_t nmid = (int64_t)hi[1] - lo[1] + 1, nout = (int64_t)hi[2] - lo[2] + 1;
    if (nmid * nout > GRID_SPARSE_ROWS * n + GRID_SPARSE_SLACK) /* a sparse body */
        return 0;
    /* coordinates by grid index */
    int32_t *gc[3] = {malloc((size_t)n * 4), malloc((size_t)n * 4), malloc((size_t)n * 4)};
    row_run *run = malloc((size_t)n * sizeof *run);
    int64_t *row_first = malloc((size_t)(nmid * nout + 1) * sizeof(int64_t));
    int *order = tile_order(G);
    if (!gc[0] || !gc[1] || !gc[2] || !run || !row_first || !order) {
        for (int a = 0; a < 3; a++)
            free(gc[a]);
        free(run);
        free(row_first);
        free(order);
        return -1;
    }
    for (int64_t i = 0; i < n; i++) {
        int64_t g = gidx_of(inv, i);
        for (int a = 0; a < 3; a++)
            gc[a][g] = G->lc[a][i];
    }
    /* runs, in grid order; rows index them */
    int64_t nrun = 0;
    for (int64_t r = 0; r <= nmid * nout; r++)
        row_first[r] = -1;
    for (int64_t g = 0; g < n; g++) {
        int same = g > 0 && gc[2][g] == gc[2][g - 1] && gc[1][g] == gc[1][g - 1] &&
                   gc[0][g] == gc[0][g - 1] + 1;
        if (same) {
            run[nrun - 1].a1++;
            continue;
        }
        run[nrun].start = g;
        run[nrun].a0 = gc[0][g];
        run[nrun].a1 = gc[0][g] + 1;
        int64_t row = (int64_t)(gc[2][g] - lo[2]) * nmid + (gc[1][g] - lo[1]);
        if (row_first[row] < 0)
            row_first[row] = nrun;
        nrun++;
    }
    /* rows without runs point at the next row's first run, so that
     * [row_first[r], row_first[r + 1]) are the runs of row r */
    row_first[nmid * nout] = nrun;
    for (int64_t r = nmid * nout - 1; r >= 0; r--)
        if (row_first[r] < 0)
            row_first[r] = row_first[r + 1];
    /* blocks: outer planes in slabs at least the stencil's reach thick */
    int thick = 0;
    for (int k = 0; k < G->nk; k++)
        thick = G->off[k][2] > thick ? G->off[k][2] : thick;
    thick = thick > 0 ? thick : 1;
    G->thick = thick;
    const int64_t base = G->blk0 >= 0 ? G->blk0 * thick : lo[2]; /* outer plane of block 0 */
    if (base > lo[2]) { /* a piece must begin on a block of the whole */
        for (int a = 0; a < 3; a++)
            free(gc[a]);
        free(run);
        free(row_first);
        free(order);
        return 0;
    }
    G->nblocks = (hi[2] - base + thick) / thick;
    G->block_run = calloc((size_t)G->nblocks + 1, sizeof(int64_t));
    G->run = malloc((size_t)(nrun + 1) * sizeof *G->run);
    int64_t cap = nrun * G->nk + 16, nseg = 0;
    G->seg = malloc((size_t)cap * sizeof *G->seg);
    int ok = G->block_run && G->run && G->seg;
    for (int64_t A = 0; A < nrun && ok; A++) {
        const int64_t blk = (gc[2][run[A].start] - base) / thick;
        G->run[A].start = run[A].start;
        G->run[A].len = run[A].a1 - run[A].a0;
        G->run[A].seg0 = nseg;
        for (int kk = 0; kk < G->nk && ok; kk++) {
            const int k = order[kk];
            const int *d = G->off[k];
            int64_t m = gc[1][run[A].start] + d[1] - lo[1], o = gc[2][run[A].start] + d[2] - lo[2];
            if (m < 0 || m >= nmid || o < 0 || o >= nout)
                continue;
            int64_t row = o * nmid + m;
            for (int64_t B = row_first[row]; B < row_first[row + 1]; B++) {
                int32_t from = run[A].a0 > run[B].a0 - d[0] ? run[A].a0 : run[B].a0 - d[0];
                int32_t to = run[A].a1 < run[B].a1 - d[0] ? run[A].a1 : run[B].a1 - d[0];
                if (from >= to)
                    continue;
                if (nseg == cap) {
                    cap += cap / 2;
                    grid_seg *ns = realloc(G->seg, (size_t)cap * sizeof *ns);
                    if (ns == NULL) {
                        ok = 0;
                        break;
                    }
                    G->seg = ns;
                }
                grid_seg *s = &G->seg[nseg++];
                s->lo = run[A].start + (from - run[A].a0);
                s->hi = run[A].start + (to - run[A].a0);
                s->shift = run[B].start - run[A].start + (run[A].a0 - run[B].a0) + d[0];
                s->k = k;
            }
        }
        G->block_run[blk + 1] = A + 1;
    }
    G->nseg = nseg;
    if (ok)
        G->run[nrun] = (grid_run){.start = n, .len = 0, .seg0 = nseg};
    for (int64_t blk = 1; blk <= G->nblocks && ok; blk++) /* blocks without runs */
        if (G->block_run[blk] < G->block_run[blk - 1])
            G->block_run[blk] = G->block_run[blk - 1];
    /* the threads' share of each phase: contiguous blocks of about equal
     * particle counts (grid_mine) */
    G->block_at = ok ? malloc((size_t)(G->nblocks > 0 ? G->nblocks : 1) * sizeof(double)) : NULL;
    ok = ok && G->block_at;
    for (int parity = 0; parity < 2 && ok; parity++) {
        double total = 0, before = 0;
        for (int64_t blk = parity; blk < G->nblocks; blk += 2)
            total += (double)(block_start(G, blk + 1) - block_start(G, blk));
        for (int64_t blk = parity; blk < G->nblocks; blk += 2) {
            double np = (double)(block_start(G, blk + 1) - block_start(G, blk));
            G->block_at[blk] = total > 0 ? (before + 0.5 * np) / total : 0.0;
            before += np;
        }
    }
    for (int a = 0; a < 3; a++)
        free(gc[a]);
    free(run);
    free(row_first);
    free(order);
    return ok ? 1 : -1;
}

/* Rebuild the masks from the half bonds' bits (and the contact masks from
 * the pairs and the lost flags). */
/* The mask bits of row i's intact half bonds (inv: i -> g, NULL for
 * none).  With `own`, only those at a positive offset, in i's own words:
 * returns 1 when it left one out. */
static int sync_row(pd_grid *G, const pd_half_bonds *h, const int64_t *inv, int64_t i, int own)
{
    const int W = G->words;
    int left = 0;
    for (int64_t q = h->offset[i]; q < h->offset[i + 1]; q++) {
        if (!pd_bond_intact(h->intact, q))
            continue;
        const int32_t j = h->neighbor[q];
        const int d[3] = {G->lc[0][j] - G->lc[0][i], G->lc[1][j] - G->lc[1][i],
                          G->lc[2][j] - G->lc[2][i]};
        int k = offset_of(G, d);
        if (k < 0 && own) {
            left = 1;
            continue;
        }
        const int64_t owner = k >= 0 ? gidx_of(inv, i) : gidx_of(inv, j);
        k = k >= 0 ? k : -1 - k;
        G->mask[owner * W + (k >> 6)] |= UINT64_C(1) << (k & 63);
    }
    return left;
}

void pd_grid_sync(pd_sim *sim, pd_grid *G)
{
    const int W = G->words;
    const int64_t n = G->n;
    int64_t *inv = NULL;
    G->energy_ok = 0;
    G->mirror_ok = 0; /* made again from the masks when next wanted */
    memset(G->mask, 0, (size_t)n * W * sizeof(uint64_t));
    if (G->perm) { /* i -> g, from the perm (a scratch made here) */
        inv = malloc((size_t)n * sizeof(int64_t));
        if (inv == NULL) {
            G->status = pd_fail(PD_ERR_NOMEM, "out of memory for the lattice bonds");
            return;
        }
        for (int64_t g = 0; g < n; g++)
            inv[G->perm[g]] = g;
    }
    const pd_half_bonds *h = &sim->half;
    /* In lattice order (no perm) a half bond i-j (j > i) is at a positive
     * offset of i and sets a bit of i's words alone: rows in parallel.  A
     * bond at a negative offset (through a perm) sets its partner's: all
     * rows one by one, over again (the same bits: or-ed in any order). */
    int serial = G->perm != NULL, negative = 0;
#pragma omp parallel for schedule(static) reduction(| : negative) if (!serial)
    for (int64_t i = 0; i < n * !serial; i++)
        negative |= sync_row(G, h, NULL, i, 1);
    serial |= negative;
    for (int64_t i = 0; i < n && serial; i++)
        sync_row(G, h, inv, i, 0);
    if (G->cmask) {
        memset(G->cmask, 0, (size_t)n * W * sizeof(uint64_t));
        const uint8_t *lost = sim->lost;
        for (int64_t s = 0; s < G->nseg; s++) {
            const grid_seg *sg = &G->seg[s];
            for (int64_t g = sg->lo; g < sg->hi; g++) {
                if (lost) {
                    int64_t i = G->perm ? G->perm[g] : g, j = G->perm ? G->perm[g + sg->shift] : g + sg->shift;
                    if (lost[i] || lost[j])
                        continue;
                }
                G->cmask[g * W + (sg->k >> 6)] |= UINT64_C(1) << (sg->k & 63);
            }
        }
    }
    free(inv);
    G->epoch = h->epoch;
}

/* May the model's stencil `kind` walk the body p, b at all?  PMB with one
 * c and s00 for every bond, or LPS with an influence function of |xi|
 * alone; equal volumes and radii. */
static int grid_candidate(const pd_particles *p, int64_t bonds, const pd_scene *sc,
                          pd_stencil_kind kind, const double *kfail)
{
    if (kind == PD_STENCIL_NONE || sc->bond_list || kfail || p->n < 2 || bonds == 0)
        return 0;
    for (int64_t i = 1; i < p->n; i++)
        if (p->volume[i] != p->volume[0] || p->radius[i] != p->radius[0])
            return 0;
    return 1;
}

/* G's lattice, stencil, gap, segments and blocks for the body p, b (a
 * piece: the whole body's axes, lattice and table): 1 when b's bonds are
 * the stencil, 0 when they are not, -1 out of memory. */
static int grid_lay(pd_grid *G, const pd_particles *p, const pd_bonds *b, const pd_piece *piece,
                    int lps)
{
    const int64_t n = p->n;
    G->n = n;
    for (int d = 0; d < 3; d++)
        G->lc[d] = malloc((size_t)n * sizeof(int32_t));
    int64_t *order = NULL, *inv = NULL;
    int ok = G->lc[0] && G->lc[1] && G->lc[2] ? 1 : -1;
    G->blk0 = -1;
    if (ok > 0 && piece) { /* a piece: the whole body's axes and lattice */
        int32_t *c[3];
        for (int a = 0; a < 3; a++)
            c[G->axis[a] = piece->axis[a]] = G->lc[a];
        ok = pd_lattice_sites(p, piece->origin, p->spacing, c);
        G->blk0 = piece->blk0;
    } else if (ok > 0)
        ok = pd_lattice_coords(p, G->axis, G->lc);
    if (ok > 0 && (order = pd_lattice_sort(n, G->lc)) == NULL)
        ok = -1;
    if (ok > 0 && order) {
        int identity = 1;
        for (int64_t g = 0; g < n && identity; g++)
            identity = order[g] == g;
        if (!identity && lps) /* LPS's arrays are in the file's order */
            ok = 0;
        else if (!identity) {
            G->perm = order;
            order = NULL;
            if ((inv = malloc((size_t)n * sizeof(int64_t))) == NULL)
                ok = -1;
            else
                for (int64_t g = 0; g < n; g++)
                    inv[G->perm[g]] = g;
        }
    }
    free(order);
    if (ok > 0)
        ok = stencil_of_bonds(G, p, b);
    if (ok > 0 && piece && piece->table) { /* the whole body's table */
        const pd_grid *W = piece->table;
        ok = W->nk == G->nk && W->reach == G->reach &&
             memcmp(W->off, G->off, (size_t)G->nk * sizeof *G->off) == 0;
        for (int k = 0; k < G->nk && ok; k++) {
            G->len[k] = W->len[k];
            G->inv_len[k] = W->inv_len[k];
            G->nu[k] = W->nu[k];
            G->dc[k] = W->dc[k];
        }
    }
    if (ok > 0) { /* the gap: over the offsets one beyond the stencil's reach */
        const int r = G->reach + 1;
        double d2min = INFINITY;
        for (int a = -r; a <= r; a++)
            for (int m = -r; m <= r; m++)
                for (int o = -r; o <= r; o++) {
                    const int d[3] = {a, m, o};
                    if ((a || m || o) && offset_of(G, d) == INT16_MIN)
                        d2min = fmin(d2min, (double)(a * a + m * m + o * o));
                }
        G->gap = p->spacing * (sqrt(d2min) - 4 * PD_LATTICE_TOL);
    }
    /* the file's families are the whole stencil: each particle has a bond
     * to every particle at a stencil offset (counted over the segments) */
    if (ok > 0)
        ok = build_segments(G, inv);
    if (ok > 0) {
        int64_t pairs = 0;
        for (int64_t s = 0; s < G->nseg; s++)
            pairs += G->seg[s].hi - G->seg[s].lo;
        ok = 2 * pairs == b->count;
    }
    free(inv);
    return ok;
}

pd_status pd_grid_plan(const pd_particles *p, const pd_bonds *b, const pd_scene *sc,
                       pd_stencil_kind kind, pd_grid **out)
{
    *out = NULL;
    if (!grid_candidate(p, b->count, sc, kind, NULL))
        return PD_OK;
    pd_grid *G = calloc(1, sizeof *G);
    const int ok = G ? grid_lay(G, p, b, NULL, kind == PD_STENCIL_LPS) : -1;
    if (ok <= 0) {
        pd_grid_free(G);
        return ok < 0 ? pd_fail(PD_ERR_NOMEM, "out of memory for the lattice bonds") : PD_OK;
    }
    *out = G;
    return PD_OK;
}

/* grid_candidate of a window of a body (pd_particles): over the ranks,
 * collective. */
static int window_candidate(const pd_particles *p, const pd_scene *sc, pd_stencil_kind kind)
{
    if (kind == PD_STENCIL_NONE || sc->bond_list || pd_body_count(p) < 2)
        return 0;
    double vlo = INFINITY, vhi = -INFINITY, rlo = INFINITY, rhi = -INFINITY;
    for (int64_t i = 0; i < p->n; i++) {
        vlo = fmin(vlo, p->volume[i]);
        vhi = fmax(vhi, p->volume[i]);
        rlo = fmin(rlo, p->radius[i]);
        rhi = fmax(rhi, p->radius[i]);
    }
    return -pd_body_max(p, -vlo) == pd_body_max(p, vhi) &&
           -pd_body_max(p, -rlo) == pd_body_max(p, rhi);
}

int pd_grid_possible(const pd_particles *p, const pd_scene *sc, pd_stencil_kind kind)
{
    if (p->window ? !window_candidate(p, sc, kind) : !grid_candidate(p, 1, sc, kind, NULL))
        return 0;
    int32_t *lc[3];
    int axis[3], ok = -1;
    for (int d = 0; d < 3; d++)
        lc[d] = malloc((size_t)(p->n > 0 ? p->n : 1) * sizeof(int32_t));
    if (p->window || (lc[0] && lc[1] && lc[2])) /* a window's ranks meet in it */
        ok = pd_lattice_coords(p, axis, lc[0] && lc[1] && lc[2] ? lc : NULL);
    for (int d = 0; d < 3; d++)
        free(lc[d]);
    /* out of memory: maybe; a window: on every rank's rows */
    return p->window ? pd_comm_min(ok != 0) == 1 : ok != 0;
}

/* The whole body's blocks of a plan over windows (pd_grid_plan_window):
 * their first rows in G->run (one block a run), counted over the ranks'
 * own rows; 0 for a sparse body, as build_segments finds it. */
static int window_blocks(pd_grid *G, const pd_particles *p)
{
    int64_t lo[3] = {INT32_MAX, INT32_MAX, INT32_MAX}, hi[3] = {INT32_MAX, INT32_MAX, INT32_MAX};
    for (int a = 0; a < 3; a++)
        for (int64_t i = 0; i < p->n; i++) {
            lo[a] = G->lc[a][i] < lo[a] ? G->lc[a][i] : lo[a];
            hi[a] = -G->lc[a][i] < hi[a] ? -G->lc[a][i] : hi[a];
        }
    pd_comm_min_int(lo, 3); /* the windows hold every row */
    pd_comm_min_int(hi, 3);
    for (int a = 0; a < 3; a++)
        hi[a] = -hi[a];
    const int64_t n = pd_body_count(p), nmid = hi[1] - lo[1] + 1, nout = hi[2] - lo[2] + 1;
    if (nmid * nout > GRID_SPARSE_ROWS * n + GRID_SPARSE_SLACK)
        return 0;
    int thick = 0;
    for (int k = 0; k < G->nk; k++)
        thick = G->off[k][2] > thick ? G->off[k][2] : thick;
    G->thick = thick = thick > 0 ? thick : 1;
    G->nblocks = (hi[2] - lo[2] + thick) / thick;
    int64_t *start = malloc(((size_t)G->nblocks + 1) * sizeof(int64_t));
    G->block_run = malloc(((size_t)G->nblocks + 1) * sizeof(int64_t));
    G->run = malloc(((size_t)G->nblocks + 1) * sizeof *G->run);
    const int ok = pd_comm_min(start && G->block_run && G->run);
    if (ok)
        pd_lattice_block_starts(G->lc[2], p->own_lo, p->own_hi, lo[2], thick, G->nblocks, start);
    for (int64_t blk = 0; ok && blk <= G->nblocks; blk++) {
        G->block_run[blk] = blk;
        G->run[blk] = (grid_run){.start = start[blk]};
    }
    free(start);
    return ok ? 1 : -1;
}

pd_status pd_grid_plan_window(const pd_particles *p, const pd_bonds *b, const pd_scene *sc,
                              pd_stencil_kind kind, pd_grid **out)
{
    *out = NULL;
    if (!window_candidate(p, sc, kind) || b->stencil == NULL)
        return PD_OK;
    const int nk = b->stencil->nk;
    pd_grid *G = calloc(1, sizeof *G);
    int32_t(*d)[3] = malloc((size_t)nk * sizeof *d), (*tg)[3] = malloc((size_t)nk * sizeof *tg);
    double *len = malloc((size_t)nk * sizeof(double)), *nu = malloc((size_t)nk * sizeof(double)),
           *spread = malloc((size_t)nk * sizeof(double));
    for (int a = 0; G && a < 3; a++)
        G->lc[a] = malloc((size_t)(p->n > 0 ? p->n : 1) * sizeof(int32_t));
    int ok = pd_comm_min(G && d && tg && len && nu && spread && G->lc[0] && G->lc[1] && G->lc[2])
                 ? 1
                 : -1;
    /* on the lattice, and the rows in its order: each window's, and so
     * across the ranks (a window holds the rows below its own) */
    if (ok > 0)
        ok = pd_lattice_coords(p, G->axis, G->lc);
    for (int64_t i = 1; ok > 0 && i < p->n; i++) {
        int a = 2;
        while (a > 0 && G->lc[a][i] == G->lc[a][i - 1])
            a--;
        ok = G->lc[a][i] > G->lc[a][i - 1];
    }
    ok = (int)pd_comm_min(ok);
    /* the table, its first bonds over the ranks; then the blocks */
    if (ok > 0 && pd_family_offsets_ranks(b, p, d, len, nu, spread) != nk)
        ok = -1;
    if (ok > 0)
        ok = table_bound(G, p->radius[0], b->horizon, nk, d, len, nu, spread, tg);
    if (ok > 0)
        ok = build_stencil(G, p, b, nk, tg, len, nu);
    ok = (int)pd_comm_min(ok); /* out of memory on one rank: on every one */
    if (ok > 0)
        ok = window_blocks(G, p);
    free(d);
    free(tg);
    free(len);
    free(nu);
    free(spread);
    if (ok <= 0) {
        pd_grid_free(G);
        return ok < 0 ? pd_fail(PD_ERR_NOMEM, "out of memory for the lattice bonds") : PD_OK;
    }
    *out = G;
    return PD_OK;
}

pd_status pd_grid_new(pd_sim *sim, pd_stencil_kind kind, pd_grid **out)
{
    *out = NULL;
    const pd_particles *p = sim->p;
    const pd_bonds *b = sim->b;
    const pd_scene *sc = &sim->sc;
    const int lps = kind == PD_STENCIL_LPS;
    if (!grid_candidate(p, b->count, sc, kind, sim->half.kfail))
        return PD_OK;
    pd_grid *G = calloc(1, sizeof *G);
    if (G == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the lattice bonds");
    const int64_t n = p->n;
    int ok = grid_lay(G, p, b, sim->piece, lps);
    if (ok > 0) {
        const double V = p->volume[0];
        G->omega = malloc((size_t)G->nk * sizeof(double));
        ok = G->omega ? ok : -1;
        for (int k = 0; k < G->nk && ok > 0; k++) {
            G->omega[k] = pd_lps_influence(sc->influence, G->len[k], b->horizon);
            G->w[k] = sc->c * V * G->nu[k]; /* c V nu, as pd_half_weights */
        }
        G->kc = PD_CONTACT_SCALE * sc->c / b->horizon * V;
        size_t words = (size_t)n * G->words;
        G->mask = malloc(words * sizeof(uint64_t));
        if (sc->has_contact)
            G->cmask = malloc(words * sizeof(uint64_t));
        G->breaks = calloc((size_t)G->nblocks, sizeof *G->breaks);
        G->released = calloc((size_t)G->nblocks, sizeof(double));
        if (!G->mask || (sc->has_contact && !G->cmask) || !G->breaks || !G->released)
            ok = -1;
        if (lps && ok > 0) { /* theta/m and 1/m of pd_grid_lps */
            G->theta_m = malloc((size_t)n * sizeof(double));
            G->inv_m = malloc((size_t)n * sizeof(double));
            ok = G->theta_m && G->inv_m ? ok : -1;
        }
        if (sim->nofail && ok > 0) { /* the --no-failure flags in grid order */
            if ((G->nofail = malloc((size_t)n)) == NULL)
                ok = -1;
            for (int64_t g = 0; g < n && ok > 0; g++)
                G->nofail[g] = sim->nofail[G->perm ? G->perm[g] : g];
        }
        if (G->perm && ok > 0) {
            for (int d = 0; d < 3; d++) {
                G->y[d] = malloc((size_t)n * sizeof(double));
                G->f[d] = malloc((size_t)n * sizeof(double));
                ok = G->y[d] && G->f[d] ? ok : -1;
            }
            if (sc->has_failure) {
                G->s0 = malloc((size_t)n * sizeof(double));
                G->s0n = malloc((size_t)n * sizeof(double));
                ok = G->s0 && G->s0n ? ok : -1;
            }
        }
    }
    if (ok <= 0) {
        pd_grid_free(G);
        return ok < 0 ? pd_fail(PD_ERR_NOMEM, "out of memory for the lattice bonds") : PD_OK;
    }
    G->walk = G->nblocks; /* a piece: not the ghosts' block above its own */
    if (sim->piece && sim->piece->own_blk_hi < G->nblocks)
        G->walk = sim->piece->own_blk_hi;
    /* a piece in grid order: from the block below its own on (a bond
     * reaches one block up at most), and of that block only the bonds
     * with a partner of its own; they put every force on its rows in the
     * whole body's order, so the same bits on any count of ranks */
    G->walk_lo = G->clip = 0;
    if (sim->piece && sim->piece->own_blk_lo > 0 && G->perm == NULL) {
        G->walk_lo = sim->piece->own_blk_lo - 1;
        G->clip = sim->piece->own_lo;
    }
    pd_grid_sync(sim, G);
#if PD_AVX512_KERNELS
    G->tile = G->words == 1 && __builtin_cpu_supports("avx512f") && !getenv("PD_NO_AVX512");
#endif
    if (G->status != PD_OK) {
        pd_status s = G->status;
        pd_grid_free(G);
        return s;
    }
    *out = G;
    sim->directed_bits = pd_grid_directed_bits;
    return PD_OK;
}

pd_status pd_grid_resync(pd_sim *sim)
{
    pd_grid *G = sim->grid;
    if (G == NULL || G->epoch == sim->half.epoch)
        return PD_OK;
    pd_grid_sync(sim, G);
    return G->status;
}

int64_t pd_grid_blocks(const pd_grid *G, int64_t *start, int axis[3], int *thick)
{
    if (G == NULL || G->perm)
        return 0;
    for (int64_t blk = 0; start && blk <= G->nblocks; blk++)
        start[blk] = block_start(G, blk);
    for (int a = 0; a < 3 && axis; a++)
        axis[a] = G->axis[a];
    if (thick)
        *thick = G->thick;
    return G->nblocks;
}

int pd_grid_offsets(const pd_grid *G)
{
    return G ? G->nk : 0;
}

double pd_grid_gap(const pd_grid *G)
{
    return G ? G->gap : 0.0;
}

int pd_grid_tiles(const pd_grid *G)
{
    return G && G->tile;
}

int pd_grid_contact(const pd_grid *G)
{
    return G && G->cmask;
}

int pd_grid_pair(const pd_grid *G, int64_t i, int64_t j)
{
    int d[3] = {G->lc[0][j] - G->lc[0][i], G->lc[1][j] - G->lc[1][i], G->lc[2][j] - G->lc[2][i]};
    return offset_of(G, d) != INT16_MIN;
}
