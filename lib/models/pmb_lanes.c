/*
 * pmb_lanes.c -- the PMB bond list in lanes (pd_half_lanes, lib/bonds/half.h):
 * eight rows a vector, one row a lane, each lane walking its row's half
 * bonds, a column of 8 bonds at a time.  pmb.c walks it in place of the
 * AVX-512 rows (pmb_rows.c, whose maths and order of operations it keeps)
 * where it is built; PD_NO_LANES keeps the rows.
 *
 * Why.  The rows take 8 bonds of one row at a time: a row of the seed's
 * perturbed disk has about 43 half bonds, so each row pays for a masked
 * last chunk, four sums across the lanes of its own forces and new s0,
 * its state bits at any bit offset and lengths and weights at any byte
 * offset.  The lanes keep 8 rows' own positions, s0 and sums in registers
 * over all their columns, read each column's lengths, weights and bits
 * as aligned vectors and a byte, and pay the sums and the tail once for 8
 * rows.  A bond's partner is read and written back as in the rows (one
 * 32-byte row of h->pack each way, the transposes in registers), in lane
 * order, so that two lanes of a column with one partner add to it in
 * turn.
 *
 * The same bits at any thread count and on MPI ranks: the blocks are the
 * rows' (a block's groups write only to the block and the next; even
 * blocks run before odd ones, pmb_walk_blocks), a block's groups run in
 * order, and every sum is in an order the groups fix.  A piece's block
 * below its own walks the same groups as the whole body's, with the lanes
 * of the rows below its first row with a partner of the piece's own
 * masked off (they put no force on its rows).  The forces differ from the
 * rows' only in the order of each particle's sums (rounding); the bond
 * states, the breaking test and new s0 are the same numbers.
 *
 * Built without -fassociative-math, as pmb_rows.c: every operation in the
 * order written.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "models/model.h"
#include "models/pmb_rows.h"

#if PD_AVX512_KERNELS

#define PMB_LANES_WINDOW 64 /* rows sorted by their half bonds within windows of */

static void *zalloc64(size_t bytes)
{
    bytes = (bytes + 63) / 64 * 64;
    void *p = aligned_alloc(64, bytes > 0 ? bytes : 64);
    if (p)
        memset(p, 0, bytes > 0 ? bytes : 64);
    return p;
}

static int64_t half_count(const pd_half_bonds *h, int64_t i)
{
    return h->offset[i + 1] - h->offset[i];
}

/* The groups of block b: its rows sorted by their half bonds, most first,
 * within windows (ties in row order), 8 a group. */
static void block_groups(pd_half_lanes *L, const pd_half_bonds *h, int64_t n, int64_t b)
{
    const int64_t r0 = b * h->block, r1 = r0 + h->block < n ? r0 + h->block : n;
    int64_t *row = L->row + 8 * L->first[b];
    for (int64_t a = 0; a < 8 * (L->first[b + 1] - L->first[b]); a++)
        row[a] = r0 + a < r1 ? r0 + a : -1;
    for (int64_t w0 = 0; w0 < r1 - r0; w0 += PMB_LANES_WINDOW) {
        const int64_t w1 = w0 + PMB_LANES_WINDOW < r1 - r0 ? w0 + PMB_LANES_WINDOW : r1 - r0;
        for (int64_t a = w0 + 1; a < w1; a++) { /* insertion: stable */
            const int64_t r = row[a];
            int64_t q = a;
            for (; q > w0 && half_count(h, row[q - 1]) < half_count(h, r); q--)
                row[q] = row[q - 1];
            row[q] = r;
        }
    }
}

