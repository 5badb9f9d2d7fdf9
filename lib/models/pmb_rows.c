/*
 * pmb_rows.c -- the PMB bond list in AVX-512 rows (lib/models/pmb.c walks
 * the blocks and holds the maths; pmb_rows.h the interface): the half
 * bonds' weights, the bond pass of a block's rows, the energies counted in
 * it or in passes of their own, each bond once for both ends.
 *
 * Built without -fassociative-math (pmb.c's portable loops need it to
 * vectorize; these are written in intrinsics): the compiler keeps every
 * operation in the order written, so that the energies the bond pass
 * counts and those of a pass of their own are the same bits.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>

#include "models/model.h"
#include "models/pmb_rows.h"

/* The half bonds' lengths and weights (model.h).  Here rather than in
 * pmb.c, whose portable loops are built with -fassociative-math: that let
 * the compiler take c V_j nu_ij as (c nu_ij) V_j in one of the two loops
 * below and (c V_i) nu_ji in the other, so that a bond's two weights,
 * equal on any body of equal volumes, differed in their last bit and
 * every body took the kernels' two-weight path.  Each product is taken
 * as written: (c V) nu, as LAMMPS peri/pmb and the stencil take it. */
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

double pmb_pair_energy(const pd_sim *sim, int64_t i, int64_t j, double L, double wij, double wji)
{
    const double dx = sim->y[0][j] - sim->y[0][i], dy = sim->y[1][j] - sim->y[1][i],
                 dz = sim->y[2][j] - sim->y[2][i];
    double dr = sqrt(dx * dx + dy * dy + dz * dz) - L;
    dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
    const double s = dr / L;
    const double *V = sim->p->volume;
    return 0.25 * s * s * L * (wij * V[i] + wji * V[j]);
}

double pmb_bond_energy(const pd_sim *sim, int64_t i, int64_t k)
{
    const pd_half_bonds *h = &sim->half;
    return pmb_pair_energy(sim, i, h->neighbor[k], h->length[k], h->w_ij[k], h->w_ji[k]);
}

#if PD_AVX512_KERNELS
/* The bond list in AVX-512, 8 bonds of a row at a time.  pmb.c's scalar-looking
 * list kernel (pmb_row) gathers each partner's position and s0 from four
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
 * lane order, into h->pack.  Lost particles are out of contact.  With ec
 * their energy as contact_row512 counts it: j's into ec[j], i's into
 * *own (the row's sum, in bond order). */
static void rows_contact(pd_sim *sim, int64_t i, int64_t k, const int64_t *jj, unsigned near,
                         const double *r, const double *dx, const double *dy, const double *dz,
                         double *ec, double *own)
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
        if (!(r[l] < d))
            continue;
        if (ec) {
            const double x = 0.25 * kc * (d - r[l]) * (d - r[l]);
            *own += x * V[j];
            ec[j] += x * V[i] * V[j];
        }
        if (!(r[l] > 0.0))
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
                *released += pmb_bond_energy(sim, i, b);
            }
        }
}

/* The energies in the rows (pmb_rows_energy): h->pack holds each particle's
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

/* Bonds k .. k+m-1 of row i (own position yi0, yi1, yi2) into *c, their
 * partners into jj; every pass of the rows takes its bonds so, to the
 * bit. */
PMB_TARGET_AVX512 static inline __attribute__((always_inline)) void
row_chunk_of(const double *pk, const int32_t *nb, const double *len, int64_t i, int64_t k, int m,
             __mmask8 act, __m512d yi0, __m512d yi1, __m512d yi2, int64_t jj[8], row_chunk *c)
{
    __m512d xj, yj, zj;
    rows_partners(pk, nb, i, k, m, jj, &xj, &yj, &zj, &c->w4);
    c->L = _mm512_mask_loadu_pd(_mm512_set1_pd(1.0), act, len + k);
    chunk_bonds(xj, yj, zj, act, yi0, yi1, yi2, c);
}

/* Of the lanes `brk` of bonds k.. of row i, those that do break (not kept
 * by --no-failure). */
