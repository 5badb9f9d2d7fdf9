/*
 * grid_impl.h -- internal to lib/stencil/: the stencil's data (struct
 * pd_grid and its parts) and the helpers that more than one of its files
 * needs.  grid.c explains the stencil and builds it; grid_pmb.c,
 * grid_energy.c and grid_lps.c walk it.  The layers above see only
 * grid.h.
 */
#ifndef PD_GRID_IMPL_H
#define PD_GRID_IMPL_H

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stencil/grid.h"

#ifdef _OPENMP
#include <omp.h>
#endif

#define GRID_NU_TOL 1e-9 /* nu of one offset equal to this, relatively    */
#define GRID_CHUNK 256   /* particles per vector pass of a segment        */
#define GRID_SAFE 16     /* shifts below this take the two-pass loop      */
#define GRID_TILE 16     /* particles of a tile (runs at least this long) */
#define GRID_REACH_MAX 12 /* the stencil's reach in spacings at most: the
                             (2 reach + 1)^3 offsets' table is int16     */
#define GRID_SPARSE_ROWS 4     /* more rows than this per particle (plus  */
#define GRID_SPARSE_SLACK 1024 /* these) is a sparse body: rows would be
                                  mostly empty, the bond lists serve    */

/* Units: lengths in m, volumes in m^3, c in N/m^6 (seed 000's micromodulus),
 * force densities in N/m^3; "grid index" g is a particle's place in grid
 * order (pd_grid.perm maps it to the particle's index i in the file). */

/* A segment: the bonds at offset k of the particles g in [lo, hi), each
 * with the partner g + shift (grid indices). */
typedef struct {
    int64_t lo, hi; /* first particles g of the segment, grid order      */
    int64_t shift;  /* partner g + shift                                  */
    int32_t k;      /* half-stencil offset                                */
} grid_seg;

/* A run: particles [start, start + len) consecutive along the inner axis,
 * whose segments are seg[seg0, next run's seg0). */
typedef struct {
    int64_t start;  /* grid index of its first particle                   */
    int64_t len;    /* its particles                                      */
    int64_t seg0;   /* its first segment                                  */
} grid_run;

/* The bonds a block broke in this step (grid indices, in the order found). */
typedef struct {
    int64_t n, cap; /* entries used, allocated                            */
    int64_t *g;     /* grid index of the first end                        */
    int32_t *k;     /* offset                                             */
    int64_t *j;     /* grid index of the partner                          */
} grid_breaks;