/* Group g's columns from the half bonds. */
static void group_fill(pd_half_lanes *L, const pd_half_bonds *h, int64_t g)
{
    const int64_t c0 = L->col[g], c1 = L->col[g + 1];
    for (int l = 0; l < 8; l++) {
        const int64_t a = L->row[8 * g + l];
        int64_t c = c0;
        for (int64_t k = a >= 0 ? h->offset[a] : 0; a >= 0 && k < h->offset[a + 1]; k++, c++) {
            L->at[8 * c + l] = (uint32_t)(8 * h->neighbor[k]);
            L->length[8 * c + l] = h->length[k];
            L->w[8 * c + l] = h->w_ij[k];
            if (L->wji)
                L->wji[8 * c + l] = h->w_ji[k];
            if (L->kfail)
                L->kfail[8 * c + l] = h->kfail[k];
            L->act[c] |= (uint8_t)(1u << l);
            L->bits[c] |= (uint8_t)(pd_bond_intact(h->intact, k) << l);
        }
        for (; c < c1; c++) { /* no bond: the lane's own row, masked */
            L->at[8 * c + l] = (uint32_t)(8 * (a >= 0 ? a : L->row[8 * g]));
            L->length[8 * c + l] = 1.0;
            if (L->kfail)
                L->kfail[8 * c + l] = 1.0;
        }
    }
}

void pmb_lanes_build(pd_sim *sim)
{
    pd_half_bonds *h = &sim->half;
    if (h->lanes || !h->pack || getenv("PD_NO_LANES") || sim->n >= (INT64_C(1) << 29))
        return; /* (a place 8 j is 32 bits) */
    pd_half_lanes *L = calloc(1, sizeof *L);
    if ((h->lanes = L) == NULL)
        return; /* out of memory: the rows */
    L->first = calloc((size_t)h->nblocks + 1, sizeof(int64_t));
    if (L->first == NULL) {
        pd_half_lanes_free(h);
        return;
    }
    for (int64_t b = 0; b < h->nblocks; b++) {
        const int64_t r0 = b * h->block, r1 = r0 + h->block < sim->n ? r0 + h->block : sim->n;
        L->first[b + 1] = L->first[b] + (r1 - r0 + 7) / 8;
    }
    L->groups = L->first[h->nblocks];
    L->row = malloc((size_t)(L->groups > 0 ? 8 * L->groups : 1) * sizeof(int64_t));
    L->col = calloc((size_t)L->groups + 1, sizeof(int64_t));
    if (!L->row || !L->col) {
        pd_half_lanes_free(h);
        return;
    }
#pragma omp parallel for schedule(dynamic, 1)
    for (int64_t b = 0; b < h->nblocks; b++)
        block_groups(L, h, sim->n, b);
    for (int64_t g = 0; g < L->groups; g++) {
        int64_t most = 0;
        for (int l = 0; l < 8; l++) {
            const int64_t a = L->row[8 * g + l];
            if (a >= 0 && half_count(h, a) > most)
                most = half_count(h, a);
        }
        L->col[g + 1] = L->col[g] + most;
    }
    const size_t nc = (size_t)L->col[L->groups];
    L->at = zalloc64(8 * nc * sizeof(uint32_t));
    L->length = zalloc64(8 * nc * sizeof(double));
    L->w = zalloc64(8 * nc * sizeof(double));
    L->wji = h->w_ji != h->w_ij ? zalloc64(8 * nc * sizeof(double)) : NULL;
    L->kfail = h->kfail ? zalloc64(8 * nc * sizeof(double)) : NULL;
    L->act = calloc(nc > 0 ? nc : 1, 1);
    L->bits = calloc(nc > 0 ? nc : 1, 1);
    if (!L->at || !L->length || !L->w || (h->w_ji != h->w_ij && !L->wji) ||
        (h->kfail && !L->kfail) || !L->act || !L->bits) {
        pd_half_lanes_free(h);
        return;
    }
#pragma omp parallel for schedule(dynamic, 64)
    for (int64_t g = 0; g < L->groups; g++)
        group_fill(L, h, g);
    L->epoch = h->epoch;
    /* the rows' lengths and weights: the lanes hold them now */
    if (h->w_ji != h->w_ij)
        free(h->w_ji);
    free(h->w_ij);
    free(h->length);
    h->w_ij = h->w_ji = h->length = NULL;
}

