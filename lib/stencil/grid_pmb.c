/*
 * grid_pmb.c -- the PMB kernels of the stencil (grid.c explains it): the
 * walk of a segment (seg_bonds), the AVX-512 tiles of the long runs
 * (tile_run), the failure bookkeeping (the broken bonds into the half
 * bonds, their released energy, the new s0) and pd_grid_pmb, which picks
 * a variant per step.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>

#include "stencil/grid_impl.h"

/* The elastic energy of bond i-j at offset k, J: 1/2 c s^2 |xi| nu V V
 * (lib/models/pmb.c's bond_energy with the offset's |xi| and c V nu). */
static double bond_energy(const pd_sim *sim, const pd_grid *G, int64_t i, int64_t j, int k)
{
    const double dx = sim->y[0][j] - sim->y[0][i], dy = sim->y[1][j] - sim->y[1][i],
                 dz = sim->y[2][j] - sim->y[2][i];
    double dr = sqrt(dx * dx + dy * dy + dz * dz) - G->len[k];
    dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
    const double s = dr * G->inv_len[k];
    return 0.5 * s * s * G->len[k] * G->w[k] * sim->p->volume[0];
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

/* The bonds (and contacts) of one segment whose partner is cut or above
 * (grid_cut).  `fused`: one pass that updates both ends as it goes (the
 * shift is at least GRID_SAFE, so the two ends of the lanes of one vector
 * never overlap); otherwise the forces go to scratch first and the two
 * ends are updated in two loops.  Runs shorter than a tile take it. */
static inline __attribute__((always_inline)) int
seg_bonds(pd_grid *G, const grid_seg *sg, int64_t cut, const grid_arrays *A, const int failure,
          const int contact, const int one_word, const int energy, grid_breaks *bl)
{
    const int k = sg->k, W = one_word ? 1 : G->words, word = k >> 6;
    const uint64_t bit = UINT64_C(1) << (k & 63);
    const int64_t shift = sg->shift;
    const double L = G->len[k], iL = G->inv_len[k], w = G->w[k], dc = G->dc[k];
    const double s00 = A->s00, alpha = A->alpha;
    const double *restrict y0 = A->y0, *restrict y1 = A->y1, *restrict y2 = A->y2;
    const double *restrict s0 = A->s0;
    double *f0 = A->f0, *f1 = A->f1, *f2 = A->f2, *s0n = A->s0n, *eb = A->eb;
    const double ce = energy ? grid_energy_c(G, k, A->V, 0) : 0.0;
    const uint64_t *restrict mask = G->mask + word;
    double brk[GRID_CHUNK], gx[GRID_CHUNK], gy[GRID_CHUNK], gz[GRID_CHUNK], t[GRID_CHUNK];
    double xe[GRID_CHUNK];
    const int fused = shift >= GRID_SAFE;
    for (int64_t c0 = grid_seg_lo(sg, cut, 0); c0 < sg->hi; c0 += GRID_CHUNK) {
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
                double b = 0.0;
                if (failure) {
                    const double thr = s0[g] < s0[j] ? s0[g] : s0[j];
                    b = s > thr ? mu : 0.0;
                    const double tt = mu > 0 ? s00 - alpha * s : -INFINITY;
                    s0n[g] = tt > s0n[g] ? tt : s0n[g];
                    s0n[j] = tt > s0n[j] ? tt : s0n[j];
                    brk[q] = b;
                    nbreak += b;
                }
                if (energy) { /* intact after this pass: mu 1, not broken */
                    const double x = mu > b ? grid_pair_energy(0, 0, r, ce, L, iL, dc) : 0.0;
                    eb[g] += x;
                    eb[j] += x;
                }
            }
        } else {
            for (int64_t q = 0; q < m; q++) {
                GRID_PMB_BOND;
                gx[q] = fs * dx;
                gy[q] = fs * dy;
                gz[q] = fs * dz;
                double b = 0.0;
                if (failure) {
                    const double thr = s0[g] < s0[j] ? s0[g] : s0[j];
                    b = brk[q] = s > thr ? mu : 0.0;
                    t[q] = mu > 0 ? s00 - alpha * s : -INFINITY;
                    nbreak += brk[q];
                }
                if (energy)
                    xe[q] = mu > b ? grid_pair_energy(0, 0, r, ce, L, iL, dc) : 0.0;
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
            if (energy) /* both ends bond by bond, as grid_energy.c adds them */
                for (int64_t q = 0; q < m; q++) {
                    eb[c0 + q] += xe[q];
                    eb[c0 + q + shift] += xe[q];
                }
        }
        /* contact: pairs closer than d_k are rare (a compression of 10%
         * and more), so the bond pass only counts them, and a second pass
         * over the chunk adds their forces when there are any */
        if (contact && near > 0)
            seg_contact(G, sg, A, c0, m, W);
        if (failure && nbreak > 0) {
            for (int64_t q = 0; q < m; q++) {
                if (brk[q] == 0)
                    continue;
                const int64_t g = c0 + q, j = g + shift;
                if (grid_may_break(G, g, j)) {
                    if (grid_break(G, g, k, j, W, bl))
                        return -1;
                } else if (energy) {
                    /* kept by --no-failure: intact after this pass after
                     * all, so its energy counts as an intact bond's does */
                    GRID_PMB_PAIR(mask[g * W], y0[g], y1[g], y2[g], y0[j], y1[j], y2[j]);
                    (void)fs;
                    (void)s;
                    const double x = mu > 0 ? grid_pair_energy(0, 0, r, ce, L, iL, dc) : 0.0;
                    eb[g] += x;
                    eb[j] += x;
                }
            }
        }
    }
    return 0;
}

