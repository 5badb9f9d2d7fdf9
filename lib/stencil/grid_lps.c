/*
 * grid_lps.c -- LPS on the stencil (grid.c explains it): the dilatation
 * theta of Algorithm 4, the pair forces of Algorithm 2 and, with failure,
 * the breaking test and the new s0, for bodies in lattice order whose
 * influence function depends on |xi| alone.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>

#include "stencil/grid_impl.h"

/* LPS on the stencil (lib/models/lps.c; omega a function of |xi|, so per offset;
 * the particles in lattice order, so lib/models/lps.c's arrays need no copies).
 * The arithmetic of each bond is lps.c's theta_row and force_row, product
 * for product; each bond is computed once and added to both ends (the pair
 * force t_ij of Algorithm 2 is symmetric: equal volumes, nu_ij = nu_ji). */

/* Algorithm 4's term omega |xi| e nu V of bond g-j (0 when broken), added
 * to the sums of both ends (the bonds of a block whose partner is cut or
 * above, grid_cut); with `energy` also omega e e nu V (energy_row's sum)
 * to sq. */
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
        if (energy) {                                                                          \
            const double q = mu * (om * e * e * V * nu);                                       \
            sq[g] += q;                                                                        \
            sq[j] += q;                                                                        \
        }                                                                                      \
    } while (0)

/* The dilatation sums of segment sg's bonds whose partner is cut or
 * above, both ends in memory; with `energy` also the energy's sums of
 * squared extensions. */
static inline __attribute__((always_inline)) void
theta_seg(const pd_grid *G, const grid_seg *sg, int64_t cut, const grid_arrays *A, double *sum,
          double *sq, double V, const int energy)
{
    const double *restrict y0 = A->y0, *restrict y1 = A->y1, *restrict y2 = A->y2;
    const int W = G->words;
    const int k = sg->k;
    const uint64_t bit = UINT64_C(1) << (k & 63);
    const uint64_t *restrict mask = G->mask + (k >> 6);
    const int64_t shift = sg->shift, lo = grid_seg_lo(sg, cut, 0);
    const double len = G->len[k], om = G->omega[k], oml = om * len, nu = G->nu[k];
    if (shift >= GRID_SAFE) {
#pragma omp simd safelen(GRID_SAFE)
        for (int64_t g = lo; g < sg->hi; g++)
            GRID_THETA_BODY;
    } else
        for (int64_t g = lo; g < sg->hi; g++)
            GRID_THETA_BODY;
}

/* The dilatation sums of one block's bonds, and with `energy` the
 * energy's sums of squared extensions. */
static inline __attribute__((always_inline)) void
theta_walk(const pd_grid *G, int64_t blk, const grid_arrays *A, double *sum, double *sq, double V,
           const int energy)
{
    const int64_t cut = grid_cut(G, blk);
    for (int64_t si = block_seg0(G, blk); si < block_seg0(G, blk + 1); si++)
        theta_seg(G, &G->seg[si], cut, A, sum, sq, V, energy);
}

PD_VECTOR_CLONES static void lps_theta_block(const pd_grid *G, int64_t blk, const grid_arrays *A,
                                             double *sum, double V)
{
    theta_walk(G, blk, A, sum, NULL, V, 0);
}

#if PD_AVX512_KERNELS
/* A dilatation tile's two halves (8 lanes each) against one segment:
 * GRID_THETA_BODY in AVX-512, operation for operation, for the lanes of
 * `acts` (bit l for lane l; `all`: every lane; a half without any is left
 * out); i's sums in registers (own), the partners' in memory.  The halves
 * are taken a phase at a time, as grid_pmb.c's tile_seg takes them, and
 * the sums stay the same to the bit. */