void pmb_lanes_sync(pd_sim *sim)
{
    pd_half_bonds *h = &sim->half;
    pd_half_lanes *L = h->lanes;
    if (L == NULL || L->epoch == h->epoch)
        return;
#pragma omp parallel for schedule(dynamic, 64)
    for (int64_t g = 0; g < L->groups; g++)
        for (int64_t c = L->col[g]; c < L->col[g + 1]; c++) {
            unsigned bits = 0;
            for (int l = 0; l < 8; l++)
                if ((L->act[c] >> l) & 1) {
                    const int64_t k = h->offset[L->row[8 * g + l]] + (c - L->col[g]);
                    bits |= (unsigned)pd_bond_intact(h->intact, k) << l;
                }
            L->bits[c] = (uint8_t)bits;
        }
    L->epoch = h->epoch;
}

/* The arrays of the lanes a pass reads, kept in registers. */
typedef struct {
    const double *pk, *length, *w, *wji, *kfail;
    const uint32_t *at;
    const uint8_t *act;
} lane_arrays;

static inline lane_arrays arrays_of(const pd_half_bonds *h)
{
    const pd_half_lanes *L = h->lanes;
    return (lane_arrays){h->pack, L->length, L->w, L->wji, L->kfail, L->at, L->act};
}

/* Column c of 8 bonds (their partners' 4th values: s0 in the bond pass,
 * volumes in the energies' own) into *k, as the rows take a chunk. */
PMB_TARGET_AVX512 static inline __attribute__((always_inline)) void
column_of(const lane_arrays *A, int64_t c, __mmask8 act, __m512d yi0, __m512d yi1, __m512d yi2,
          row_chunk *k)
{
    const uint32_t *at = A->at + 8 * c;
    __m256d row[8];
    for (int l = 0; l < 8; l++)
        row[l] = _mm256_load_pd(A->pk + at[l]);
    __m512d xj, yj, zj;
    rows_to_lanes(row, &xj, &yj, &zj, &k->w4);
    k->L = _mm512_load_pd(A->length + 8 * c);
    chunk_bonds(xj, yj, zj, act, yi0, yi1, yi2, k);
}

/* Group g's rows (lanes without one, or below row lo: not `live`) and
 * their own positions and 4th values (lanes without a row: the group's
 * first row's). */
PMB_TARGET_AVX512 static inline __attribute__((always_inline)) __mmask8
group_own(const pd_half_lanes *L, const double *pk, int64_t g, int64_t lo, int64_t rows[8],
          __m512d *yi0, __m512d *yi1, __m512d *yi2, __m512d *w4)
{
    __m256d row[8];
    unsigned live = 0;
    for (int l = 0; l < 8; l++) {
        rows[l] = L->row[8 * g + l];
        live |= (unsigned)(rows[l] >= lo) << l;
        row[l] = _mm256_load_pd(pk + 8 * (rows[l] >= 0 ? rows[l] : L->row[8 * g]));
    }
    rows_to_lanes(row, yi0, yi1, yi2, w4);
    return (__mmask8)live;
}

/* The near pairs of a column (contact): r below min(0.9 |xi|, cap). */
PMB_TARGET_AVX512 static inline __attribute__((always_inline)) __mmask8
column_near(__m512d cap, const row_chunk *k, __mmask8 act)
{
    return _mm512_mask_cmp_pd_mask(
        act, k->r, _mm512_min_pd(_mm512_mul_pd(_mm512_set1_pd(PD_CONTACT_REF_FRAC), k->L), cap),
        _CMP_LT_OQ);
}

/* The contact of the near pairs of column c (distances r, bond vectors dx,
 * dy, dz): seed 000 eqs. 13-15 as pmb_rows.c's rows_contact takes them,
 * each pair once for both ends, in lane order; with `forces` into
 * h->pack, with ec the energies (i's into own_c[l], the partner's into
 * ec[j]).  Lost particles are out of contact.  Out of line, so that the
 * columns' loop keeps its values in registers. */
