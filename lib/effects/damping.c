/*
 * damping.c -- viscous, mass-proportional damping (pd-run --damping C[,SET];
 * LAMMPS fix viscous with gamma = C m): the force density -C rho_i v_i on
 * every particle, or on those of a set.
 *
 * The force of step n+1 is taken at the velocities the forces see, v at
 * n+1/2 (after the first half kick and the drift).  The power it takes,
 * sum V_i C rho_i |v_i|^2, is integrated over the step by the trapezoidal
 * rule into pd_energy.damped (pd_sim_compute_forces, lib/run/sim.c),
 * apart from the work of the loads: the balance books what the damping
 * took, and the energy put in (the energy alarm's measure) is not lessened
 * by it.  With --relax, C is the relaxation's own damping instead
 * (lib/run/relax.c).
 */
#include <stdlib.h>
#include <string.h>

#include "base/comm.h"
#include "effects/effect.h"

typedef struct {
    int64_t n;
    int64_t *rows; /* NULL: every particle; a piece of a body on MPI
                      ranks: -1 for a member beyond it               */
    double *terms; /* a piece with a set: each member's power, W     */
} damping_state;

static void damping_free(void *state)
{
    damping_state *st = state;
    if (st) {
        free(st->rows);
        free(st->terms);
    }
    free(st);
}

static pd_status damping_init(pd_sim *sim, void **state)
{
    damping_state *st = calloc(1, sizeof *st);
    if (st == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the damping");
    st->n = sim->n;
    const char *name = sim->sc.damping_set;
    if (name[0] != '\0') {
        const pd_set *set = pd_sets_find(sim->sc.sets, name);
        if (set == NULL) {
            free(st);
            return pd_fail(PD_ERR_INVALID,
                           "--damping: the model has no set '%s' (pd-lattice --set names them)",
                           name);
        }
        st->n = set->n;
        pd_status s = sim->piece ? pd_set_rows_present(set, sim->p, &st->rows)
                                 : pd_set_rows(set, sim->p, &st->rows);
        if (s == PD_OK && sim->piece &&
            (st->terms = malloc((size_t)(set->n > 0 ? set->n : 1) * sizeof(double))) == NULL)
            s = pd_fail(PD_ERR_NOMEM, "out of memory for the damping");
        if (s != PD_OK) {
            damping_free(st);
            return s;
        }
    }
    *state = st;
    return PD_OK;
}

/* damping_force for a piece of a body on MPI ranks: the force on its rows,
 * the power summed in the one rank's order (every particle: its rows' in
 * a chain over the ranks; a set: its members' in the set's order). */
static pd_status piece_damping(pd_sim *sim, const damping_state *st)
{
    const pd_piece *pc = sim->piece;
    const double c = sim->sc.damping, *rho = sim->p->density, *V = sim->p->volume;
    const uint8_t *lost = sim->lost;
    double *const *v = sim->v, *const *f = sim->f;
    const int64_t n = st->rows ? st->n : sim->n;
    if (st->terms)
        memset(st->terms, 0, (size_t)st->n * sizeof(double));
    double power = st->rows ? 0.0 : pd_comm_chain_in();
    for (int64_t m = 0; m < n; m++) {
        const int64_t i = st->rows ? st->rows[m] : m;
        if (i < 0 || (lost && lost[i]))
            continue;
        const double k = c * rho[i];
        for (int d = 0; d < 3; d++)
            f[d][i] -= k * v[d][i];
        if (i < pc->own_lo || i >= pc->own_hi)
            continue; /* a ghost: its owner's term */
        const double t = V[i] * k * (v[0][i] * v[0][i] + v[1][i] * v[1][i] + v[2][i] * v[2][i]);
        if (st->terms)
            st->terms[m] = t;
        else
            power += t;
    }
    if (st->terms) { /* each member's term from its owner: exact sums */
        pd_comm_add(st->terms, st->n);
        for (int64_t m = 0; m < st->n; m++)
            power += st->terms[m];
    } else
        power = pd_comm_chain_out(power);
    sim->damp_power += power;
    return PD_OK;
}

static pd_status damping_force(pd_sim *sim, void *state)
{
    const damping_state *st = state;
    if (sim->piece)
        return piece_damping(sim, st);
    const double c = sim->sc.damping, *rho = sim->p->density, *V = sim->p->volume;
    const uint8_t *lost = sim->lost;
    double *const *v = sim->v, *const *f = sim->f;
    double power = 0; /* in row order: the same at any thread count */
    for (int64_t m = 0; m < st->n; m++) {
        const int64_t i = st->rows ? st->rows[m] : m;
        if (lost && lost[i])
            continue;
        const double k = c * rho[i];
        for (int d = 0; d < 3; d++)
            f[d][i] -= k * v[d][i];
        power += V[i] * k * (v[0][i] * v[0][i] + v[1][i] * v[1][i] + v[2][i] * v[2][i]);
    }
    sim->damp_power += power;
    return PD_OK;
}

static int damping_declared(const pd_scene *s)
{
    return s->damping > 0 && !s->relax; /* relaxed: the relaxation's damping */
}

const pd_effect pd_effect_damping = {
    .name = "damping", .timer = PD_T_INTEGRATE, .init = damping_init, .force = damping_force,
    .free = damping_free, .declared = damping_declared};