struct pd_grid {
    int64_t n;           /* particles                                      */
    int nk;              /* half-stencil offsets k                         */
    int words;           /* 64-bit mask words per particle, (nk + 63) / 64 */
    int reach;           /* largest |d| component of the stencil, lattice
                            spacings                                       */
    int (*off)[3];       /* nk offsets d, (inner, mid, outer), spacings    */
    /* per offset k (nk each): */
    double *len;         /* reference bond length |xi_k|, m                */
    double *inv_len;     /* 1 / |xi_k|, 1/m                                */
    double *nu;          /* partial-volume factor nu_k, dimensionless      */
    double *w;           /* c V nu_k (as pd_half_weights): force density
                            per unit stretch, N/m^3                        */
    double *dc;          /* contact distance d_k = min(0.9 |xi_k|,
                            1.35 (r + r)), m (seed 000 eq. 15)             */
    double *omega;       /* LPS's influence omega(|xi_k|), omega's unit
                            (pd_lps_influence: 1, 1/m or dimensionless)    */
    int16_t *lookup;     /* (2 reach + 1)^3: k for d, -1 - k for -d, or
                            INT16_MIN: not a stencil offset                */
    int axis[3];         /* inner, mid, outer: 0, 1, 2 for x, y, z         */
    int32_t *lc[3];      /* lattice coordinates of particle i (sim order),
                            spacings                                       */
    int64_t *perm;       /* g -> i, NULL when grid order is sim order      */
    uint8_t *nofail;     /* grid order: 1 for a particle no bond of which
                            breaks (pd-run --no-failure), NULL: none       */
    uint64_t *mask;      /* words per particle (grid order): bit k set
                            while the bond at offset k is intact           */
    uint64_t *cmask;     /* words per particle: bit k set for a contact
                            pair at offset k (NULL: no contact)            */
    grid_seg *seg;       /* the segments, run by run (tile order within)   */
    int64_t nseg;        /* segments                                       */
    grid_run *run;       /* the runs and a last one with start n, seg0 nseg */
    int64_t nblocks;     /* blocks of outer planes                         */
    int64_t blk0;        /* -1, or (a piece of a body, lib/run/piece.c) the
                            whole body's block of block 0: blocks are cut
                            from the whole body's outer plane 0 on, in its
                            lattice coordinates                           */
    int thick;           /* outer planes a block                           */
    int64_t walk;        /* blocks whose bonds the force and energy passes
                            walk: nblocks, or (a piece) up to its own last:
                            the block above is ghosts, whose forces are
                            not wanted                                    */
    int64_t walk_lo;     /* the first block they walk: 0, or (a piece in
                            grid order) the block below its own; the
                            blocks below that put no force on its rows   */
    int64_t clip;        /* 0, or (that piece, when walk_lo is not its
                            own) its first own row: block walk_lo's bonds
                            are walked only where the partner is at or
                            above it, the others join ghosts alone        */
    int64_t *block_run;  /* nblocks + 1: block b holds the runs
                            [block_run[b], block_run[b + 1])               */
    double *block_at;    /* nblocks: where a block's middle particle falls
                            among those of its parity, in [0, 1)           */
    grid_breaks *breaks; /* per block: the bonds broken this step          */
    double *released;    /* per block: their elastic energy, J             */
    double kc;           /* (c_S / delta) V: contact force density per
                            metre of overlap, N/m^4 (seed 000 eq. 14)      */
    /* grid-order copies, through perm only (PMB; NULL in lattice order): */
    double *y[3];        /* positions, m                                   */
    double *f[3];        /* force densities, N/m^3                         */
    double *s0;          /* critical stretch of the previous step          */
    double *s0n;         /* new critical stretch, being computed           */
    /* LPS's per-particle factors of the pair force (pd_grid_lps; lattice
     * order, NULL for PMB), m the weighted volume (m^5 times omega's unit,
     * lib/models/lps.c): */
    double *theta_m;     /* theta_i / m_i, 1/m^5 over omega's unit         */
    double *inv_m;       /* 1 / m_i, 1/m^5 over omega's unit               */
    uint64_t epoch;      /* of the half bonds the masks were built from    */
    int tile;            /* the force pass walks runs as tiles (AVX-512;
                            PMB and LPS)                                   */
    const double *s0n_ready; /* the s0 array the last step's end filled with
                            -inf for the next one's new s0 (PMB, lattice
                            order)                                         */
    double *eb, *ec;     /* n each, grid order: the energies the last bond
                            pass counted (grid_arrays), when energy_ok     */
    int energy_ok;       /* they are those of step energy_step, with the
                            half bonds at energy_epoch                     */
    int64_t energy_step;
    uint64_t energy_epoch;
    /* the file's rows read off the masks (grid_bits.c), made on first use: */
    uint64_t *pos, *neg; /* n: bit k set when g has a partner at d_k, -d_k */
    uint64_t *mirror;    /* n: bit 63 - k the state of g's bond at -d_k    */
    int mirror_ok;       /* mirror holds the masks' bits: made from them
                            once, then each break clears its bit in both
                            (grid_break); a sync of the masks drops it     */
    int rows;            /* 0 not tried, 1 made, -1 the rows cannot be read
                            off (or out of memory)                         */
    double *vsum;        /* the volume of m bonds, as pd_damage sums them  */
    int vsum_ok;         /* 0 not made, 1 made, -1 the volumes differ      */
    double gap;          /* the shortest lattice distance not in the
                            stencil, less the sites' tolerance, m          */
    int status;          /* PD_OK, or the error a parallel pass met        */
};

/* The arrays a force kernel walks, in grid order: the particles' own
 * (lattice order) or pd_grid's copies (through perm). */
typedef struct {
    const double *y0, *y1, *y2, *s0;
    double *f0, *f1, *f2, *s0n;
    double s00, alpha;
    /* the energies counted on the way (pd_sim_energy_next), grid order, J,
     * half of each pair to each end; NULL: not this step */
    double *eb;          /* the intact bonds' elastic energy               */
    double *ec;          /* the contact energy of the stencil pairs        */
    double V;            /* the particles' volume, m^3                     */
} grid_arrays;

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

