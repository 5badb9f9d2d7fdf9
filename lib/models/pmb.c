/*
 * pmb.c -- the prototype microelastic brittle (PMB) bond force, seed 000
 * eqs. 5-7 and Algorithm 5; seed 004 eqs. 20-28.
 *
 * For every intact bond i-j with reference length |xi| and current length
 * r = |y_j - y_i|:
 *   s = (r - |xi|) / |xi|                      bond stretch
 *   f_i += c s nu_ij V_j (y_j - y_i) / r       force density on i
 *   f_j -= c s nu_ji V_i (y_j - y_i) / r       force density on j
 * with dr = r - |xi| set to 0 when |dr| < eps_machine (seed 000, "A
 * Numerical Example"), and no force when r = 0.
 *
 * Failure (seed 000 eqs. 8-9, seed 004 eq. 28): a bond breaks when
 * s > min(s0_i, s0_j), with s0 of the *previous* step; after the test,
 *   s0_i(new) = s00 - alpha s_min = max over i's intact bonds of (s00 - alpha s)
 * (DESIGN.md: eq. 9, not Algorithm 5's min line).  s0 starts at +inf, so no
 * bond breaks before the first step's forces are known, and a bond that
 * breaks still carries its force in the step it breaks (LAMMPS peri/pmb).
 * Bonds never heal.
 *
 * The run keeps each bond once (i < j, "half bonds"), so a bond's stretch,
 * test and state are computed once and its force is added to both ends.
 * Rows are cut into blocks of at least the largest row distance j - i of a
 * bond, so a block writes only to itself and the next block; even blocks run
 * in parallel, then odd blocks.  Every force density is summed in an order
 * fixed by the blocks alone: the result does not depend on the thread count.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>

#include "models/model.h"
#include "stencil/grid.h"

#define PMB_CHUNK 256 /* bonds per vector pass */

/* The rows in AVX-512 (pmb_row512; PD_AVX512_KERNELS, state/sim.h) are
 * taken where the processor has AVX-512 F, VL and DQ and PD_NO_AVX512 is
 * not set; any other build or processor walks pmb_row. */
#define PMB_TARGET_AVX512 __attribute__((target("avx512f,avx512vl,avx512dq")))

pd_status pd_half_weights(const pd_particles *p, const pd_bonds *b, double c, pd_half_bonds *h)
{
    const int64_t n = h->n;
    size_t m = (size_t)(h->count > 0 ? h->count : 1);
    h->length = malloc(m * sizeof(double));
    h->w_ij = malloc(m * sizeof(double));
    h->w_ji = malloc(m * sizeof(double));
    if (!h->length || !h->w_ij || !h->w_ji)
        return pd_fail(PD_ERR_NOMEM, "out of memory for %lld bonds", (long long)h->count);
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++) {
        int64_t k = b->offset[i + 1] - (h->offset[i + 1] - h->offset[i]);
        for (int64_t q = h->offset[i]; q < h->offset[i + 1]; q++, k++) {
            h->length[q] = b->length[k];
            /* (c V_j) nu in the order LAMMPS peri/pmb multiplies them */
            h->w_ij[q] = c * p->volume[h->neighbor[q]] * b->vfactor[k];
        }
    }
    /* the mirror j-i of each bond: rows i meet the entries below the
     * diagonal of row j in ascending order, so a cursor per row finds it */
    for (int64_t j = 0; j < n; j++)
        h->cursor[j] = b->offset[j];
    int same = 1;
    for (int64_t i = 0; i < n; i++)
        for (int64_t q = h->offset[i]; q < h->offset[i + 1]; q++) {
            int64_t back = h->cursor[h->neighbor[q]]++;
            h->w_ji[q] = c * p->volume[i] * b->vfactor[back];
            same &= h->w_ji[q] == h->w_ij[q];
        }
    /* equal volumes and radii (any pd-lattice body): one weight per bond,
     * one stream less for the kernel to read */
    if (same) {
        free(h->w_ji);
        h->w_ji = h->w_ij;
    }
    return PD_OK;
}

/* The elastic energy of half bond k of row i, J: 1/2 c s^2 |xi| nu V_i V_j,
 * with the mean of nu_ij and nu_ji (w = c V nu holds the rest). */
static double bond_energy(const pd_sim *sim, int64_t i, int64_t k)
{
    const pd_half_bonds *h = &sim->half;
    const int32_t j = h->neighbor[k];
    const double dx = sim->y[0][j] - sim->y[0][i], dy = sim->y[1][j] - sim->y[1][i],
                 dz = sim->y[2][j] - sim->y[2][i];
    double dr = sqrt(dx * dx + dy * dy + dz * dz) - h->length[k];
    dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
    const double s = dr / h->length[k];
    const double *V = sim->p->volume;
    return 0.25 * s * s * h->length[k] * (h->w_ij[k] * V[i] + h->w_ji[k] * V[j]);
}

/* mu[q] = the state bit of bond c0 + q, q < m (0 or 1): a word at a time,
 * its bits in a loop the compiler vectorizes. */
static inline __attribute__((always_inline)) void chunk_states(const uint64_t *bits, int64_t c0,
                                                               int64_t m, double *mu)
{
    for (int64_t q = 0; q < m;) {
        const int64_t k = c0 + q, take = 64 - (k & 63) < m - q ? 64 - (k & 63) : m - q;
        const uint64_t w = __atomic_load_n(&bits[k >> 6], __ATOMIC_RELAXED) >> (k & 63);
        for (int64_t t = 0; t < take; t++)
            mu[q + t] = (double)((w >> t) & 1);
        q += take;
    }
}

/* The forces of the half bonds of row i (and with `failure` their breaking
 * test and the new s0 of both ends; PD_BONDS_FAILURE_LAWS: each bond's threshold times
 * its kfail, lib/models/materials.c), branch-free so that the arithmetic
 * vectorizes; the scatter to the partners j is a plain loop. */
