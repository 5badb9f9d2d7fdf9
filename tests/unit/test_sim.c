/*
 * test_sim -- the run (lib/run/sim.c with its effects): velocity Verlet over the
 * PMB bond force, bond failure and contact.
 *
 * Proves: a free body (no indenter, no boundary condition) given random
 * initial velocities keeps its total momentum sum rho_i V_i v_i to round-off
 * over 100 steps, with failure and contact declared as well as without;
 * without failure and contact the total energy, kinetic plus the PMB strain
 * energy 1/2 sum_i V_i sum_j 1/4 c s^2 |xi| nu V_j, stays bounded over 100
 * steps at 0.8 of the stable step and is conserved to second order in dt
 * (the error over a fixed time falls by 4 when dt is halved, as it does for
 * velocity Verlet only when the force derives from that energy); pd_sim_kinetic is sum 1/2 rho V |v|^2; the
 * effects list names exactly the declared effects; and the trajectory is
 * bit-identical with 1 and 2 OpenMP threads.
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "pd.h"


static const double H = 1e-3, K = 14.9e9, RHO = 2200.0;

/* A perturbed 9x9x9 block and its bonds (delta = 3.0001 h). */
static void model(pd_particles **pp, pd_bonds **bp)
{
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, "0,0.008,0,0.008,0,0.008", &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {H, RHO, 1, 0.05 * H, 11};
    if (pd_lattice_make(&r, 1, &lp, pp) != PD_OK || pd_bonds_build(*pp, 3.0001 * H, bp) != PD_OK)
        die("model");
}

static pd_sim *start(const pd_particles *p, const pd_bonds *b, int failure, int contact,
                     double amplitude, double safety)
{
    pd_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.model = PD_MODEL_PMB;
    sc.c = pd_pmb_c_from_bulk(K, b->horizon);
    sc.bulk_modulus = K;
    sc.safety = safety;
    sc.dt_stable = pd_stable_dt(p, b, &sc);
    sc.dt = sc.safety * sc.dt_stable;
    sc.steps = 100;
    if (failure) {
        sc.has_failure = 1;
        sc.s00 = 0.0005;
        sc.alpha = 0.25;
    }
    if (contact) {
        sc.has_contact = 1;
        sc.contact_skin = 0.5 * H;
    }
    pd_sim *sim = NULL;
    if (pd_sim_new(p, b, &sc, &sim) != PD_OK)
        die("pd_sim_new");
    /* random velocities, seeded per particle id so the start is reproducible */
    double *const *v = pd_sim_velocities(sim);
    for (int64_t i = 0; i < p->n; i++) {
        uint64_t s = (uint64_t)p->id[i] * 0x9E3779B97F4A7C15ULL;
        for (int d = 0; d < 3; d++) {
            s ^= s >> 30;
            s *= 0xBF58476D1CE4E5B9ULL;
            s ^= s >> 27;
            s *= 0x94D049BB133111EBULL;
            s ^= s >> 31;
            v[d][i] = amplitude * (2.0 * (double)(s >> 11) / 9007199254740992.0 - 1.0);
        }
    }
    if (pd_sim_setup(sim) != PD_OK)
        die("setup");
    return sim;
}

static void momentum(const pd_sim *sim, const pd_particles *p, double P[3], double *scale)
{
    double *const *v = pd_sim_velocities(sim);
    P[0] = P[1] = P[2] = 0;
    *scale = 0;
    for (int64_t i = 0; i < p->n; i++) {
        double m = p->density[i] * p->volume[i];
        for (int d = 0; d < 3; d++) {
            P[d] += m * v[d][i];
            *scale += m * fabs(v[d][i]);
        }
    }
}