/* The first block of `phase` (0: even blocks, 1: odd ones, of the whole
 * body: a piece's local block b is its block blk0 + b) the force and
 * energy passes walk. */
static inline int64_t grid_walk0(const pd_grid *G, int phase)
{
    const int64_t b0 = G->blk0 > 0 ? G->blk0 : 0;
    return G->walk_lo + ((b0 + G->walk_lo + phase) & 1);
}

/* The first partner row the bonds of block blk are walked for (grid
 * order): a piece's own first row in the block below its own, else 0.
 * A bond g-j (j = g + shift) is walked when j >= it: a segment's
 * particles from grid_seg_lo on. */
static inline int64_t grid_cut(const pd_grid *G, int64_t blk)
{
    return blk == G->walk_lo ? G->clip : 0;
}

/* The first particle of segment sg walked, its partners cut or above, from
 * particle `from` on: max(sg->lo, from, cut - shift). */
static inline int64_t grid_seg_lo(const grid_seg *sg, int64_t cut, int64_t from)
{
    const int64_t lo = sg->lo > from ? sg->lo : from;
    return lo > cut - sg->shift ? lo : cut - sg->shift;
}

/* A tile (grid_pmb.c, grid_lps.c): GRID_TILE particles of a run from g0,
 * of which those before `own` are the tile before's (the run's last tile
 * is moved back to end with the run).  The lanes of the tile that segment
 * sg walks, its partners cut or above: bit l for particle g0 + l, lanes
 * [*lo, *hi) - g0; 0 when none. */
static inline uint32_t grid_tile_acts(const grid_seg *sg, int64_t cut, int64_t own, int64_t g0,
                                      int64_t *lo, int64_t *hi)
{
    *lo = grid_seg_lo(sg, cut, own);
    *hi = sg->hi < g0 + GRID_TILE ? sg->hi : g0 + GRID_TILE;
    if (*lo >= *hi)
        return 0;
    return (uint32_t)(((UINT64_C(1) << (*hi - g0)) - 1) & ~((UINT64_C(1) << (*lo - g0)) - 1));
}

/* The first particle of run R's tile that starts at t (the last one moved
 * back to end with the run). */
static inline int64_t grid_tile_g0(const grid_run *R, int64_t t)
{
    return R->start + (t + GRID_TILE <= R->len ? t : R->len - GRID_TILE);
}

#if PD_AVX512_KERNELS
/* The lanes of a tile's two halves (8 each) that a segment walks (acts:
 * bit l for lane l), act[h] for half h; `all`: every lane (plain loads
 * and stores, and acts not looked at).  The tiles (tile_seg,
 * theta_tile_seg, lps_tile_seg) take a half with `all || act[h]` and
 * leave out one with no lane of its own (the lanes of the tile before, in
 * a run's last tile moved back): it would load and store nothing and add
 * +0 to the tile's sums, which start at +0 and so are never -0. */
static inline void grid_tile_halves(uint32_t acts, const int all, __mmask8 act[2])
{
    act[0] = all ? (__mmask8)0xff : (__mmask8)acts;
    act[1] = all ? (__mmask8)0xff : (__mmask8)(acts >> 8);
}

/* Eight lanes of a tile (own positions yi0, yi1, yi2; the lanes of `act`,
 * `all`: every lane) against their partners' positions at Y0, Y1, Y2 (a
 * lane outside act loads nothing and takes its own): the bond vectors d,
 * the lengths r and the extensions e = r - L, 0 below eps_machine of
 * extension, operation for operation as the segment loops take them
 * (GRID_PMB_PAIR's dr, GRID_LPS_BODY's and GRID_THETA_BODY's e). */