static inline __attribute__((always_inline)) void pmb_row(pd_sim *sim, int64_t i,
                                                          const pd_bond_mode failure, double *released)
{
    pd_half_bonds *h = &sim->half;
    const double s00 = sim->sc.s00, alpha = sim->sc.alpha;
    const double *restrict y0 = sim->y[0], *restrict y1 = sim->y[1], *restrict y2 = sim->y[2];
    const double *restrict len = h->length, *restrict wij = h->w_ij, *restrict wji = h->w_ji;
    const int32_t *restrict nb = h->neighbor;
    const double *restrict s0 = sim->s0;
    const double *restrict kf = h->kfail;
    double *restrict fx = sim->f[0], *restrict fy = sim->f[1], *restrict fz = sim->f[2];
    double *restrict s0_new = sim->s0_new;
    const double yi0 = y0[i], yi1 = y1[i], yi2 = y2[i];
    const double s0i_old = failure ? s0[i] : 0;
    double ax = 0, ay = 0, az = 0, s0i = -INFINITY;
    double mu[PMB_CHUNK], gx[PMB_CHUNK], gy[PMB_CHUNK], gz[PMB_CHUNK], t[PMB_CHUNK],
        brk[PMB_CHUNK];
    for (int64_t c0 = h->offset[i]; c0 < h->offset[i + 1]; c0 += PMB_CHUNK) {
        const int64_t m = h->offset[i + 1] - c0 < PMB_CHUNK ? h->offset[i + 1] - c0 : PMB_CHUNK;
        chunk_states(h->intact, c0, m, mu);
        for (int64_t q = 0; q < m; q++) {
            const int64_t k = c0 + q;
            const int32_t j = nb[k];
            const double dx = y0[j] - yi0, dy = y1[j] - yi1, dz = y2[j] - yi2;
            const double r = sqrt(dx * dx + dy * dy + dz * dz);
            double dr = r - len[k];
            dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
            const double s = dr / len[k];
            const double fi = r > 0.0 ? wij[k] * s * mu[q] / r : 0.0;
            const double fj = r > 0.0 ? wji[k] * s * mu[q] / r : 0.0;
            ax += fi * dx;
            ay += fi * dy;
            az += fi * dz;
            gx[q] = fj * dx;
            gy[q] = fj * dy;
            gz[q] = fj * dz;
            if (failure) { /* ternaries, not fmin/fmax: they vectorize */
                const double thr = failure == PD_BONDS_FAILURE_LAWS ? kf[k] * (s0i_old < s0[j] ? s0i_old : s0[j])
                                                : s0i_old < s0[j] ? s0i_old : s0[j];
                brk[q] = s > thr ? mu[q] : 0.0;
                t[q] = mu[q] > 0 ? s00 - alpha * s : -INFINITY;
            }
        }
        /* the partners' share, and the per-particle reductions of failure */
        double nbreak = 0;
        for (int64_t q = 0; q < m; q++) {
            const int32_t j = nb[c0 + q];
            fx[j] -= gx[q];
            fy[j] -= gy[q];
            fz[j] -= gz[q];
            if (failure) {
                s0_new[j] = t[q] > s0_new[j] ? t[q] : s0_new[j];
                s0i = t[q] > s0i ? t[q] : s0i;
                nbreak += brk[q];
            }
        }
        if (failure && nbreak > 0)
            for (int64_t q = 0; q < m; q++)
                if (brk[q] > 0 && pd_sim_may_break(sim, i, nb[c0 + q])) {
                    pd_bond_break(h->intact, c0 + q);
                    *released += bond_energy(sim, i, c0 + q);
                }
    }
    fx[i] += ax;
    fy[i] += ay;
    fz[i] += az;
    if (failure)
        s0_new[i] = s0i > s0_new[i] ? s0i : s0_new[i];
}

/* Rows compiled for AVX-512, AVX2 and the baseline, picked at run time. */
PD_VECTOR_CLONES static void pmb_block_elastic(pd_sim *sim, int64_t lo, int64_t hi)
{
    for (int64_t i = lo; i < hi; i++)
        pmb_row(sim, i, PD_BONDS_ELASTIC, NULL);
}

PD_VECTOR_CLONES static void pmb_block_failure(pd_sim *sim, int64_t lo, int64_t hi,
                                               double *released)
{
    for (int64_t i = lo; i < hi; i++)
        pmb_row(sim, i, PD_BONDS_FAILURE, released);
}

/* The same with each bond's own critical stretch (h->kfail). */
PD_VECTOR_CLONES static void pmb_block_failure_laws(pd_sim *sim, int64_t lo, int64_t hi,
                                                    double *released)
{
    for (int64_t i = lo; i < hi; i++)
        pmb_row(sim, i, PD_BONDS_FAILURE_LAWS, released);
}

#if PD_AVX512_KERNELS
/* The bond list in AVX-512, 8 bonds of a row at a time.  The scalar-looking
 * list kernel above gathers each partner's position and s0 from four
 * arrays and scatters its force and new s0 into four more, one element at
 * a time: on a processor whose gathers are slow (AMD Zen 4: about 10 cycles
 * for one of 8 doubles) those moves cost more than the arithmetic.  Here
 * each particle's position and s0 sit in one 32-byte row of h->pack, and
 * its force and new s0 in the next 32 bytes (one cache line a particle):
 * a partner is one aligned 256-bit load, eight partners are turned into
 * four vectors by a transpose in registers (about twice as fast as four
 * gathers on Zen 4), and the partners' updates go back through the
 * inverse transpose as one 256-bit read-modify-write each.  Own sums stay
 * in registers over the row.  The partners of one row are distinct, so
 * the 8 lanes never update one particle twice.  The arithmetic is pmb_row's
 * with one division for its three: q = 1/(|xi| r), the force w dr q and
 * the stretch dr (r q) (the stencil too takes the stretch as a product,
 * dr times 1/|xi|), so the two kernels agree to rounding; each is the same
 * at any thread count. */

/* 8 rows of 4 (a_l b_l c_l d_l, lanes l = 0..7) into 4 vectors of 8. */
PMB_TARGET_AVX512 static inline __attribute__((always_inline)) void
rows_to_lanes(const __m256d r[8], __m512d *a, __m512d *b, __m512d *c, __m512d *d)
{
    const __m512d p0 = _mm512_insertf64x4(_mm512_castpd256_pd512(r[0]), r[4], 1);
    const __m512d p1 = _mm512_insertf64x4(_mm512_castpd256_pd512(r[1]), r[5], 1);
    const __m512d p2 = _mm512_insertf64x4(_mm512_castpd256_pd512(r[2]), r[6], 1);
    const __m512d p3 = _mm512_insertf64x4(_mm512_castpd256_pd512(r[3]), r[7], 1);
    const __m512d q0 = _mm512_unpacklo_pd(p0, p1), q1 = _mm512_unpackhi_pd(p0, p1);
    const __m512d q2 = _mm512_unpacklo_pd(p2, p3), q3 = _mm512_unpackhi_pd(p2, p3);
    const __m512i lo = _mm512_set_epi64(13, 12, 5, 4, 9, 8, 1, 0),
                  hi = _mm512_set_epi64(15, 14, 7, 6, 11, 10, 3, 2);
    *a = _mm512_permutex2var_pd(q0, lo, q2);
    *c = _mm512_permutex2var_pd(q0, hi, q2);
    *b = _mm512_permutex2var_pd(q1, lo, q3);
    *d = _mm512_permutex2var_pd(q1, hi, q3);
}