#if PD_AVX512_KERNELS
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
        if (mu > 0 && s > thr && grid_may_break(G, g, j) && grid_break(G, g, k, j, W, bl))
            return -1;
    }
    return 0;
}

/* Of the lanes `gone` of a tile's half (particle g = g8 + lane, partner
 * g + shift), whose bonds' stretch breaks them, those that do break: not
 * kept by --no-failure. */
static __mmask8 tile_gone(const pd_grid *G, int64_t g8, int64_t shift, __mmask8 gone)
{
    for (int l = 0; l < 8; l++)
        if (((gone >> l) & 1) && !grid_may_break(G, g8 + l, g8 + l + shift))
            gone = (__mmask8)(gone & ~(1u << l));
    return gone;
}

/* A tile's two halves (8 lanes each) against one segment: GRID_PMB_PAIR
 * in AVX-512, operation for operation (no fused multiply-adds:
 * tile_breaks must find the same stretches), for the lanes of `acts` (bit
 * l for lane l); the others load nothing and store nothing, and a half
 * without any is left out.  `all`: every lane is active (plain loads and
 * stores).  Both halves are taken a phase at a time (positions and
 * lengths, stretches and force factors, failure, forces) rather than one
 * after the other: the processor then finds the other half's work beside
 * the square roots and divisions each half waits for (the seed's PMB pass
 * about 10% faster on an AMD EPYC Zen 4).  Each array is still read and
 * written half 0 first, so the sums are the same to the bit.  Sets in
 * *near the lanes closer than d_k (contact) and in *brk those whose bond
 * breaks; with `energy` it adds the energies of the bonds intact after
 * the pass to both ends (the tile's own into ea); without `forces`, no
 * force. */