__attribute__((target("avx512f"))) static inline __attribute__((always_inline)) void
grid_tile_pair(__mmask8 act, const int all, const double *Y0, const double *Y1, const double *Y2,
               __m512d yi0, __m512d yi1, __m512d yi2, __m512d L, __m512d d[3], __m512d *r,
               __m512d *e)
{
    const __m512d xj = all ? _mm512_loadu_pd(Y0) : _mm512_mask_loadu_pd(yi0, act, Y0);
    const __m512d yj = all ? _mm512_loadu_pd(Y1) : _mm512_mask_loadu_pd(yi1, act, Y1);
    const __m512d zj = all ? _mm512_loadu_pd(Y2) : _mm512_mask_loadu_pd(yi2, act, Y2);
    pd_bonds8(xj, yj, zj, yi0, yi1, yi2, L, d, r, e);
}

/* Half h of a tile from g0 against a segment whose partners start at j0
 * (lanes of `act`, `all`: every lane): the lanes whose bond is intact
 * (bit vbit of their mask words) and grid_tile_pair's d, r and e. */
__attribute__((target("avx512f"))) static inline __attribute__((always_inline)) __mmask8
grid_tile_half(const pd_grid *G, const grid_arrays *A, int64_t g0, int64_t j0, int h,
               __mmask8 act, const int all, __m512i vbit, __m512d yi0, __m512d yi1,
               __m512d yi2, __m512d L, __m512d d[3], __m512d *r, __m512d *e)
{
    const int64_t o = j0 + 8 * h;
    const __m512i mw = _mm512_loadu_si512((const void *)(G->mask + g0 + 8 * h));
    grid_tile_pair(act, all, A->y0 + o, A->y1 + o, A->y2 + o, yi0, yi1, yi2, L, d, r, e);
    return _mm512_mask_test_epi64_mask(act, mw, vbit);
}

/* The breaking test and the new s0 of eight lanes of a tile (lanes of
 * `act`, `all`: every lane) whose intact bonds (kmu) have stretches s:
 * returns the lanes whose s passes min(s0 of both ends) (own si, the
 * partners' at A->s0 + o); s00 - alpha s of an intact bond (-inf for
 * another) the larger into the own *sm and the partners' A->s0n + o. */
__attribute__((target("avx512f"))) static inline __attribute__((always_inline)) __mmask8
grid_tile_fail(const grid_arrays *A, int64_t o, __mmask8 act, const int all, __mmask8 kmu,
               __m512d s, __m512d si, __m512d *sm)
{
    const __m512d sj = all ? _mm512_loadu_pd(A->s0 + o) : _mm512_mask_loadu_pd(si, act, A->s0 + o);
    const __mmask8 hb = _mm512_mask_cmp_pd_mask(kmu, s, _mm512_min_pd(si, sj), _CMP_GT_OQ);
    const __m512d tt = _mm512_mask_sub_pd(_mm512_set1_pd(-INFINITY), kmu, _mm512_set1_pd(A->s00),
                                          _mm512_mul_pd(_mm512_set1_pd(A->alpha), s));
    *sm = _mm512_max_pd(tt, *sm);
    const __m512d sn = all ? _mm512_loadu_pd(A->s0n + o) : _mm512_maskz_loadu_pd(act, A->s0n + o);
    if (all)
        _mm512_storeu_pd(A->s0n + o, _mm512_max_pd(tt, sn));
    else
        _mm512_mask_storeu_pd(A->s0n + o, act, _mm512_max_pd(tt, sn));
    return hb;
}

/* Eight lanes' forces on their partners: gx, gy, gz taken from F0, F1, F2
 * for the lanes of `act` (`all`: every lane, plain loads and stores). */
__attribute__((target("avx512f"))) static inline __attribute__((always_inline)) void
grid_tile_sub(__mmask8 act, const int all, double *F0, double *F1, double *F2, __m512d gx,
              __m512d gy, __m512d gz)
{
    if (all) {
        _mm512_storeu_pd(F0, _mm512_sub_pd(_mm512_loadu_pd(F0), gx));
        _mm512_storeu_pd(F1, _mm512_sub_pd(_mm512_loadu_pd(F1), gy));
        _mm512_storeu_pd(F2, _mm512_sub_pd(_mm512_loadu_pd(F2), gz));
    } else {
        _mm512_mask_storeu_pd(F0, act, _mm512_sub_pd(_mm512_maskz_loadu_pd(act, F0), gx));
        _mm512_mask_storeu_pd(F1, act, _mm512_sub_pd(_mm512_maskz_loadu_pd(act, F1), gy));
        _mm512_mask_storeu_pd(F2, act, _mm512_sub_pd(_mm512_maskz_loadu_pd(act, F2), gz));
    }
}