__attribute__((target("avx512f"))) static inline __attribute__((always_inline)) void
theta_tile_seg(const pd_grid *G, const grid_seg *sg, const grid_arrays *A, double *sum, double V,
               int64_t g0, uint32_t acts, const int all, const __m512d yi0[2],
               const __m512d yi1[2], const __m512d yi2[2], __m512d own[2])
{
    const __m512d zero = _mm512_setzero_pd(), one = _mm512_set1_pd(1.0), vV = _mm512_set1_pd(V);
    const int k = sg->k;
    const __m512i vbit = _mm512_set1_epi64((long long)(UINT64_C(1) << k));
    const double len = G->len[k], om = G->omega[k];
    const __m512d vlen = _mm512_set1_pd(len), voml = _mm512_set1_pd(om * len);
    const __m512d vnu = _mm512_set1_pd(G->nu[k]);
    const int64_t j0 = g0 + sg->shift;
    __mmask8 act[2];
    grid_tile_halves(acts, all, act);
    __m512d mu[2] = {zero, zero}, e[2] = {zero, zero};
    for (int h = 0; h < 2; h++) /* extensions */
        if (all || act[h]) {
            __m512d d[3], r;
            mu[h] = _mm512_maskz_mov_pd(grid_tile_half(G, A, g0, j0, h, act[h], all, vbit, yi0[h],
                                                       yi1[h], yi2[h], vlen, d, &r, &e[h]),
                                        one);
        }
    for (int h = 0; h < 2; h++) /* the terms, to both ends */
        if (all || act[h]) {
            double *S = sum + j0 + 8 * h;
            const __m512d c = _mm512_mul_pd(
                mu[h], _mm512_mul_pd(_mm512_mul_pd(_mm512_mul_pd(voml, e[h]), vV), vnu));
            own[h] = _mm512_add_pd(own[h], c);
            if (all)
                _mm512_storeu_pd(S, _mm512_add_pd(_mm512_loadu_pd(S), c));
            else
                _mm512_mask_storeu_pd(S, act[h],
                                      _mm512_add_pd(_mm512_maskz_loadu_pd(act[h], S), c));
        }
}

/* The dilatation sums of a run at least a tile long, as lps_tile_run
 * walks its forces: each bond's term GRID_THETA_BODY's, bit for bit; the
 * sums in another order than theta_seg's. */
__attribute__((target("avx512f"))) static inline __attribute__((always_inline)) void
theta_tile_run(const pd_grid *G, const grid_run *R, int64_t cut, const grid_arrays *A, double *sum,
               double V)
{
    const __m512d zero = _mm512_setzero_pd();
    for (int64_t t = 0; t < R->len; t += GRID_TILE) {
        const int64_t g0 = grid_tile_g0(R, t);
        const int64_t own0 = R->start + t; /* the lanes before are the last tile's */
        __m512d yi0[2], yi1[2], yi2[2], own[2] = {zero, zero};
        grid_tile_pos(A, g0, yi0, yi1, yi2);
        for (int64_t q = R->seg0; q < R[1].seg0; q++) {
            const grid_seg *sg = &G->seg[q];
            int64_t lo, hi;
            const uint32_t acts = grid_tile_acts(sg, cut, own0, g0, &lo, &hi);
            if (acts == 0)
                continue;
            if (acts == 0xffff)
                theta_tile_seg(G, sg, A, sum, V, g0, acts, 1, yi0, yi1, yi2, own);
            else
                theta_tile_seg(G, sg, A, sum, V, g0, acts, 0, yi0, yi1, yi2, own);
        }
        double ts[GRID_TILE];
        for (int h = 0; h < 2; h++)
            _mm512_storeu_pd(ts + 8 * h, own[h]);
        for (int64_t g = own0; g < g0 + GRID_TILE; g++)
            sum[g] += ts[g - g0];
    }
}

/* The dilatation sums of one block: runs at least a tile long in tiles,
 * shorter ones by theta_seg. */
__attribute__((target("avx512f"))) static void lps_theta_tiles(const pd_grid *G, int64_t blk,
                                                               const grid_arrays *A, double *sum,
                                                               double V)
{
    const int64_t cut = grid_cut(G, blk);
    for (int64_t r = G->block_run[blk]; r < G->block_run[blk + 1]; r++) {
        const grid_run *R = &G->run[r];
        if (R->len >= GRID_TILE)
            theta_tile_run(G, R, cut, A, sum, V);
        else
            for (int64_t s = R->seg0; s < R[1].seg0; s++)
                theta_seg(G, &G->seg[s], cut, A, sum, NULL, V, 0);
    }
}
#endif

/* The pair force of bond g-j (Algorithm 2), its force on g and -it on j,
 * and with failure the test and the new s0 of both ends (as seg_bonds).
 * With ta = theta/m and tb = 1/m of each particle (pd_grid.theta_m and
 * inv_m, computed once a step) and per offset c1 = (3K - 5G) V nu omega
 * |xi| and c2 = 15 G V nu omega,
 *   t = c1 (ta_g + ta_j) + c2 (tb_g + tb_j) e,
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

/* The per-offset factors of GRID_LPS_BODY's pair force for offset k:
 * c1 = (3K - 5G) V nu omega |xi| (dil = the pair factor of K and G) and
 * c2 = 15 G V nu omega (shear = G); the segment loop and the tile take
 * them from here, so that their products are the same bits. */
