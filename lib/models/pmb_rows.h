/*
 * pmb_rows.h -- internal to lib/models/: the PMB bond list's AVX-512 rows
 * (pmb_rows.c) as pmb.c calls them, and what they share with it.
 */
#ifndef PD_PMB_ROWS_H
#define PD_PMB_ROWS_H

#include "models/model.h"

/* The rows' instruction sets: AVX-512 F, VL and DQ. */
#define PMB_TARGET_AVX512 __attribute__((target("avx512f,avx512vl,avx512dq")))

#if PD_AVX512_KERNELS
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

/* The stretch of 8 bonds of length L at distance r (dr = r - L, 0 below
 * eps of extension): dr (r q) with q = 1/(|xi| r) (pmb_row512's one
 * division, *q for its force), dr/|xi| where r = 0; every pass of the
 * rows takes it, so that their energies are the same bits. */
PMB_TARGET_AVX512 static inline __attribute__((always_inline)) __m512d
row_stretch(__m512d r, __m512d L, __m512d dr, __mmask8 act, __mmask8 *pos, __m512d *q)
{
    *pos = _mm512_mask_cmp_pd_mask(act, r, _mm512_setzero_pd(), _CMP_GT_OQ);
    *q = _mm512_maskz_div_pd(*pos, _mm512_set1_pd(1.0), _mm512_mul_pd(L, r));
    __m512d s = _mm512_mul_pd(dr, _mm512_mul_pd(r, *q));
    if ((__mmask8)(act & ~*pos))
        s = _mm512_mask_div_pd(s, (__mmask8)(act & ~*pos), dr, L);
    return s;
}

/* 1/4 s^2 |xi| of the lanes of `keep`, 0 elsewhere: a bond's elastic
 * energy over w = c V nu and the volume of the end it goes to. */
PMB_TARGET_AVX512 static inline __attribute__((always_inline)) __m512d
row_energy(__m512d s, __m512d L, __mmask8 keep)
{
    return _mm512_maskz_mul_pd(keep, _mm512_mul_pd(_mm512_mul_pd(_mm512_set1_pd(0.25), s), s), L);
}

/* A chunk of 8 bonds of a row: its partners' 4th values (s0 in the bond
 * pass, volumes in the energies' passes), the bond vectors, lengths r and
 * |xi|, the extension dr (0 below eps of extension), the stretch s and
 * row_stretch's q and pos. */
typedef struct {
    __m512d w4, L, dx, dy, dz, r, dr, s, q;
    __mmask8 pos;
} row_chunk;

/* The bonds of a chunk (rows) or column (lanes) of 8 whose partners are at
 * xj, yj, zj and lengths in c->L: the bond vectors, lengths r, the
 * extension dr (0 below eps of extension), the stretch and row_stretch's
 * q and pos; every pass of the rows and of the lanes takes its bonds so,
 * to the bit. */
PMB_TARGET_AVX512 static inline __attribute__((always_inline)) void
chunk_bonds(__m512d xj, __m512d yj, __m512d zj, __mmask8 act, __m512d yi0, __m512d yi1,
            __m512d yi2, row_chunk *c)
{
    __m512d d[3];
    pd_bonds8(xj, yj, zj, yi0, yi1, yi2, c->L, d, &c->r, &c->dr);
    c->dx = d[0];
    c->dy = d[1];
    c->dz = d[2];
    c->s = row_stretch(c->r, c->L, c->dr, act, &c->pos, &c->q);
}
#endif

/* M(mode, contact) for a pass's failure mode and contact: a variant of the
 * AVX-512 passes (rows and lanes) for each, the tests out of the loops. */