/* A tile's own positions, two halves of 8 from particle g0. */
__attribute__((target("avx512f"))) static inline __attribute__((always_inline)) void
grid_tile_pos(const grid_arrays *A, int64_t g0, __m512d yi0[2], __m512d yi1[2], __m512d yi2[2])
{
    for (int h = 0; h < 2; h++) {
        yi0[h] = _mm512_loadu_pd(A->y0 + g0 + 8 * h);
        yi1[h] = _mm512_loadu_pd(A->y1 + g0 + 8 * h);
        yi2[h] = _mm512_loadu_pd(A->y2 + g0 + 8 * h);
    }
}

/* A tile's own values at its start (grid_tile_add's counterpart): its
 * positions and, with `failure`, its s0 (else 0); its force sums 0 and
 * new s0 -inf. */
__attribute__((target("avx512f"))) static inline __attribute__((always_inline)) void
grid_tile_own(const grid_arrays *A, int64_t g0, const int failure, __m512d yi0[2],
              __m512d yi1[2], __m512d yi2[2], __m512d si[2], __m512d ax[2], __m512d ay[2],
              __m512d az[2], __m512d sm[2])
{
    grid_tile_pos(A, g0, yi0, yi1, yi2);
    for (int h = 0; h < 2; h++) {
        si[h] = failure ? _mm512_loadu_pd(A->s0 + g0 + 8 * h) : _mm512_setzero_pd();
        ax[h] = ay[h] = az[h] = _mm512_setzero_pd();
        sm[h] = _mm512_set1_pd(-INFINITY);
    }
}

/* A tile's own sums into memory at its end: the forces (ax, ay, az; two
 * halves each) added to f0, f1, f2 and, with `failure`, the new s0 (sm)
 * the larger into s0n, for the particles from `own` on (those before are
 * the tile before's). */
__attribute__((target("avx512f"))) static inline __attribute__((always_inline)) void
grid_tile_add(const grid_arrays *A, int64_t g0, int64_t own, const __m512d ax[2],
              const __m512d ay[2], const __m512d az[2], const __m512d sm[2], const int forces,
              const int failure)
{
    double tx[GRID_TILE], ty[GRID_TILE], tz[GRID_TILE], ts[GRID_TILE];
    for (int h = 0; h < 2; h++) {
        _mm512_storeu_pd(tx + 8 * h, ax[h]);
        _mm512_storeu_pd(ty + 8 * h, ay[h]);
        _mm512_storeu_pd(tz + 8 * h, az[h]);
        _mm512_storeu_pd(ts + 8 * h, sm[h]);
    }
    for (int64_t g = own; g < g0 + GRID_TILE; g++) {
        if (forces) {
            A->f0[g] += tx[g - g0];
            A->f1[g] += ty[g - g0];
            A->f2[g] += tz[g - g0];
        }
        if (failure)
            A->s0n[g] = ts[g - g0] > A->s0n[g] ? ts[g - g0] : A->s0n[g];
    }
}
#endif

/* Is block blk (of the phase being walked) the calling thread's?  Each
 * thread takes a contiguous run of the phase's blocks holding about its
 * share of the particles, the same in every pass of every step: a thread
 * then finds in its own caches what it touched in the pass before, and
 * lib/run/sim.c's passes over the particles split them the same way (static
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

/* Rebuild the masks from the half bonds' bits (grid.c); the kernels call
 * it when the half bonds' epoch has moved on. */
void pd_grid_sync(pd_sim *sim, pd_grid *G);
/* G->vsum[m] = the volume of m bonds summed one by one, as pd_damage sums
 * them, up to the longest family, made on first use (grid_bits.c): 1, or
 * 0 when the volumes differ (or out of memory). */
int grid_volume_sums(pd_grid *G, const pd_sim *sim);

/* The energies of now counted into G->eb and G->ec as a bond pass in
 * tiles counts them, to the bit (grid_pmb.c): 1, or 0 when the grid has
 * no tiles, its masks lag behind the half bonds or memory is short. */