PMB_TARGET_AVX512 __attribute__((noinline, cold)) static void
column_contact(const pd_sim *sim, int64_t c, const int64_t *rows, __mmask8 near, __m512d r,
               __m512d dx, __m512d dy, __m512d dz, int forces, double *own_c, double *ec)
{
    const pd_half_bonds *h = &sim->half;
    const pd_half_lanes *L = h->lanes;
    double *pk = h->pack;
    const double *rad = sim->p->radius, *V = sim->p->volume;
    const double kc = PD_CONTACT_SCALE * sim->sc.c / sim->b->horizon;
    double rr[8], ex[8], ey[8], ez[8];
    _mm512_storeu_pd(rr, r);
    _mm512_storeu_pd(ex, dx);
    _mm512_storeu_pd(ey, dy);
    _mm512_storeu_pd(ez, dz);
    for (int l = 0; l < 8; l++) {
        const int64_t i = rows[l], j = L->at[8 * c + l] / 8;
        if (!((near >> l) & 1) || (sim->lost && (sim->lost[i] || sim->lost[j])))
            continue;
        const double d = fmin(PD_CONTACT_REF_FRAC * L->length[8 * c + l],
                              PD_CONTACT_RADIUS_FAC * (rad[i] + rad[j]));
        if (!(rr[l] < d))
            continue;
        if (ec) {
            const double x = 0.25 * kc * (d - rr[l]) * (d - rr[l]);
            own_c[l] += x * V[j];
            ec[j] += x * V[i] * V[j];
        }
        if (!forces || !(rr[l] > 0.0))
            continue;
        const double fs = kc * (rr[l] - d) / rr[l];
        pk[8 * i + 4] += fs * V[j] * ex[l];
        pk[8 * i + 5] += fs * V[j] * ey[l];
        pk[8 * i + 6] += fs * V[j] * ez[l];
        pk[8 * j + 4] -= fs * V[i] * ex[l];
        pk[8 * j + 5] -= fs * V[i] * ey[l];
        pk[8 * j + 6] -= fs * V[i] * ez[l];
    }
}

/* Of the lanes `brk` of column c of group g, those that break (not kept
 * by --no-failure): broken, their lanes' bits cleared, their energy
 * released into *released in lane order. */
__attribute__((noinline, cold)) static __mmask8 lanes_breaks(pd_sim *sim, int64_t g, int64_t c,
                                                             const int64_t *rows, __mmask8 brk,
                                                             double *released)
{
    pd_half_bonds *h = &sim->half;
    pd_half_lanes *L = h->lanes;
    for (int l = 0; l < 8; l++) {
        if (!((brk >> l) & 1))
            continue;
        const int64_t i = rows[l], k = h->offset[i] + (c - L->col[g]);
        if (!pd_sim_may_break(sim, i, h->neighbor[k])) {
            brk = (__mmask8)(brk & ~(1u << l));
            continue;
        }
        L->bits[c] &= (uint8_t) ~(1u << l);
        pd_bond_break(h->intact, k);
        const double w = L->w[8 * c + l];
        *released += pmb_pair_energy(sim, i, h->neighbor[k], L->length[8 * c + l], w,
                                     L->wji ? L->wji[8 * c + l] : w);
    }
    return brk;
}

/* Group g's bond pass: pmb_row512's maths for 8 rows at once (its comment
 * holds them); the partners' forces and new s0 into h->pack in lane
 * order, the rows' own at the end; with `energy` the energies counted
 * into h->eb and h->ec as the rows count them. */