__attribute__((target("avx512f"))) static inline __attribute__((always_inline)) void
tile_seg(const pd_grid *G, const grid_seg *sg, const grid_arrays *A, int64_t g0, uint32_t acts,
         const int all, const int failure, const int contact, const int energy, const int forces,
         const __m512d yi0[2], const __m512d yi1[2], const __m512d yi2[2], const __m512d si[2],
         __m512d ax[2], __m512d ay[2], __m512d az[2], __m512d sm[2], __m512d ea[2],
         __mmask8 *near, __mmask8 *brk)
{
    const __m512d zero = _mm512_setzero_pd(), one = _mm512_set1_pd(1.0);
    const int k = sg->k;
    const __m512i vbit = _mm512_set1_epi64((long long)(UINT64_C(1) << k));
    const __m512d vL = _mm512_set1_pd(G->len[k]), viL = _mm512_set1_pd(G->inv_len[k]);
    const __m512d vw = _mm512_set1_pd(G->w[k]), vdc = _mm512_set1_pd(G->dc[k]);
    const __m512d vce = _mm512_set1_pd(energy ? grid_energy_c(G, k, A->V, 0) : 0.0);
    const int64_t j0 = g0 + sg->shift;
    __mmask8 act[2];
    grid_tile_halves(acts, all, act);
    __m512d d[2][3] = {{zero, zero, zero}, {zero, zero, zero}}, r[2] = {zero, zero},
            dr[2] = {zero, zero}, s[2] = {zero, zero}, fs[2] = {zero, zero};
    __mmask8 kmu[2] = {0, 0}, hb[2] = {0, 0}; /* hb: the lanes whose stretch breaks them */
    for (int h = 0; h < 2; h++) /* positions and lengths */
        if (all || act[h])
            kmu[h] = grid_tile_half(G, A, g0, j0, h, act[h], all, vbit, yi0[h], yi1[h], yi2[h],
                                    vL, d[h], &r[h], &dr[h]);
    for (int h = 0; h < 2; h++) /* stretches and force factors */
        if (all || act[h]) {
            s[h] = _mm512_mul_pd(dr[h], viL);
            const __m512d fb = _mm512_maskz_mul_pd(kmu[h], _mm512_mul_pd(vw, s[h]), one);
            fs[h] = _mm512_maskz_div_pd(_mm512_cmp_pd_mask(r[h], zero, _CMP_GT_OQ), fb, r[h]);
        }
    for (int h = 0; h < 2; h++) /* contact, failure and energies */
        if (all || act[h]) {
            const int64_t o = j0 + 8 * h;
            if (contact)
                *near |= _mm512_mask_cmp_pd_mask(act[h], r[h], vdc, _CMP_LT_OQ);
            if (failure) {
                hb[h] = grid_tile_fail(A, o, act[h], all, kmu[h], s[h], si[h], &sm[h]);
                *brk |= hb[h];
            }
            if (energy) { /* grid_pair_energy's c (s s) of a bond intact after the pass,
                             to the partner in memory, to its own end in the tile's sums */
                const __mmask8 gone =
                    hb[h] && G->nofail ? tile_gone(G, g0 + 8 * h, sg->shift, hb[h]) : hb[h];
                const __m512d x = _mm512_maskz_mul_pd((__mmask8)(kmu[h] & ~gone), vce,
                                                      _mm512_mul_pd(s[h], s[h]));
                _mm512_mask_storeu_pd(
                    A->eb + o, act[h],
                    _mm512_add_pd(_mm512_maskz_loadu_pd(act[h], A->eb + o), x));
                ea[h] = _mm512_add_pd(ea[h], x);
            }
        }
    for (int h = 0; h < 2; h++) /* forces */
        if (all || act[h]) {
            const int64_t o = j0 + 8 * h;
            const __m512d gx = _mm512_mul_pd(fs[h], d[h][0]), gy = _mm512_mul_pd(fs[h], d[h][1]),
                          gz = _mm512_mul_pd(fs[h], d[h][2]);
            ax[h] = _mm512_add_pd(ax[h], gx);
            ay[h] = _mm512_add_pd(ay[h], gy);
            az[h] = _mm512_add_pd(az[h], gz);
            if (forces)
                grid_tile_sub(act[h], all, A->f0 + o, A->f1 + o, A->f2 + o, gx, gy, gz);
        }
}

/* The bonds (and contacts) of a run at least a tile long (one mask word
 * per particle) whose partner is cut or above (grid_cut), a tile of 16
 * consecutive particles at a time (the last
 * one moved back to end with the run; its lanes of the tile before are
 * left out).  A tile walks the run's segments (in tile order) with its own
 * positions, forces and new s0 in registers, so that a bond loads and
 * stores only its partner's: half the memory traffic of seg_bonds.
 * `energy`: the energies of the bonds intact after the pass into A->eb
 * (the partner's half in memory, the tile's own halves summed in
 * registers and added at the tile's end, as its forces are: two masked
 * loads and stores a half fewer, about 5% of a pass that counts them) and
 * those of the contact pairs into A->ec, half to each end; without
 * `forces` (and failure) only them, in the same order to the bit
 * (grid_tile_energies). */