int grid_tile_energies(const pd_sim *sim);

/* The two helpers of the force kernels (grid_pmb.c and grid_lps.c) are
 * plain static functions, not inline ones, as they were when the kernels
 * shared one file: the compiler then keeps them out of line as before, and
 * the kernels compile to the same instructions.  (unused: grid.c and
 * grid_energy.c do not call them.) */

/* The energy of a stencil pair of squared length r2 and length r, half to
 * each end, J, with c = grid_energy_c: with `contact`, 1/4 (c_S/delta)
 * (d_k - r)^2 V V when closer than d_k (else 0); otherwise 1/4 c s^2 |xi|
 * nu V V (lib/models/pmb.c's pmb_energy).  The energy pass (grid_energy.c)
 * and the bond pass that counts the energies (grid_pmb.c) both take it,
 * so that they agree bit for bit. */
static inline __attribute__((always_inline)) double grid_pair_energy(const int contact, double r2,
                                                                   double r, double c, double L,
                                                                   double iL, double dc)
{
    if (contact)
        return r2 < dc * dc && r < dc ? c * (dc - r) * (dc - r) : 0.0;
    double dr = r - L;
    dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
    return c * ((dr * iL) * (dr * iL));
}

/* grid_pair_energy's c for offset k and particle volume V. */
static inline double grid_energy_c(const pd_grid *G, int k, double V, const int contact)
{
    return contact ? 0.25 * G->kc * V : 0.25 * G->w[k] * G->len[k] * V;
}

/* May the bond g-j (grid order) break, or is an end of it in a
 * --no-failure set?  Asked only of a bond whose stretch breaks it. */
static inline int grid_may_break(const pd_grid *G, int64_t g, int64_t j)
{
    return G->nofail == NULL || !(G->nofail[g] | G->nofail[j]);
}

/* The broken bond g-j at offset k into a block's list (PMB and LPS):
 * 0, or -1 when out of memory. */
static __attribute__((unused)) int record_break(grid_breaks *bl, int64_t g, int32_t k, int64_t j)
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

/* Bond g-j at offset k breaks (W mask words a particle): its bit cleared
 * in g's mask and, while the mirror holds the masks' bits (W is 1 then),
 * in j's mirror (j is in g's block or the next, as the partner's forces
 * are), and the break recorded: 0, or -1 when out of memory. */
static inline int grid_break(pd_grid *G, int64_t g, int k, int64_t j, int W, grid_breaks *bl)
{
    G->mask[g * W + (k >> 6)] &= ~(UINT64_C(1) << (k & 63));
    if (G->mirror_ok)
        G->mirror[j] &= ~(UINT64_C(1) << (63 - k));
    return record_break(bl, g, k, j);
}

/* The contact forces of the pairs of a segment's chunk [c0, c0 + m) that
 * are closer than d_k (seed 000 eqs. 13-15), both ends; with A->ec their
 * energy too (grid_pair_energy, in the energy pass's order), and with no
 * A->f0 only that. */
static __attribute__((unused)) void seg_contact(const pd_grid *G, const grid_seg *sg,
                                                const grid_arrays *A, int64_t c0, int64_t m,
                                                int W)
{
    const int k = sg->k;
    const uint64_t bit = UINT64_C(1) << (k & 63);
    const double dc = G->dc[k], kc = G->kc, ce = grid_energy_c(G, k, A->V, 1);
    const double *y0 = A->y0, *y1 = A->y1, *y2 = A->y2;
    double *ec = A->ec;
    for (int64_t q = 0; q < m; q++) {
        const int64_t g = c0 + q, j = g + sg->shift;
        const double dx = y0[j] - y0[g], dy = y1[j] - y1[g], dz = y2[j] - y2[g];
        const double r2 = dx * dx + dy * dy + dz * dz;
        const double r = sqrt(r2);
        if (!(r < dc) || !(G->cmask[g * W + (k >> 6)] & bit))
            continue;
        if (ec) {
            const double x = grid_pair_energy(1, r2, r, ce, 0, 0, dc);
            ec[g] += x;
            ec[j] += x;
        }
        if (!(r > 0.0) || A->f0 == NULL) /* NULL: the energies alone */
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

#endif