static inline void lps_factors(const pd_grid *G, int k, double V, double dil, double shear,
                               double *c1, double *c2)
{
    *c1 = dil * V * G->nu[k] * G->omega[k] * G->len[k];
    *c2 = PD_LPS_SHEAR_FACTOR * shear * V * G->nu[k] * G->omega[k];
}

/* The pair forces of segment sg's bonds whose partner is cut or above
 * (grid_cut), chunk by chunk, both ends in memory; with `failure` the
 * bonds that break into bl.  0, or -1 when out of memory. */
static inline __attribute__((always_inline)) int
lps_seg(pd_grid *G, const grid_seg *sg, int64_t cut, const grid_arrays *A,
        const double *restrict ta, const double *restrict tb, double V, double dil, double shear,
        const int failure, grid_breaks *bl)
{
    const int W = G->words;
    const double *restrict y0 = A->y0, *restrict y1 = A->y1, *restrict y2 = A->y2;
    const double *restrict s0 = A->s0;
    double *f0 = A->f0, *f1 = A->f1, *f2 = A->f2, *s0n = A->s0n;
    const double s00 = A->s00, alpha = A->alpha;
    double brk[GRID_CHUNK];
    const int k = sg->k;
    const uint64_t bit = UINT64_C(1) << (k & 63);
    const uint64_t *restrict mask = G->mask + (k >> 6);
    const int64_t shift = sg->shift;
    const double len = G->len[k], il = G->inv_len[k], dc = G->dc[k];
    double c1, c2;
    lps_factors(G, k, V, dil, shear, &c1, &c2);
    for (int64_t c0 = grid_seg_lo(sg, cut, 0); c0 < sg->hi; c0 += GRID_CHUNK) {
        const int64_t n = sg->hi - c0 < GRID_CHUNK ? sg->hi - c0 : GRID_CHUNK;
        double nbreak = 0, near = 0;
        if (shift >= GRID_SAFE) {
#pragma omp simd reduction(+ : nbreak, near) safelen(16)
            for (int64_t q = 0; q < n; q++)
                GRID_LPS_BODY;
        } else
            for (int64_t q = 0; q < n; q++)
                GRID_LPS_BODY;
        if (G->cmask && near > 0)
            seg_contact(G, sg, A, c0, n, W);
        if (failure && nbreak > 0)
            for (int64_t q = 0; q < n; q++)
                if (brk[q] > 0 && grid_may_break(G, c0 + q, c0 + q + shift) &&
                    grid_break(G, c0 + q, k, c0 + q + shift, W, bl))
                    return -1;
    }
    return 0;
}

#define GRID_LPS_BLOCK(name, with_failure)                                                     \
    PD_VECTOR_CLONES static int name(pd_grid *G, int64_t blk, const grid_arrays *A,            \
                                     const double *restrict ta, const double *restrict tb,     \
                                     double V, double dil, double shear)                       \
    {                                                                                          \
        const int64_t cut = grid_cut(G, blk);                                                  \
        for (int64_t si = block_seg0(G, blk); si < block_seg0(G, blk + 1); si++)               \
            if (lps_seg(G, &G->seg[si], cut, A, ta, tb, V, dil, shear, with_failure,           \
                        &G->breaks[blk]))                                                      \
                return -1;                                                                     \
        return 0;                                                                              \
    }
GRID_LPS_BLOCK(lps_force_block_0, 0)
GRID_LPS_BLOCK(lps_force_block_1, 1)

#if PD_AVX512_KERNELS
/* An LPS tile's two halves (8 lanes each) against one segment:
 * GRID_LPS_BODY in AVX-512, operation for operation (no fused
 * multiply-adds), for the lanes of `acts` (bit l for lane l; the others
 * load nothing and store nothing, and a half without any is left out;
 * `all`: every lane is).  Own sums in registers, the partners' forces and
 * new s0 in memory.  Both halves' lengths first, then each half's pair
 * force, forces and failure (each array read and written half 0 first).
 * Sets in *near the lanes closer than d_k and in *brk those whose bond
 * breaks: the caller clears and records them after the segment.  (With
 * the breaks taken inside the tile, lane by lane as each half found them,
 * the seed's LPS pass took 1.17 times as long on an AMD EPYC Zen 4; both
 * halves a phase at a time, as tile_seg takes PMB's, gains nothing over
 * this.) */