static void test_momentum(void)
{
    int f0 = failures;
    pd_particles *p;
    pd_bonds *b;
    model(&p, &b);
    for (int variant = 0; variant < 2; variant++) {
        /* 20 m/s: enough to break bonds when failure is declared */
        pd_sim *sim = start(p, b, variant, variant, 20.0, 0.8);
        const char *want = variant ? "pmb+failure contact" : "pmb";
        CHECK(strcmp(pd_sim_effects(sim), want) == 0, "effects '%s', expected '%s'",
              pd_sim_effects(sim), want);
        double P0[3], scale;
        momentum(sim, p, P0, &scale);
        double worst = 0;
        for (int n = 0; n < 100; n++) {
            if (pd_sim_step(sim) != PD_OK)
                die("step");
            double P[3], s;
            momentum(sim, p, P, &s);
            for (int d = 0; d < 3; d++)
                worst = fmax(worst, fabs(P[d] - P0[d]));
        }
        CHECK(worst <= 1e-12 * scale, "%s: momentum drifts by %g (scale %g)", want, worst, scale);
        if (variant)
            CHECK(pd_sim_broken(sim) > 0, "the random velocities should break bonds");
        else
            CHECK(pd_sim_broken(sim) == 0, "no failure declared, yet bonds broke");
        CHECK(pd_sim_stepno(sim) == 100, "step count");
        pd_sim_free(sim);
    }
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "a free body keeps its momentum to round-off (with and without failure, contact)");
}

/* PMB strain energy: each directed bond holds half of 1/2 c s^2 |xi| nu V_i V_j. */
static double strain_energy(const pd_sim *sim, const pd_particles *p, const pd_bonds *b, double c)
{
    double *const *y = pd_sim_positions(sim);
    double w = 0;
    for (int64_t i = 0; i < p->n; i++)
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            int64_t j = b->neighbor[k];
            double dx = y[0][j] - y[0][i], dy = y[1][j] - y[1][i], dz = y[2][j] - y[2][i];
            double s = (sqrt(dx * dx + dy * dy + dz * dz) - b->length[k]) / b->length[k];
            w += 0.25 * c * s * s * b->length[k] * b->vfactor[k] * p->volume[i] *
                 p->volume[j];
        }
    return w;
}

static double kinetic(const pd_sim *sim, const pd_particles *p)
{
    double *const *v = pd_sim_velocities(sim);
    double e = 0;
    for (int64_t i = 0; i < p->n; i++)
        e += 0.5 * p->density[i] * p->volume[i] *
             (v[0][i] * v[0][i] + v[1][i] * v[1][i] + v[2][i] * v[2][i]);
    return e;
}

/* Largest |E - E0| over `steps` steps at `safety` times the stable step. */
static double energy_drift(const pd_particles *p, const pd_bonds *b, double safety, int steps,
                           double *e0_out, double *wmax_out)
{
    const double c = pd_pmb_c_from_bulk(K, b->horizon);
    pd_sim *sim = start(p, b, 0, 0, 1.0, safety);
    double ke0 = kinetic(sim, p);
    CHECK(fabs(pd_sim_kinetic(sim) - ke0) <= 1e-12 * ke0, "pd_sim_kinetic %g, expected %g",
          pd_sim_kinetic(sim), ke0);
    double e0 = ke0 + strain_energy(sim, p, b, c);
    double worst = 0, wmax = 0;
    for (int n = 0; n < steps; n++) {
        if (pd_sim_step(sim) != PD_OK)
            die("step");
        double ke = kinetic(sim, p), w = strain_energy(sim, p, b, c);
        CHECK(isfinite(ke) && ke <= 1.2 * e0, "kinetic energy runs away at step %d", n + 1);
        pd_energy en;
        if (pd_sim_energy(sim, &en, NULL) != PD_OK)
            die("pd_sim_energy");
        CHECK(fabs(en.kinetic - ke) <= 1e-12 * e0 && fabs(en.elastic - w) <= 1e-12 * e0 &&
                  en.contact == 0 && en.work == 0 && en.released == 0,
              "pd_sim_energy at step %d: kinetic %g elastic %g, expected %g %g", n + 1,
              en.kinetic, en.elastic, ke, w);
        worst = fmax(worst, fabs(ke + w - e0));
        wmax = fmax(wmax, w);
    }
    pd_sim_free(sim);
    *e0_out = e0;
    *wmax_out = wmax;
    return worst;
}