__attribute__((target("avx512f"))) static inline __attribute__((always_inline)) int
tile_run(pd_grid *G, const grid_run *R, int64_t cut, const grid_arrays *A, const int failure,
         const int contact, const int energy, const int forces, grid_breaks *bl)
{
    for (int64_t t = 0; t < R->len; t += GRID_TILE) {
        const int64_t g0 = grid_tile_g0(R, t);
        const int64_t own = R->start + t; /* the lanes before are the last tile's */
        __m512d yi0[2], yi1[2], yi2[2], si[2], ax[2], ay[2], az[2], sm[2];
        grid_tile_own(A, g0, failure, yi0, yi1, yi2, si, ax, ay, az, sm);
        __m512d ea[2] = {_mm512_setzero_pd(), _mm512_setzero_pd()};
        for (int64_t q = R->seg0; q < R[1].seg0; q++) {
            const grid_seg *sg = &G->seg[q];
            int64_t lo, hi;
            const uint32_t acts = grid_tile_acts(sg, cut, own, g0, &lo, &hi);
            if (acts == 0)
                continue;
            __mmask8 near = 0, brk = 0;
            if (acts == 0xffff)
                tile_seg(G, sg, A, g0, acts, 1, failure, contact, energy, forces, yi0, yi1, yi2,
                         si, ax, ay, az, sm, ea, &near, &brk);
            else
                tile_seg(G, sg, A, g0, acts, 0, failure, contact, energy, forces, yi0, yi1, yi2,
                         si, ax, ay, az, sm, ea, &near, &brk);
            if (contact && near)
                seg_contact(G, sg, A, lo, hi - lo, 1);
            if (failure && brk && tile_breaks(G, sg, A, lo, hi, 1, bl))
                return -1;
        }
        grid_tile_add(A, g0, own, ax, ay, az, sm, forces, failure);
        if (energy) {
            double te[GRID_TILE];
            _mm512_storeu_pd(te, ea[0]);
            _mm512_storeu_pd(te + 8, ea[1]);
            for (int64_t g = own; g < g0 + GRID_TILE; g++)
                A->eb[g] += te[g - g0];
        }
    }
    return 0;
}

/* The AVX-512 variants: runs at least a tile long take tile_run, shorter
 * ones seg_bonds. */
#define GRID_TILE_BLOCK(name, failure, contact, energy)                                        \
    __attribute__((target("avx512f"))) static int name(pd_grid *G, int64_t blk,                \
                                                       const grid_arrays *A)                   \
    {                                                                                          \
        const int64_t cut = grid_cut(G, blk);                                                  \
        for (int64_t r = G->block_run[blk]; r < G->block_run[blk + 1]; r++) {                  \
            const grid_run *R = &G->run[r];                                                    \
            if (R->len >= GRID_TILE) {                                                         \
                if (tile_run(G, R, cut, A, failure, contact, energy, 1, &G->breaks[blk]))      \
                    return -1;                                                                 \
            } else                                                                             \
                for (int64_t s = R->seg0; s < R[1].seg0; s++)                                  \
                    if (seg_bonds(G, &G->seg[s], cut, A, failure, contact, 1, energy,          \
                                  &G->breaks[blk]))                                            \
                        return -1;                                                             \
        }                                                                                      \
        return 0;                                                                              \
    }
GRID_TILE_BLOCK(grid_tile_000, PD_BONDS_ELASTIC, 0, 0)
GRID_TILE_BLOCK(grid_tile_010, PD_BONDS_ELASTIC, 1, 0)
GRID_TILE_BLOCK(grid_tile_100, PD_BONDS_FAILURE, 0, 0)
GRID_TILE_BLOCK(grid_tile_110, PD_BONDS_FAILURE, 1, 0)
GRID_TILE_BLOCK(grid_tile_001, PD_BONDS_ELASTIC, 0, 1)
GRID_TILE_BLOCK(grid_tile_011, PD_BONDS_ELASTIC, 1, 1)
GRID_TILE_BLOCK(grid_tile_101, PD_BONDS_FAILURE, 0, 1)
GRID_TILE_BLOCK(grid_tile_111, PD_BONDS_FAILURE, 1, 1)

/* The energies of a short run's segment as seg_bonds counts them (one
 * mask word per particle), bit for bit: the intact bonds', both ends bond
 * by bond, and with `contact` the contact pairs'.  (But for a bond kept by
 * --no-failure in the step its stretch passed s0: seg_bonds adds it after
 * its chunk, this in its place; the sums then differ in rounding.) */
