/*
 * sim.c -- the run: state arrays, the effect list, and velocity Verlet
 * (seed 000 Algorithm 1):
 *   1. v^{n+1/2} = v^n + dt/(2 rho) f^n
 *   2. y^{n+1}   = y^n + dt v^{n+1/2}
 *      f^{n+1}   = sum of the declared effects at y^{n+1}
 *   3. v^{n+1}   = v^{n+1/2} + dt/(2 rho) f^{n+1}
 * f is a force density (N/m^3), so the acceleration is f/rho (LAMMPS peri
 * stores the density as the particle "mass").
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/comm.h"
#include "effects/effect.h"
#include "models/model.h"
#include "stencil/grid.h"

static pd_status add_effect(pd_sim *sim, const pd_effect *e)
{
    if (sim->neffects == PD_MAX_EFFECTS)
        return pd_fail(PD_ERR_INVALID, "too many effects");
    sim->effects[sim->neffects] = e;
    sim->state[sim->neffects] = NULL;
    if (e->init) {
        pd_status s = e->init(sim, &sim->state[sim->neffects]);
        if (s != PD_OK)
            return s;
    }
    sim->neffects++;
    sim->constrained |= e->constrain != NULL;
    size_t len = strlen(sim->names);
    snprintf(sim->names + len, sizeof sim->names - len, "%s%s", len ? " " : "", e->name);
    return PD_OK;
}

double pd_lost_margin_default(const pd_particles *p)
{
    double lo[3], hi[3], edge = p->spacing;
    pd_body_bounds(p, lo, hi);
    for (int d = 0; d < 3; d++)
        if (hi[d] > lo[d])
            edge = fmax(edge, hi[d] - lo[d]);
    return PD_LOST_MARGIN_FAC * edge;
}

void pd_lost_box(const pd_particles *p, double lost_margin, double lo[3], double hi[3])
{
    double margin = lost_margin > 0 ? lost_margin : pd_lost_margin_default(p);
    pd_body_bounds(p, lo, hi);
    for (int d = 0; d < 3; d++) {
        lo[d] -= margin;
        hi[d] += margin;
    }
}

/* The --no-failure flags: 1 for each particle of the scene's no-failure
 * sets. */