__attribute__((target("avx512f"))) static inline __attribute__((always_inline)) void
lps_tile_seg(const pd_grid *G, const grid_seg *sg, const grid_arrays *A, const double *ta,
             const double *tb, double V, double dil, double shear, int64_t g0, uint32_t acts,
             const int all, const int failure, const int contact, const __m512d yi0[2],
             const __m512d yi1[2], const __m512d yi2[2], const __m512d tai[2],
             const __m512d tbi[2], const __m512d si[2], __m512d ax[2], __m512d ay[2],
             __m512d az[2], __m512d sm[2], __mmask8 *near, uint32_t *brk)
{
    const __m512d zero = _mm512_setzero_pd(), one = _mm512_set1_pd(1.0);
    const int k = sg->k;
    const __m512i vbit = _mm512_set1_epi64((long long)(UINT64_C(1) << k));
    const __m512d vlen = _mm512_set1_pd(G->len[k]);
    double c1, c2;
    lps_factors(G, k, V, dil, shear, &c1, &c2);
    const __m512d vc1 = _mm512_set1_pd(c1), vc2 = _mm512_set1_pd(c2);
    const int64_t j0 = g0 + sg->shift;
    __mmask8 act[2];
    grid_tile_halves(acts, all, act);
    __m512d d[2][3] = {{zero, zero, zero}, {zero, zero, zero}}, e[2] = {zero, zero},
            r[2] = {zero, zero};
    __mmask8 kmu[2] = {0, 0};
    for (int h = 0; h < 2; h++) /* positions and lengths */
        if (all || act[h]) {
            kmu[h] = grid_tile_half(G, A, g0, j0, h, act[h], all, vbit, yi0[h], yi1[h], yi2[h],
                                    vlen, d[h], &r[h], &e[h]);
            if (contact)
                *near |= _mm512_mask_cmp_pd_mask(act[h], r[h], _mm512_set1_pd(G->dc[k]),
                                                 _CMP_LT_OQ);
        }
    for (int h = 0; h < 2; h++) /* pair forces, forces, failure */
        if (all || act[h]) {
            const int64_t o = j0 + 8 * h;
            const __m512d taj = all ? _mm512_loadu_pd(ta + o)
                                    : _mm512_mask_loadu_pd(tai[h], act[h], ta + o);
            const __m512d tbj = all ? _mm512_loadu_pd(tb + o)
                                    : _mm512_mask_loadu_pd(tbi[h], act[h], tb + o);
            const __m512d t =
                _mm512_add_pd(_mm512_mul_pd(vc1, _mm512_add_pd(tai[h], taj)),
                              _mm512_mul_pd(_mm512_mul_pd(vc2, _mm512_add_pd(tbi[h], tbj)), e[h]));
            const __m512d fb =
                _mm512_maskz_div_pd(_mm512_cmp_pd_mask(r[h], zero, _CMP_GT_OQ),
                                    _mm512_mul_pd(_mm512_maskz_mov_pd(kmu[h], one), t), r[h]);
            const __m512d gx = _mm512_mul_pd(d[h][0], fb), gy = _mm512_mul_pd(d[h][1], fb),
                          gz = _mm512_mul_pd(d[h][2], fb);
            ax[h] = _mm512_add_pd(ax[h], gx);
            ay[h] = _mm512_add_pd(ay[h], gy);
            az[h] = _mm512_add_pd(az[h], gz);
            grid_tile_sub(act[h], all, A->f0 + o, A->f1 + o, A->f2 + o, gx, gy, gz);
            if (failure) {
                const __m512d s = _mm512_mul_pd(e[h], _mm512_set1_pd(G->inv_len[k]));
                *brk |= (uint32_t)grid_tile_fail(A, o, act[h], all, kmu[h], s, si[h], &sm[h])
                        << (8 * h);
            }
        }
}

/* The pair forces of a run at least a tile long (one mask word per
 * particle) whose partner is cut or above (grid_cut), as grid_pmb.c's
 * tile_run walks PMB's: a tile of 16 consecutive particles at a time (the
 * last one moved back to end with the run; its lanes of the tile before
 * left out) walks the run's segments with its own positions, theta/m,
 * 1/m, s0, forces and new s0 in registers, so that a bond loads and
 * stores only its partner's.  Each bond's arithmetic is GRID_LPS_BODY's,
 * bit for bit; the sums are taken in another order than lps_seg's, so the
 * two agree to rounding.  The bonds that break are cleared and recorded
 * after their segment, in lane order. */
