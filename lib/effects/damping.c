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

#include "effects/effect.h"

typedef struct {
    int64_t n;
    int64_t *rows; /* NULL: every particle */
} damping_state;

static void damping_free(void *state)
{
    damping_state *st = state;
    if (st)
        free(st->rows);
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
        pd_status s = pd_set_rows(set, sim->p, &st->rows);
        if (s != PD_OK) {
            free(st);
            return s;
        }
    }
    *state = st;
    return PD_OK;
}

static pd_status damping_force(pd_sim *sim, void *state)
{
    const damping_state *st = state;
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