/* The inverse: 4 vectors of 8 into 8 rows of 4. */
PMB_TARGET_AVX512 static inline __attribute__((always_inline)) void
lanes_to_rows(__m512d a, __m512d b, __m512d c, __m512d d, __m256d r[8])
{
    const __m512d q0 = _mm512_unpacklo_pd(a, b), q1 = _mm512_unpackhi_pd(a, b);
    const __m512d q2 = _mm512_unpacklo_pd(c, d), q3 = _mm512_unpackhi_pd(c, d);
    const __m512i lo = _mm512_set_epi64(13, 12, 5, 4, 9, 8, 1, 0),
                  hi = _mm512_set_epi64(15, 14, 7, 6, 11, 10, 3, 2);
    const __m512d p0 = _mm512_permutex2var_pd(q0, lo, q2), p2 = _mm512_permutex2var_pd(q0, hi, q2);
    const __m512d p1 = _mm512_permutex2var_pd(q1, lo, q3), p3 = _mm512_permutex2var_pd(q1, hi, q3);
    r[0] = _mm512_castpd512_pd256(p0);
    r[4] = _mm512_extractf64x4_pd(p0, 1);
    r[1] = _mm512_castpd512_pd256(p1);
    r[5] = _mm512_extractf64x4_pd(p1, 1);
    r[2] = _mm512_castpd512_pd256(p2);
    r[6] = _mm512_extractf64x4_pd(p2, 1);
    r[3] = _mm512_castpd512_pd256(p3);
    r[7] = _mm512_extractf64x4_pd(p3, 1);
}

/* The state bits of bonds k .. k+7 (those past the last word read 0). */
static inline unsigned bits8(const uint64_t *bits, int64_t k, int64_t nwords)
{
    const int64_t w = k >> 6;
    const int sh = (int)(k & 63);
    uint64_t v = __atomic_load_n(&bits[w], __ATOMIC_RELAXED) >> sh;
    if (sh > 56 && w + 1 < nwords)
        v |= __atomic_load_n(&bits[w + 1], __ATOMIC_RELAXED) << (64 - sh);
    return (unsigned)(v & 0xff);
}

/* The contact of the pairs of `near` (lanes of bonds k.. of row i closer
 * than 0.9 |xi| and the common cap): seed 000 eqs. 13-15 as
 * lib/effects/contact.c computes them, each pair once for both ends, in
 * lane order, into h->pack.  Lost particles are out of contact. */
static void rows_contact(pd_sim *sim, int64_t i, int64_t k, const int64_t *jj, unsigned near,
                         const double *r, const double *dx, const double *dy, const double *dz)
{
    double *pk = sim->half.pack;
    const double *rad = sim->p->radius, *V = sim->p->volume, *len = sim->half.length;
    const double kc = PD_CONTACT_SCALE * sim->sc.c / sim->b->horizon;
    for (int l = 0; l < 8; l++) {
        const int64_t j = jj[l];
        if (!((near >> l) & 1) || (sim->lost && (sim->lost[i] || sim->lost[j])))
            continue;
        const double d = fmin(PD_CONTACT_REF_FRAC * len[k + l],
                              PD_CONTACT_RADIUS_FAC * (rad[i] + rad[j]));
        if (!(r[l] < d) || !(r[l] > 0.0))
            continue;
        const double fs = kc * (r[l] - d) / r[l];
        pk[8 * i + 4] += fs * V[j] * dx[l];
        pk[8 * i + 5] += fs * V[j] * dy[l];
        pk[8 * i + 6] += fs * V[j] * dz[l];
        pk[8 * j + 4] -= fs * V[i] * dx[l];
        pk[8 * j + 5] -= fs * V[i] * dy[l];
        pk[8 * j + 6] -= fs * V[i] * dz[l];
    }
}

#define PMB_ROW_CHUNKS 32 /* chunks of 8 whose breaks a row keeps to the end */

/* The bonds of `brks` (lanes of the n chunks of 8 from bond k of row i)
 * that may break (--no-failure) break, their energy released, in bond
 * order. */
static void row_breaks(pd_sim *sim, int64_t i, int64_t k, const uint8_t *brks, int n,
                       double *released)
{
    for (int c = 0; c < n; c++)
        for (int l = 0; brks[c] >> l; l++) {
            const int64_t b = k + 8 * c + l;
            if (((brks[c] >> l) & 1) && pd_sim_may_break(sim, i, sim->half.neighbor[b])) {
                pd_bond_break(sim->half.intact, b);
                *released += bond_energy(sim, i, b);
            }
        }
}

/* pmb_row on h->pack (its comment holds the maths), 8 bonds at a time; a
 * row's last 8 are masked.  With `failure` the bonds whose stretch breaks
 * them are kept a chunk's lanes at a time and broken after the row's
 * chunks (row_breaks): a chunk reads only its own bonds' bits. */