static pd_status no_failure_rows(pd_sim *sim)
{
    const pd_scene *sc = &sim->sc;
    if (sc->nno_failure == 0)
        return PD_OK;
    if ((sim->nofail = calloc((size_t)sim->n, 1)) == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for --no-failure");
    for (int k = 0; k < sc->nno_failure; k++) {
        const pd_set *set = pd_sets_find(sc->sets, sc->no_failure[k]);
        if (set == NULL)
            return pd_fail(PD_ERR_INVALID,
                           "--no-failure: the model has no set '%s' (pd-lattice --set and "
                           "pd-mesh name them)",
                           sc->no_failure[k]);
        int64_t *rows = NULL; /* a piece: -1 for members beyond it */
        pd_status s = sim->piece ? pd_set_rows_present(set, sim->p, &rows)
                                 : pd_set_rows(set, sim->p, &rows);
        if (s != PD_OK)
            return s;
        for (int64_t m = 0; m < set->n; m++)
            if (rows[m] >= 0)
                sim->nofail[rows[m]] = 1;
        free(rows);
    }
    return PD_OK;
}

/* The rows of each of the scene's named sets (the time series'). */
static pd_status set_rows(pd_sim *sim)
{
    const pd_sets *sets = sim->sc.sets;
    if (sets == NULL || sets->count == 0)
        return PD_OK;
    if ((sim->set_rows = calloc((size_t)sets->count, sizeof *sim->set_rows)) == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the sets");
    sim->nsets = sets->count;
    for (int k = 0; k < sets->count; k++) { /* a piece: -1 for members beyond it */
        pd_status s = sim->piece ? pd_set_rows_present(&sets->set[k], sim->p, &sim->set_rows[k])
                                 : pd_set_rows(&sets->set[k], sim->p, &sim->set_rows[k]);
        if (s != PD_OK)
            return s;
    }
    return PD_OK;
}

/* The lists of the run's compact families, owned by the run. */
static pd_status own_lists(pd_sim *sim)
{
    pd_status s = pd_bonds_with_lists(sim->p, sim->b, &sim->own);
    if (s == PD_OK)
        sim->b = sim->own;
    return s;
}

/* A piece walked as a bond list (lib/run/piece.c): the half bonds cut into
 * the whole body's blocks, walked from the block below its own (a bond
 * spans one block at most), from that block's first row with a partner of
 * its own, up to its own last block (the one above is ghosts, whose forces
 * are not wanted).  The rows skipped put no force on its own. */
static pd_status piece_half_blocks(pd_sim *sim)
{
    const pd_piece *pc = sim->piece;
    pd_half_bonds *h = &sim->half;
    if (pc == NULL || pc->grid)
        return PD_OK;
    pd_status st = pd_half_set_block(h, pc->half_block);
    if (st != PD_OK)
        return st;
    h->blk0 = pc->blk0;
    if (pc->own_blk_hi < h->nblocks)
        h->walk = pc->own_blk_hi;
    if (pc->own_blk_lo > 0) {
        h->walk_lo = pc->own_blk_lo - 1;
        h->clip = pc->own_lo;
    }
    return PD_OK;
}

pd_status pd_sim_new(const pd_particles *p, const pd_bonds *b, const pd_scene *s, pd_sim **out)
{
    return pd_sim_new_cut(p, b, s, NULL, out);
}

pd_status pd_sim_new_cut(const pd_particles *p, const pd_bonds *b, const pd_scene *s,
                         pd_piece *piece, pd_sim **out)
{
    if (!(s->dt > 0) || !isfinite(s->dt))
        return pd_fail(PD_ERR_INVALID, "time step must be positive");
    pd_sim *sim = calloc(1, sizeof *sim);
    if (sim == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    sim->p = p;
    sim->b = b;
    sim->sc = *s;
    sim->piece = piece; /* the grid and the half bonds are cut as it says */
    sim->n = p->n;
    size_t n = (size_t)p->n;
    int ok = 1;
    for (int d = 0; d < 3; d++) {
        sim->y[d] = malloc(n * sizeof(double));
        sim->v[d] = calloc(n, sizeof(double));
        sim->f[d] = calloc(n, sizeof(double));
        ok = ok && sim->y[d] && sim->v[d] && sim->f[d];
    }
    int64_t words = pd_bits_words(b->count) + 1;
    sim->intact = malloc((size_t)words * sizeof(uint64_t));
    ok = ok && sim->intact;
    if (s->has_failure) {
        sim->s0 = malloc(n * sizeof(double));
        sim->s0_new = malloc(n * sizeof(double));
        ok = ok && sim->s0 && sim->s0_new;
    }
    if (!ok) {
        pd_sim_free(sim);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the run state");
    }
    for (int d = 0; d < 3; d++)
        memcpy(sim->y[d], p->x[d], n * sizeof(double));
    memcpy(sim->intact, b->intact, (size_t)words * sizeof(uint64_t));
    /* the bonds as the model's kernels walk them: the lattice stencil when
     * the model and the body allow it, else the half bonds' list */
    sim->model = pd_model_of(s->model);
    pd_status st = sim->model ? PD_OK : pd_fail(PD_ERR_INVALID, "unknown model %d", (int)s->model);
    /* compact families (pd_read_bonds_compact) stay compact where the PMB
     * stencil walks them; any other kernel gets their lists */
    if (st == PD_OK && !pd_bonds_has_lists(b) && sim->model->stencil(s) != PD_STENCIL_PMB)
        st = own_lists(sim);
    if (st == PD_OK)
        st = pd_half_build(sim->b, &sim->half);
    if (st == PD_OK)
        st = piece_half_blocks(sim);
    if (st == PD_OK)
        st = no_failure_rows(sim);
    if (st == PD_OK)
        st = pd_grid_new(sim, sim->model->stencil(s), &sim->grid);
    if (st == PD_OK && sim->grid == NULL && !pd_bonds_has_lists(sim->b)) {
        pd_half_free(&sim->half); /* the bond list's, from the lists */
        memset(&sim->half, 0, sizeof sim->half);
        st = own_lists(sim);
        if (st == PD_OK)
            st = pd_half_build(sim->b, &sim->half);
        if (st == PD_OK)
            st = piece_half_blocks(sim);
    }
    if (st == PD_OK && piece && piece->grid != (sim->grid != NULL))
        st = pd_fail(PD_ERR_INVALID, "a piece of the body is not walked as the whole body is");
    if (st != PD_OK) {
        pd_sim_free(sim); /* the piece is the caller's still */
        return st;
    }
    if (s->has_failure)
        for (size_t i = 0; i < n; i++)
            sim->s0[i] = sim->s0_new[i] = DBL_MAX;
    pd_lost_box(p, s->lost_margin, sim->box_lo, sim->box_hi);
    st = set_rows(sim);
    if (st != PD_OK) {
        pd_sim_free(sim);
        return st;
    }

    /* The step is assembled from the model's force and the declared
     * effects only. */
    st = add_effect(sim, s->has_failure ? sim->model->force_failure : sim->model->force);
    for (int k = 0; pd_effects[k] && st == PD_OK; k++)
        if (pd_effects[k]->declared(s))
            st = add_effect(sim, pd_effects[k]);
    if (st != PD_OK) {
        pd_sim_free(sim);
        return st;
    }
    *out = sim;
    return PD_OK;
}

void pd_sim_free(pd_sim *sim)
{
    if (sim == NULL)
        return;
    for (int k = 0; k < sim->neffects; k++)
        if (sim->effects[k]->free)
            sim->effects[k]->free(sim->state[k]);
    for (int d = 0; d < 3; d++) {
        free(sim->y[d]);
        free(sim->v[d]);
        free(sim->f[d]);
    }
    free(sim->intact);
    free(sim->rel_held);
    pd_half_free(&sim->half);
    pd_grid_free(sim->grid);
    pd_bonds_free(sim->own);
    free(sim->s0);
    free(sim->s0_new);
    free(sim->nofail);
    free(sim->lost);
    for (int k = 0; k < sim->nsets; k++)
        free(sim->set_rows[k]);
    free(sim->set_rows);
    free(sim->held);
    if (sim->relax_free)
        sim->relax_free(sim->relax);
    if (sim->piece_owned)
        pd_piece_free(sim->piece);
    free(sim);
}

/* All force densities at the current positions; the power the effects put
 * in is integrated into the work, and the power --damping takes into
 * pd_energy.damped, with the trapezoidal rule over the step. */
pd_status pd_sim_compute_forces(pd_sim *sim)
{
    double before = sim->power, damp_before = sim->damp_power;
    sim->power = sim->damp_power = 0;
    if (!sim->f_zeroed)
        for (int d = 0; d < 3; d++)
            memset(sim->f[d], 0, (size_t)sim->n * sizeof(double));
    sim->f_zeroed = 0;
    for (int k = 0; k < sim->neffects; k++) {
        if (sim->effects[k]->force == NULL)
            continue;
        double t0 = pd_wtime(), ranks = sim->timers[PD_T_RANKS];
        pd_status s = sim->effects[k]->force(sim, sim->state[k]);
        /* its sums over the ranks are the ranks' time */
        sim->timers[sim->effects[k]->timer] += pd_wtime() - t0 - (sim->timers[PD_T_RANKS] - ranks);
        if (s != PD_OK)
            return s;
    }
    if (sim->nlost > 0) /* lost particles feel nothing: they stay at rest */
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < sim->n; i++)
            if (sim->lost[i])
                sim->f[0][i] = sim->f[1][i] = sim->f[2][i] = 0;
    if (!sim->setup && !sim->sc.relax) { /* the relaxation books its own */
        sim->work += 0.5 * sim->sc.dt * (before + sim->power);
        sim->damped += 0.5 * sim->sc.dt * (damp_before + sim->damp_power);
    }
    return PD_OK;
}

/* Is particle i outside the box?  (Not finite is not outside: the
 * numerical guard names those.) */
static inline int outside(const pd_sim *sim, int64_t i)
{
    int out = 0;
    for (int d = 0; d < 3; d++)
        out |= sim->y[d][i] < sim->box_lo[d] || sim->y[d][i] > sim->box_hi[d];
    return out;
}

/* The constrain hooks of the effects at a phase of the step (nothing to
 * do, and no cost, when no effect holds prescribed motion). */
pd_status pd_sim_constrain(pd_sim *sim, int phase)
{
    if (!sim->constrained)
        return PD_OK;
    double t0 = pd_wtime();
    pd_status s = PD_OK;
    for (int k = 0; k < sim->neffects && s == PD_OK; k++)
        if (sim->effects[k]->constrain)
            s = sim->effects[k]->constrain(sim, sim->state[k], phase);
    sim->timers[PD_T_INTEGRATE] += pd_wtime() - t0;
    return s;
}

void pd_sim_energy_next(pd_sim *sim)
{
    sim->energy_next = 1;
}

pd_status pd_sim_setup(pd_sim *sim)
{
    sim->setup = 1;
    sim->energy_next = 1; /* energy0, below */
    pd_status s = pd_sim_constrain(sim, PD_PHASE_SETUP);
    if (s == PD_OK)
        s = pd_sim_compute_forces(sim);
    sim->setup = 0;
    pd_energy e;
    if (s == PD_OK && (s = pd_sim_energy(sim, &e, NULL)) == PD_OK)
        sim->energy0 = e.kinetic + e.elastic + e.contact + e.projectile;
    if (s == PD_OK)
        sim->penalty0 = e.contact;
    return s;
}

/* The energy of straining the whole body uniformly by PD_PENALTY_STRAIN,
 * 1/2 K (3 s)^2 V: a penalty energy below it is negligible (two spheres
 * that touch to rounding). */
static double strain_energy_scale(const pd_sim *sim)
{
    double k = sim->sc.bulk_modulus;
    if (!(k > 0)) /* c given: c is linear in K */
        k = sim->sc.c / pd_pmb_c_for(sim->p, 1.0, sim->b->horizon);
    const double s = PD_PENALTY_STRAIN;
    return 0.5 * k * 9.0 * s * s * pd_sum_fixed(sim->p->volume, sim->n);
}

int pd_sim_start_penalty(const pd_sim *sim, char *text, size_t len)
{
    const double penalty = sim->penalty0, rest = sim->energy0 - penalty;
    if (!(penalty > rest) || !(penalty > strain_energy_scale(sim)))
        return 0;
    snprintf(text, len,
             "%.3g J of the %.3g J at step 0 (%.0f%%) is penalty energy of contact or of an "
             "overlap, not motion: the body starts compressed rather than loaded by the "
             "scene, and the energy balance counts it as energy put in",
             penalty, sim->energy0, 100.0 * penalty / sim->energy0);
    return 1;
}

_Static_assert(sizeof(((pd_scene *)0)->damping_set) == PD_SET_NAME_MAX,
              "pd_scene.damping_set holds a set name");

/* The energy put in: that of step 0 and the work done on the body. */
static double energy_in(const pd_sim *sim, double work)
{
    return sim->energy0 + fmax(work, 0.0);
}

int pd_energy_runaway(const pd_sim *sim, const pd_energy *e, double *ratio)
{
    double in = energy_in(sim, e->work);
    *ratio = in > 0 ? e->kinetic / in : INFINITY;
    return e->kinetic > PD_KE_GROWTH * in;
}

double pd_energy_drift(const pd_sim *sim, const pd_energy *e)
{
    const double in = energy_in(sim, e->work), d = pd_energy_total(e) - sim->energy0;
    if (in > 0)
        return d / in;
    return d == 0 ? 0 : copysign(INFINITY, d);
}

pd_status pd_sim_check_balance(const pd_sim *sim, const pd_energy *e)
{
    const double limit = sim->sc.balance_limit, drift = pd_energy_drift(sim, e);
    const int gain = drift > limit, loss = -drift > limit && !pd_model_of(sim->sc.model)->dissipative;
    if (!(limit > 0) || !(gain || loss) || sim->sc.relax) /* relaxed: no dynamics */
        return PD_OK;
    return pd_fail(PD_ERR_UNSTABLE,
                   "at step %lld the energy balance %s %.3g J since step 0, %.3g times the "
                   "energy put in (%.3g J), above --balance-limit %g: the run is unstable; try "
                   "a smaller time step (--dt, --safety) or contact stiffness",
                   (long long)sim->step, gain ? "gained" : "lost",
                   fabs(pd_energy_total(e) - sim->energy0), fabs(drift),
                   energy_in(sim, e->work), limit);
}

/* The alarm's test between status lines: a kinetic energy above (1 +
 * limit) times the energy put in means the balance gained more than the
 * limit (every other term of pd_energy_total is non-negative, and -work
 * is at least -max(work, 0)); only then are the energies taken. */
static pd_status watch_balance(const pd_sim *sim)
{
    const double limit = sim->sc.balance_limit;
    if (!(limit > 0) || sim->step % PD_BALANCE_EVERY != 0)
        return PD_OK;
    if (!(pd_sim_kinetic(sim) > (1.0 + limit) * energy_in(sim, sim->work)))
        return PD_OK;
    pd_energy e;
    pd_status s = pd_sim_energy(sim, &e, NULL);
    return s == PD_OK ? pd_sim_check_balance(sim, &e) : s;
}

/* Particles that left the box: lost, when the energy is sane (their bonds
 * broken, at rest where they are, out of contact and of the balance but
 * for pd_energy.lost); when the kinetic energy has run away, the run is
 * unstable instead. */
static pd_status take_lost(pd_sim *sim)
{
    pd_energy e = {.kinetic = pd_sim_kinetic(sim), .work = sim->work}; /* what the test needs */
    double ratio;
    if (sim->lost == NULL && (sim->lost = calloc((size_t)sim->n, 1)) == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for lost particles");
    const pd_piece *pc = sim->piece;
    const int64_t own_lo = pc ? pc->own_lo : 0, own_hi = pc ? pc->own_hi : sim->n;
    if (pd_energy_runaway(sim, &e, &ratio)) { /* the first particle away names it */
        int64_t first = INT64_MAX, id = INT64_MAX;
        for (int64_t i = own_lo; i < own_hi && first == INT64_MAX; i++)
            if (!sim->lost[i] && outside(sim, i))
                first = i + (pc ? pc->first : 0);
        if (pc) {
            first = pd_comm_min(first);
            id = pd_comm_min(first - pc->first >= own_lo && first - pc->first < own_hi
                                 ? sim->p->id[first - pc->first]
                                 : INT64_MAX);
        } else if (first < INT64_MAX)
            id = sim->p->id[first];
        if (first < INT64_MAX)
            return pd_fail(PD_ERR_UNSTABLE,
                           "particle %lld (id %lld) flew off at step %lld while the kinetic "
                           "energy is %.3g times the energy put in: the run is unstable; the "
                           "time step may be too large for the bonds or the contact stiffness",
                           (long long)first, (long long)id, (long long)sim->step, ratio);
    }
    /* the kinetic energy each takes away, in row order (a piece: its own
     * rows'; the ranks' then in rank order, the whole body's) */
    double *ke = pc ? pc->sum3 : NULL;
    int64_t nke = 0;
    for (int64_t i = 0; i < sim->n; i++) {
        if (sim->lost[i] || !outside(sim, i))
            continue;
        const double *v[3] = {sim->v[0], sim->v[1], sim->v[2]};
        const double k = 0.5 * sim->p->density[i] * sim->p->volume[i] *
                         (v[0][i] * v[0][i] + v[1][i] * v[1][i] + v[2][i] * v[2][i]);
        if (pc == NULL)
            sim->lost_energy += k;
        else if (i >= own_lo && i < own_hi)
            ke[nke++] = k;
        for (int d = 0; d < 3; d++)
            sim->v[d][i] = sim->f[d][i] = 0;
        pd_half_break_all(&sim->half, sim->b, i);
        sim->intact_stale = 1;
        sim->lost[i] = 1;
        sim->nlost++;
    }
    if (pc)
        return pd_piece_add_in_order(sim, ke, nke, &sim->lost_energy);
    return PD_OK;
}

/* Half a kick of particles [lo, hi): v += dt/(2 rho) f.  Returns 1 when
 * some velocity is not finite (a NaN or Inf in the forces or positions
 * spreads to it). */
PD_VECTOR_CLONES static int half_kick_block(pd_sim *sim, int64_t lo, int64_t hi)
{
    const double half = 0.5 * sim->sc.dt;
    const double *restrict rho = sim->p->density;
    double *restrict v0 = sim->v[0], *restrict v1 = sim->v[1], *restrict v2 = sim->v[2];
    const double *restrict f0 = sim->f[0], *restrict f1 = sim->f[1], *restrict f2 = sim->f[2];
    int bad = 0;
#pragma omp simd reduction(| : bad)
    for (int64_t i = lo; i < hi; i++) {
        const double dtfm = half / rho[i];
        v0[i] += dtfm * f0[i];
        v1[i] += dtfm * f1[i];
        v2[i] += dtfm * f2[i];
        bad |= !isfinite(v0[i] + v1[i] + v2[i]);
    }
    return bad;
}

/* Half a kick of every particle; 1 when some velocity is not finite. */
static int half_kick(pd_sim *sim)
{
    /* each thread its static share (pd_thread_share), as the passes
     * before and after cut the particles: a thread walks what it touched
     * last (the stencil's blocks are split likewise, lib/stencil/grid.c) */
    int bad = 0;
#pragma omp parallel reduction(| : bad)
    {
        int64_t lo, hi;
        pd_thread_share(sim->n, &lo, &hi);
        bad |= half_kick_block(sim, lo, hi);
    }
    return bad;
}

/* The numerical guard: name the first particle whose state is not finite. */
static pd_status not_finite(const pd_sim *sim)
{
    const pd_piece *pc = sim->piece;
    if (pc) { /* the first over the ranks, named by its whole body's row */
        int64_t mine = INT64_MAX, id = INT64_MAX;
        for (int64_t i = pc->own_lo; i < pc->own_hi && mine == INT64_MAX; i++)
            for (int d = 0; d < 3; d++)
                if (!isfinite(sim->f[d][i]) || !isfinite(sim->y[d][i]) || !isfinite(sim->v[d][i]))
                    mine = i;
        if (mine < INT64_MAX)
            id = sim->p->id[mine], mine += pc->first;
        const int64_t first = pd_comm_min(mine);
        id = pd_comm_min(mine == first ? id : INT64_MAX);
        return pd_fail(PD_ERR_UNSTABLE,
                       "the state of particle %lld (id %lld) is not finite at step %lld: the "
                       "time step may be too large for the bonds or the contact stiffness",
                       (long long)first, (long long)id, (long long)sim->step);
    }
    for (int64_t i = 0; i < sim->n; i++) {
        const char *what = NULL;
        for (int d = 0; d < 3 && what == NULL; d++)
            what = !isfinite(sim->f[d][i])   ? "force"
                   : !isfinite(sim->y[d][i]) ? "position"
                   : !isfinite(sim->v[d][i]) ? "velocity"
                                             : NULL;
        if (what)
            return pd_fail(PD_ERR_UNSTABLE,
                           "the %s of particle %lld (id %lld) is not finite at step %lld: the time "
                           "step may be too large for the bonds or the contact stiffness",
                           what, (long long)i, (long long)sim->p->id[i], (long long)sim->step);
    }
    return pd_fail(PD_ERR_UNSTABLE, "the state is not finite at step %lld", (long long)sim->step);
}

/* The drift y += dt v of particles [lo, hi) (after the first half kick v
 * += dt/(2 rho) f when `kick`, which then also zeroes f for the forces to
 * come: they are read for the last time here), branch-free so that it
 * vectorizes.  Returns 1 when some particle (not lost already) is outside
 * the box; a position that is not finite is not outside (the guard names
 * it). */
static inline __attribute__((always_inline)) int drift_range(pd_sim *sim, int64_t lo,
                                                             int64_t hi, const int kick,
                                                             const int lost_any)
{
    const double dt = sim->sc.dt, half = 0.5 * dt;
    const double *restrict rho = sim->p->density;
    const uint8_t *restrict lost = sim->lost;
    double *restrict y0 = sim->y[0], *restrict y1 = sim->y[1], *restrict y2 = sim->y[2];
    double *restrict v0 = sim->v[0], *restrict v1 = sim->v[1], *restrict v2 = sim->v[2];
    double *restrict f0 = sim->f[0], *restrict f1 = sim->f[1], *restrict f2 = sim->f[2];
    const double lo0 = sim->box_lo[0], lo1 = sim->box_lo[1], lo2 = sim->box_lo[2];
    const double hi0 = sim->box_hi[0], hi1 = sim->box_hi[1], hi2 = sim->box_hi[2];
    int away = 0;
#pragma omp simd reduction(| : away)
    for (int64_t i = lo; i < hi; i++) {
        if (kick) {
            const double dtfm = half / rho[i];
            v0[i] += dtfm * f0[i];
            v1[i] += dtfm * f1[i];
            v2[i] += dtfm * f2[i];
            f0[i] = f1[i] = f2[i] = 0.0;
        }
        y0[i] += dt * v0[i];
        y1[i] += dt * v1[i];
        y2[i] += dt * v2[i];
        const int out = (y0[i] < lo0) | (y0[i] > hi0) | (y1[i] < lo1) | (y1[i] > hi1) |
                        (y2[i] < lo2) | (y2[i] > hi2);
        away |= lost_any ? out & (lost[i] == 0) : out;
    }
    return away;
}

PD_VECTOR_CLONES static int drift_block(pd_sim *sim, int64_t lo, int64_t hi, int kick,
                                        int lost_any)
{
    if (kick)
        return lost_any ? drift_range(sim, lo, hi, 1, 1) : drift_range(sim, lo, hi, 1, 0);
    return lost_any ? drift_range(sim, lo, hi, 0, 1) : drift_range(sim, lo, hi, 0, 0);
}

/* The drift of every particle (with the first half kick when `kick`); 1
 * when some particle left the box. */
static int drift(pd_sim *sim, int kick)
{
    const int lost_any = sim->lost != NULL;
    int away = 0;
#pragma omp parallel reduction(| : away)
    {
        int64_t lo, hi;
        pd_thread_share(sim->n, &lo, &hi);
        away |= drift_block(sim, lo, hi, kick, lost_any);
    }
    return away;
}

pd_status pd_sim_step(pd_sim *sim)
{
    double t0 = pd_wtime();
    const double dt = sim->sc.dt;
    /* without a hold between them the first half kick and the drift are
     * one pass over the particles (the same arithmetic, less traffic) */
    const int fused = !sim->constrained;
    if (!fused) {
        half_kick(sim);
        pd_status s = pd_sim_constrain(sim, PD_PHASE_KICK1);
        if (s != PD_OK)
            return s;
    }
    for (int k = 0; k < sim->neffects; k++) /* the effects' own motion */
        if (sim->effects[k]->kick)
            sim->effects[k]->kick(sim, sim->state[k], 0);
    const int away = drift(sim, fused);
    sim->f_zeroed = fused;
    for (int k = 0; k < sim->neffects; k++)
        if (sim->effects[k]->drift)
            sim->effects[k]->drift(sim, sim->state[k]);
    sim->step++;
    sim->time = (double)sim->step * dt;
    sim->timers[PD_T_INTEGRATE] += pd_wtime() - t0;
    pd_status s = pd_sim_constrain(sim, PD_PHASE_DRIFT);
    int gone = away;
    if (sim->piece && s == PD_OK) { /* the ghosts' positions and s0 from their owners */
        unsigned ask = away ? 1u : 0u; /* and, in one reduction, the effects' questions */
        for (int k = 0; k < sim->neffects; k++)
            if (sim->effects[k]->moved) {
                const double tq = pd_wtime(); /* the effect's own time */
                ask |= sim->effects[k]->moved(sim, sim->state[k]) ? 2u : 0u;
                sim->timers[sim->effects[k]->timer] += pd_wtime() - tq;
            }
        const double th = pd_wtime();
        s = pd_piece_halo(sim);
        const unsigned agreed = pd_comm_bits(ask);
        gone = agreed & 1u;
        sim->moved = 1 + (int)((agreed >> 1) & 1u);
        sim->timers[PD_T_RANKS] += pd_wtime() - th;
    }
    if (s == PD_OK && gone) {
        double tl = pd_wtime(); /* breaking the lost particles' bonds */
        s = take_lost(sim);
        sim->timers[PD_T_FAILURE] += pd_wtime() - tl;
    }
    if (s == PD_OK)
        s = pd_sim_compute_forces(sim);
    sim->moved = 0; /* asked for these forces alone */
    if (s != PD_OK)
        return s;
    t0 = pd_wtime();
    if (sim->piece) /* the ghosts' forces lack bonds: they stay at rest */
        pd_piece_ghosts_rest(sim);
    int bad = half_kick(sim);
    if (sim->piece) {
        const double th = pd_wtime();
        bad = pd_comm_or(bad);
        sim->timers[PD_T_RANKS] += pd_wtime() - th;
        t0 += pd_wtime() - th;
    }
    for (int k = 0; k < sim->neffects && s == PD_OK; k++)
        if (sim->effects[k]->kick)
            s = sim->effects[k]->kick(sim, sim->state[k], 1);
    if (s != PD_OK)
        return s;
    sim->timers[PD_T_INTEGRATE] += pd_wtime() - t0;
    if (!bad && (s = pd_sim_constrain(sim, PD_PHASE_KICK2)) != PD_OK)
        return s;
    return bad ? not_finite(sim) : watch_balance(sim);
}

int pd_sim_stencil(const pd_sim *sim)
{
    return pd_grid_offsets(sim->grid);
}

int pd_sim_stencil_tiles(const pd_sim *sim)
{
    return pd_grid_tiles(sim->grid);
}

int pd_sim_list_rows(const pd_sim *sim)
{
    return sim->grid == NULL && sim->half.pack != NULL;
}

int pd_sim_list_lanes(const pd_sim *sim)
{
    return sim->grid == NULL && sim->half.lanes != NULL;
}

/* 1/2 rho V |v|^2 of every particle into e. */
static void kinetic_each(const pd_sim *sim, double *e)
{
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        double v2 = sim->v[0][i] * sim->v[0][i] + sim->v[1][i] * sim->v[1][i] +
                    sim->v[2][i] * sim->v[2][i];
        e[i] = 0.5 * sim->p->density[i] * sim->p->volume[i] * v2;
    }
}

double pd_sim_kinetic(const pd_sim *sim)
{
    double *buf = malloc((size_t)(sim->n > 0 ? sim->n : 1) * sizeof(double));
    if (sim->piece && pd_comm_or(buf == NULL)) { /* every rank, or none, goes on */
        free(buf);
        buf = NULL;
    }
    if (buf == NULL)
        return NAN;
    kinetic_each(sim, buf);
    double e;
    pd_sim_sum(sim, (const double *const *)&buf, 1, &e);
    free(buf);
    return e;
}

pd_status pd_sim_energy(const pd_sim *sim, pd_energy *e, double *density)
{
    pd_sim_released(sim); /* a piece's steps not yet summed (collective) */
    memset(e, 0, sizeof *e);
    double *buf = malloc((size_t)(sim->n > 0 ? sim->n : 1) * sizeof(double));
    if (sim->piece && pd_comm_or(buf == NULL)) { /* every rank, or none, goes on */
        free(buf);
        buf = NULL;
    }
    if (buf == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the energies");
    kinetic_each(sim, buf);
    pd_sim_sum(sim, (const double *const *)&buf, 1, &e->kinetic);
    if (density)
        memset(density, 0, (size_t)sim->n * sizeof(double));
    for (int k = 0; k < sim->neffects; k++) {
        const pd_effect *ef = sim->effects[k];
        if (ef->energy == NULL)
            continue;
        memset(buf, 0, (size_t)sim->n * sizeof(double));
        ef->energy(sim, sim->state[k], buf);
        double sum;
        pd_sim_sum(sim, (const double *const *)&buf, 1, &sum);
        if (ef->kind == PD_ENERGY_ELASTIC) {
            e->elastic += sum;
            if (density)
                for (int64_t i = 0; i < sim->n; i++)
                    density[i] += buf[i] / sim->p->volume[i];
        } else
            e->contact += sum;
    }
    e->released = sim->released;
    e->lost = sim->lost_energy;
    e->work = sim->work;
    e->damped = sim->damped;
    if (sim->has_projectile)
        e->projectile = 0.5 * sim->sc.proj_mass *
                        (sim->proj_v[0] * sim->proj_v[0] + sim->proj_v[1] * sim->proj_v[1] +
                         sim->proj_v[2] * sim->proj_v[2]);
    free(buf);
    return PD_OK;
}

pd_status pd_sim_stress(const pd_sim *sim, double *stress)
{
    memset(stress, 0, (size_t)sim->n * 9 * sizeof(double));
    for (int k = 0; k < sim->neffects; k++)
        if (sim->effects[k]->stress)
            sim->effects[k]->stress(sim, sim->state[k], stress);
    return PD_OK;
}

double pd_von_mises(const double s[9])
{
    const double xy = 0.5 * (s[1] + s[3]), yz = 0.5 * (s[5] + s[7]), zx = 0.5 * (s[2] + s[6]);
    const double a = s[0] - s[4], b = s[4] - s[8], c = s[8] - s[0];
    return sqrt(0.5 * (a * a + b * b + c * c) + 3.0 * (xy * xy + yz * yz + zx * zx));
}

double pd_energy_total(const pd_energy *e)
{
    return e->kinetic + e->elastic + e->contact + e->released + e->lost - e->work +
           e->projectile + e->damped;
}

void pd_sim_accumulated(const pd_sim *sim, pd_restart *r)
{
    pd_sim_released(sim); /* a piece's steps not yet summed (collective) */
    r->work = sim->work;
    r->released = sim->released;
    r->power = sim->power;
    r->lost_energy = sim->lost_energy;
    r->energy0 = sim->energy0;
    r->has_damping = pd_sim_damping(sim) > 0;
    r->damping[0] = sim->damped;
    r->damping[1] = sim->damp_power;
    r->lost = sim->lost;
    for (int d = 0; d < 3; d++) {
        r->position[d] = sim->y[d];
        r->force[d] = sim->f[d];
    }
    r->s0 = sim->sc.has_failure ? sim->s0 : NULL;
    for (int k = 0; k < sim->neffects; k++) /* what the effects keep */
        if (sim->effects[k]->save)
            sim->effects[k]->save(sim, sim->state[k], r);
}

pd_status pd_sim_damage_stats_of(const pd_sim *sim, const double *damage, double threshold,
                                 double *max_damage, int64_t *above)
{
    const pd_piece *pc = sim->piece;
    double m = 0;
    int64_t count = 0;
    for (int64_t i = pc ? pc->own_lo : 0; i < (pc ? pc->own_hi : sim->n); i++) {
        m = fmax(m, damage[i]);
        count += damage[i] > threshold;
    }
    *max_damage = pc ? pd_comm_max(m) : m;
    *above = pc ? pd_comm_total(count) : count;
    return PD_OK;
}

pd_status pd_sim_damage_stats(const pd_sim *sim, double threshold, double *max_damage,
                              int64_t *above)
{
    const pd_piece *pc = sim->piece;
    if (pc == NULL && pd_grid_damage(sim, threshold, max_damage, above)) /* the stencil's masks */
        return PD_OK;
    /* a piece: its own rows (whole families), then over the ranks */
    double *dmg = malloc((size_t)(sim->n > 0 ? sim->n : 1) * sizeof(double));
    if (pc && pd_comm_or(dmg == NULL)) { /* every rank, or none, goes on */
        free(dmg);
        dmg = NULL;
    }
    if (dmg == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the damage");
    /* the bond list's own bits where they do (no directed bits made) */
    if (pc || sim->grid || !pd_half_damage(sim->p, sim->b, &sim->half, dmg))
        pd_damage(sim->p, sim->b, pd_sim_intact(sim), dmg);
    pd_status s = pd_sim_damage_stats_of(sim, dmg, threshold, max_damage, above);
    free(dmg);
    return s;
}

void pd_sim_damage(const pd_sim *sim, double *damage)
{
    if (!pd_grid_damage_counted(sim, 1.0, damage, NULL, NULL)) /* refuses a piece */
        pd_damage(sim->p, sim->b, pd_sim_intact(sim), damage);
}

double pd_sim_max_damage(const pd_sim *sim)
{
    double m;
    int64_t above;
    return pd_sim_damage_stats(sim, 1.0, &m, &above) == PD_OK ? m : NAN;
}

pd_status pd_sim_restore(pd_sim *sim, int64_t step, const pd_restart *r, double *const v[3],
                         const uint64_t *intact)
{
    size_t bytes = (size_t)sim->n * sizeof(double);
    for (int d = 0; d < 3; d++) {
        memcpy(sim->y[d], r->position[d], bytes);
        memcpy(sim->v[d], v[d], bytes);
        memcpy(sim->f[d], r->force[d], bytes);
    }
    if (sim->sc.has_failure) {
        if (r->s0 == NULL)
            return pd_fail(PD_ERR_FORMAT, "the restart data have no s0, the scene has failure");
        memcpy(sim->s0, r->s0, bytes);
    }
    /* the run's bond bits from the frame's: rebuild the half bonds' */
    memcpy(sim->intact, intact, (size_t)pd_bits_words(sim->b->count) * sizeof(uint64_t));
    pd_half_set_state(&sim->half, sim->b, intact);
    sim->intact_stale = 0;
    sim->step = step;
    sim->time = (double)step * sim->sc.dt;
    sim->work = r->work;
    sim->released = r->released;
    sim->power = r->power;
    sim->lost_energy = r->lost_energy;
    sim->energy0 = r->energy0;
    if (r->has_damping) {
        sim->damped = r->damping[0];
        sim->damp_power = r->damping[1];
    }
    if (r->lost) {
        free(sim->lost);
        if ((sim->lost = malloc((size_t)sim->n)) == NULL)
            return pd_fail(PD_ERR_NOMEM, "out of memory for lost particles");
        memcpy(sim->lost, r->lost, (size_t)sim->n);
        sim->nlost = 0;
        for (int64_t i = 0; i < sim->n; i++)
            sim->nlost += sim->lost[i] != 0;
    }
    pd_status s = PD_OK; /* what the effects keep */
    for (int k = 0; k < sim->neffects && s == PD_OK; k++)
        if (sim->effects[k]->restore)
            s = sim->effects[k]->restore(sim, sim->state[k], r);
    return s;
}

int64_t pd_sim_no_failure(const pd_sim *sim)
{
    int64_t n = 0; /* a piece: its own rows' */
    const int64_t lo = sim->piece ? sim->piece->own_lo : 0,
                  hi = sim->piece ? sim->piece->own_hi : sim->n;
    for (int64_t i = lo; sim->nofail && i < hi; i++)
        n += sim->nofail[i];
    return n;
}

double pd_sim_damping(const pd_sim *sim)
{
    return sim->sc.relax ? 0.0 : sim->sc.damping; /* relaxed: the relaxation's */
}