static void seg_energies(const pd_grid *G, const grid_seg *sg, int64_t cut, const grid_arrays *A,
                         const int contact)
{
    const int k = sg->k;
    const int64_t lo = grid_seg_lo(sg, cut, 0);
    const uint64_t bit = UINT64_C(1) << k;
    const double L = G->len[k], iL = G->inv_len[k], w = G->w[k], dc = G->dc[k];
    const double ce = grid_energy_c(G, k, A->V, 0);
    for (int64_t g = lo; g < sg->hi; g++) {
        const int64_t j = g + sg->shift;
        GRID_PMB_PAIR(G->mask[g], A->y0[g], A->y1[g], A->y2[g], A->y0[j], A->y1[j], A->y2[j]);
        (void)fs;
        (void)s;
        const double x = mu > 0 ? grid_pair_energy(0, 0, r, ce, L, iL, dc) : 0.0;
        A->eb[g] += x;
        A->eb[j] += x;
    }
    if (contact && lo < sg->hi)
        seg_contact(G, sg, A, lo, sg->hi - lo, 1);
}

/* The energies of one block as its bond pass with energies counts them. */
__attribute__((target("avx512f"))) static void tile_energy_block(pd_grid *G, int64_t blk,
                                                                 const grid_arrays *A,
                                                                 const int contact)
{
    const int64_t cut = grid_cut(G, blk);
    for (int64_t r = G->block_run[blk]; r < G->block_run[blk + 1]; r++) {
        const grid_run *R = &G->run[r];
        if (R->len < GRID_TILE)
            for (int64_t s = R->seg0; s < R[1].seg0; s++)
                seg_energies(G, &G->seg[s], cut, A, contact);
        else if (contact)
            tile_run(G, R, cut, A, 0, 1, 1, 0, NULL);
        else
            tile_run(G, R, cut, A, 0, 0, 1, 0, NULL);
    }
}
#endif

/* The kernel's variants: with or without failure and contact, with one
 * mask word per particle (up to 64 offsets, delta < 3.3 h: the words load
 * as one vector) or more, and counting the energies or not. */
#define GRID_BLOCK(name, failure, contact, one_word, energy)                                  \
    PD_VECTOR_CLONES static int name(pd_grid *G, int64_t blk, const grid_arrays *A)          \
    {                                                                                         \
        const int64_t cut = grid_cut(G, blk);                                                 \
        for (int64_t s = block_seg0(G, blk); s < block_seg0(G, blk + 1); s++)                 \
            if (seg_bonds(G, &G->seg[s], cut, A, failure, contact, one_word, energy,          \
                          &G->breaks[blk]))                                                   \
                return -1;                                                                    \
        return 0;                                                                             \
    }
GRID_BLOCK(grid_block_000, PD_BONDS_ELASTIC, 0, 0, 0)
GRID_BLOCK(grid_block_010, PD_BONDS_ELASTIC, 1, 0, 0)
GRID_BLOCK(grid_block_100, PD_BONDS_FAILURE, 0, 0, 0)
GRID_BLOCK(grid_block_110, PD_BONDS_FAILURE, 1, 0, 0)
GRID_BLOCK(grid_block_001, PD_BONDS_ELASTIC, 0, 1, 0)
GRID_BLOCK(grid_block_011, PD_BONDS_ELASTIC, 1, 1, 0)
GRID_BLOCK(grid_block_101, PD_BONDS_FAILURE, 0, 1, 0)
GRID_BLOCK(grid_block_111, PD_BONDS_FAILURE, 1, 1, 0)
GRID_BLOCK(grid_energy_000, PD_BONDS_ELASTIC, 0, 0, 1)
GRID_BLOCK(grid_energy_010, PD_BONDS_ELASTIC, 1, 0, 1)
GRID_BLOCK(grid_energy_100, PD_BONDS_FAILURE, 0, 0, 1)
GRID_BLOCK(grid_energy_110, PD_BONDS_FAILURE, 1, 0, 1)
GRID_BLOCK(grid_energy_001, PD_BONDS_ELASTIC, 0, 1, 1)
GRID_BLOCK(grid_energy_011, PD_BONDS_ELASTIC, 1, 1, 1)
GRID_BLOCK(grid_energy_101, PD_BONDS_FAILURE, 0, 1, 1)
GRID_BLOCK(grid_energy_111, PD_BONDS_FAILURE, 1, 1, 1)

typedef int (*grid_block_fn)(pd_grid *, int64_t, const grid_arrays *);
static const grid_block_fn grid_blocks[16] = {
    grid_block_000,  grid_block_001,  grid_block_010,  grid_block_011,
    grid_block_100,  grid_block_101,  grid_block_110,  grid_block_111,
    grid_energy_000, grid_energy_001, grid_energy_010, grid_energy_011,
    grid_energy_100, grid_energy_101, grid_energy_110, grid_energy_111};