PMB_TARGET_AVX512 static inline __attribute__((always_inline)) void
pmb_row512(pd_sim *sim, int64_t i, const pd_bond_mode failure, const int contact, const int sym,
           double *released, int64_t nwords)
{
    pd_half_bonds *h = &sim->half;
    double *restrict pk = h->pack;
    const double *restrict len = h->length, *restrict wij = h->w_ij, *restrict wji = h->w_ji;
    const double *restrict kf = h->kfail;
    const int32_t *restrict nb = h->neighbor;
    const int64_t k1 = h->offset[i + 1];
    const __m512d zero = _mm512_setzero_pd(), one = _mm512_set1_pd(1.0);
    const __m512d ninf = _mm512_set1_pd(-INFINITY), vnz = _mm512_set1_pd(PD_NEAR_ZERO);
    const __m512d vs00 = _mm512_set1_pd(sim->sc.s00), valpha = _mm512_set1_pd(sim->sc.alpha);
    const __m512d vref = _mm512_set1_pd(PD_CONTACT_REF_FRAC), vcap = _mm512_set1_pd(h->contact_cap);
    const __m512d yi0 = _mm512_set1_pd(pk[8 * i]), yi1 = _mm512_set1_pd(pk[8 * i + 1]),
                  yi2 = _mm512_set1_pd(pk[8 * i + 2]), s0i = _mm512_set1_pd(pk[8 * i + 3]);
    __m512d ax = zero, ay = zero, az = zero, sm = ninf;
    uint8_t brks[PMB_ROW_CHUNKS]; /* each chunk's breaking lanes, from kbrk on */
    int nbrk = 0;
    int64_t kbrk = h->offset[i];
    unsigned anybrk = 0;
    for (int64_t k = h->offset[i]; k < k1; k += 8) {
        const int m = k1 - k < 8 ? (int)(k1 - k) : 8;
        const __mmask8 act = (__mmask8)(m == 8 ? 0xff : (1u << m) - 1);
        const __mmask8 kmu = (__mmask8)(act & bits8(h->intact, k, nwords));
        int64_t jj[8];
        __m256d row[8];
        for (int l = 0; l < 8; l++) { /* a lane past the row reads its own row */
            jj[l] = l < m ? nb[k + l] : i;
            row[l] = _mm256_load_pd(pk + 8 * jj[l]);
        }
        __m512d xj, yj, zj, sj;
        rows_to_lanes(row, &xj, &yj, &zj, &sj);
        const __m512d L = _mm512_mask_loadu_pd(one, act, len + k);
        const __m512d dx = _mm512_sub_pd(xj, yi0), dy = _mm512_sub_pd(yj, yi1),
                      dz = _mm512_sub_pd(zj, yi2);
        const __m512d r = _mm512_sqrt_pd(_mm512_add_pd(
            _mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)), _mm512_mul_pd(dz, dz)));
        __m512d dr = _mm512_sub_pd(r, L);
        dr = _mm512_mask_mov_pd(dr, _mm512_cmp_pd_mask(_mm512_abs_pd(dr), vnz, _CMP_LT_OQ), zero);
        /* one division for both: q = 1/(|xi| r), s/r = dr q, s = dr (r q)
         * (dr/|xi| itself where r = 0) */
        const __mmask8 pos = _mm512_mask_cmp_pd_mask(act, r, zero, _CMP_GT_OQ);
        const __m512d q = _mm512_maskz_div_pd(pos, one, _mm512_mul_pd(L, r));
        const __m512d g = _mm512_maskz_mul_pd((__mmask8)(kmu & pos), dr, q);
        /* the force on i, and (the same unless the weights differ) j's */
        const __m512d fi = _mm512_mul_pd(_mm512_maskz_loadu_pd(act, wij + k), g);
        const __m512d gx = _mm512_mul_pd(fi, dx), gy = _mm512_mul_pd(fi, dy),
                      gz = _mm512_mul_pd(fi, dz);
        ax = _mm512_add_pd(ax, gx);
        ay = _mm512_add_pd(ay, gy);
        az = _mm512_add_pd(az, gz);
        __m512d hx = gx, hy = gy, hz = gz;
        if (!sym) {
            const __m512d fj = _mm512_mul_pd(_mm512_maskz_loadu_pd(act, wji + k), g);
            hx = _mm512_mul_pd(fj, dx);
            hy = _mm512_mul_pd(fj, dy);
            hz = _mm512_mul_pd(fj, dz);
        }
        __m512d t = zero;
        __mmask8 brk = 0;
        if (failure) {
            __m512d s = _mm512_mul_pd(dr, _mm512_mul_pd(r, q));
            if ((__mmask8)(act & ~pos))
                s = _mm512_mask_div_pd(s, (__mmask8)(act & ~pos), dr, L);
            __m512d thr = _mm512_min_pd(s0i, sj);
            if (failure == PD_BONDS_FAILURE_LAWS)
                thr = _mm512_mul_pd(_mm512_maskz_loadu_pd(act, kf + k), thr);
            brk = _mm512_mask_cmp_pd_mask(kmu, s, thr, _CMP_GT_OQ);
            t = _mm512_mask_sub_pd(ninf, kmu, vs00, _mm512_mul_pd(valpha, s));
            sm = _mm512_max_pd(sm, t);
        }
        __m256d out[8];
        lanes_to_rows(hx, hy, hz, t, out);
        for (int l = 0; l < m; l++) {
            double *p = pk + 8 * jj[l] + 4;
            const __m256d v = _mm256_load_pd(p);
            __m256d nv = _mm256_sub_pd(v, out[l]);
            if (failure) /* the new s0: the larger */
                nv = _mm256_mask_max_pd(nv, 0x8, v, out[l]);
            _mm256_store_pd(p, nv);
        }
        /* contact: any pair of the row, intact or not, closer than its
         * d_ij (or, with radii of their own, than 0.9 |xi|); rare */
        const __mmask8 near =
            contact ? _mm512_mask_cmp_pd_mask(act, r, _mm512_min_pd(_mm512_mul_pd(vref, L), vcap),
                                              _CMP_LT_OQ)
                    : 0;
        if (near) {
            double rr[8], ex[8], ey[8], ez[8];
            _mm512_storeu_pd(rr, r);
            _mm512_storeu_pd(ex, dx);
            _mm512_storeu_pd(ey, dy);
            _mm512_storeu_pd(ez, dz);
            rows_contact(sim, i, k, jj, near, rr, ex, ey, ez);
        }
        if (failure) { /* the breaks after the chunks, in bond order */
            if (nbrk == PMB_ROW_CHUNKS) {
                row_breaks(sim, i, kbrk, brks, nbrk, released);
                kbrk = k;
                nbrk = 0;
            }
            brks[nbrk++] = brk;
            anybrk |= brk;
        }
    }
    if (anybrk)
        row_breaks(sim, i, kbrk, brks, nbrk, released);
    double *p = pk + 8 * i + 4;
    p[0] += _mm512_reduce_add_pd(ax);
    p[1] += _mm512_reduce_add_pd(ay);
    p[2] += _mm512_reduce_add_pd(az);
    if (failure) {
        const double s0 = _mm512_reduce_max_pd(sm);
        p[3] = s0 > p[3] ? s0 : p[3];
    }
}

/* The rows of a block, a variant per failure mode, contact and symmetric
 * weights (w_ji the same array as w_ij: one force for both ends). */
#define PMB_ROWS(mode, contact)                                                                \
    do {                                                                                       \
        if (sim->half.w_ji == sim->half.w_ij)                                                  \
            for (int64_t i = lo; i < hi; i++)                                                  \
                pmb_row512(sim, i, mode, contact, 1, released, nwords);                        \
        else                                                                                   \
            for (int64_t i = lo; i < hi; i++)                                                  \
                pmb_row512(sim, i, mode, contact, 0, released, nwords);                        \
    } while (0)

PMB_TARGET_AVX512 static void pmb_block512(pd_sim *sim, int64_t lo, int64_t hi,
                                           const pd_bond_mode failure, double *released)
{
    const int64_t nwords = pd_bits_words(sim->half.count);
    const int contact = sim->half.contact;
    if (failure == PD_BONDS_FAILURE_LAWS && contact)
        PMB_ROWS(PD_BONDS_FAILURE_LAWS, 1);
    else if (failure == PD_BONDS_FAILURE_LAWS)
        PMB_ROWS(PD_BONDS_FAILURE_LAWS, 0);
    else if (failure && contact)
        PMB_ROWS(PD_BONDS_FAILURE, 1);
    else if (failure)
        PMB_ROWS(PD_BONDS_FAILURE, 0);
    else if (contact)
        PMB_ROWS(PD_BONDS_ELASTIC, 1);
    else
        PMB_ROWS(PD_BONDS_ELASTIC, 0);
}

/* The energies in the rows (rows_energy): h->pack holds each particle's
 * position and, in the place of its s0, its volume.  Row i's partners j
 * are loaded and transposed as pmb_row512 does. */
PMB_TARGET_AVX512 static inline __attribute__((always_inline)) void
rows_partners(const double *pk, const int32_t *nb, int64_t i, int64_t k, int m, int64_t jj[8],
              __m512d *xj, __m512d *yj, __m512d *zj, __m512d *vj)
{
    __m256d row[8];
    for (int l = 0; l < 8; l++) { /* a lane past the row reads its own row */
        jj[l] = l < m ? nb[k + l] : i;
        row[l] = _mm256_load_pd(pk + 8 * jj[l]);
    }
    rows_to_lanes(row, xj, yj, zj, vj);
}

/* The elastic energy of the intact half bonds of row i, pmb_energy_uniform's
 * 1/4 c s^2 |xi| nu_ij V_i V_j to i and 1/4 c s^2 |xi| nu_ji V_j V_i to j
 * (w = c V nu holds c, nu and the other end's volume): i's summed in
 * registers over the row, each partner's added to e[j] in bond order. */
