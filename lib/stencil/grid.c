/*
 * grid.c -- the bonds of a body on a lattice, walked as a stencil (PMB, and
 * LPS without ellipsoids).
 *
 * A body made by pd-lattice sits on a simple cubic (or, for a plate,
 * square) lattice of spacing h, and pd-bonds gives every particle a bond to
 * each particle at a lattice offset d with |d| h <= delta.  Such a bond is
 * named by its first particle and its offset: no neighbour index, length or
 * weight needs to be stored per bond, only one bit of state.  When pd-run
 * finds a PMB scene, or an LPS one whose influence depends on |xi| alone,
 * on such a body (pd_grid_new checks every condition below; any other
 * scene keeps the bond lists of lib/pmb.c and lib/lps.c), it walks the
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
 *   - Tiles (PMB, AVX-512).  A run at least GRID_TILE long is walked 16
 *     particles at a time: the tile keeps its own positions, forces and
 *     new s0 in registers over all its segments, so that a bond loads and
 *     stores only its partner's (a segment loop stores both ends, and the
 *     stores bound it).  The segments of a run are in tile order (by inner
 *     offset first), so that the partner windows of consecutive offsets do
 *     not overlap: a load that overlaps a store still in flight would wait
 *     for it.  Breaks and contacts are only flagged in the vector loop and
 *     found by a scalar pass over the segment (bit for bit the same
 *     arithmetic).  Other processors, and PD_NO_AVX512 set in the
 *     environment, walk the segments alone.
 *   - Threads.  Outer planes are cut into blocks at least as thick as the
 *     stencil's reach, so a block's bonds write only to the block and the
 *     next one; even blocks run in parallel, then odd blocks (lib/pmb.c's
 *     scheme).  Every sum is taken in an order fixed by the blocks: the
 *     result does not depend on the thread count.
 *
 * The arithmetic of a bond is lib/pmb.c's (the stretch, the eps_machine
 * guard, the failure test against min(s0_i, s0_j) of the previous step and
 * the new s0 of both ends), with one division by r per bond and the
 * reciprocal of |xi| from the table.  The contact forces of seed 000 eqs.
 * 13-15 between the two ends of every stencil pair, bonded or not, are
 * added in the same pass (their d_ij is d_k); lib/contact.c leaves these
 * pairs out of its list, which then holds only pairs that were farther
 * than the horizon apart in the reference configuration.  Sums are rounded
 * in another order than the bond list's, so the two kernels agree to
 * rounding, not bit for bit.
 *
 * The bond state lives in both places: the masks (walked every step) and
 * the half bonds' bits (lib/pmb.c), which the rest of pd-run reads.  A bond
 * the kernel breaks is cleared in both (and its energy booked as
 * released); a change made to the half bonds from outside (a restart, a
 * lost particle) bumps their epoch and the masks are rebuilt from them.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stencil/grid.h"

#ifdef _OPENMP
#include <omp.h>
#endif

/* The tile kernel of PMB is written for AVX-512 (x86-64, GCC or clang),
 * taken when the processor has it; any other build or processor walks the
 * segments alone. */
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(PD_NO_CLONES)
#define PD_GRID_AVX512 1
#include <immintrin.h>
#else
#define PD_GRID_AVX512 0
#endif

#define GRID_NU_TOL 1e-9 /* nu of one offset equal to this, relatively    */
#define GRID_CHUNK 256   /* particles per vector pass of a segment        */
#define GRID_SAFE 16     /* shifts below this take the two-pass loop      */
#define GRID_TILE 16     /* particles of a tile (runs at least this long) */

typedef struct {
    int64_t lo, hi; /* first particles g of the segment, grid order      */
    int64_t shift;  /* partner g + shift                                  */
    int32_t k;      /* half-stencil offset                                */
} grid_seg;

/* A run: particles [start, start + len) consecutive along the inner axis,
 * whose segments are seg[seg0, next run's seg0). */
typedef struct {
    int64_t start, len, seg0;
} grid_run;

typedef struct {
    int64_t n, cap;
    int64_t *g;     /* grid index of the first end                        */
    int32_t *k;     /* offset                                             */
    int64_t *j;     /* grid index of the partner                          */
} grid_breaks;

struct pd_grid {
    int64_t n;
    int nk, words;       /* half-stencil offsets, mask words per particle  */
    int reach;           /* largest |d| component of the stencil           */
    int (*off)[3];       /* nk offsets, (inner, mid, outer)                */
    double *len, *inv_len, *w, *dc;
    double *nu, *omega;  /* per offset: nu, and LPS's omega(|xi|)         */
    int16_t *lookup;     /* (2 reach + 1)^3: k for d, -1 - k for -d, or
                            INT16_MIN: not a stencil offset                */
    int axis[3];         /* inner, mid, outer: 0, 1, 2 for x, y, z         */
    int32_t *lc[3];      /* lattice coordinates of particle i (sim order)  */
    int64_t *perm;       /* g -> i, NULL when grid order is sim order      */
    uint64_t *mask;      /* words per particle: bond intact                */
    uint64_t *cmask;     /* words per particle: contact pair (NULL: none)  */
    grid_seg *seg;
    int64_t nseg;
    grid_run *run;       /* the runs and a last one with start n, seg0 nseg */
    int64_t nblocks;
    int64_t *block_run;  /* nblocks + 1                                    */
    double *block_at;    /* nblocks: where a block's middle particle falls
                            among those of its parity, in [0, 1)           */
    grid_breaks *breaks; /* per block                                      */
    double *released;    /* per block                                      */
    double kc;           /* (c_S / delta) V: contact force per overlap     */
    double *y[3], *f[3], *s0, *s0n; /* grid-order copies (perm only)       */
    uint64_t epoch;      /* of the half bonds the masks were built from    */
    int tile;            /* PMB walks runs as tiles (AVX-512)              */
    const double *s0n_ready; /* the s0 array the last step's end filled with
                            -inf for the next one's new s0 (PMB, lattice
                            order)                                         */
    double gap;          /* the shortest lattice distance not in the
                            stencil, less the sites' tolerance, m          */
    int status;          /* PD_OK, or the error a parallel pass met        */
};

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
    free(G->lookup);
    for (int d = 0; d < 3; d++) {
        free(G->lc[d]);
        free(G->y[d]);
        free(G->f[d]);
    }
    free(G->perm);
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
    free(G);
}

/* The first segment and the first particle of block blk (blk = nblocks:
 * one past the last). */
static inline int64_t block_seg0(const pd_grid *G, int64_t blk)
{
    return G->run[G->block_run[blk]].seg0;
}

static inline int64_t block_start(const pd_grid *G, int64_t blk)
{
    return G->run[G->block_run[blk]].start;
}

/* Is block blk (of the phase being walked) the calling thread's?  Each
 * thread takes a contiguous run of the phase's blocks holding about its
 * share of the particles, the same in every pass of every step: a thread
 * then finds in its own caches what it touched in the pass before, and
 * lib/sim.c's passes over the particles split them the same way (static
 * halves).  A block handed to whichever thread is free would move its
 * data between the cores' caches every step (measured: the bond pass 10%
 * and the integration 30% slower on 2 threads).  Called inside a parallel
 * region. */
