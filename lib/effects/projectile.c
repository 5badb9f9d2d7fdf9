/*
 * projectile.c -- a rigid spherical projectile that the body pushes back
 * (pd-run --projectile; seed 004 §6, the Hertzian cone crack: a sphere of
 * given mass and velocity that slows, stops and rebounds).
 *
 * The force law on the particles is the indenter's (lib/effects/indenter.c): every
 * particle inside the sphere, r = |y_i - X| < R, feels the force density
 *   f_i += K (R - r)^2 (y_i - X) / r,                       N/m^3,
 * and the sphere, of mass M, feels the reaction
 *   F = - sum_i V_i f_i,                                    N,
 * so that the particles and the sphere together exchange no momentum with
 * the outside.  The sphere moves by velocity Verlet with the particles'
 * step (lib/run/sim.c pd_sim_step): half kick V += dt/(2M) F, drift
 * X += dt V together with the particles, forces at the new positions, half
 * kick.  Its penalty energy sum V_i K (R - r)^3 / 3 is contact energy and
 * 1/2 M |V|^2 its own term of the balance (pd_energy.projectile); it does
 * no external work.  Lost particles are left out.
 *
 * Default K (no K given).  The penalty's tangent stiffness per unit
 * volume, d|f_i|/dp = 2 K p at a penetration p = R - r, grows with the
 * penetration; the bonds' is bounded by the sum of seed 004 eq. 46,
 * S_i = sum_p V_p nu c/|xi|, which sets the stable step.  K is chosen so
 * that 2 K p equals max_i S_i at p = PD_PROJECTILE_DEPTH x spacing (a
 * quarter of the spacing): the sphere stops within a fraction of a
 * particle spacing of the surface it first meets (a hard contact, as
 * Hertz's), while at the penetrations an impact reaches the penalty adds
 * about as much stiffness as the bonds, which the 0.8 safety factor and
 * eq. 46's conservatism in 3-D (a factor of about 2, pd-run(1)) absorb.
 */
#include <math.h>

#include "effects/effect.h"
#include "models/model.h"
#include "stencil/grid.h"

double pd_projectile_default_k(const pd_particles *p, const pd_bonds *b, const pd_scene *s)
{
    double smax = 0; /* a window: its own rows (pd_read_body_ranks) */
    for (int64_t i = p->window ? p->own_lo : 0; i < (p->window ? p->own_hi : b->n); i++)
        smax = fmax(smax, pd_scene_has_laws(s) ? pd_bond_stiffness_laws(p, b, s, i)
                                               : pd_bond_stiffness(p, b, s->c, i));
    return smax / (2.0 * PD_PROJECTILE_DEPTH * p->spacing);
}

/* The force densities on the particles inside the sphere, and the reaction
 * on the sphere (pd_sphere_push: the same at any thread count). */
static pd_status projectile_force(pd_sim *sim, void *state)
{
    (void)state;
    double F[3];
    pd_sphere_push(sim, sim->proj_x, sim->sc.proj_radius, sim->sc.proj_k, F);
    for (int d = 0; d < 3; d++)
        sim->proj_f[d] = -F[d];
    return PD_OK;
}

/* The penalty energy, V_i K (R - r)^3 / 3 (contact energy). */
static void projectile_energy(const pd_sim *sim, void *state, double *e)
{
    (void)state;
    pd_sphere_energy(sim, sim->proj_x, sim->sc.proj_radius, sim->sc.proj_k, e);
}

/* The sphere at t = 0, with the default K when the scene gives none. */
static pd_status projectile_init(pd_sim *sim, void **state)
{
    (void)state;
    const pd_scene *s = &sim->sc;
    if (!(s->proj_radius > 0) || !(s->proj_mass > 0) || !(s->proj_k >= 0))
        return pd_fail(PD_ERR_INVALID, "the projectile's radius, mass and stiffness must be "
                                       "positive");
    if (!(s->proj_k > 0))
        sim->sc.proj_k = pd_projectile_default_k(sim->p, sim->b, s);
    sim->has_projectile = 1;
    for (int d = 0; d < 3; d++) {
        sim->proj_x[d] = s->proj_center[d];
        sim->proj_v[d] = s->proj_velocity[d];
    }
    return PD_OK;
}

static int projectile_declared(const pd_scene *s)
{
    return s->has_projectile;
}

/* Its half kick V += dt/(2M) F, and its drift X += dt V. */
static pd_status projectile_kick(pd_sim *sim, void *state, int second)
{
    (void)state;
    const double h = 0.5 * sim->sc.dt / sim->sc.proj_mass;
    for (int d = 0; d < 3; d++)
        sim->proj_v[d] += h * sim->proj_f[d];
    if (second && !isfinite(sim->proj_v[0] + sim->proj_v[1] + sim->proj_v[2]))
        return pd_fail(PD_ERR_UNSTABLE,
                       "the projectile's velocity is not finite at step %lld: the time step "
                       "may be too large for its stiffness",
                       (long long)sim->step);
    return PD_OK;
}

static void projectile_drift(pd_sim *sim, void *state)
{
    (void)state;
    for (int d = 0; d < 3; d++)
        sim->proj_x[d] += sim->sc.dt * sim->proj_v[d];
}

static void projectile_save(const pd_sim *sim, void *state, pd_restart *r)
{
    (void)state;
    r->has_projectile = 1;
    for (int d = 0; d < 3; d++) {
        r->projectile[d] = sim->proj_x[d];
        r->projectile[3 + d] = sim->proj_v[d];
        r->projectile[6 + d] = sim->proj_f[d];
    }
}

static pd_status projectile_restore(pd_sim *sim, void *state, const pd_restart *r)
{
    (void)state;
    if (!r->has_projectile)
        return pd_fail(PD_ERR_FORMAT, "the restart data have no projectile, the scene has one");
    for (int d = 0; d < 3; d++) {
        sim->proj_x[d] = r->projectile[d];
        sim->proj_v[d] = r->projectile[3 + d];
        sim->proj_f[d] = r->projectile[6 + d];
    }
    return PD_OK;
}

int pd_sim_projectile(const pd_sim *sim, double x[3], double v[3])
{
    if (!sim->has_projectile)
        return 0;
    for (int d = 0; d < 3; d++) {
        x[d] = sim->proj_x[d];
        v[d] = sim->proj_v[d];
    }
    return 1;
}

const pd_effect pd_effect_projectile = {
    .name = "projectile", .timer = PD_T_INDENTER, .init = projectile_init,
    .force = projectile_force, .energy = projectile_energy, .kind = PD_ENERGY_CONTACT,
    .declared = projectile_declared, .kick = projectile_kick, .drift = projectile_drift,
    .save = projectile_save, .restore = projectile_restore};