PMB_TARGET_AVX512 static void energy_row512(const pd_sim *sim, int64_t i, double *e,
                                            int64_t nwords)
{
    const pd_half_bonds *h = &sim->half;
    const double *restrict pk = h->pack;
    const double *restrict len = h->length, *restrict wij = h->w_ij, *restrict wji = h->w_ji;
    const int64_t k1 = h->offset[i + 1];
    const __m512d zero = _mm512_setzero_pd(), one = _mm512_set1_pd(1.0);
    const __m512d vnz = _mm512_set1_pd(PD_NEAR_ZERO), quarter = _mm512_set1_pd(0.25);
    const __m512d yi0 = _mm512_set1_pd(pk[8 * i]), yi1 = _mm512_set1_pd(pk[8 * i + 1]),
                  yi2 = _mm512_set1_pd(pk[8 * i + 2]);
    __m512d own = zero;
    for (int64_t k = h->offset[i]; k < k1; k += 8) {
        const int m = k1 - k < 8 ? (int)(k1 - k) : 8;
        const __mmask8 act = (__mmask8)(m == 8 ? 0xff : (1u << m) - 1);
        const __mmask8 kmu = (__mmask8)(act & bits8(h->intact, k, nwords));
        int64_t jj[8];
        __m512d xj, yj, zj, vj;
        rows_partners(pk, h->neighbor, i, k, m, jj, &xj, &yj, &zj, &vj);
        const __m512d L = _mm512_mask_loadu_pd(one, act, len + k);
        const __m512d dx = _mm512_sub_pd(xj, yi0), dy = _mm512_sub_pd(yj, yi1),
                      dz = _mm512_sub_pd(zj, yi2);
        const __m512d r = _mm512_sqrt_pd(_mm512_add_pd(
            _mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)), _mm512_mul_pd(dz, dz)));
        __m512d dr = _mm512_sub_pd(r, L);
        dr = _mm512_mask_mov_pd(dr, _mm512_cmp_pd_mask(_mm512_abs_pd(dr), vnz, _CMP_LT_OQ), zero);
        const __m512d s = _mm512_div_pd(dr, L);
        /* 1/4 s^2 |xi|, 0 for a broken bond */
        const __m512d x = _mm512_maskz_mul_pd(kmu, _mm512_mul_pd(_mm512_mul_pd(quarter, s), s), L);
        own = _mm512_add_pd(own, _mm512_mul_pd(x, _mm512_maskz_loadu_pd(act, wij + k)));
        double to[8];
        _mm512_storeu_pd(to, _mm512_mul_pd(_mm512_mul_pd(x, _mm512_maskz_loadu_pd(act, wji + k)),
                                           vj));
        for (int l = 0; l < m; l++)
            e[jj[l]] += to[l];
    }
    e[i] += _mm512_reduce_add_pd(own) * pk[8 * i + 3];
}

/* The contact energy of the pairs of row i (intact or not; neither end
 * lost): pd_half_contact_energy's 1/4 (c_S/delta) (d - r)^2 V_i V_j to
 * each end, i's summed over the row in bond order.  Pairs closer than d
 * are rare: the lanes compare r^2 with d^2 (d's bound over the radii,
 * h->contact_cap; d^2 enlarged by 1e-12, so that rounding drops no pair)
 * and only those within it are looked at one by one. */
PMB_TARGET_AVX512 static void contact_row512(const pd_sim *sim, int64_t i, double *e)
{
    const pd_half_bonds *h = &sim->half;
    const double *restrict pk = h->pack, *len = h->length, *rad = sim->p->radius;
    const double kc = PD_CONTACT_SCALE * sim->sc.c / sim->b->horizon;
    const int64_t k1 = h->offset[i + 1];
    const __m512d one = _mm512_set1_pd(1.0), vref = _mm512_set1_pd(PD_CONTACT_REF_FRAC),
                  vcap = _mm512_set1_pd(h->contact_cap);
    /* d^2 a little enlarged: no pair with r < d has r^2 above it */
    const __m512d enlarge = _mm512_set1_pd(1.0 + 1e-12);
    const __m512d yi0 = _mm512_set1_pd(pk[8 * i]), yi1 = _mm512_set1_pd(pk[8 * i + 1]),
                  yi2 = _mm512_set1_pd(pk[8 * i + 2]);
    if (sim->lost && sim->lost[i])
        return;
    double own = 0;
    for (int64_t k = h->offset[i]; k < k1; k += 8) {
        const int m = k1 - k < 8 ? (int)(k1 - k) : 8;
        const __mmask8 act = (__mmask8)(m == 8 ? 0xff : (1u << m) - 1);
        int64_t jj[8];
        __m512d xj, yj, zj, vj;
        rows_partners(pk, h->neighbor, i, k, m, jj, &xj, &yj, &zj, &vj);
        const __m512d dx = _mm512_sub_pd(xj, yi0), dy = _mm512_sub_pd(yj, yi1),
                      dz = _mm512_sub_pd(zj, yi2);
        const __m512d r2 = _mm512_add_pd(
            _mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)), _mm512_mul_pd(dz, dz));
        const __m512d d =
            _mm512_min_pd(_mm512_mul_pd(vref, _mm512_mask_loadu_pd(one, act, len + k)), vcap);
        const __mmask8 near = _mm512_mask_cmp_pd_mask(
            act, r2, _mm512_mul_pd(_mm512_mul_pd(d, d), enlarge), _CMP_LT_OQ);
        if (!near)
            continue;
        double rr[8];
        _mm512_storeu_pd(rr, r2);
        for (int l = 0; l < m; l++) {
            const int64_t j = jj[l];
            if (!((near >> l) & 1) || (sim->lost && sim->lost[j]))
                continue;
            const double d0 = PD_CONTACT_REF_FRAC * len[k + l],
                         d1 = PD_CONTACT_RADIUS_FAC * (rad[i] + rad[j]);
            const double dl = d0 < d1 ? d0 : d1, rl = sqrt(rr[l]);
            if (!(rl < dl))
                continue;
            const double x = 0.25 * kc * (dl - rl) * (dl - rl);
            own += x * pk[8 * j + 3];
            e[j] += x * pk[8 * i + 3] * pk[8 * j + 3];
        }
    }
    e[i] += own * pk[8 * i + 3];
}

PMB_TARGET_AVX512 static void energy_block512(const pd_sim *sim, int64_t lo, int64_t hi,
                                              int contact, double *e)
{
    const int64_t nwords = pd_bits_words(sim->half.count);
    for (int64_t i = lo; i < hi; i++)
        if (contact)
            contact_row512(sim, i, e);
        else
            energy_row512(sim, i, e, nwords);
}
#endif

/* The rows [*lo, *hi) of block blk that the list's passes walk: the whole
 * block, but a piece's block below its own from its first row with a
 * partner of the piece's own (pd_half_bonds.clip; the partners ascend). */