PMB_TARGET_AVX512 static inline __attribute__((always_inline)) void
group_pass(pd_sim *sim, int64_t g, int64_t lo, const pd_bond_mode failure, const int contact,
           const int sym, const int energy, double *released)
{
    pd_half_bonds *h = &sim->half;
    pd_half_lanes *L = h->lanes;
    const lane_arrays A = arrays_of(h);
    double *restrict pk = h->pack;
    uint8_t *const bits = L->bits;
    const double *V = sim->p->volume;
    const __m512d zero = _mm512_setzero_pd(), ninf = _mm512_set1_pd(-INFINITY);
    const __m512d vs00 = _mm512_set1_pd(sim->sc.s00), valpha = _mm512_set1_pd(sim->sc.alpha);
    const __m512d cap = _mm512_set1_pd(h->contact_cap);
    int64_t rows[8];
    __m512d yi0, yi1, yi2, s0i;
    const __mmask8 live = group_own(L, pk, g, lo, rows, &yi0, &yi1, &yi2, &s0i);
    __m512d ax = zero, ay = zero, az = zero, sm = ninf, own = zero;
    double own_c[8] = {0};
    const int64_t c1 = L->col[g + 1];
    for (int64_t c = L->col[g]; c < c1; c++) {
        const __mmask8 act = (__mmask8)(A.act[c] & live), kmu = (__mmask8)(bits[c] & live);
        row_chunk k;
        column_of(&A, c, act, yi0, yi1, yi2, &k);
        const __m512d gg = _mm512_maskz_mul_pd((__mmask8)(kmu & k.pos), k.dr, k.q);
        /* the force on i, and (the same unless the weights differ) j's */
        const __m512d wi = _mm512_load_pd(A.w + 8 * c);
        const __m512d fi = _mm512_mul_pd(wi, gg);
        const __m512d gx = _mm512_mul_pd(fi, k.dx), gy = _mm512_mul_pd(fi, k.dy),
                      gz = _mm512_mul_pd(fi, k.dz);
        ax = _mm512_add_pd(ax, gx);
        ay = _mm512_add_pd(ay, gy);
        az = _mm512_add_pd(az, gz);
        __m512d hx = gx, hy = gy, hz = gz;
        const __m512d wj = sym ? wi : _mm512_load_pd(A.wji + 8 * c);
        if (!sym) {
            const __m512d fj = _mm512_mul_pd(wj, gg);
            hx = _mm512_mul_pd(fj, k.dx);
            hy = _mm512_mul_pd(fj, k.dy);
            hz = _mm512_mul_pd(fj, k.dz);
        }
        __m512d t = zero;
        __mmask8 brk = 0;
        if (failure) {
            __m512d thr = _mm512_min_pd(s0i, k.w4);
            if (failure == PD_BONDS_FAILURE_LAWS)
                thr = _mm512_mul_pd(_mm512_load_pd(A.kfail + 8 * c), thr);
            brk = _mm512_mask_cmp_pd_mask(kmu, k.s, thr, _CMP_GT_OQ);
            t = _mm512_mask_sub_pd(ninf, kmu, vs00, _mm512_mul_pd(valpha, k.s));
            sm = _mm512_max_pd(sm, t);
        }
        const __mmask8 near = contact ? column_near(cap, &k, act) : 0;
        if (__builtin_expect((brk | near) != 0, 0)) { /* rare */
            if (brk)
                brk = lanes_breaks(sim, g, c, rows, brk, released);
            if (near)
                column_contact(sim, c, rows, near, k.r, k.dx, k.dy, k.dz, 1, own_c,
                               energy ? h->ec : NULL);
        }
        if (energy) { /* the bonds intact after this pass */
            const __m512d x = row_energy(k.s, k.L, (__mmask8)(kmu & ~brk));
            own = _mm512_add_pd(own, _mm512_mul_pd(x, wi));
            double to[8];
            _mm512_storeu_pd(to, _mm512_mul_pd(x, wj));
            for (int l = 0; l < 8; l++)
                if ((act >> l) & 1)
                    h->eb[A.at[8 * c + l] / 8] += to[l] * V[A.at[8 * c + l] / 8];
        }
        __m256d out[8];
        lanes_to_rows(hx, hy, hz, t, out);
        for (int l = 0; l < 8; l++) { /* a lane without a bond adds 0 to its own row */
            double *p = pk + A.at[8 * c + l] + 4;
            const __m256d v = _mm256_load_pd(p);
            __m256d nv = _mm256_sub_pd(v, out[l]);
            if (failure) /* the new s0: the larger */
                nv = _mm256_mask_max_pd(nv, 0x8, v, out[l]);
            _mm256_store_pd(p, nv);
        }
    }
    double o[5][8];
    _mm512_storeu_pd(o[0], ax);
    _mm512_storeu_pd(o[1], ay);
    _mm512_storeu_pd(o[2], az);
    _mm512_storeu_pd(o[3], sm);
    _mm512_storeu_pd(o[4], own);
    for (int l = 0; l < 8; l++) {
        if (!((live >> l) & 1))
            continue;
        const int64_t i = rows[l];
        double *p = pk + 8 * i + 4;
        p[0] += o[0][l];
        p[1] += o[1][l];
        p[2] += o[2][l];
        if (failure)
            p[3] = o[3][l] > p[3] ? o[3][l] : p[3];
        if (energy) {
            h->eb[i] += o[4][l] * V[i];
            if (contact)
                h->ec[i] += own_c[l] * V[i];
        }
    }
}