#define PMB_VARIANTS(M, failure, contact)                                                      \
    do {                                                                                       \
        if ((failure) == PD_BONDS_FAILURE_LAWS && (contact))                                   \
            M(PD_BONDS_FAILURE_LAWS, 1);                                                       \
        else if ((failure) == PD_BONDS_FAILURE_LAWS)                                           \
            M(PD_BONDS_FAILURE_LAWS, 0);                                                       \
        else if ((failure) && (contact))                                                       \
            M(PD_BONDS_FAILURE, 1);                                                            \
        else if (failure)                                                                      \
            M(PD_BONDS_FAILURE, 0);                                                            \
        else if (contact)                                                                      \
            M(PD_BONDS_ELASTIC, 1);                                                            \
        else                                                                                   \
            M(PD_BONDS_ELASTIC, 0);                                                            \
    } while (0)

/* The elastic energy of half bond k of row i, J: 1/2 c s^2 |xi| nu V_i
 * V_j, with the mean of nu_ij and nu_ji (w = c V nu holds the rest;
 * pmb_rows.c; pmb.c's portable rows take it too); and of the bond i-j of
 * length L and weights wij, wji (the lanes', which hold their own). */
double pmb_bond_energy(const pd_sim *sim, int64_t i, int64_t k);
double pmb_pair_energy(const pd_sim *sim, int64_t i, int64_t j, double L, double wij, double wji);
/* fn(sim, blk, lo, hi, ctx) for each block of the half bonds and the rows
 * [lo, hi) of it that the list's passes walk: even blocks in parallel,
 * then odd ones (of the whole body, pd_half_bonds.blk0; a block writes
 * only to itself and the next), so that every sum is in an order the
 * blocks fix, whatever the thread count.  A piece's block below its own
 * is walked from its first row with a partner of the piece's own
 * (pd_half_bonds.clip; the partners ascend). */
typedef void pmb_block_fn(const pd_sim *sim, int64_t blk, int64_t lo, int64_t hi, void *ctx);
void pmb_walk_blocks(const pd_sim *sim, pmb_block_fn *fn, void *ctx);
#if PD_AVX512_KERNELS
/* The bond pass of rows [lo, hi) in AVX-512 (h->pack), with `energy` the
 * energies counted into h->eb and h->ec; the released energy of the bonds
 * it breaks into *released. */
PMB_TARGET_AVX512 void pmb_rows_block(pd_sim *sim, int64_t lo, int64_t hi, pd_bond_mode failure,
                                      int energy, double *released);
#endif
/* The bond list in lanes (pmb_lanes.c; pd_half_lanes): built in h->lanes
 * where the run has the rows (h->pack), unless PD_NO_LANES is set or
 * memory is short (the rows then); its bits brought up to the half bonds'
 * where their epoch moved on (a restart, a lost particle). */
void pmb_lanes_build(pd_sim *sim);
void pmb_lanes_sync(pd_sim *sim);
#if PD_AVX512_KERNELS
/* pmb_rows_block's pass over block blk in lanes, from row lo (a piece's
 * block below its own: its first row with a partner of the piece's). */
PMB_TARGET_AVX512 void pmb_lanes_block(pd_sim *sim, int64_t blk, int64_t lo, pd_bond_mode failure,
                                       int energy, double *released);
#endif
/* e_i += the elastic (contact 0) or contact (1) energies of block blk's
 * rows from lo, and their partners' shares, as the bond pass counts them
 * (h->pack: positions and volumes): the lanes' (pmb_lanes_energy_block,
 * AVX-512). */
typedef void pmb_energy_block_fn(const pd_sim *sim, int64_t blk, int64_t lo, int contact,
                                 double *e);
#if PD_AVX512_KERNELS
PMB_TARGET_AVX512 pmb_energy_block_fn pmb_lanes_energy_block;
#endif
/* e_i += the elastic (contact 0) or contact (1) energy of particle i in
 * the rows, counted by the step's bond pass or in a pass of their own,
 * block by block in the rows or, with `lanes`, by that (the lanes'): 1,
 * or 0 when this run has no rows (the families then). */
int pmb_rows_energy(const pd_sim *sim, double *e, int contact, pmb_energy_block_fn *lanes);
/* Does the bond pass about to run count the energies (pd_sim_energy_next)?
 * It then has h->eb and h->ec, zero. */
int pmb_rows_count(pd_sim *sim);

#endif