static void block_rows(const pd_half_bonds *h, int64_t blk, int64_t n, int64_t *lo, int64_t *hi)
{
    *lo = blk * h->block;
    *hi = *lo + h->block < n ? *lo + h->block : n;
    if (blk == h->walk_lo && h->clip > 0)
        while (*lo < *hi && (h->offset[*lo + 1] == h->offset[*lo] ||
                             h->neighbor[h->offset[*lo + 1] - 1] < h->clip))
            (*lo)++;
}

/* e_i += the elastic energy (contact 0) or the contact energy (1) of
 * particle i in the AVX-512 rows, where this run has them: 1, else 0 (the
 * families then).  A pass of the half bonds, each bond once for both ends,
 * in the blocks' order as the forces are (the same sums at any thread
 * count); h->pack, the rows' scratch, takes the positions and volumes. */
static int rows_energy(const pd_sim *sim, double *e, int contact)
{
#if PD_AVX512_KERNELS
    const pd_half_bonds *h = &sim->half;
    if (!h->pack || (!contact && pd_scene_has_laws(&sim->sc)) || (contact && !h->contact))
        return 0;
    double *pk = h->pack;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        pk[8 * i] = sim->y[0][i];
        pk[8 * i + 1] = sim->y[1][i];
        pk[8 * i + 2] = sim->y[2][i];
        pk[8 * i + 3] = sim->p->volume[i];
    }
    for (int phase = 0; phase < 2; phase++) {
        const int64_t first = h->walk_lo + ((h->blk0 + h->walk_lo + phase) & 1);
#pragma omp parallel for schedule(dynamic, 1)
        for (int64_t blk = first; blk < h->walk; blk += 2) {
            int64_t lo, hi;
            block_rows(h, blk, sim->n, &lo, &hi);
            energy_block512(sim, lo, hi, contact, e);
        }
    }
    return 1;
#else
    (void)sim;
    (void)e;
    (void)contact;
    return 0;
#endif
}

void pd_half_contact_energy(const pd_sim *sim, double *e)
{
    if (!sim->half.contact || rows_energy(sim, e, 1))
        return;
    const pd_bonds *b = sim->b;
    const double k = PD_CONTACT_SCALE * sim->sc.c / b->horizon;
    const double *V = sim->p->volume, *rad = sim->p->radius;
    double *const *y = sim->y;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        if (sim->lost && sim->lost[i])
            continue;
        double sum = 0;
        for (int64_t q = b->offset[i]; q < b->offset[i + 1]; q++) {
            const int32_t j = b->neighbor[q];
            if (sim->lost && sim->lost[j])
                continue;
            const double dx = y[0][j] - y[0][i], dy = y[1][j] - y[1][i], dz = y[2][j] - y[2][i];
            const double r2 = dx * dx + dy * dy + dz * dz;
            const double d0 = PD_CONTACT_REF_FRAC * b->length[q],
                         d1 = PD_CONTACT_RADIUS_FAC * (rad[i] + rad[j]);
            const double d = d0 < d1 ? d0 : d1; /* fmin, inlined */
            if (!(r2 < d * d)) /* most pairs: no square root */
                continue;
            const double r = sqrt(r2);
            if (r < d)
                sum += 0.25 * k * (d - r) * (d - r) * V[j];
        }
        e[i] += sum * V[i];
    }
}

double pd_half_contact_cap(const pd_particles *p)
{
    double rmin = INFINITY, rmax = 0;
    for (int64_t i = 0; i < p->n; i++) {
        rmin = fmin(rmin, p->radius[i]);
        rmax = fmax(rmax, p->radius[i]);
    }
    rmin = -pd_body_max(p, -rmin); /* a window: over the ranks */
    rmax = pd_body_max(p, rmax);
    return rmin == rmax ? PD_CONTACT_RADIUS_FAC * (rmax + rmax) : INFINITY;
}

/* Does this run take the AVX-512 rows?  Then h->pack is there. */
static pd_status pmb_rows_init(pd_sim *sim)
{
#if PD_AVX512_KERNELS
    pd_half_bonds *h = &sim->half;
    if (h->pack || !__builtin_cpu_supports("avx512f") || !__builtin_cpu_supports("avx512vl") ||
        !__builtin_cpu_supports("avx512dq") || getenv("PD_NO_AVX512"))
        return PD_OK;
    size_t bytes = (size_t)(sim->n > 0 ? sim->n : 1) * 8 * sizeof(double);
    if ((h->pack = aligned_alloc(64, bytes)) == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the bond list's rows");
    if (!sim->sc.has_contact)
        return PD_OK;
    /* the rows take the contact of the half bonds' pairs; the contact list
     * the others, which started at least `gap` apart (the horizon, unless
     * the families leave out a closer pair) */
    pd_status s = pd_half_gap(h, sim->b, sim->p, &h->gap);
    if (s != PD_OK)
        return s;
    h->contact_cap = pd_half_contact_cap(sim->p);
    h->contact = 1;
#else
    (void)sim;
#endif
    return PD_OK;
}

/* The blocks of the half bonds: even blocks in parallel, then odd ones (of
 * the whole body, pd_half_bonds.blk0; a block writes only to itself and
 * the next).  Every sum is in an order the
 * blocks fix, whatever the thread count.  A piece's block below its own is
 * walked from its first row with a partner of the piece's own
 * (pd_half_bonds.clip; the partners ascend). */
static void pmb_blocks(pd_sim *sim, pd_bond_mode failure)
{
    const pd_half_bonds *h = &sim->half;
    for (int phase = 0; phase < 2; phase++) {
        const int64_t first = h->walk_lo + ((h->blk0 + h->walk_lo + phase) & 1);
#pragma omp parallel for schedule(dynamic, 1)
        for (int64_t blk = first; blk < h->walk; blk += 2) {
            int64_t lo, hi;
            block_rows(h, blk, sim->n, &lo, &hi);
            if (failure)
                h->released[blk] = 0;
#if PD_AVX512_KERNELS
            if (h->pack) {
                pmb_block512(sim, lo, hi, failure, &h->released[blk]);
                continue;
            }
#endif
            if (failure == PD_BONDS_FAILURE_LAWS)
                pmb_block_failure_laws(sim, lo, hi, &h->released[blk]);
            else if (failure)
                pmb_block_failure(sim, lo, hi, &h->released[blk]);
            else
                pmb_block_elastic(sim, lo, hi);
        }
    }
}

static void pmb_kernel(pd_sim *sim, pd_bond_mode failure)
{
    const pd_half_bonds *h = &sim->half;
    double *restrict pk = h->pack;
    /* failure's bookkeeping outside the fused loop (the s0_new reset and
     * finish, the released-energy sum) goes to its own timer, taken out of
     * the bonds' one that pd_sim_compute_forces charges the whole call to;
     * the rows' copy in and out, which does the reset and finish too, is
     * the bonds' */
    double tf = 0, t0;
    if (pk) /* the rows' copy: positions and s0, forces 0 and new s0 -inf */
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < sim->n; i++) {
            double *p = pk + 8 * i;
            p[0] = sim->y[0][i];
            p[1] = sim->y[1][i];
            p[2] = sim->y[2][i];
            p[3] = failure ? sim->s0[i] : 0.0;
            p[4] = p[5] = p[6] = 0.0;
            p[7] = -INFINITY;
        }
    else if (failure) {
        t0 = pd_wtime();
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < sim->n; i++)
            sim->s0_new[i] = -INFINITY;
        tf += pd_wtime() - t0;
    }
    pmb_blocks(sim, !failure ? PD_BONDS_ELASTIC : h->kfail ? PD_BONDS_FAILURE_LAWS : failure);
    if (pk) /* the rows' forces added to the step's, and their new s0 */
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < sim->n; i++) {
            const double *p = pk + 8 * i + 4;
            sim->f[0][i] += p[0];
            sim->f[1][i] += p[1];
            sim->f[2][i] += p[2];
            if (failure) /* no intact bond: +inf (DBL_MAX, as LAMMPS) */
                sim->s0_new[i] = p[3] == -INFINITY ? DBL_MAX : p[3];
        }
    if (!failure)
        return;
    t0 = pd_wtime();
    if (!pk)
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < sim->n; i++) /* no intact bond: +inf (DBL_MAX, as LAMMPS) */
            if (sim->s0_new[i] == -INFINITY)
                sim->s0_new[i] = DBL_MAX;
    pd_sim_add_released(sim, h->released, h->nblocks); /* in block order: any thread count */
    tf += pd_wtime() - t0;
    sim->timers[PD_T_FAILURE] += tf;
    sim->timers[PD_T_BONDS] -= tf;
}