/* The energy buffers of a pass that counts them (zeroed; 0 when out of
 * memory: the pass then counts nothing and pd_sim_energy walks the bonds). */
static int energy_buffers(pd_grid *G)
{
    const size_t n = (size_t)(G->n > 0 ? G->n : 1);
    if (G->eb == NULL)
        G->eb = malloc(n * sizeof(double));
    if (G->cmask && G->ec == NULL)
        G->ec = malloc(n * sizeof(double));
    if (G->eb == NULL || (G->cmask && G->ec == NULL))
        return 0;
#pragma omp parallel for schedule(static)
    for (int64_t g = 0; g < G->n; g++) {
        G->eb[g] = 0;
        if (G->ec)
            G->ec[g] = 0;
    }
    return 1;
}

int grid_tile_energies(const pd_sim *sim)
{
#if PD_AVX512_KERNELS
    pd_grid *G = sim->grid;
    /* PMB's: an LPS grid (theta_m) walks tiles too, but not these energies */
    if (!G->tile || G->theta_m || G->epoch != sim->half.epoch || !energy_buffers(G))
        return 0;
    grid_arrays A = {.V = sim->p->volume[0], .eb = G->eb, .ec = G->ec};
    if (G->perm) {
#pragma omp parallel for schedule(static)
        for (int64_t g = 0; g < G->n; g++)
            for (int d = 0; d < 3; d++)
                G->y[d][g] = sim->y[d][G->perm[g]];
        A.y0 = G->y[0], A.y1 = G->y[1], A.y2 = G->y[2];
    } else {
        A.y0 = sim->y[0], A.y1 = sim->y[1], A.y2 = sim->y[2];
    }
    const int contact = G->cmask != NULL;
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel
        for (int64_t blk = grid_walk0(G, phase); blk < G->walk; blk += 2)
            if (grid_mine(G, blk))
                tile_energy_block(G, blk, &A, contact);
    }
    G->energy_ok = 1;
    G->energy_step = sim->step;
    G->energy_epoch = sim->half.epoch;
    return 1;
#else
    (void)sim;
    return 0;
#endif
}

pd_status pd_grid_pmb(pd_sim *sim, pd_bond_mode failure)
{
    pd_grid *G = sim->grid;
    const int64_t n = G->n;
    if (G->epoch != sim->half.epoch) {
        pd_grid_sync(sim, G);
        if (G->status != PD_OK)
            return G->status;
    }
    double tf = pd_wtime();
    grid_arrays A = {.s00 = sim->sc.s00, .alpha = sim->sc.alpha, .V = sim->p->volume[0]};
    /* the energies on the way when the step's are wanted */
    G->energy_ok = 0;
    const int energy = sim->energy_next && energy_buffers(G);
    sim->energy_next = 0;
    if (energy) {
        A.eb = G->eb;
        A.ec = G->ec;
    }
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
    grid_block_fn fn =
        grid_blocks[8 * energy + 4 * (failure != 0) + 2 * contact + (G->words == 1)];
#if PD_AVX512_KERNELS
    static const grid_block_fn tiles[8] = {grid_tile_000, grid_tile_010, grid_tile_100,
                                           grid_tile_110, grid_tile_001, grid_tile_011,
                                           grid_tile_101, grid_tile_111};
    if (G->tile)
        fn = tiles[4 * energy + 2 * (failure != 0) + contact];
#endif
    int bad = 0;
    for (int64_t blk = 0; blk < G->nblocks; blk++)
        G->breaks[blk].n = 0;
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel reduction(| : bad)
        for (int64_t blk = grid_walk0(G, phase); blk < G->walk; blk += 2)
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
            for (int64_t blk = grid_walk0(G, phase); blk < G->walk; blk += 2) {
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
        pd_sim_add_released(sim, G->released, G->nblocks);
        /* the caller swaps s0 and s0_new (lib/models/pmb.c) */
        G->s0n_ready = perm ? NULL : sim->s0;
    }
    if (energy) {
        G->energy_ok = 1;
        G->energy_step = sim->step;
        G->energy_epoch = sim->half.epoch;
    }
    tf += pd_wtime() - t0;
    sim->timers[PD_T_FAILURE] += tf;
    sim->timers[PD_T_BONDS] -= tf;
    return PD_OK;
}
