/*
 * grid.h -- internal (lib/stencil/): the bonds of a body on a lattice,
 * walked as a stencil.
 */
#ifndef PD_GRID_H
#define PD_GRID_H

#include "state/sim.h"

/* Which lattice stencil (lib/stencil/) can walk a model's bonds. */
typedef enum {
    PD_STENCIL_NONE = 0, /* none: the bonds need data of their own (laws, ellipsoids) */
    PD_STENCIL_PMB,      /* the PMB kernels, with failure and contact            */
    PD_STENCIL_LPS       /* LPS's dilatation and pair forces                     */
} pd_stencil_kind;

/* The PMB bonds of a body on a lattice, walked as a stencil (lib/stencil/grid.c).
 * pd_grid_new builds the stencil of `kind` (the model's, lib/models/) and
 * leaves *out NULL when the body or the scene (--bond-list) does not allow
 * it (then the model's bond list serves). */
pd_status pd_grid_new(pd_sim *sim, pd_stencil_kind kind, pd_grid **out);
/* The lattice, stencil and blocks alone that pd_grid_new would find for a
 * run of the scene sc on the whole body p, b (no state: no masks, tiles or
 * scratch): what a piece of the body is cut from and takes its stencil's
 * table from (lib/run/piece.c), without the whole body's run.  *out NULL
 * when pd_grid_new would find none. */
pd_status pd_grid_plan(const pd_particles *p, const pd_bonds *b, const pd_scene *sc,
                       pd_stencil_kind kind, pd_grid **out);
/* The same plan of a body spread over MPI ranks as windows of compact
 * families (collective): each rank's p, b its window, whose own rows
 * [p->own_lo, p->own_hi) have whole families and whose rows reach the
 * rows below its own; the whole body's table and blocks (the blocks' first
 * rows only: no runs or segments).  *out NULL (on every rank) where the
 * windows cannot show that pd_grid_plan of the whole body would find this
 * stencil: its rows out of lattice order, a bound on the table that does
 * not settle it, a sparse body. */
pd_status pd_grid_plan_window(const pd_particles *p, const pd_bonds *b, const pd_scene *sc,
                              pd_stencil_kind kind, pd_grid **out);
/* 0 when no stencil of `kind` can walk the body p under the scene sc,
 * whatever its bonds (its particles are off any lattice, say): a piece of
 * it on MPI ranks may then read its own rows alone.  p may be a window of
 * the body (pd_particles): then over the ranks' windows (collective). */
int pd_grid_possible(const pd_particles *p, const pd_scene *sc, pd_stencil_kind kind);
void pd_grid_free(pd_grid *g);
/* The PMB forces (and with `failure` the breaking test and s0), and the
 * contact forces of the stencil pairs when the scene has contact. */
pd_status pd_grid_pmb(pd_sim *sim, pd_bond_mode failure);
/* Half-stencil offsets (0: no grid); are its rows walked in AVX-512
 * tiles; does the kernel take the contact of the stencil pairs; is i-j a
 * stencil pair. */
int pd_grid_offsets(const pd_grid *g);
/* The masks brought up to the half bonds' bits when these changed from
 * outside (their epoch): at once rather than at the next bond pass, for
 * the energies of a state set from outside (lib/run/piece.c's gather). */
pd_status pd_grid_resync(pd_sim *sim);
/* The blocks of outer planes the kernel cuts the body into: their count,
 * and (where not NULL) the first row of each and the row after the last
 * in start[0..count], the axes (inner, mid, outer), the planes a block;
 * 0 when there is no grid, or its rows are not in lattice order. */
int64_t pd_grid_blocks(const pd_grid *g, int64_t *start, int axis[3], int *thick);
int pd_grid_tiles(const pd_grid *g);
/* The shortest reference distance of a pair that is not a stencil pair,
 * m (lib/effects/contact.c searches only particles that moved enough to close
 * it). */
double pd_grid_gap(const pd_grid *g);
/* The largest damage of a particle (seed 000 eq. 10) and the number of
 * particles damaged above `threshold`, counted on the stencil's masks in
 * parallel: 1 when they are set, 0 when the grid cannot tell (none, or its
 * masks lag behind the half bonds). */
int pd_grid_damage(const pd_sim *sim, double threshold, double *max_damage, int64_t *above);
int pd_grid_contact(const pd_grid *g);
int pd_grid_pair(const pd_grid *g, int64_t i, int64_t j);
/* LPS on the stencil (lib/models/lps.c without ellipsoids, particles in lattice
 * order): theta of Algorithm 4 into theta (m: the weighted volumes), the
 * forces of Algorithm 2 and with failure the test and s0_new; each broken
 * bond i-j (i < j) goes to mark(ctx, i, j), its stencil bit already
 * cleared. */
pd_status pd_grid_lps(pd_sim *sim, const double *m, double *theta, pd_bond_mode failure,
                      void (*mark)(void *ctx, int64_t i, int64_t j), void *ctx);
/* LPS's elastic energy V_i W*_i of now, J, added to e[i] (lps.c's
 * energy_row, its sums over the bonds walked as the stencil walks them:
 * equal to rounding); 1, or 0 when the grid cannot (out of memory, the
 * masks not to be had): the caller walks the families. */
int pd_grid_lps_energy(const pd_sim *sim, const double *m, double *e);
/* The directed state bits of the file's families (b's order) read off
 * the masks (grid_bits.c): 1 when written, 0 when the grid cannot tell
 * (particles not in grid order, more than 64 offsets, masks lagging
 * behind the half bonds); pd_sim_intact then expands the half bonds. */
int pd_grid_directed_bits(const pd_sim *sim, uint64_t *intact);
/* The damage of each particle (seed 000 eq. 10, pd_damage's figures to the
 * bit) counted off the masks and their mirror (grid_bits.c) into damage
 * (NULL: not kept), its largest and the number of particles above
 * threshold (either NULL: not wanted): 1, or 0 when the grid cannot tell
 * (as pd_grid_directed_bits, volumes that differ, or an MPI rank's piece). */
int pd_grid_damage_counted(const pd_sim *sim, double threshold, double *damage,
                           double *max_damage, int64_t *above);
/* The bonds' elastic energy, J, added to e[i]. */
void pd_grid_pmb_energy(const pd_sim *sim, double *e);
/* The contact energy of the stencil pairs, J, added to e[i]. */
void pd_grid_contact_energy(const pd_sim *sim, double *e);

#endif