static pd_status pmb_force(pd_sim *sim, void *state)
{
    (void)state;
    if (sim->grid)
        return pd_grid_pmb(sim, PD_BONDS_ELASTIC);
    pmb_kernel(sim, PD_BONDS_ELASTIC);
    return PD_OK;
}

static pd_status pmb_failure_force(pd_sim *sim, void *state)
{
    (void)state;
    if (sim->setup) {
        /* the initial state: forces only; s0 stays +inf (seed 000,
         * "Breaking Bonds": no bond breaks before the second step) */
        if (sim->grid)
            return pd_grid_pmb(sim, PD_BONDS_ELASTIC);
        pmb_kernel(sim, PD_BONDS_ELASTIC);
        return PD_OK;
    }
    if (sim->grid) {
        pd_status st = pd_grid_pmb(sim, PD_BONDS_FAILURE);
        if (st != PD_OK)
            return st;
    } else
        pmb_kernel(sim, PD_BONDS_FAILURE);
    double *t = sim->s0;
    sim->s0 = sim->s0_new;
    sim->s0_new = t;
    sim->intact_stale = 1;
    return PD_OK;
}

/* sum_j 1/4 c s^2 |xi| nu V_j over the intact bonds of family F of
 * particle i, branch-free (a broken bond times 0) so that it vectorizes. */
PD_VECTOR_CLONES static double family_energy(const pd_family *F, const uint64_t *intact,
                                             double *const *y, const double *V, double c,
                                             int64_t i)
{
    double sum = 0, mu[PMB_CHUNK];
    for (int64_t c0 = 0; c0 < F->n; c0 += PMB_CHUNK) {
        const int64_t m = F->n - c0 < PMB_CHUNK ? F->n - c0 : PMB_CHUNK;
        chunk_states(intact, F->first + c0, m, mu);
        for (int64_t t = 0; t < m; t++) {
            const int32_t j = F->j[c0 + t];
            const double L = F->length[c0 + t];
            const double dx = y[0][j] - y[0][i], dy = y[1][j] - y[1][i], dz = y[2][j] - y[2][i];
            double dr = sqrt(dx * dx + dy * dy + dz * dz) - L;
            dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
            const double s = dr / L;
            sum += mu[t] * (0.25 * c * s * s * L * F->vfactor[c0 + t] * V[j]);
        }
    }
    return sum;
}

/* The bonds' energy, half of each bond to each end (directed bonds, each
 * row its own sum): e_i += sum_j 1/4 c s^2 |xi| nu_ij V_i V_j. */
static void pmb_energy_uniform(const pd_sim *sim, void *state, double *e)
{
    (void)state;
    const pd_bonds *b = sim->b;
    const uint64_t *intact = pd_sim_intact(sim);
    const double *V = sim->p->volume, c = sim->sc.c;
    double *const *y = sim->y;
#pragma omp parallel
    {
        pd_family_buf fb = {0};
        pd_family F;
#pragma omp for schedule(static)
        for (int64_t i = 0; i < sim->n; i++) {
            if (pd_family_get(b, sim->p, i, &fb, &F) != 0) {
                e[i] = NAN; /* out of memory: never a wrong number */
                continue;
            }
            e[i] += family_energy(&F, intact, y, V, c, i) * V[i];
        }
        pd_family_buf_free(&fb);
    }
}

/* The static virial of each particle's intact bonds (pd_sim_stress):
 * s_i += 1/2 sum_j V_j f_ij (x) xi_ij with f_ij = c s nu_ij (y_j - y_i)/r,
 * the force density bond j puts on i per unit volume of j.  Directed
 * bonds, each row its own sum: the same at any thread count. */
static void pmb_stress_uniform(const pd_sim *sim, void *state, double *out)
{
    (void)state;
    const pd_bonds *b = sim->b;
    const uint64_t *intact = pd_sim_intact(sim);
    const double *V = sim->p->volume, c = sim->sc.c;
    double *const *y = sim->y;
    double *const *x = sim->p->x;
#pragma omp parallel
    {
        pd_family_buf fb = {0};
        pd_family F;
#pragma omp for schedule(static)
        for (int64_t i = 0; i < sim->n; i++) {
            double sum[9] = {0};
            if (pd_family_get(b, sim->p, i, &fb, &F) != 0)
                for (int m = 0; m < 9; m++) /* out of memory: never a wrong number */
                    sum[m] = NAN;
            for (int64_t t = 0; t < F.n; t++) {
                if (!pd_bond_intact(intact, F.first + t))
                    continue;
                const int32_t j = F.j[t];
                const double e[3] = {y[0][j] - y[0][i], y[1][j] - y[1][i], y[2][j] - y[2][i]};
                const double r = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
                double dr = r - F.length[t];
                dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
                if (r <= 0.0)
                    continue;
                const double f = 0.5 * c * (dr / F.length[t]) * F.vfactor[t] * V[j] / r;
                const double xi[3] = {x[0][j] - x[0][i], x[1][j] - x[1][i], x[2][j] - x[2][i]};
                for (int a = 0; a < 3; a++)
                    for (int d = 0; d < 3; d++)
                        sum[3 * a + d] += f * e[a] * xi[d];
            }
            for (int m = 0; m < 9; m++)
                out[9 * i + m] += sum[m];
        }
        pd_family_buf_free(&fb);
    }
}

/* The same two with each bond's own c (lib/models/materials.c), apart so that a
 * scene without laws keeps the loops above bit for bit. */
