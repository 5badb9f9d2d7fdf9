/*
 * state.c -- the run's state as the kernels and the programs read it:
 * the step, the time, positions, velocities, forces, s0, the bond states
 * (the directed bits brought up to date from the half bonds on demand),
 * lost particles, timers.  Nothing here steps or calls an effect: the
 * integrator that does is lib/run/sim.c.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/comm.h"
#include "state/sim.h"

const char *pd_sim_effects(const pd_sim *sim)
{
    return sim->names;
}

int64_t pd_sim_stepno(const pd_sim *sim)
{
    return sim->step;
}

double pd_sim_time(const pd_sim *sim)
{
    return sim->time;
}

int64_t pd_sim_lost(const pd_sim *sim)
{
    const pd_piece *pc = sim->piece;
    if (pc == NULL)
        return sim->nlost;
    int64_t mine = 0; /* the own rows' (a ghost is its owner's) */
    for (int64_t i = pc->own_lo; sim->lost && i < pc->own_hi; i++)
        mine += sim->lost[i] != 0;
    return pd_comm_total(mine);
}

int64_t pd_sim_broken(const pd_sim *sim)
{
    const pd_piece *pc = sim->piece;
    const pd_half_bonds *h = &sim->half;
    if (pc == NULL)
        return pd_bits_count_broken(h->intact, h->count);
    /* the half bonds of the own rows: each bond of the body once */
    const int64_t q0 = h->offset[pc->own_lo], q1 = h->offset[pc->own_hi];
    return pd_comm_total(pd_bits_count_broken(h->intact, q1) -
                         pd_bits_count_broken(h->intact, q0));
}

const double *pd_sim_timers(const pd_sim *sim)
{
    return sim->timers;
}

const pd_particles *pd_sim_particles(const pd_sim *sim)
{
    return sim->p;
}

const pd_bonds *pd_sim_bonds(const pd_sim *sim)
{
    return sim->b;
}

double *const *pd_sim_positions(const pd_sim *sim)
{
    return sim->y;
}

double *const *pd_sim_velocities(const pd_sim *sim)
{
    return sim->v;
}

const uint64_t *pd_sim_intact(const pd_sim *sim)
{
    pd_sim *mut = (pd_sim *)sim; /* a cache: the state itself does not change */
    if (mut->intact_stale) {
        if (!(mut->directed_bits && mut->directed_bits(sim, mut->intact)))
            pd_half_expand(&mut->half, sim->b, mut->intact);
        mut->intact_stale = 0;
    }
    return sim->intact;
}

double *const *pd_sim_forces(const pd_sim *sim)
{
    return sim->f;
}

const double *pd_sim_s0(const pd_sim *sim)
{
    return sim->sc.has_failure ? sim->s0 : NULL;
}

void pd_sim_add_released(pd_sim *sim, const double *released, int64_t nblocks)
{
    const pd_piece *pc = sim->piece;
    if (pc == NULL) {
        for (int64_t blk = 0; blk < nblocks; blk++) /* in block order: any thread count */
            sim->released += released[blk];
        return;
    }
    /* a piece: its own blocks' kept, every rank's added later in the whole
     * body's order (pd_sim_released) */
    if (sim->rel_steps == PD_RELEASED_STEPS) { /* the ranks' time, not the failure's it is
                                                  called in (pd_sim_compute_forces takes the
                                                  ranks' off the bonds') */
        const double t0 = pd_wtime();
        pd_sim_released(sim);
        const double dt = pd_wtime() - t0;
        sim->timers[PD_T_FAILURE] -= dt;
        sim->timers[PD_T_BONDS] += dt;
    }
    const int64_t own = pc->blocks[pc->rank];
    memcpy(sim->rel_held + sim->rel_steps * own, released + pc->own_blk_lo,
           (size_t)own * sizeof(double));
    sim->rel_steps++;
}

void pd_sim_released(const pd_sim *csim)
{
    pd_sim *sim = (pd_sim *)csim; /* the sums owed to `released` */
    const pd_piece *pc = sim->piece;
    if (pc == NULL || sim->rel_steps == 0)
        return;
    /* every rank's own blocks of each step, step by step, in rank order:
     * the whole body's block order, as one rank adds them (the time it
     * takes is the ranks') */
    const double t0 = pd_wtime();
    const int P = pc->ranks;
    const int64_t m = sim->rel_steps;
    int64_t counts[P], at[P], total = 0;
    for (int r = 0; r < P; r++) {
        counts[r] = m * pc->blocks[r];
        at[r] = total;
        total += counts[r];
    }
    double *all = malloc((size_t)(total > 0 ? total : 1) * sizeof(double));
    if (pd_comm_or(all == NULL)) /* a few doubles a block; nothing sane goes on */
        sim->released = NAN;
    else {
        pd_comm_allgather(sim->rel_held, counts, all);
        for (int64_t st = 0; st < m; st++)
            for (int r = 0; r < P; r++)
                for (int64_t blk = 0; blk < pc->blocks[r]; blk++)
                    sim->released += all[at[r] + st * pc->blocks[r] + blk];
    }
    free(all);
    sim->rel_steps = 0;
    sim->timers[PD_T_RANKS] += pd_wtime() - t0;
}

void pd_sim_sum(const pd_sim *sim, const double *const *x, int m, double *sums)
{
    const pd_piece *pc = sim->piece;
    if (pc == NULL) {
        for (int c = 0; c < m; c++)
            sums[c] = pd_sum_fixed(x[c], sim->n);
        return;
    }
    const double *own[8], t0 = pd_wtime();
    for (int c = 0; c < m && c < 8; c++)
        own[c] = x[c] + pc->own_lo;
    pd_comm_sum_fixed(own, m, pc->first + pc->own_lo, pc->own_hi - pc->own_lo, pc->n_whole, sums);
    ((pd_sim *)sim)->timers[PD_T_RANKS] += pd_wtime() - t0; /* a clock, not the state */
}
