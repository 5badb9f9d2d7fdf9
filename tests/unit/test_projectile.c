/*
 * test_projectile -- the projectile (lib/effects/projectile.c) against the head-on
 * elastic collision of two bodies.
 *
 * Proves: a sphere of mass M at velocity V that hits a free particle of
 * mass m = rho V_p at rest, head on, leaves with V' = (M - m)/(M + m) V
 * and gives the particle v' = 2M/(M + m) V (momentum and kinetic energy
 * of the two conserved: the penalty K (R - r)^2 is conservative), to second
 * order in dt; momentum M V + m v is conserved to rounding at every step;
 * and the balance kinetic + contact + projectile stays at 1/2 M V^2.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "pd.h"

static const double RHO = 2200.0, VP = 1e-9, M = 4.4e-6, V0 = -10.0, R = 1e-3;

/* Runs the collision with step dt for a time T; returns V', v'. */
static void collide(double dt, double T, double *Vout, double *vout, double *dp, double *de)
{
    pd_particles *p = pd_particles_new(1);
    if (p == NULL)
        die("particles");
    p->x[0][0] = p->x[1][0] = p->x[2][0] = 0;
    p->volume[0] = VP;
    p->density[0] = RHO;
    p->radius[0] = 0.5e-3;
    p->material[0] = 1;
    p->id[0] = 1;
    p->spacing = 1e-3;
    p->dimension = 3;
    pd_bonds *b = NULL;
    if (pd_bonds_build(p, 3.0001e-3, &b) != PD_OK)
        die("bonds");
    pd_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.model = PD_MODEL_PMB;
    sc.c = 1e21;
    sc.dt = dt;
    sc.dt_stable = INFINITY;
    sc.has_projectile = 1;
    sc.proj_center[2] = R + 1e-4; /* 0.1 mm above the particle */
    sc.proj_radius = R;
    sc.proj_mass = M;
    sc.proj_velocity[2] = V0;
    sc.proj_k = 1e17;
    pd_sim *sim = NULL;
    if (pd_sim_new(p, b, &sc, &sim) != PD_OK || pd_sim_setup(sim) != PD_OK)
        die("sim");
    const double m = RHO * VP, e0 = 0.5 * M * V0 * V0;
    *dp = *de = 0;
    int64_t steps = (int64_t)llround(T / dt);
    for (int64_t n = 0; n < steps; n++) {
        if (pd_sim_step(sim) != PD_OK)
            die("step");
        double x[3], v[3];
        pd_sim_projectile(sim, x, v);
        *dp = fmax(*dp, fabs(M * v[2] + m * pd_sim_velocities(sim)[2][0] - M * V0) / fabs(M * V0));
        pd_energy e;
        if (pd_sim_energy(sim, &e, NULL) != PD_OK)
            die("energy");
        *de = fmax(*de, fabs(pd_energy_total(&e) - e0) / e0);
    }
    double x[3], v[3];
    pd_sim_projectile(sim, x, v);
    *Vout = v[2];
    *vout = pd_sim_velocities(sim)[2][0];
    pd_sim_free(sim);
    pd_bonds_free(b);
    pd_particles_free(p);
}

static void test_collision(void)
{
    int f0 = failures;
    const double m = RHO * VP, T = 6e-5;
    const double Vw = (M - m) / (M + m) * V0, vw = 2 * M / (M + m) * V0;
    double V1, v1, dp1, de1, V2, v2, dp2, de2;
    collide(2e-8, T, &V1, &v1, &dp1, &de1);
    collide(1e-8, T, &V2, &v2, &dp2, &de2);
    double err1 = fmax(fabs(V1 - Vw), fabs(v1 - vw)) / fabs(V0);
    double err2 = fmax(fabs(V2 - Vw), fabs(v2 - vw)) / fabs(V0);
    printf("  V' = %.9g (want %.9g), v' = %.9g (want %.9g); error %.3g at dt, %.3g at dt/2\n",
           V2, Vw, v2, vw, err1, err2);
    printf("  momentum error %.3g, energy error %.3g\n", fmax(dp1, dp2), fmax(de1, de2));
    CHECK(err2 < 1e-8, "velocities after the collision off by %g", err2);
    CHECK(err2 < 0.5 * err1, "not converging: %g then %g", err1, err2);
    CHECK(fmax(dp1, dp2) < 1e-14, "momentum not conserved: %g", fmax(dp1, dp2));
    CHECK(fmax(de1, de2) < 1e-5, "energy balance off: %g", fmax(de1, de2));
    proved(f0, "a sphere hitting a free particle head on: the elastic collision's velocities, "
               "momentum to rounding, the energy balance");
}

int main(void)
{
    test_collision();
    return failures ? 1 : 0;
}