static void test_energy(void)
{
    int f0 = failures;
    pd_particles *p;
    pd_bonds *b;
    model(&p, &b);
    double e0, wmax;
    /* the default step: bounded, no drift away */
    double d08 = energy_drift(p, b, 0.8, 100, &e0, &wmax);
    CHECK(wmax > 0.1 * e0, "the body should store strain energy (%g of %g)", wmax, e0);
    CHECK(d08 <= 0.15 * e0, "safety 0.8: energy off by %.3g of %.3g", d08, e0);
    /* over the same time, halving dt divides the error by 4 (Verlet is
     * second order, which holds only if the force derives from the energy) */
    double d04 = energy_drift(p, b, 0.4, 100, &e0, &wmax);
    double d02 = energy_drift(p, b, 0.2, 200, &e0, &wmax);
    CHECK(d02 <= 0.01 * e0, "safety 0.2: energy off by %.3g of %.3g", d02, e0);
    CHECK(d02 / d04 > 0.2 && d02 / d04 < 0.3, "error ratio %.3f for dt/2, expected 1/4",
          d02 / d04);
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "total energy (kinetic + PMB strain) is conserved to O(dt^2): bounded at the "
               "default step, error / 4 when dt / 2");
}

static void test_threads(void)
{
    int f0 = failures;
    pd_particles *p;
    pd_bonds *b;
    model(&p, &b);
    double *y1[3];
    for (int t = 1; t <= 2; t++) {
        omp_set_num_threads(t);
        pd_sim *sim = start(p, b, 1, 1, 20.0, 0.8);
        for (int n = 0; n < 50; n++)
            if (pd_sim_step(sim) != PD_OK)
                die("step");
        double *const *y = pd_sim_positions(sim);
        for (int d = 0; d < 3; d++) {
            if (t == 1) {
                y1[d] = malloc((size_t)p->n * sizeof(double));
                memcpy(y1[d], y[d], (size_t)p->n * sizeof(double));
            } else {
                CHECK(memcmp(y1[d], y[d], (size_t)p->n * sizeof(double)) == 0,
                      "positions differ between 1 and 2 threads (axis %d)", d);
                free(y1[d]);
            }
        }
        pd_sim_free(sim);
    }
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "the trajectory is bit-identical with 1 and 2 threads");
}

/* Two particles brought to one point (bonded, and in contact range) give
 * no NaN: the bond and contact forces of a pair at r = 0 are 0. */
static void test_coincident(void)
{
    int f0 = failures;
    pd_particles *p;
    pd_bonds *b;
    model(&p, &b);
    for (int failure = 0; failure <= 1; failure++) {
        pd_sim *sim = start(p, b, failure, 1, 0.0, 0.8);
        double *const *y = pd_sim_positions(sim);
        int32_t j = b->neighbor[b->offset[0]]; /* a partner of particle 0 */
        for (int d = 0; d < 3; d++)
            y[d][j] = y[d][0];
        for (int n = 0; n < 20; n++)
            if (pd_sim_step(sim) != PD_OK)
                CHECK(0, "step %d: %s", n + 1, pd_errmsg());
        pd_energy e;
        CHECK(pd_sim_energy(sim, &e, NULL) == PD_OK && isfinite(pd_energy_total(&e)),
              "energies not finite");
        pd_sim_free(sim);
    }
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "two particles at one point give finite forces and energies");
}

int main(void)
{
    test_momentum();
    test_energy();
    test_threads();
    test_coincident();
    if (failures)
        fprintf(stderr, "test_sim: %d failures\n", failures);
    return failures != 0;
}