__attribute__((target("avx512f"))) static inline __attribute__((always_inline)) int
lps_tile_run(pd_grid *G, const grid_run *R, int64_t cut, const grid_arrays *A,
             const double *ta, const double *tb, double V, double dil, double shear,
             const int failure, grid_breaks *bl)
{
    const int contact = G->cmask != NULL;
    for (int64_t t = 0; t < R->len; t += GRID_TILE) {
        const int64_t g0 = grid_tile_g0(R, t);
        const int64_t own = R->start + t; /* the lanes before are the last tile's */
        __m512d yi0[2], yi1[2], yi2[2], tai[2], tbi[2], si[2], ax[2], ay[2], az[2], sm[2];
        grid_tile_own(A, g0, failure, yi0, yi1, yi2, si, ax, ay, az, sm);
        for (int h = 0; h < 2; h++) {
            tai[h] = _mm512_loadu_pd(ta + g0 + 8 * h);
            tbi[h] = _mm512_loadu_pd(tb + g0 + 8 * h);
        }
        for (int64_t q = R->seg0; q < R[1].seg0; q++) {
            const grid_seg *sg = &G->seg[q];
            int64_t lo, hi;
            const uint32_t acts = grid_tile_acts(sg, cut, own, g0, &lo, &hi);
            if (acts == 0)
                continue;
            __mmask8 near = 0;
            uint32_t brk = 0;
            if (acts == 0xffff)
                lps_tile_seg(G, sg, A, ta, tb, V, dil, shear, g0, acts, 1, failure, contact, yi0,
                             yi1, yi2, tai, tbi, si, ax, ay, az, sm, &near, &brk);
            else
                lps_tile_seg(G, sg, A, ta, tb, V, dil, shear, g0, acts, 0, failure, contact, yi0,
                             yi1, yi2, tai, tbi, si, ax, ay, az, sm, &near, &brk);
            if (contact && near)
                seg_contact(G, sg, A, lo, hi - lo, 1);
            for (int l = 0; brk >> l; l++) { /* breaks are rare */
                const int64_t g = g0 + l, j = g + sg->shift;
                if (((brk >> l) & 1) && grid_may_break(G, g, j) &&
                    grid_break(G, g, sg->k, j, 1, bl))
                    return -1;
            }
        }
        grid_tile_add(A, g0, own, ax, ay, az, sm, 1, failure);
    }
    return 0;
}

/* The AVX-512 variants: runs at least a tile long take lps_tile_run,
 * shorter ones lps_seg. */
#define LPS_TILE_BLOCK(name, with_failure)                                                     \
    __attribute__((target("avx512f"))) static int name(                                        \
        pd_grid *G, int64_t blk, const grid_arrays *A, const double *restrict ta,              \
        const double *restrict tb, double V, double dil, double shear)                         \
    {                                                                                          \
        const int64_t cut = grid_cut(G, blk);                                                  \
        for (int64_t r = G->block_run[blk]; r < G->block_run[blk + 1]; r++) {                  \
            const grid_run *R = &G->run[r];                                                    \
            if (R->len >= GRID_TILE) {                                                         \
                if (lps_tile_run(G, R, cut, A, ta, tb, V, dil, shear, with_failure,            \
                                 &G->breaks[blk]))                                             \
                    return -1;                                                                 \
            } else                                                                             \
                for (int64_t s = R->seg0; s < R[1].seg0; s++)                                  \
                    if (lps_seg(G, &G->seg[s], cut, A, ta, tb, V, dil, shear, with_failure,    \
                                &G->breaks[blk]))                                              \
                        return -1;                                                             \
        }                                                                                      \
        return 0;                                                                              \
    }
LPS_TILE_BLOCK(lps_tile_block_0, 0)
LPS_TILE_BLOCK(lps_tile_block_1, 1)
#endif

/* Of one block's intact bonds (with their partner cut or above), both
 * ends: th += omega |xi| e nu V and sq += omega e e nu V (energy_row's). */
PD_VECTOR_CLONES static void lps_energy_block(const pd_grid *G, int64_t blk, const grid_arrays *A,
                                              double *th, double *sq, double V)
{
    theta_walk(G, blk, A, th, sq, V, 1);
}

