/*
 * test_ves -- the viscoelastic solid (--model ves, lib/models/lps.c) under a
 * held deformation.
 *
 * Proves: under a simple shear gamma held fixed (the force evaluated again
 * and again at the same positions, as a step with no motion would), the
 * back extension of each bond follows e^b_1 = beta e^d, e^b_{n+1} = e^d
 * (1 - d) + e^b_n d (d = exp(-dt/tau), beta = 1 - tau/dt (1 - d)), so the
 * interior shear stress relaxes as
 *   s(n) / s_el = (1 - lambda) + lambda (1 - beta) exp(-(n-1) dt/tau),
 * s_el the stress with lambda = 0: the exponential with time constant tau
 * down to the elastic fraction 1 - lambda.  The relaxed energy density is
 * (1 - lambda) of the elastic one plus what the Maxwell branch keeps.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "pd.h"
#include "state/sim.h"

static const double RHO = 2200.0, H = 1e-3, DELTA = 3.0001e-3;
static const int M = 10; /* particles per edge */

static pd_particles *cube(void)
{
    char spec[128];
    snprintf(spec, sizeof spec, "0,%.17g,0,%.17g,0,%.17g", M * H, M * H, M * H);
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, spec, &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {H, RHO, 1, 0, 1};
    pd_particles *p = NULL;
    if (pd_lattice_make(&r, 1, &lp, &p) != PD_OK)
        die("lattice");
    return p;
}

static int interior(const pd_particles *p, int64_t i)
{
    for (int d = 0; d < 3; d++)
        if (p->x[d][i] < DELTA || p->x[d][i] > (M - 1) * H - DELTA)
            return 0;
    return 1;
}

/* A VES run with the simple shear y_x = x + gamma z in place. */
static pd_sim *ves_sheared(const pd_particles *p, const pd_bonds *b, double lambda, double tau,
                           double dt, double gamma)
{
    pd_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.model = PD_MODEL_VES;
    sc.bulk_modulus = 14.9e9;
    sc.shear_modulus = 6e9;
    sc.ves_lambda = lambda;
    sc.ves_tau = tau;
    sc.c = pd_pmb_c_from_bulk(sc.bulk_modulus, b->horizon);
    sc.dt = dt;
    sc.safety = 1;
    sc.steps = 1;
    sc.dt_stable = pd_stable_dt(p, b, &sc);
    pd_sim *sim = NULL;
    if (pd_sim_new(p, b, &sc, &sim) != PD_OK)
        die("pd_sim_new");
    double *const *y = pd_sim_positions(sim);
    for (int64_t i = 0; i < p->n; i++)
        y[0][i] = p->x[0][i] + gamma * p->x[2][i];
    return sim;
}

/* One force evaluation of the model (advancing the bond history). */
static void evaluate(pd_sim *sim)
{
    if (sim->effects[0]->force(sim, sim->state[0]) != PD_OK)
        die("force");
}

/* The mean interior shear stress (s_xz + s_zx)/2, Pa, and energy density. */
static void interior_means(const pd_particles *p, pd_sim *sim, double *s, double *w)
{
    double *st = malloc((size_t)p->n * 9 * sizeof(double));
    double *wd = malloc((size_t)p->n * sizeof(double));
    pd_energy e;
    if (st == NULL || wd == NULL || pd_sim_stress(sim, st) != PD_OK ||
        pd_sim_energy(sim, &e, wd) != PD_OK)
        die("stress");
    double sum = 0, wsum = 0;
    int cnt = 0;
    for (int64_t i = 0; i < p->n; i++)
        if (interior(p, i)) {
            sum += 0.5 * (st[9 * i + 2] + st[9 * i + 6]);
            wsum += wd[i];
            cnt++;
        }
    *s = sum / cnt;
    *w = wsum / cnt;
    free(st);
    free(wd);
}

static void test_relaxation(const pd_particles *p, const pd_bonds *b)
{
    int f0 = failures;
    const double lambda = 0.4, dt = 1e-8, tau = 25 * dt, gamma = 1e-4;
    const double d = exp(-dt / tau), beta = 1 - tau / dt * (1 - d);
    double s_el, w_el;
    pd_sim *el = ves_sheared(p, b, 0.0, tau, dt, gamma);
    evaluate(el);
    interior_means(p, el, &s_el, &w_el);
    pd_sim *sim = ves_sheared(p, b, lambda, tau, dt, gamma);
    double worst = 0, s = 0, w = 0;
    for (int n = 1; n <= 200; n++) {
        evaluate(sim);
        interior_means(p, sim, &s, &w);
        const double want = (1 - lambda) + lambda * (1 - beta) * exp(-(n - 1) * dt / tau);
        worst = fmax(worst, fabs(s / s_el - want));
    }
    /* the residue is the O(gamma^2) dilatation of the shear */
    CHECK(worst <= 1e-8, "s(n)/s_el off the exponential by %.3g", worst);
    CHECK(fabs(s / s_el - (1 - lambda)) <= 1e-3, "relaxed s/s_el %.9f, 1 - lambda %.3f",
          s / s_el, 1 - lambda);
    /* relaxed: the Maxwell spring is unloaded, the elastic one keeps 1 - lambda */
    CHECK(fabs(w / w_el - (1 - lambda)) <= 1e-3, "relaxed W/W_el %.9f", w / w_el);
    CHECK(s_el > 0.5 * 6e9 * gamma && s_el < 1.5 * 6e9 * gamma, "s_el %.6g vs G gamma %.6g",
          s_el, 6e9 * gamma);
    printf("  relaxation: |s(n)/s_el - exponential| <= %.2g over 200 evaluations, s_el / "
           "(G gamma) = %.4f, relaxed s/s_el = %.6f\n",
           worst, s_el / (6e9 * gamma), s / s_el);
    pd_sim_free(el);
    pd_sim_free(sim);
    proved(f0, "held shear: the stress relaxes as exp(-t/tau) to (1 - lambda) of the elastic");
}

int main(void)
{
    pd_particles *p = cube();
    pd_bonds *b = NULL;
    if (pd_bonds_build(p, DELTA, &b) != PD_OK)
        die("bonds");
    test_relaxation(p, b);
    pd_bonds_free(b);
    pd_particles_free(p);
    return failures != 0;
}