static inline int grid_mine(const pd_grid *G, int64_t blk)
{
#ifdef _OPENMP
    const int T = omp_get_num_threads(), t = omp_get_thread_num();
    int owner = (int)(G->block_at[blk] * T);
    return (owner < T ? owner : T - 1) == t;
#else
    (void)G;
    (void)blk;
    return 1;
#endif
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

/* The stencil from the file's bonds: every offset a bond has, with its
 * length and nu from the first bond of it (and nu checked on all).
 * Returns 0 when the bonds are not a stencil. */
static int build_stencil(pd_grid *G, const pd_particles *p, const pd_bonds *b)
{
    int reach = 0;
    for (int64_t i = 0; i < b->n; i++)
        for (int64_t q = b->offset[i]; q < b->offset[i + 1]; q++)
            for (int a = 0; a < 3; a++) {
                int d = abs(G->lc[a][b->neighbor[q]] - G->lc[a][i]);
                reach = d > reach ? d : reach;
            }
    if (reach > 12) /* (2 reach + 1)^3 half offsets must fit an int16 */
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
    for (int64_t i = 0; i < b->n && ok; i++)
        for (int64_t q = b->offset[i]; q < b->offset[i + 1] && ok; q++) {
            int32_t j = b->neighbor[q];
            int d[3] = {G->lc[0][j] - G->lc[0][i], G->lc[1][j] - G->lc[1][i],
                        G->lc[2][j] - G->lc[2][i]};
            int at = lookup_index(G, d);
            if (d[0] == 0 && d[1] == 0 && d[2] == 0)
                ok = 0;
            else if (isnan(nu[at])) {
                nu[at] = b->vfactor[q];
                len[at] = b->length[q];
            } else
                ok = fabs(b->vfactor[q] - nu[at]) <= GRID_NU_TOL * nu[at];
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
            G->w[k] = nu[q]; /* times c V below */
            G->dc[k] = fmin(PD_CONTACT_REF_FRAC * len[q], PD_CONTACT_RADIUS_FAC * 2.0 * p->radius[0]);
            k++;
        }
    }
    free(nu);
    free(len);
    return ok && nk > 0;
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
    if (nmid * nout > 4 * n + 1024) /* a sparse body: rows would be mostly empty */
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
    G->nblocks = (nout + thick - 1) / thick;
    G->block_run = calloc((size_t)G->nblocks + 1, sizeof(int64_t));
    G->run = malloc((size_t)(nrun + 1) * sizeof *G->run);
    int64_t cap = nrun * G->nk + 16, nseg = 0;
    G->seg = malloc((size_t)cap * sizeof *G->seg);
    int ok = G->block_run && G->run && G->seg;
    for (int64_t A = 0; A < nrun && ok; A++) {
        const int64_t blk = (gc[2][run[A].start] - lo[2]) / thick;
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
static void grid_sync(pd_sim *sim, pd_grid *G)
{
    const int W = G->words;
    const int64_t n = G->n;
    int64_t *inv = NULL;
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
    for (int64_t i = 0; i < n; i++)
        for (int64_t q = h->offset[i]; q < h->offset[i + 1]; q++) {
            if (!pd_bond_intact(h->intact, q))
                continue;
            int32_t j = h->neighbor[q];
            int d[3] = {G->lc[0][j] - G->lc[0][i], G->lc[1][j] - G->lc[1][i],
                        G->lc[2][j] - G->lc[2][i]};
            int k = offset_of(G, d);
            int64_t owner = k >= 0 ? gidx_of(inv, i) : gidx_of(inv, j);
            k = k >= 0 ? k : -1 - k;
            G->mask[owner * W + (k >> 6)] |= UINT64_C(1) << (k & 63);
        }
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

pd_status pd_grid_new(pd_sim *sim, pd_stencil_kind kind, pd_grid **out)
{
    *out = NULL;
    const pd_particles *p = sim->p;
    const pd_bonds *b = sim->b;
    const pd_scene *sc = &sim->sc;
    /* the model's stencil (PMB with one c and s00 for every bond, or LPS
     * with an influence function of |xi| alone); equal volumes and radii */
    const int lps = kind == PD_STENCIL_LPS;
    if (kind == PD_STENCIL_NONE || sc->bond_list || sim->half.kfail || p->n < 2 ||
        b->count == 0)
        return PD_OK;
    for (int64_t i = 1; i < p->n; i++)
        if (p->volume[i] != p->volume[0] || p->radius[i] != p->radius[0])
            return PD_OK;
    pd_grid *G = calloc(1, sizeof *G);
    if (G == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the lattice bonds");
    const int64_t n = p->n;
    G->n = n;
    for (int d = 0; d < 3; d++)
        G->lc[d] = malloc((size_t)n * sizeof(int32_t));
    int64_t *order = NULL, *inv = NULL;
    int ok = G->lc[0] && G->lc[1] && G->lc[2] ? 1 : -1;
    if (ok > 0)
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
        ok = build_stencil(G, p, b);
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
    if (ok > 0) {
        const double V = p->volume[0];
        G->omega = malloc((size_t)G->nk * sizeof(double));
        ok = G->omega ? ok : -1;
        for (int k = 0; k < G->nk && ok > 0; k++) {
            G->omega[k] = pd_lps_influence(sc->influence, G->len[k], b->horizon);
            G->nu[k] = G->w[k];
            G->w[k] = sc->c * V * G->w[k]; /* c V nu, as pd_half_weights */
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
        if (lps && ok > 0) { /* a = theta/m and b = 1/m of pd_grid_lps */
            G->y[0] = malloc((size_t)n * sizeof(double));
            G->y[1] = malloc((size_t)n * sizeof(double));
            ok = G->y[0] && G->y[1] ? ok : -1;
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
    free(inv);
    if (ok <= 0) {
        pd_grid_free(G);
        return ok < 0 ? pd_fail(PD_ERR_NOMEM, "out of memory for the lattice bonds") : PD_OK;
    }
    grid_sync(sim, G);
#if PD_GRID_AVX512
    G->tile = !lps && G->words == 1 && __builtin_cpu_supports("avx512f") && !getenv("PD_NO_AVX512");
#endif
    if (G->status != PD_OK) {
        pd_status s = G->status;
        pd_grid_free(G);
        return s;
    }
    *out = G;
    return PD_OK;
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

/* ----------------------------------------------------------------- kernel */

/* The elastic energy of bond i-j at offset k, J: 1/2 c s^2 |xi| nu V V
 * (lib/pmb.c's bond_energy with the offset's |xi| and c V nu). */
static double bond_energy(const pd_sim *sim, const pd_grid *G, int64_t i, int64_t j, int k)
{
    const double dx = sim->y[0][j] - sim->y[0][i], dy = sim->y[1][j] - sim->y[1][i],
                 dz = sim->y[2][j] - sim->y[2][i];
    double dr = sqrt(dx * dx + dy * dy + dz * dz) - G->len[k];
    dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
    const double s = dr * G->inv_len[k];
    return 0.5 * s * s * G->len[k] * G->w[k] * sim->p->volume[0];
}

typedef struct {
    const double *y0, *y1, *y2, *s0;
    double *f0, *f1, *f2, *s0n;
    double s00, alpha;
} grid_arrays;

static int record_break(grid_breaks *bl, int64_t g, int32_t k, int64_t j)
{
    if (bl->n == bl->cap) {
        int64_t cap = bl->cap ? 2 * bl->cap : 64;
        int64_t *ng = realloc(bl->g, (size_t)cap * sizeof(int64_t));
        if (ng)
            bl->g = ng;
        int32_t *nk = realloc(bl->k, (size_t)cap * sizeof(int32_t));
        if (nk)
            bl->k = nk;
        int64_t *nj = realloc(bl->j, (size_t)cap * sizeof(int64_t));
        if (nj)
            bl->j = nj;
        if (!ng || !nk || !nj)
            return -1;
        bl->cap = cap;
    }
    bl->g[bl->n] = g;
    bl->k[bl->n] = k;
    bl->j[bl->n] = j;
    bl->n++;
    return 0;
}

/* The contact forces of the pairs of a segment's chunk [c0, c0 + m) that
 * are closer than d_k (seed 000 eqs. 13-15), both ends. */
static void seg_contact(pd_grid *G, const grid_seg *sg, const grid_arrays *A, int64_t c0,
                        int64_t m, int W)
{
    const int k = sg->k;
    const uint64_t bit = UINT64_C(1) << (k & 63);
    const double dc = G->dc[k], kc = G->kc;
    const double *y0 = A->y0, *y1 = A->y1, *y2 = A->y2;
    for (int64_t q = 0; q < m; q++) {
        const int64_t g = c0 + q, j = g + sg->shift;
        const double dx = y0[j] - y0[g], dy = y1[j] - y1[g], dz = y2[j] - y2[g];
        const double r = sqrt(dx * dx + dy * dy + dz * dz);
        if (!(r < dc) || !(r > 0.0) || !(G->cmask[g * W + (k >> 6)] & bit))
            continue;
        const double fs = kc * (r - dc) / r;
        A->f0[g] += fs * dx;
        A->f1[g] += fs * dy;
        A->f2[g] += fs * dz;
        A->f0[j] -= fs * dx;
        A->f1[j] -= fs * dy;
        A->f2[j] -= fs * dz;
    }
}

/* The bond from the particle at (xg, yg, zg) to the one at (xj, yj, zj),
 * with mask word mw: its state mu (0 or 1, bit `bit`), vector d = y_j -
 * y_g, length r, stretch s (0 below eps_machine of extension, seed 000)
 * and force per unit length fs (f_g += fs d; 0 when r = 0), for the offset
 * of L, iL and w.  Every PMB loop of the stencil takes it, so that a bond
 * recomputed in another loop comes out bit for bit the same. */
#define GRID_PMB_PAIR(mw, xg, yg, zg, xj, yj, zj)                                              \
    const double mu = ((mw) & bit) ? 1.0 : 0.0;                                                \
    const double dx = (xj) - (xg), dy = (yj) - (yg), dz = (zj) - (zg);                         \
    const double r = sqrt(dx * dx + dy * dy + dz * dz);                                        \
    double dr = r - L;                                                                         \
    dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;                                                   \
    const double s = dr * iL;                                                                  \
    const double fb = w * s * mu;                                                              \
    const double fs = r > 0.0 ? fb / r : 0.0

/* The bond of lane q of a segment's chunk (particle g = c0 + q, partner j
 * = g + shift); near counts the pairs closer than d_k.  Both loops of
 * seg_bonds share it. */
#define GRID_PMB_BOND                                                                          \
    const int64_t g = c0 + q, j = g + shift;                                                   \
    GRID_PMB_PAIR(mask[g * W], y0[g], y1[g], y2[g], y0[j], y1[j], y2[j]);                      \
    if (contact)                                                                               \
        near += r < dc ? 1.0 : 0.0

/* The bonds (and contacts) of one segment.  `fused`: one pass that updates
 * both ends as it goes (the shift is at least GRID_SAFE, so the two ends of
 * the lanes of one vector never overlap); otherwise the forces go to
 * scratch first and the two ends are updated in two loops.  Runs shorter
 * than a tile take it. */
static inline __attribute__((always_inline)) int
seg_bonds(pd_grid *G, const grid_seg *sg, const grid_arrays *A, const int failure,
          const int contact, const int one_word, grid_breaks *bl)
{
    const int k = sg->k, W = one_word ? 1 : G->words, word = k >> 6;
    const uint64_t bit = UINT64_C(1) << (k & 63);
    const int64_t shift = sg->shift;
    const double L = G->len[k], iL = G->inv_len[k], w = G->w[k], dc = G->dc[k];
    const double s00 = A->s00, alpha = A->alpha;
    const double *restrict y0 = A->y0, *restrict y1 = A->y1, *restrict y2 = A->y2;
    const double *restrict s0 = A->s0;
    double *f0 = A->f0, *f1 = A->f1, *f2 = A->f2, *s0n = A->s0n;
    const uint64_t *restrict mask = G->mask + word;
    double brk[GRID_CHUNK], gx[GRID_CHUNK], gy[GRID_CHUNK], gz[GRID_CHUNK], t[GRID_CHUNK];
    const int fused = shift >= GRID_SAFE;
    for (int64_t c0 = sg->lo; c0 < sg->hi; c0 += GRID_CHUNK) {
        const int64_t m = sg->hi - c0 < GRID_CHUNK ? sg->hi - c0 : GRID_CHUNK;
        double nbreak = 0, near = 0;
        if (fused) {
#pragma omp simd reduction(+ : nbreak, near) safelen(GRID_SAFE)
            for (int64_t q = 0; q < m; q++) {
                GRID_PMB_BOND;
                f0[g] += fs * dx;
                f1[g] += fs * dy;
                f2[g] += fs * dz;
                f0[j] -= fs * dx;
                f1[j] -= fs * dy;
                f2[j] -= fs * dz;
                if (failure) {
                    const double thr = s0[g] < s0[j] ? s0[g] : s0[j];
                    const double b = s > thr ? mu : 0.0;
                    const double tt = mu > 0 ? s00 - alpha * s : -INFINITY;
                    s0n[g] = tt > s0n[g] ? tt : s0n[g];
                    s0n[j] = tt > s0n[j] ? tt : s0n[j];
                    brk[q] = b;
                    nbreak += b;
                }
            }
        } else {
            for (int64_t q = 0; q < m; q++) {
                GRID_PMB_BOND;
                gx[q] = fs * dx;
                gy[q] = fs * dy;
                gz[q] = fs * dz;
                if (failure) {
                    const double thr = s0[g] < s0[j] ? s0[g] : s0[j];
                    brk[q] = s > thr ? mu : 0.0;
                    t[q] = mu > 0 ? s00 - alpha * s : -INFINITY;
                    nbreak += brk[q];
                }
            }
            for (int64_t q = 0; q < m; q++) {
                f0[c0 + q] += gx[q];
                f1[c0 + q] += gy[q];
                f2[c0 + q] += gz[q];
                if (failure)
                    s0n[c0 + q] = t[q] > s0n[c0 + q] ? t[q] : s0n[c0 + q];
            }
            for (int64_t q = 0; q < m; q++) {
                const int64_t j = c0 + q + shift;
                f0[j] -= gx[q];
                f1[j] -= gy[q];
                f2[j] -= gz[q];
                if (failure)
                    s0n[j] = t[q] > s0n[j] ? t[q] : s0n[j];
            }
        }
        /* contact: pairs closer than d_k are rare (a compression of 10%
         * and more), so the bond pass only counts them, and a second pass
         * over the chunk adds their forces when there are any */
        if (contact && near > 0)
            seg_contact(G, sg, A, c0, m, W);
        if (failure && nbreak > 0)
            for (int64_t q = 0; q < m; q++)
                if (brk[q] > 0) {
                    G->mask[(c0 + q) * W + word] &= ~bit;
                    if (record_break(bl, c0 + q, k, c0 + q + shift))
                        return -1;
                }
    }
    return 0;
}

#if PD_GRID_AVX512
/* The broken bonds of a tile's segment: its bonds recomputed one by one
 * (bit for bit the vector loop's) and those with s > min(s0_g, s0_j)
 * cleared and recorded.  Breaks are rare: the vector loop only counts
 * them. */
static int tile_breaks(pd_grid *G, const grid_seg *sg, const grid_arrays *A, int64_t lo,
                       int64_t hi, int W, grid_breaks *bl)
{
    const int k = sg->k, word = k >> 6;
    const uint64_t bit = UINT64_C(1) << (k & 63);
    const double L = G->len[k], iL = G->inv_len[k], w = G->w[k];
    for (int64_t g = lo; g < hi; g++) {
        const int64_t j = g + sg->shift;
        GRID_PMB_PAIR(G->mask[g * W + word], A->y0[g], A->y1[g], A->y2[g], A->y0[j], A->y1[j],
                      A->y2[j]);
        (void)fs;
        const double thr = A->s0[g] < A->s0[j] ? A->s0[g] : A->s0[j];
        if (mu > 0 && s > thr) {
            G->mask[g * W + word] &= ~bit;
            if (record_break(bl, g, k, j))
                return -1;
        }
    }
    return 0;
}

/* One half (8 lanes) of a tile against one segment: GRID_PMB_PAIR in
 * AVX-512, operation for operation (no fused multiply-adds: tile_breaks
 * must find the same stretches), for the lanes of `act`; the others load
 * nothing and store nothing.  `all`: every lane is active (plain loads and
 * stores).  Returns the lanes closer than d_k (contact) and, through brk,
 * the lanes whose bond breaks. */
#define TILE_HALF(h, all)                                                                      \
    do {                                                                                       \
        const __mmask8 act = (__mmask8)(acts >> (8 * (h)));                                    \
        const __m512i mw = _mm512_loadu_si512((const void *)(M + 8 * (h)));                    \
        const __mmask8 kmu = _mm512_mask_test_epi64_mask(act, mw, vbit);                       \
        const __m512d xj = (all) ? _mm512_loadu_pd(Y0 + 8 * (h))                               \
                                 : _mm512_mask_loadu_pd(yi0[h], act, Y0 + 8 * (h));            \
        const __m512d yj = (all) ? _mm512_loadu_pd(Y1 + 8 * (h))                               \
                                 : _mm512_mask_loadu_pd(yi1[h], act, Y1 + 8 * (h));            \
        const __m512d zj = (all) ? _mm512_loadu_pd(Y2 + 8 * (h))                               \
                                 : _mm512_mask_loadu_pd(yi2[h], act, Y2 + 8 * (h));            \
        const __m512d dx = _mm512_sub_pd(xj, yi0[h]), dy = _mm512_sub_pd(yj, yi1[h]),          \
                      dz = _mm512_sub_pd(zj, yi2[h]);                                          \
        const __m512d r = _mm512_sqrt_pd(_mm512_add_pd(                                        \
            _mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)), _mm512_mul_pd(dz, dz))); \
        __m512d dr = _mm512_sub_pd(r, vL);                                                     \
        dr = _mm512_mask_mov_pd(dr, _mm512_cmp_pd_mask(_mm512_abs_pd(dr), vnz, _CMP_LT_OQ),    \
                                zero);                                                         \
        const __m512d s = _mm512_mul_pd(dr, viL);                                              \
        const __m512d fb = _mm512_maskz_mul_pd(kmu, _mm512_mul_pd(vw, s), one);                \
        const __m512d fs =                                                                     \
            _mm512_maskz_div_pd(_mm512_cmp_pd_mask(r, zero, _CMP_GT_OQ), fb, r);               \
        const __m512d gx = _mm512_mul_pd(fs, dx), gy = _mm512_mul_pd(fs, dy),                  \
                      gz = _mm512_mul_pd(fs, dz);                                              \
        ax[h] = _mm512_add_pd(ax[h], gx);                                                      \
        ay[h] = _mm512_add_pd(ay[h], gy);                                                      \
        az[h] = _mm512_add_pd(az[h], gz);                                                      \
        if (all) {                                                                             \
            _mm512_storeu_pd(F0 + 8 * (h), _mm512_sub_pd(_mm512_loadu_pd(F0 + 8 * (h)), gx));  \
            _mm512_storeu_pd(F1 + 8 * (h), _mm512_sub_pd(_mm512_loadu_pd(F1 + 8 * (h)), gy));  \
            _mm512_storeu_pd(F2 + 8 * (h), _mm512_sub_pd(_mm512_loadu_pd(F2 + 8 * (h)), gz));  \
        } else {                                                                               \
            _mm512_mask_storeu_pd(F0 + 8 * (h), act,                                           \
                                  _mm512_sub_pd(_mm512_maskz_loadu_pd(act, F0 + 8 * (h)), gx)); \
            _mm512_mask_storeu_pd(F1 + 8 * (h), act,                                           \
                                  _mm512_sub_pd(_mm512_maskz_loadu_pd(act, F1 + 8 * (h)), gy)); \
            _mm512_mask_storeu_pd(F2 + 8 * (h), act,                                           \
                                  _mm512_sub_pd(_mm512_maskz_loadu_pd(act, F2 + 8 * (h)), gz)); \
        }                                                                                      \
        if (contact)                                                                           \
            near |= _mm512_mask_cmp_pd_mask(act, r, vdc, _CMP_LT_OQ);                          \
        if (failure) {                                                                         \
            const __m512d sj = (all) ? _mm512_loadu_pd(S0 + 8 * (h))                           \
                                     : _mm512_mask_loadu_pd(si[h], act, S0 + 8 * (h));         \
            const __m512d thr = _mm512_min_pd(si[h], sj);                                      \
            brk |= _mm512_mask_cmp_pd_mask(kmu, s, thr, _CMP_GT_OQ);                           \
            const __m512d tt =                                                                 \
                _mm512_mask_sub_pd(ninf, kmu, vs00, _mm512_mul_pd(valpha, s));                 \
            sm[h] = _mm512_max_pd(tt, sm[h]);                                                  \
            const __m512d sn = (all) ? _mm512_loadu_pd(SN + 8 * (h))                           \
                                     : _mm512_maskz_loadu_pd(act, SN + 8 * (h));               \
            _mm512_mask_storeu_pd(SN + 8 * (h), act, _mm512_max_pd(tt, sn));                   \
        }                                                                                      \
    } while (0)

/* The bonds (and contacts) of a run at least a tile long (one mask word
 * per particle), a tile of 16 consecutive particles at a time (the last
 * one moved back to end with the run; its lanes of the tile before are
 * left out).  A tile walks the run's segments (in tile order) with its own
 * positions, forces and new s0 in registers, so that a bond loads and
 * stores only its partner's: half the memory traffic of seg_bonds. */
__attribute__((target("avx512f"))) static inline __attribute__((always_inline)) int
tile_run(pd_grid *G, const grid_run *R, const grid_arrays *A, const int failure,
         const int contact, grid_breaks *bl)
{
    const __m512d zero = _mm512_setzero_pd(), one = _mm512_set1_pd(1.0);
    const __m512d ninf = _mm512_set1_pd(-INFINITY), vnz = _mm512_set1_pd(PD_NEAR_ZERO);
    const __m512d vs00 = _mm512_set1_pd(A->s00), valpha = _mm512_set1_pd(A->alpha);
    for (int64_t t = 0; t < R->len; t += GRID_TILE) {
        const int64_t g0 = R->start + (t + GRID_TILE <= R->len ? t : R->len - GRID_TILE);
        const int64_t own = R->start + t; /* the lanes before are the last tile's */
        __m512d yi0[2], yi1[2], yi2[2], si[2], ax[2], ay[2], az[2], sm[2];
        for (int h = 0; h < 2; h++) {
            yi0[h] = _mm512_loadu_pd(A->y0 + g0 + 8 * h);
            yi1[h] = _mm512_loadu_pd(A->y1 + g0 + 8 * h);
            yi2[h] = _mm512_loadu_pd(A->y2 + g0 + 8 * h);
            si[h] = failure ? _mm512_loadu_pd(A->s0 + g0 + 8 * h) : zero;
            ax[h] = ay[h] = az[h] = zero;
            sm[h] = ninf;
        }
        for (int64_t q = R->seg0; q < R[1].seg0; q++) {
            const grid_seg *sg = &G->seg[q];
            const int64_t lo = sg->lo > own ? sg->lo : own;
            const int64_t hi = sg->hi < g0 + GRID_TILE ? sg->hi : g0 + GRID_TILE;
            if (lo >= hi)
                continue;
            const int k = sg->k;
            const __m512i vbit = _mm512_set1_epi64((long long)(UINT64_C(1) << k));
            const __m512d vL = _mm512_set1_pd(G->len[k]), viL = _mm512_set1_pd(G->inv_len[k]);
            const __m512d vw = _mm512_set1_pd(G->w[k]), vdc = _mm512_set1_pd(G->dc[k]);
            const int64_t j0 = g0 + sg->shift;
            const uint64_t *M = G->mask + g0;
            const double *Y0 = A->y0 + j0, *Y1 = A->y1 + j0, *Y2 = A->y2 + j0;
            const double *S0 = failure ? A->s0 + j0 : NULL;
            double *F0 = A->f0 + j0, *F1 = A->f1 + j0, *F2 = A->f2 + j0;
            double *SN = failure ? A->s0n + j0 : NULL;
            const uint32_t acts = (uint32_t)(((UINT64_C(1) << (hi - g0)) - 1) &
                                             ~((UINT64_C(1) << (lo - g0)) - 1));
            __mmask8 near = 0, brk = 0;
            if (acts == 0xffff) {
                TILE_HALF(0, 1);
                TILE_HALF(1, 1);
            } else {
                TILE_HALF(0, 0);
                TILE_HALF(1, 0);
            }
            if (contact && near)
                seg_contact(G, sg, A, lo, hi - lo, 1);
            if (failure && brk && tile_breaks(G, sg, A, lo, hi, 1, bl))
                return -1;
        }
        double tx[GRID_TILE], ty[GRID_TILE], tz[GRID_TILE], ts[GRID_TILE];
        for (int h = 0; h < 2; h++) {
            _mm512_storeu_pd(tx + 8 * h, ax[h]);
            _mm512_storeu_pd(ty + 8 * h, ay[h]);
            _mm512_storeu_pd(tz + 8 * h, az[h]);
            _mm512_storeu_pd(ts + 8 * h, sm[h]);
        }
        for (int64_t g = own; g < g0 + GRID_TILE; g++) {
            A->f0[g] += tx[g - g0];
            A->f1[g] += ty[g - g0];
            A->f2[g] += tz[g - g0];
            if (failure)
                A->s0n[g] = ts[g - g0] > A->s0n[g] ? ts[g - g0] : A->s0n[g];
        }
    }
    return 0;
}

/* The AVX-512 variants: runs at least a tile long take tile_run, shorter
 * ones seg_bonds. */
#define GRID_TILE_BLOCK(name, failure, contact)                                                \
    __attribute__((target("avx512f"))) static int name(pd_grid *G, int64_t blk,                \
                                                       const grid_arrays *A)                   \
    {                                                                                          \
        for (int64_t r = G->block_run[blk]; r < G->block_run[blk + 1]; r++) {                  \
            const grid_run *R = &G->run[r];                                                    \
            if (R->len >= GRID_TILE) {                                                         \
                if (tile_run(G, R, A, failure, contact, &G->breaks[blk]))                      \
                    return -1;                                                                 \
            } else                                                                             \
                for (int64_t s = R->seg0; s < R[1].seg0; s++)                                  \
                    if (seg_bonds(G, &G->seg[s], A, failure, contact, 1, &G->breaks[blk]))     \
                        return -1;                                                             \
        }                                                                                      \
        return 0;                                                                              \
    }
GRID_TILE_BLOCK(grid_tile_00, 0, 0)
GRID_TILE_BLOCK(grid_tile_01, 0, 1)
GRID_TILE_BLOCK(grid_tile_10, 1, 0)
GRID_TILE_BLOCK(grid_tile_11, 1, 1)
#endif

/* The kernel's variants: with or without failure and contact, and with
 * one mask word per particle (up to 64 offsets, delta < 3.3 h: the
 * words load as one vector) or more. */
#define GRID_BLOCK(name, failure, contact, one_word)                                          \
    PD_VECTOR_CLONES static int name(pd_grid *G, int64_t blk, const grid_arrays *A)          \
    {                                                                                         \
        for (int64_t s = block_seg0(G, blk); s < block_seg0(G, blk + 1); s++)                 \
            if (seg_bonds(G, &G->seg[s], A, failure, contact, one_word, &G->breaks[blk]))     \
                return -1;                                                                    \
        return 0;                                                                             \
    }
GRID_BLOCK(grid_block_000, 0, 0, 0)
GRID_BLOCK(grid_block_010, 0, 1, 0)
GRID_BLOCK(grid_block_100, 1, 0, 0)
GRID_BLOCK(grid_block_110, 1, 1, 0)
GRID_BLOCK(grid_block_001, 0, 0, 1)
GRID_BLOCK(grid_block_011, 0, 1, 1)
GRID_BLOCK(grid_block_101, 1, 0, 1)
GRID_BLOCK(grid_block_111, 1, 1, 1)

typedef int (*grid_block_fn)(pd_grid *, int64_t, const grid_arrays *);
static const grid_block_fn grid_blocks[8] = {grid_block_000, grid_block_001, grid_block_010,
                                             grid_block_011, grid_block_100, grid_block_101,
                                             grid_block_110, grid_block_111};

pd_status pd_grid_pmb(pd_sim *sim, int failure)
{
    pd_grid *G = sim->grid;
    const int64_t n = G->n;
    if (G->epoch != sim->half.epoch) {
        grid_sync(sim, G);
        if (G->status != PD_OK)
            return G->status;
    }
    double tf = pd_wtime();
    grid_arrays A = {.s00 = sim->sc.s00, .alpha = sim->sc.alpha};
    const int64_t *perm = G->perm;
    if (perm) {
#pragma omp parallel for schedule(static)
        for (int64_t g = 0; g < n; g++) {
            const int64_t i = perm[g];
            for (int d = 0; d < 3; d++) {
                G->y[d][g] = sim->y[d][i];
                G->f[d][g] = 0;
            }
            if (failure) {
                G->s0[g] = sim->s0[i];
                G->s0n[g] = -INFINITY;
            }
        }
        A.y0 = G->y[0], A.y1 = G->y[1], A.y2 = G->y[2];
        A.f0 = G->f[0], A.f1 = G->f[1], A.f2 = G->f[2];
        A.s0 = G->s0, A.s0n = G->s0n;
    } else {
        A.y0 = sim->y[0], A.y1 = sim->y[1], A.y2 = sim->y[2];
        A.f0 = sim->f[0], A.f1 = sim->f[1], A.f2 = sim->f[2];
        A.s0 = sim->s0, A.s0n = sim->s0_new;
        if (failure && sim->s0_new != G->s0n_ready) /* else the last step's end did */
#pragma omp parallel for schedule(static)
            for (int64_t g = 0; g < n; g++)
                sim->s0_new[g] = -INFINITY;
    }
    tf = pd_wtime() - tf;
    const int contact = G->cmask != NULL;
    grid_block_fn fn = grid_blocks[4 * (failure != 0) + 2 * contact + (G->words == 1)];
#if PD_GRID_AVX512
    static const grid_block_fn tiles[4] = {grid_tile_00, grid_tile_01, grid_tile_10, grid_tile_11};
    if (G->tile)
        fn = tiles[2 * (failure != 0) + contact];
#endif
    int bad = 0;
    for (int64_t blk = 0; blk < G->nblocks; blk++)
        G->breaks[blk].n = 0;
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel reduction(| : bad)
        for (int64_t blk = phase; blk < G->nblocks; blk += 2)
            if (grid_mine(G, blk))
                bad |= fn(G, blk, &A) != 0;
    }
    if (bad)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the broken bonds of a step");
    double t0 = pd_wtime();
    if (perm) {
#pragma omp parallel for schedule(static)
        for (int64_t g = 0; g < n; g++) {
            const int64_t i = perm[g];
            for (int d = 0; d < 3; d++)
                sim->f[d][i] += G->f[d][g];
            if (failure)
                sim->s0_new[i] = G->s0n[g];
        }
    }
    if (failure) {
        if (perm)
#pragma omp parallel for schedule(static)
            for (int64_t i = 0; i < n; i++) /* no intact bond: +inf (DBL_MAX, as LAMMPS) */
                if (sim->s0_new[i] == -INFINITY)
                    sim->s0_new[i] = DBL_MAX;
        /* the broken bonds into the half bonds, and their energy: per block,
         * summed in block order (the same at any thread count).  In lattice
         * order a block's bonds are half bonds of its own rows, whose bits
         * other blocks than its neighbours never share: even blocks, then
         * odd ones, in parallel; through a permutation, one by one.  In
         * lattice order a block also finishes the new s0 of its particles
         * (no intact bond: +inf, DBL_MAX as LAMMPS) and fills the old s0,
         * which the step is done with and which becomes the next step's
         * new s0, with -inf: two passes over the particles fewer. */
        for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel if (!perm)
            for (int64_t blk = phase; blk < G->nblocks; blk += 2) {
                if (!grid_mine(G, blk))
                    continue;
                if (!perm)
                    for (int64_t i = block_start(G, blk); i < block_start(G, blk + 1); i++) {
                        sim->s0_new[i] = sim->s0_new[i] == -INFINITY ? DBL_MAX : sim->s0_new[i];
                        sim->s0[i] = -INFINITY;
                    }
                const grid_breaks *bl = &G->breaks[blk];
                double rel = 0;
                for (int64_t e = 0; e < bl->n; e++) {
                    int64_t i = perm ? perm[bl->g[e]] : bl->g[e];
                    int64_t j = perm ? perm[bl->j[e]] : bl->j[e];
                    int64_t q = pd_half_find(&sim->half, i < j ? i : j, i < j ? j : i);
                    if (q < 0)
                        continue; /* cannot be: the masks came from the half bonds */
                    pd_bond_break(sim->half.intact, q);
                    rel += bond_energy(sim, G, i, j, bl->k[e]);
                }
                G->released[blk] = rel;
            }
        }
        for (int64_t blk = 0; blk < G->nblocks; blk++)
            sim->released += G->released[blk];
        /* the caller swaps s0 and s0_new (lib/pmb.c) */
        G->s0n_ready = perm ? NULL : sim->s0;
    }
    tf += pd_wtime() - t0;
    sim->timers[PD_T_FAILURE] += tf;
    sim->timers[PD_T_BONDS] -= tf;
    return PD_OK;
}

/* The energy of the stencil pairs, half of each pair to each end: with
 * `contact`, e_i += 1/4 (c_S/delta) (d_k - r)^2 V_i V_j over the contact
 * pairs closer than d_k (lib/contact.c's), else e_i += 1/4 c s^2 |xi| nu
 * V_i V_j over the intact bonds (lib/pmb.c's pmb_energy).  Even blocks,
 * then odd ones, so that no two threads add to one particle. */
/* The energy of a pair of squared length r2 and length r, half to each end
 * (0 outside contact with `contact`). */
static inline __attribute__((always_inline)) double pair_x(const int contact, double r2, double r,
                                                          double c, double L, double iL, double dc)
{
    if (contact)
        return r2 < dc * dc && r < dc ? c * (dc - r) * (dc - r) : 0.0;
    double dr = r - L;
    dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
    return c * ((dr * iL) * (dr * iL));
}

static inline __attribute__((always_inline)) void
seg_energy(const pd_sim *sim, const pd_grid *G, const grid_seg *sg, double *e, const int contact)
{
    const double V = sim->p->volume[0];
    const int W = G->words, k = sg->k;
    const uint64_t bit = UINT64_C(1) << (k & 63);
    const uint64_t *bits = (contact ? G->cmask : G->mask) + (k >> 6);
    const double L = G->len[k], iL = G->inv_len[k], dc = G->dc[k];
    const double c = contact ? 0.25 * G->kc * V : 0.25 * G->w[k] * L * V;
    const double *restrict y0 = sim->y[0], *restrict y1 = sim->y[1], *restrict y2 = sim->y[2];
    const int64_t shift = sg->shift;
    if (G->perm == NULL && shift >= GRID_SAFE) { /* the two ends never share a vector */
#pragma omp simd safelen(GRID_SAFE)
        for (int64_t g = sg->lo; g < sg->hi; g++) {
            const int64_t j = g + shift;
            const double dx = y0[j] - y0[g], dy = y1[j] - y1[g], dz = y2[j] - y2[g];
            const double r2 = dx * dx + dy * dy + dz * dz;
            const double x = (bits[g * W] & bit) ? pair_x(contact, r2, sqrt(r2), c, L, iL, dc) : 0.0;
            e[g] += x;
            e[j] += x;
        }
        return;
    }
    for (int64_t g = sg->lo; g < sg->hi; g++) {
        if (!(bits[g * W] & bit))
            continue;
        const int64_t i = G->perm ? G->perm[g] : g;
        const int64_t j = G->perm ? G->perm[g + shift] : g + shift;
        const double dx = y0[j] - y0[i], dy = y1[j] - y1[i], dz = y2[j] - y2[i];
        const double r2 = dx * dx + dy * dy + dz * dz;
        if (contact && !(r2 < dc * dc)) /* the most, no square root */
            continue;
        const double x = pair_x(contact, r2, sqrt(r2), c, L, iL, dc);
        e[i] += x;
        e[j] += x;
    }
}

/* The pairs of one block (the vector loop where the particles are in grid
 * order and the two ends of a segment's lanes never meet). */
PD_VECTOR_CLONES static void block_energy(const pd_sim *sim, int64_t blk, double *e, int contact)
{
    const pd_grid *G = sim->grid;
    for (int64_t si = block_seg0(G, blk); si < block_seg0(G, blk + 1); si++)
        if (contact)
            seg_energy(sim, G, &G->seg[si], e, 1);
        else
            seg_energy(sim, G, &G->seg[si], e, 0);
}

static void pair_energy(const pd_sim *sim, double *e, const int contact)
{
    const pd_grid *G = sim->grid;
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel
        for (int64_t blk = phase; blk < G->nblocks; blk += 2)
            if (grid_mine(G, blk))
                block_energy(sim, blk, e, contact);
    }
}

int pd_grid_max_damage(const pd_sim *sim, double *max_damage)
{
    const pd_grid *G = sim->grid;
    if (G == NULL || G->epoch != sim->half.epoch)
        return 0;
    const int64_t n = G->n;
    const int W = G->words;
    int32_t *kept = calloc((size_t)(n > 0 ? n : 1), sizeof(int32_t));
    if (kept == NULL)
        return 0;
    /* the intact bonds of each particle, both ends of each (even blocks,
     * then odd ones: no two threads count into one particle) */
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel
        for (int64_t blk = phase; blk < G->nblocks; blk += 2) {
            if (!grid_mine(G, blk))
                continue;
            for (int64_t si = block_seg0(G, blk); si < block_seg0(G, blk + 1); si++) {
                const grid_seg *sg = &G->seg[si];
                const int k = sg->k;
                const uint64_t bit = UINT64_C(1) << (k & 63);
                for (int64_t g = sg->lo; g < sg->hi; g++) {
                    const int32_t m = (G->mask[g * W + (k >> 6)] & bit) != 0;
                    kept[g] += m;
                    kept[g + sg->shift] += m;
                }
            }
        }
    }
    /* equal volumes: damage = 1 - intact / family, the family counting
     * every bond of the file (pd_damage) */
    const int64_t *off = sim->b->offset;
    double dmax = 0;
#pragma omp parallel for schedule(static) reduction(max : dmax)
    for (int64_t g = 0; g < n; g++) {
        const int64_t i = G->perm ? G->perm[g] : g;
        const int64_t all = off[i + 1] - off[i];
        const double d = all > 0 ? 1.0 - (double)kept[g] / (double)all : 0.0;
        dmax = d > dmax ? d : dmax;
    }
    free(kept);
    *max_damage = dmax;
    return 1;
}

void pd_grid_contact_energy(const pd_sim *sim, double *e)
{
    if (sim->grid && sim->grid->cmask)
        pair_energy(sim, e, 1);
}

void pd_grid_pmb_energy(const pd_sim *sim, double *e)
{
    pair_energy(sim, e, 0);
}

/* ------------------------------------------------------------------- LPS */

/* LPS on the stencil (lib/lps.c; omega a function of |xi|, so per offset;
 * the particles in lattice order, so lib/lps.c's arrays need no copies).
 * The arithmetic of each bond is lps.c's theta_row and force_row, product
 * for product; each bond is computed once and added to both ends (the pair
 * force t_ij of Algorithm 2 is symmetric: equal volumes, nu_ij = nu_ji). */

/* Algorithm 4's term omega |xi| e nu V of bond g-j (0 when broken), added
 * to the sums of both ends. */
#define GRID_THETA_BODY                                                                        \
    do {                                                                                       \
        const int64_t j = g + shift;                                                           \
        const double mu = (mask[g * W] & bit) ? 1.0 : 0.0;                                     \
        const double dx = y0[j] - y0[g], dy = y1[j] - y1[g], dz = y2[j] - y2[g];               \
        const double r = sqrt(dx * dx + dy * dy + dz * dz);                                    \
        double e = r - len;                                                                    \
        e = fabs(e) < PD_NEAR_ZERO ? 0.0 : e;                                                  \
        const double c = mu * (oml * e * V * nu);                                              \
        sum[g] += c;                                                                           \
        sum[j] += c;                                                                           \
    } while (0)

PD_VECTOR_CLONES static void lps_theta_block(const pd_grid *G, int64_t blk, const grid_arrays *A,
                                             double *sum, double V)
{
    const double *restrict y0 = A->y0, *restrict y1 = A->y1, *restrict y2 = A->y2;
    const int W = G->words;
    for (int64_t si = block_seg0(G, blk); si < block_seg0(G, blk + 1); si++) {
        const grid_seg *sg = &G->seg[si];
        const int k = sg->k;
        const uint64_t bit = UINT64_C(1) << (k & 63);
        const uint64_t *restrict mask = G->mask + (k >> 6);
        const int64_t shift = sg->shift;
        const double len = G->len[k], oml = G->omega[k] * len, nu = G->nu[k];
        if (shift >= GRID_SAFE) {
#pragma omp simd safelen(GRID_SAFE)
            for (int64_t g = sg->lo; g < sg->hi; g++)
                GRID_THETA_BODY;
        } else
            for (int64_t g = sg->lo; g < sg->hi; g++)
                GRID_THETA_BODY;
    }
}

/* The pair force of bond g-j (Algorithm 2), its force on g and -it on j,
 * and with failure the test and the new s0 of both ends (as seg_bonds).
 * With a = theta/m and b = 1/m of each particle (computed once a step) and
 * per offset c1 = (3K - 5G) V nu omega |xi| and c2 = 15 G V nu omega,
 *   t = c1 (a_g + a_j) + c2 (b_g + b_j) e,
 * force_row's t with its products regrouped (equal to rounding). */
#define GRID_LPS_BODY                                                                          \
    do {                                                                                       \
        const int64_t g = c0 + q, j = g + shift;                                               \
        const double mu = (mask[g * W] & bit) ? 1.0 : 0.0;                                     \
        const double dx = y0[j] - y0[g], dy = y1[j] - y1[g], dz = y2[j] - y2[g];               \
        const double r = sqrt(dx * dx + dy * dy + dz * dz);                                    \
        double e = r - len;                                                                    \
        e = fabs(e) < PD_NEAR_ZERO ? 0.0 : e;                                                  \
        const double t = c1 * (ta[g] + ta[j]) + c2 * (tb[g] + tb[j]) * e;                     \
        const double fb = r > 0.0 ? mu * t / r : 0.0;                                          \
        f0[g] += dx * fb;                                                                      \
        f1[g] += dy * fb;                                                                      \
        f2[g] += dz * fb;                                                                      \
        f0[j] -= dx * fb;                                                                      \
        f1[j] -= dy * fb;                                                                      \
        f2[j] -= dz * fb;                                                                      \
        near += r < dc ? 1.0 : 0.0;                                                            \
        if (failure) {                                                                         \
            const double s = e * il;                                                           \
            const double thr = s0[g] < s0[j] ? s0[g] : s0[j];                                  \
            brk[q] = s > thr ? mu : 0.0;                                                       \
            nbreak += brk[q];                                                                  \
            const double tt = mu > 0 ? s00 - (alpha * s) : -INFINITY;                          \
            s0n[g] = tt > s0n[g] ? tt : s0n[g];                                                \
            s0n[j] = tt > s0n[j] ? tt : s0n[j];                                                \
        }                                                                                      \
    } while (0)

#define GRID_LPS_BLOCK(name, with_failure)                                                     \
    PD_VECTOR_CLONES static int name(pd_grid *G, int64_t blk, const grid_arrays *A,            \
                                     const double *restrict ta, const double *restrict tb,     \
                                     double V, double dil, double shear)                       \
    {                                                                                          \
        const int W = G->words, failure = with_failure;                                        \
        const double *restrict y0 = A->y0, *restrict y1 = A->y1, *restrict y2 = A->y2;         \
        const double *restrict s0 = A->s0;                                                     \
        double *f0 = A->f0, *f1 = A->f1, *f2 = A->f2, *s0n = A->s0n;                           \
        const double s00 = A->s00, alpha = A->alpha;                                           \
        double brk[GRID_CHUNK];                                                                \
        for (int64_t si = block_seg0(G, blk); si < block_seg0(G, blk + 1); si++) {             \
            const grid_seg *sg = &G->seg[si];                                                  \
            const int k = sg->k;                                                               \
            const uint64_t bit = UINT64_C(1) << (k & 63);                                      \
            const uint64_t *restrict mask = G->mask + (k >> 6);                                \
            const int64_t shift = sg->shift;                                                   \
            const double len = G->len[k], il = G->inv_len[k], dc = G->dc[k];                   \
            const double c1 = dil * V * G->nu[k] * G->omega[k] * len,                          \
                         c2 = PD_LPS_SHEAR_FACTOR * shear * V * G->nu[k] * G->omega[k];        \
            for (int64_t c0 = sg->lo; c0 < sg->hi; c0 += GRID_CHUNK) {                         \
                const int64_t n = sg->hi - c0 < GRID_CHUNK ? sg->hi - c0 : GRID_CHUNK;         \
                double nbreak = 0, near = 0;                                                   \
                if (shift >= GRID_SAFE) {                                                      \
                    _Pragma("omp simd reduction(+ : nbreak, near) safelen(16)")               \
                    for (int64_t q = 0; q < n; q++)                                            \
                        GRID_LPS_BODY;                                                         \
                } else                                                                         \
                    for (int64_t q = 0; q < n; q++)                                            \
                        GRID_LPS_BODY;                                                         \
                if (G->cmask && near > 0)                                                      \
                    seg_contact(G, sg, A, c0, n, W);                                           \
                if (failure && nbreak > 0)                                                     \
                    for (int64_t q = 0; q < n; q++)                                            \
                        if (brk[q] > 0) {                                                      \
                            G->mask[(c0 + q) * W + (k >> 6)] &= ~bit;                          \
                            if (record_break(&G->breaks[blk], c0 + q, k, c0 + q + shift))      \
                                return -1;                                                     \
                        }                                                                      \
            }                                                                                  \
        }                                                                                      \
        return 0;                                                                              \
    }
GRID_LPS_BLOCK(lps_force_block_0, 0)
GRID_LPS_BLOCK(lps_force_block_1, 1)

pd_status pd_grid_lps(pd_sim *sim, const double *m, double *theta, int failure,
                      void (*mark)(void *ctx, int64_t i, int64_t j), void *ctx)
{
    pd_grid *G = sim->grid;
    const int64_t n = G->n;
    if (G->epoch != sim->half.epoch) {
        grid_sync(sim, G);
        if (G->status != PD_OK)
            return G->status;
    }
    const double V = sim->p->volume[0];
    const double dil = (3.0 * sim->sc.bulk_modulus) - (5.0 * sim->sc.shear_modulus);
    grid_arrays A = {.y0 = sim->y[0], .y1 = sim->y[1], .y2 = sim->y[2], .f0 = sim->f[0],
                     .f1 = sim->f[1], .f2 = sim->f[2], .s0 = sim->s0, .s0n = sim->s0_new,
                     .s00 = sim->sc.s00, .alpha = sim->sc.alpha};
    /* theta (Algorithm 4): the sums over the bonds, then 3/m_i */
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++)
        theta[i] = 0.0;
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel
        for (int64_t blk = phase; blk < G->nblocks; blk += 2)
            if (grid_mine(G, blk))
                lps_theta_block(G, blk, &A, theta, V);
    }
    double *ta = G->y[0], *tb = G->y[1]; /* scratch of the lattice order */
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++) {
        theta[i] = m[i] != 0.0 ? (3.0 / m[i]) * theta[i] : 0.0;
        ta[i] = m[i] != 0.0 ? theta[i] / m[i] : 0.0;
        tb[i] = m[i] != 0.0 ? 1.0 / m[i] : 0.0;
        if (failure)
            sim->s0_new[i] = -INFINITY;
    }
    /* the forces (Algorithm 2) and the breaking test */
    int bad = 0;
    for (int64_t blk = 0; blk < G->nblocks; blk++)
        G->breaks[blk].n = 0;
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel reduction(| : bad)
        for (int64_t blk = phase; blk < G->nblocks; blk += 2)
            if (grid_mine(G, blk))
                bad |= (failure ? lps_force_block_1 : lps_force_block_0)(
                           G, blk, &A, ta, tb, V, dil, sim->sc.shear_modulus) != 0;
    }
    if (bad)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the broken bonds of a step");
    if (!failure)
        return PD_OK;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++) /* no intact bond: +inf (DBL_MAX, as LAMMPS) */
        if (sim->s0_new[i] == -INFINITY)
            sim->s0_new[i] = DBL_MAX;
    for (int64_t blk = 0; blk < G->nblocks; blk++)
        for (int64_t e = 0; e < G->breaks[blk].n; e++)
            mark(ctx, G->breaks[blk].g[e], G->breaks[blk].j[e]);
    return PD_OK;
}
