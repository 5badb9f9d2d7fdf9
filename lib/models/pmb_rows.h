/*
 * pmb_rows.h -- internal to lib/models/: the PMB bond list's AVX-512 rows
 * (pmb_rows.c) as pmb.c calls them, and what they share with it.
 */
#ifndef PD_PMB_ROWS_H
#define PD_PMB_ROWS_H

#include "models/model.h"

/* The rows' instruction sets: AVX-512 F, VL and DQ. */
#define PMB_TARGET_AVX512 __attribute__((target("avx512f,avx512vl,avx512dq")))

/* The elastic energy of half bond k of row i, J (pmb_rows.c; pmb.c's
 * portable rows take it too). */
double pmb_bond_energy(const pd_sim *sim, int64_t i, int64_t k);
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
/* e_i += the elastic (contact 0) or contact (1) energy of particle i in
 * the rows, counted by the step's bond pass or in a pass of their own: 1,
 * or 0 when this run has no rows (the families then). */
int pmb_rows_energy(const pd_sim *sim, double *e, int contact);
/* Does the bond pass about to run count the energies (pd_sim_energy_next)?
 * It then has h->eb and h->ec, zero. */
int pmb_rows_count(pd_sim *sim);

#endif