static __mmask8 row_gone(const pd_sim *sim, int64_t i, const int64_t *jj, __mmask8 brk)
{
    for (int l = 0; l < 8; l++)
        if (((brk >> l) & 1) && !pd_sim_may_break(sim, i, jj[l]))
            brk = (__mmask8)(brk & ~(1u << l));
    return brk;
}

/* pmb_row on h->pack (its comment holds the maths), 8 bonds at a time; a
 * row's last 8 are masked.  With `failure` the bonds whose stretch breaks
 * them are kept a chunk's lanes at a time and broken after the row's
 * chunks (row_breaks): a chunk reads only its own bonds' bits. */
PMB_TARGET_AVX512 static inline __attribute__((always_inline)) void
pmb_row512(pd_sim *sim, int64_t i, const pd_bond_mode failure, const int contact, const int sym,
           const int energy, double *released, int64_t nwords)
{
    pd_half_bonds *h = &sim->half;
    double *restrict pk = h->pack;
    const double *restrict len = h->length, *restrict wij = h->w_ij, *restrict wji = h->w_ji;
    const double *restrict kf = h->kfail;
    const int32_t *restrict nb = h->neighbor;
    const int64_t k1 = h->offset[i + 1];
    const __m512d zero = _mm512_setzero_pd(), ninf = _mm512_set1_pd(-INFINITY);
    const __m512d vs00 = _mm512_set1_pd(sim->sc.s00), valpha = _mm512_set1_pd(sim->sc.alpha);
    const __m512d vref = _mm512_set1_pd(PD_CONTACT_REF_FRAC), vcap = _mm512_set1_pd(h->contact_cap);
    const __m512d yi0 = _mm512_set1_pd(pk[8 * i]), yi1 = _mm512_set1_pd(pk[8 * i + 1]),
                  yi2 = _mm512_set1_pd(pk[8 * i + 2]), s0i = _mm512_set1_pd(pk[8 * i + 3]);
    __m512d ax = zero, ay = zero, az = zero, sm = ninf;
    /* with `energy`, the energies of the bonds intact after the pass and of
     * the contact pairs, as pmb_rows_energy counts them: i's summed over the
     * row, its partners' into h->eb and h->ec */
    __m512d own = zero;
    double own_c = 0;
    const double *V = sim->p->volume;
    uint8_t brks[PMB_ROW_CHUNKS]; /* each chunk's breaking lanes, from kbrk on */
    int nbrk = 0;
    int64_t kbrk = h->offset[i];
    unsigned anybrk = 0;
    for (int64_t k = h->offset[i]; k < k1; k += 8) {
        const int m = k1 - k < 8 ? (int)(k1 - k) : 8;
        const __mmask8 act = (__mmask8)(m == 8 ? 0xff : (1u << m) - 1);
        const __mmask8 kmu = (__mmask8)(act & bits8(h->intact, k, nwords));
        int64_t jj[8];
        row_chunk c;
        row_chunk_of(pk, nb, len, i, k, m, act, yi0, yi1, yi2, jj, &c);
        const __m512d sj = c.w4, L = c.L, dx = c.dx, dy = c.dy, dz = c.dz, r = c.r, dr = c.dr;
        /* one division for both: q = 1/(|xi| r), s/r = dr q, s = dr (r q)
         * (dr/|xi| itself where r = 0) */
        const __mmask8 pos = c.pos;
        const __m512d q = c.q, s = c.s;
        const __m512d g = _mm512_maskz_mul_pd((__mmask8)(kmu & pos), dr, q);
        /* the force on i, and (the same unless the weights differ) j's */
        const __m512d wi = _mm512_maskz_loadu_pd(act, wij + k);
        const __m512d fi = _mm512_mul_pd(wi, g);
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
            __m512d thr = _mm512_min_pd(s0i, sj);
            if (failure == PD_BONDS_FAILURE_LAWS)
                thr = _mm512_mul_pd(_mm512_maskz_loadu_pd(act, kf + k), thr);
            brk = _mm512_mask_cmp_pd_mask(kmu, s, thr, _CMP_GT_OQ);
            t = _mm512_mask_sub_pd(ninf, kmu, vs00, _mm512_mul_pd(valpha, s));
            sm = _mm512_max_pd(sm, t);
        }
        if (energy) { /* the bonds intact after this pass: not those that break in
                         it (rare), unless --no-failure keeps them */
            const __mmask8 gone = brk && sim->nofail ? row_gone(sim, i, jj, brk) : brk;
            const __m512d x = row_energy(s, L, (__mmask8)(kmu & ~gone));
            own = _mm512_add_pd(own, _mm512_mul_pd(x, wi));
            double to[8];
            _mm512_storeu_pd(to, _mm512_mul_pd(x, _mm512_maskz_loadu_pd(act, wji + k)));
            for (int l = 0; l < m; l++)
                h->eb[jj[l]] += to[l] * V[jj[l]];
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
            rows_contact(sim, i, k, jj, near, rr, ex, ey, ez, energy ? h->ec : NULL, &own_c);
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
    if (energy) {
        h->eb[i] += _mm512_reduce_add_pd(own) * V[i];
        if (contact)
            h->ec[i] += own_c * V[i];
    }
}

/* The rows of a block, a variant per failure mode, contact and symmetric
 * weights (w_ji the same array as w_ij: one force for both ends). */
#define PMB_ROWS_E(mode, contact, energy)                                                      \
    do {                                                                                       \
        if (sim->half.w_ji == sim->half.w_ij)                                                  \
            for (int64_t i = lo; i < hi; i++)                                                  \
                pmb_row512(sim, i, mode, contact, 1, energy, released, nwords);                \
        else                                                                                   \
            for (int64_t i = lo; i < hi; i++)                                                  \
                pmb_row512(sim, i, mode, contact, 0, energy, released, nwords);                \
    } while (0)
/* ... and with the energies counted (a step whose energies are wanted) */
#define PMB_ROWS(mode, contact)                                                                \
    do {                                                                                       \
        if (energy)                                                                            \
            PMB_ROWS_E(mode, contact, 1);                                                      \
        else                                                                                   \
            PMB_ROWS_E(mode, contact, 0);                                                      \
    } while (0)

PMB_TARGET_AVX512 void pmb_rows_block(pd_sim *sim, int64_t lo, int64_t hi, pd_bond_mode failure,
                                      int energy, double *released)
{
    const int64_t nwords = pd_bits_words(sim->half.count);
    const int contact = sim->half.contact;
    PMB_VARIANTS(PMB_ROWS, failure, contact);
}

/* The elastic energy of the intact half bonds of row i, pmb_energy_uniform's
 * 1/4 c s^2 |xi| nu_ij V_i V_j to i and 1/4 c s^2 |xi| nu_ji V_j V_i to j
 * (w = c V nu holds c, nu and the other end's volume): i's summed in
 * registers over the row, each partner's added to e[j] in bond order;
 * the arithmetic and the order of pmb_row512's `energy`, to the bit. */
PMB_TARGET_AVX512 static void energy_row512(const pd_sim *sim, int64_t i, double *e,
                                            int64_t nwords)
{
    const pd_half_bonds *h = &sim->half;
    const double *restrict pk = h->pack;
    const double *restrict len = h->length, *restrict wij = h->w_ij, *restrict wji = h->w_ji;
    const int64_t k1 = h->offset[i + 1];
    const __m512d zero = _mm512_setzero_pd();
    const __m512d yi0 = _mm512_set1_pd(pk[8 * i]), yi1 = _mm512_set1_pd(pk[8 * i + 1]),
                  yi2 = _mm512_set1_pd(pk[8 * i + 2]);
    __m512d own = zero;
    for (int64_t k = h->offset[i]; k < k1; k += 8) {
        const int m = k1 - k < 8 ? (int)(k1 - k) : 8;
        const __mmask8 act = (__mmask8)(m == 8 ? 0xff : (1u << m) - 1);
        const __mmask8 kmu = (__mmask8)(act & bits8(h->intact, k, nwords));
        int64_t jj[8];
        row_chunk c;
        row_chunk_of(pk, h->neighbor, len, i, k, m, act, yi0, yi1, yi2, jj, &c);
        const __m512d vj = c.w4, x = row_energy(c.s, c.L, kmu); /* 0 for a broken bond */
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

/* A block of an energies' pass (pmb_walk_blocks): the contact energy or
 * the elastic one into e. */
typedef struct {
    int contact;
    double *e;
    pmb_energy_block_fn *lanes; /* or NULL: the rows' own */
} energy_pass;

PMB_TARGET_AVX512 static void energy_block512(const pd_sim *sim, int64_t blk, int64_t lo,
                                              int64_t hi, void *ctx)
{
    const energy_pass *ps = ctx;
    const int64_t nwords = pd_bits_words(sim->half.count);
    if (ps->lanes) {
        ps->lanes(sim, blk, lo, ps->contact, ps->e);
        return;
    }
    for (int64_t i = lo; i < hi; i++)
        if (ps->contact)
            contact_row512(sim, i, ps->e);
        else
            energy_row512(sim, i, ps->e, nwords);
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

void pmb_walk_blocks(const pd_sim *sim, pmb_block_fn *fn, void *ctx)
{
    const pd_half_bonds *h = &sim->half;
    for (int phase = 0; phase < 2; phase++) {
        const int64_t first = h->walk_lo + ((h->blk0 + h->walk_lo + phase) & 1);
#pragma omp parallel for schedule(dynamic, 1)
        for (int64_t blk = first; blk < h->walk; blk += 2) {
            int64_t lo, hi;
            block_rows(h, blk, sim->n, &lo, &hi);
            fn(sim, blk, lo, hi, ctx);
        }
    }
}

/* e_i += the elastic energy (contact 0) or the contact energy (1) of
 * particle i in the AVX-512 rows, where this run has them: 1, else 0 (the
 * families then).  Those the step's bond pass counted (pd_sim_energy_next),
 * or else a pass of the half bonds of their own, each bond once for both
 * ends, in the blocks' order as the forces are (the same sums at any
 * thread count, and the same bits as the bond pass counts); h->pack, the
 * rows' scratch, takes the positions and volumes. */
int pmb_rows_energy(const pd_sim *sim, double *e, int contact, pmb_energy_block_fn *lanes)
{
#if PD_AVX512_KERNELS
    const pd_half_bonds *h = &sim->half;
    if (!h->pack || (!contact && pd_scene_has_laws(&sim->sc)) || (contact && !h->contact))
        return 0;
    double *out = contact ? h->ec : h->eb;
    const int counted = out && h->energy_ok && h->energy_step == sim->step &&
                        h->energy_epoch == h->epoch;
    if (!counted) { /* a pass of their own */
        if (!out && !(out = calloc((size_t)(sim->n > 0 ? sim->n : 1), sizeof(double))))
            return 0; /* out of memory: the families' walk */
        pd_half_bonds *mut = (pd_half_bonds *)h; /* scratch the run keeps */
        *(contact ? &mut->ec : &mut->eb) = out;
        double *pk = h->pack;
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < sim->n; i++) {
            pk[8 * i] = sim->y[0][i];
            pk[8 * i + 1] = sim->y[1][i];
            pk[8 * i + 2] = sim->y[2][i];
            pk[8 * i + 3] = sim->p->volume[i];
            out[i] = 0;
        }
        energy_pass ps = {contact, out, lanes};
        pmb_walk_blocks(sim, energy_block512, &ps);
    }
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++)
        e[i] += out[i];
    return 1;
#else
    (void)sim;
    (void)e;
    (void)contact;
    (void)lanes;
    return 0;
#endif
}


/* Does this bond pass count the energies (pd_sim_energy_next: a status
 * line or frame wants them after this step)?  In the AVX-512 rows, without
 * per-bond laws: then h->eb and h->ec are there and zero, and the counted
 * ones before are stale. */
int pmb_rows_count(pd_sim *sim)
{
    pd_half_bonds *h = &sim->half;
    const int want = sim->energy_next;
    sim->energy_next = 0;
    h->energy_ok = 0;
    if (!want || !h->pack || pd_scene_has_laws(&sim->sc))
        return 0;
    const size_t n = (size_t)(sim->n > 0 ? sim->n : 1);
    if (!h->eb)
        h->eb = malloc(n * sizeof(double));
    if (!h->ec)
        h->ec = malloc(n * sizeof(double));
    if (!h->eb || !h->ec)
        return 0; /* out of memory: a pass of their own when asked */
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++)
        h->eb[i] = h->ec[i] = 0;
    return 1;
}