/* The groups of a block, a variant per failure mode, contact, symmetric
 * weights and `energy`. */
#define LANES_S(mode, contact, energy)                                                         \
    do {                                                                                       \
        if (L->wji == NULL)                                                                    \
            for (int64_t g = g0; g < g1; g++)                                                  \
                group_pass(sim, g, lo, mode, contact, 1, energy, released);                    \
        else                                                                                   \
            for (int64_t g = g0; g < g1; g++)                                                  \
                group_pass(sim, g, lo, mode, contact, 0, energy, released);                    \
    } while (0)
#define LANES(mode, contact)                                                                   \
    do {                                                                                       \
        if (energy)                                                                            \
            LANES_S(mode, contact, 1);                                                         \
        else                                                                                   \
            LANES_S(mode, contact, 0);                                                         \
    } while (0)

PMB_TARGET_AVX512 void pmb_lanes_block(pd_sim *sim, int64_t blk, int64_t lo, pd_bond_mode failure,
                                       int energy, double *released)
{
    const pd_half_lanes *L = sim->half.lanes;
    const int64_t g0 = L->first[blk], g1 = L->first[blk + 1];
    const int contact = sim->half.contact;
    PMB_VARIANTS(LANES, failure, contact);
}

/* Group g's elastic (contact 0) or contact (1) energies into e, as its
 * bond pass counts them, to the bit (h->pack: positions and volumes). */
PMB_TARGET_AVX512 static void group_energy(const pd_sim *sim, int64_t g, int64_t lo, int contact,
                                           double *e)
{
    const pd_half_bonds *h = &sim->half;
    const pd_half_lanes *L = h->lanes;
    const lane_arrays A = arrays_of(h);
    const double *V = sim->p->volume;
    const __m512d cap = _mm512_set1_pd(h->contact_cap);
    int64_t rows[8];
    __m512d yi0, yi1, yi2, vi, own = _mm512_setzero_pd();
    const __mmask8 live = group_own(L, A.pk, g, lo, rows, &yi0, &yi1, &yi2, &vi);
    double own_c[8] = {0};
    for (int64_t c = L->col[g]; c < L->col[g + 1]; c++) {
        const __mmask8 act = (__mmask8)(A.act[c] & live);
        row_chunk k;
        column_of(&A, c, act, yi0, yi1, yi2, &k);
        if (contact) {
            const __mmask8 near = column_near(cap, &k, act);
            if (near)
                column_contact(sim, c, rows, near, k.r, k.dx, k.dy, k.dz, 0, own_c, e);
            continue;
        }
        const __m512d wi = _mm512_load_pd(A.w + 8 * c);
        const __m512d wj = A.wji ? _mm512_load_pd(A.wji + 8 * c) : wi;
        const __m512d x = row_energy(k.s, k.L, (__mmask8)(L->bits[c] & live));
        own = _mm512_add_pd(own, _mm512_mul_pd(x, wi));
        double to[8];
        _mm512_storeu_pd(to, _mm512_mul_pd(x, wj));
        for (int l = 0; l < 8; l++)
            if ((act >> l) & 1)
                e[A.at[8 * c + l] / 8] += to[l] * V[A.at[8 * c + l] / 8];
    }
    double o[8];
    _mm512_storeu_pd(o, own);
    for (int l = 0; l < 8; l++)
        if ((live >> l) & 1)
            e[rows[l]] += (contact ? own_c[l] : o[l]) * V[rows[l]];
}

PMB_TARGET_AVX512 void pmb_lanes_energy_block(const pd_sim *sim, int64_t blk, int64_t lo,
                                              int contact, double *e)
{
    const pd_half_lanes *L = sim->half.lanes;
    for (int64_t g = L->first[blk]; g < L->first[blk + 1]; g++)
        group_energy(sim, g, lo, contact, e);
}

#else
void pmb_lanes_build(pd_sim *sim)
{
    (void)sim;
}

void pmb_lanes_sync(pd_sim *sim)
{
    (void)sim;
}
#endif