int pd_grid_lps_energy(const pd_sim *sim, const double *m, double *e)
{
    pd_grid *G = sim->grid;
    if (G == NULL || G->omega == NULL || G->perm)
        return 0;
    if (G->epoch != sim->half.epoch) { /* the masks of the bonds of now */
        pd_grid_sync((pd_sim *)sim, G);
        if (G->status != PD_OK)
            return 0;
    }
    const int64_t n = G->n;
    double *th = calloc((size_t)(n > 0 ? n : 1), sizeof(double));
    double *sq = calloc((size_t)(n > 0 ? n : 1), sizeof(double));
    if (th == NULL || sq == NULL) {
        free(th);
        free(sq);
        return 0;
    }
    const double V = sim->p->volume[0], K = sim->sc.bulk_modulus, Gs = sim->sc.shear_modulus;
    const grid_arrays A = {.y0 = sim->y[0], .y1 = sim->y[1], .y2 = sim->y[2]};
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel
        for (int64_t blk = grid_walk0(G, phase); blk < G->walk; blk += 2)
            if (grid_mine(G, blk))
                lps_energy_block(G, blk, &A, th, sq, V);
    }
    /* energy_row's: V_i ((K/2 - 5G/6) theta^2 + 15G/2 sum / m_i) */
    const double *Vi = sim->p->volume;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++) {
        if (m[i] == 0.0)
            continue;
        const double t = (PD_LPS_DILATATION / m[i]) * th[i];
        e[i] += Vi[i] * ((0.5 * K - 5.0 * Gs / 6.0) * t * t +
                         0.5 * PD_LPS_SHEAR_FACTOR * Gs / m[i] * sq[i]);
    }
    free(th);
    free(sq);
    return 1;
}

pd_status pd_grid_lps(pd_sim *sim, const double *m, double *theta, pd_bond_mode failure,
                      void (*mark)(void *ctx, int64_t i, int64_t j), void *ctx)
{
    pd_grid *G = sim->grid;
    const int64_t n = G->n;
    if (G->epoch != sim->half.epoch) {
        pd_grid_sync(sim, G);
        if (G->status != PD_OK)
            return G->status;
    }
    const double V = sim->p->volume[0];
    const double dil = PD_LPS_PAIR_FACTOR(sim->sc.bulk_modulus, sim->sc.shear_modulus);
    grid_arrays A = {.y0 = sim->y[0], .y1 = sim->y[1], .y2 = sim->y[2], .f0 = sim->f[0],
                     .f1 = sim->f[1], .f2 = sim->f[2], .s0 = sim->s0, .s0n = sim->s0_new,
                     .s00 = sim->sc.s00, .alpha = sim->sc.alpha};
    /* theta (Algorithm 4): the sums over the bonds, then 3/m_i */
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++)
        theta[i] = 0.0;
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel
        for (int64_t blk = grid_walk0(G, phase); blk < G->walk; blk += 2)
            if (grid_mine(G, blk)) {
#if PD_AVX512_KERNELS
                if (G->tile) {
                    lps_theta_tiles(G, blk, &A, theta, V);
                    continue;
                }
#endif
                lps_theta_block(G, blk, &A, theta, V);
            }
    }
    double *ta = G->theta_m, *tb = G->inv_m;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++)
        theta[i] = m[i] != 0.0 ? (PD_LPS_DILATATION / m[i]) * theta[i] : 0.0;
    if (sim->piece) /* the ghosts' theta from their owners (theirs lack bonds) */
        pd_piece_exchange(sim, &theta, 1);
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++) {
        ta[i] = m[i] != 0.0 ? theta[i] / m[i] : 0.0;
        tb[i] = m[i] != 0.0 ? 1.0 / m[i] : 0.0;
        if (failure)
            sim->s0_new[i] = -INFINITY;
    }
    /* the forces (Algorithm 2) and the breaking test */
    int bad = 0;
    for (int64_t blk = 0; blk < G->nblocks; blk++)
        G->breaks[blk].n = 0;
    typedef int (*lps_block_fn)(pd_grid *, int64_t, const grid_arrays *, const double *,
                                const double *, double, double, double);
    lps_block_fn fn = failure ? lps_force_block_1 : lps_force_block_0;
#if PD_AVX512_KERNELS
    if (G->tile)
        fn = failure ? lps_tile_block_1 : lps_tile_block_0;
#endif
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel reduction(| : bad)
        for (int64_t blk = grid_walk0(G, phase); blk < G->walk; blk += 2)
            if (grid_mine(G, blk))
                bad |= fn(G, blk, &A, ta, tb, V, dil, sim->sc.shear_modulus) != 0;
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