static void pmb_energy_laws(const pd_sim *sim, double *e)
{
    const pd_bonds *b = sim->b;
    const uint64_t *intact = pd_sim_intact(sim);
    const double *V = sim->p->volume;
    double *const *y = sim->y;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        double sum = 0;
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            if (!pd_bond_intact(intact, k))
                continue;
            const int32_t j = b->neighbor[k];
            const double dx = y[0][j] - y[0][i], dy = y[1][j] - y[1][i], dz = y[2][j] - y[2][i];
            double dr = sqrt(dx * dx + dy * dy + dz * dz) - b->length[k];
            dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
            const double s = dr / b->length[k];
            double c, s00;
            pd_bond_law_of(sim->p, &sim->sc, i, j, &c, &s00);
            sum += 0.25 * c * s * s * b->length[k] * b->vfactor[k] * V[j];
        }
        e[i] += sum * V[i];
    }
}

static void pmb_stress_laws(const pd_sim *sim, double *out)
{
    const pd_bonds *b = sim->b;
    const uint64_t *intact = pd_sim_intact(sim);
    const double *V = sim->p->volume;
    double *const *y = sim->y;
    double *const *x = sim->p->x;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        double sum[9] = {0};
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            if (!pd_bond_intact(intact, k))
                continue;
            const int32_t j = b->neighbor[k];
            const double e[3] = {y[0][j] - y[0][i], y[1][j] - y[1][i], y[2][j] - y[2][i]};
            const double r = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
            double dr = r - b->length[k];
            dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
            if (r <= 0.0)
                continue;
            double c, s00;
            pd_bond_law_of(sim->p, &sim->sc, i, j, &c, &s00);
            const double f = 0.5 * c * (dr / b->length[k]) * b->vfactor[k] * V[j] / r;
            const double xi[3] = {x[0][j] - x[0][i], x[1][j] - x[1][i], x[2][j] - x[2][i]};
            for (int a = 0; a < 3; a++)
                for (int d = 0; d < 3; d++)
                    sum[3 * a + d] += f * e[a] * xi[d];
        }
        for (int m = 0; m < 9; m++)
            out[9 * i + m] += sum[m];
    }
}

static void pmb_energy(const pd_sim *sim, void *state, double *e)
{
    if (sim->grid)
        pd_grid_pmb_energy(sim, e);
    else if (pd_scene_has_laws(&sim->sc))
        pmb_energy_laws(sim, e);
    else if (!rows_energy(sim, e, 0))
        pmb_energy_uniform(sim, state, e);
}

static void pmb_stress(const pd_sim *sim, void *state, double *out)
{
    if (pd_scene_has_laws(&sim->sc))
        pmb_stress_laws(sim, out);
    else
        pmb_stress_uniform(sim, state, out);
}

/* The bond list's lengths and weights where the lattice stencil does not
 * walk the bonds, each bond's own c and failure factor with laws. */
static pd_status pmb_init(pd_sim *sim, void **state)
{
    (void)state;
    pd_status s = pd_scene_has_laws(&sim->sc) ? pd_bond_laws_check(sim->p, &sim->sc) : PD_OK;
    if (s == PD_OK && !sim->grid)
        s = pd_half_weights(sim->p, sim->b, sim->sc.c, &sim->half);
    if (s == PD_OK && !sim->grid && pd_scene_has_laws(&sim->sc))
        s = pd_half_laws(sim->p, sim->b, &sim->sc, &sim->half);
    if (s == PD_OK && !sim->grid)
        s = pmb_rows_init(sim);
    return s;
}

const pd_effect pd_effect_pmb = {
    .name = "pmb", .timer = PD_T_BONDS, .init = pmb_init, .force = pmb_force,
    .energy = pmb_energy, .kind = PD_ENERGY_ELASTIC, .stress = pmb_stress};
const pd_effect pd_effect_pmb_failure = {
    .name = "pmb+failure", .timer = PD_T_BONDS, .init = pmb_init, .force = pmb_failure_force,
    .energy = pmb_energy, .kind = PD_ENERGY_ELASTIC, .stress = pmb_stress};

/* pd_bond_stiffness with the caller's buffer: a compact family goes
 * through arrays too, so that the compiler's vectorized sum (VEC_CFLAGS)
 * is the lists' own. */
static double stiffness(const pd_particles *p, const pd_bonds *b, double c, int64_t i,
                        pd_family_buf *fb)
{
    pd_family F;
    if (pd_family_get(b, p, i, fb, &F) != 0)
        return NAN;
    double sum = 0;
    for (int64_t t = 0; t < F.n; t++)
        sum += p->volume[F.j[t]] * F.vfactor[t] * c / F.length[t];
    return sum;
}

double pd_bond_stiffness(const pd_particles *p, const pd_bonds *b, double c, int64_t i)
{
    pd_family_buf fb = {0};
    const double sum = stiffness(p, b, c, i, &fb);
    pd_family_buf_free(&fb);
    return sum;
}

static double pmb_stable_dt(const pd_particles *p, const pd_bonds *b, const pd_scene *s)
{
    /* seed 004 eq. 46: dt < sqrt(2 rho_i / sum_p V_p C_ip), C_ip = c/|xi|
     * for PMB (|df/deta| of f = c s), here with the partial volume nu V_p
     * that the discrete force uses; the smallest over all particles. */
    double best = INFINITY;
    int bad = 0; /* a buffer out of memory: NaN, never a wrong step */
#pragma omp parallel reduction(min : best) reduction(| : bad)
    {
        pd_family_buf fb = {0};
#pragma omp for schedule(static) /* each particle's own sum; min in any order */
        for (int64_t i = 0; i < b->n; i++) {
            double sum = pd_scene_has_laws(s) ? pd_bond_stiffness_laws(p, b, s, i)
                                              : stiffness(p, b, s->c, i, &fb);
            bad |= isnan(sum);
            if (sum > 0)
                best = fmin(best, sqrt(2.0 * p->density[i] / sum));
        }
        pd_family_buf_free(&fb);
    }
    return bad ? NAN : best;
}

/* One c and s00 for every bond: the lattice stencil's PMB kernels. */
static pd_stencil_kind pmb_stencil(const pd_scene *s)
{
    return pd_scene_has_laws(s) ? PD_STENCIL_NONE : PD_STENCIL_PMB;
}

static const char *const pmb_takes[] = {"--c", "--bulk-modulus", "--youngs-modulus",
                                        "--failure-energy", "--material", "--interface",
                                        "--fibre", NULL};

const pd_model pd_model_pmb = {
    .name = "pmb", .kind = PD_MODEL_PMB, .force = &pd_effect_pmb,
    .force_failure = &pd_effect_pmb_failure, .stable_dt = pmb_stable_dt, .stencil = pmb_stencil,
    .takes = pmb_takes, .fields = PD_FIELD_ENERGY | PD_FIELD_STRESS};

double pd_pmb_c_from_bulk(double bulk_modulus, double horizon)
{
    const double pi = 3.14159265358979323846;
    return PD_PMB_C_FACTOR * bulk_modulus / (pi * pow(horizon, 4));
}

double pd_pmb_s0_from_energy(double g0, double c, double horizon)
{
    const double pi = 3.14159265358979323846;
    return sqrt(10.0 * g0 / (pi * c * pow(horizon, 5)));
}
