/*
 * test_materials -- bonds with their own PMB constants (lib/models/materials.c):
 * fibres (seed 004 eq. 10), materials and interfaces, seen through the
 * public run interface.
 *
 * Forces are read off the velocities after one velocity-Verlet step with a
 * tiny dt from rest, f = rho v / dt (as test_pmb).
 *
 * Proves: a bond along the fibre direction g gets c_fibre, one across g
 * c_matrix, one at 45 degrees the mean (beta^2 = 1/2), in the force, the
 * elastic energy 1/2 c s^2 |xi| nu V_i V_j and the stable step of eq. 46;
 * a bond inside a material takes its law, a bond between two materials the
 * interface law or, without one, the harmonic mean of the two; a bond's own
 * critical stretch (interface or fibre) breaks it exactly above its
 * threshold and not below; an unknown material id is refused.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "pd.h"

static const double RHO = 2200.0;
static const double H = 1e-3, V = 1e-9, DT = 1e-13;

/* Two particles, the second at H dir from the first, materials m0 and m1. */
static pd_particles *pair(const double dir[3], int32_t m0, int32_t m1)
{
    pd_particles *p = pd_particles_new(2);
    double len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    for (int i = 0; i < 2; i++) {
        for (int d = 0; d < 3; d++)
            p->x[d][i] = i * H * dir[d] / len;
        p->volume[i] = V;
        p->density[i] = RHO;
        p->radius[i] = 0.5 * H;
        p->material[i] = i ? m1 : m0;
        p->id[i] = i + 1;
    }
    p->spacing = H;
    return p;
}

static pd_scene scene(double c)
{
    pd_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.model = PD_MODEL_PMB;
    sc.c = c;
    sc.dt = DT;
    sc.safety = 1;
    sc.steps = 1;
    return sc;
}

/* The micromodulus the run gives the pair's bond, from the force on
 * particle 0 at stretch s along the bond (nu = 3/4 at horizon 1.25 H):
 * |f_0| = c s nu V; also the elastic energy and the stable step. */
static double pair_c(const pd_particles *p, pd_scene *sc, double *c_energy, double *c_dt)
{
    pd_bonds *b = NULL;
    if (pd_bonds_build(p, 1.25 * H, &b) != PD_OK || b->count != 2)
        die("pair bonds");
    sc->dt_stable = pd_stable_dt(p, b, sc);
    *c_dt = 2 * RHO / (sc->dt_stable * sc->dt_stable * V * 0.75 / H);
    pd_sim *sim = NULL;
    if (pd_sim_new(p, b, sc, &sim) != PD_OK)
        die("pd_sim_new");
    const double s = 1e-3;
    double *const *y = pd_sim_positions(sim);
    for (int d = 0; d < 3; d++)
        y[d][1] = p->x[d][1] * (1 + s);
    pd_energy e;
    if (pd_sim_energy(sim, &e, NULL) != PD_OK)
        die("energy");
    *c_energy = e.elastic / (0.5 * s * s * H * 0.75 * V * V);
    if (pd_sim_setup(sim) != PD_OK || pd_sim_step(sim) != PD_OK)
        die("step");
    double *const *v = pd_sim_velocities(sim), f = 0;
    for (int d = 0; d < 3; d++)
        f += (RHO * v[d][0] / DT) * (RHO * v[d][0] / DT);
    pd_sim_free(sim);
    pd_bonds_free(b);
    return sqrt(f) / (s * 0.75 * V);
}

static int close_to(double a, double b)
{
    return fabs(a - b) <= 1e-9 * fabs(b);
}

static void test_fibre(void)
{
    int f0 = failures;
    const double cf = 3e20, cm = 1e20;
    const struct {
        double dir[3], want;
        const char *what;
    } cases[] = {{{1, 0, 0}, cf, "along g"},
                 {{0, 1, 0}, cm, "across g"},
                 {{0, 0, 1}, cm, "across g (z)"},
                 {{1, 1, 0}, 0.5 * (cf + cm), "at 45 degrees"},
                 {{-1, 0, 1}, 0.5 * (cf + cm), "at 135 degrees"}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        pd_particles *p = pair(cases[k].dir, 1, 1);
        pd_scene sc = scene(cm);
        sc.has_fibre = 1;
        sc.fibre_g[0] = 2; /* any length */
        sc.fibre_c[0] = cf;
        sc.fibre_c[1] = cm;
        double ce, cdt, c = pair_c(p, &sc, &ce, &cdt), cl, s00;
        pd_bond_law_of(p, &sc, 0, 1, &cl, &s00);
        CHECK(close_to(c, cases[k].want), "%s: force c %.17g, expected %.17g", cases[k].what, c,
              cases[k].want);
        CHECK(close_to(ce, cases[k].want), "%s: energy c %.17g", cases[k].what, ce);
        CHECK(close_to(cdt, cases[k].want), "%s: eq. 46 c %.17g", cases[k].what, cdt);
        CHECK(close_to(cl, cases[k].want), "%s: pd_bond_law_of c %.17g", cases[k].what, cl);
        pd_particles_free(p);
    }
    proved(f0, "fibres (seed 004 eq. 10): c_fibre along g, c_matrix across, the mean at 45 "
               "degrees, in force, energy and the stable step");
}

static void test_materials(void)
{
    int f0 = failures;
    const double dir[3] = {1, 0, 0}, c1 = 1e20, c2 = 4e20, ci = 5e19;
    pd_bond_law laws[3] = {{1, 1, c1, 0}, {2, 2, c2, 0}, {2, 1, ci, 0}};
    double ce, cdt, c;
    /* inside material 2 */
    pd_particles *p = pair(dir, 2, 2);
    pd_scene sc = scene(7e20);
    sc.nlaws = 1;
    sc.laws = laws + 1;
    c = pair_c(p, &sc, &ce, &cdt);
    CHECK(close_to(c, c2) && close_to(ce, c2) && close_to(cdt, c2), "material 2: c %g", c);
    pd_particles_free(p);
    sc.nlaws = 2;
    sc.laws = laws;
    /* between 1 and 2 without an interface: harmonic mean 2 c1 c2/(c1 + c2) */
    p = pair(dir, 1, 2);
    c = pair_c(p, &sc, &ce, &cdt);
    double hm = 2 * c1 * c2 / (c1 + c2);
    CHECK(close_to(c, hm) && close_to(ce, hm) && close_to(cdt, hm), "1-2 harmonic: c %g", c);
    /* with the interface (given as 2,1) */
    sc.nlaws = 3;
    c = pair_c(p, &sc, &ce, &cdt);
    CHECK(close_to(c, ci) && close_to(ce, ci) && close_to(cdt, ci), "1-2 interface: c %g", c);
    pd_particles_free(p);
    /* a material the body does not have */
    p = pair(dir, 1, 1);
    pd_bonds *b = NULL;
    if (pd_bonds_build(p, 1.25 * H, &b) != PD_OK)
        die("bonds");
    pd_sim *sim = NULL;
    CHECK(pd_bond_laws_check(p, &sc) == PD_ERR_INVALID && strstr(pd_errmsg(), "material 2"),
          "an unknown material: %s", pd_errmsg());
    CHECK(pd_sim_new(p, b, &sc, &sim) == PD_ERR_INVALID && sim == NULL,
          "pd_sim_new refuses an unknown material");
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "materials: a bond takes its material's law, the interface law between two, "
               "else the harmonic mean; unknown ids refused");
}

/* Broken bonds after 5 steps of the pair held at stretch s. */
static int64_t broken_at(const pd_particles *p, pd_scene *sc, double s)
{
    pd_bonds *b = NULL;
    if (pd_bonds_build(p, 1.25 * H, &b) != PD_OK)
        die("bonds");
    sc->dt_stable = pd_stable_dt(p, b, sc);
    pd_sim *sim = NULL;
    if (pd_sim_new(p, b, sc, &sim) != PD_OK)
        die("pd_sim_new");
    double *const *y = pd_sim_positions(sim);
    for (int d = 0; d < 3; d++)
        y[d][1] = p->x[d][1] * (1 + s);
    if (pd_sim_setup(sim) != PD_OK)
        die("setup");
    for (int n = 0; n < 5; n++)
        if (pd_sim_step(sim) != PD_OK)
            die("step");
    int64_t broken = pd_sim_broken(sim);
    pd_sim_free(sim);
    pd_bonds_free(b);
    return broken;
}

static void test_critical_stretch(void)
{
    int f0 = failures;
    const double x[3] = {1, 0, 0}, y45[3] = {1, 1, 0};
    /* a weak interface: s00 5e-4 against the scene's 1e-3 (alpha = 0) */
    pd_bond_law laws[1] = {{1, 2, 1e20, 5e-4}};
    pd_particles *p = pair(x, 1, 2);
    pd_scene sc = scene(1e20);
    sc.has_failure = 1;
    sc.s00 = 1e-3;
    sc.nlaws = 1;
    sc.laws = laws;
    CHECK(broken_at(p, &sc, 4.99e-4) == 0, "interface: s = 4.99e-4 < 5e-4 stays intact");
    CHECK(broken_at(p, &sc, 5.01e-4) == 1, "interface: s = 5.01e-4 > 5e-4 breaks");
    /* alpha > 0: the threshold k (s00 - alpha s_min), k = 5e-4/1e-3; a
     * lone stretched bond has s_min = s: s > 5e-4 - 0.5 alpha s */
    sc.alpha = 0.25;
    const double thr = 5e-4 / (1 + 0.5 * 0.25);
    CHECK(broken_at(p, &sc, 0.99 * thr) == 0, "alpha: below k (s00 - alpha s) intact");
    CHECK(broken_at(p, &sc, 1.01 * thr) == 1, "alpha: above k (s00 - alpha s) breaks");
    pd_particles_free(p);
    /* fibres: s00 2e-3 along g, 1e-3 across; at 45 degrees 1.5e-3 */
    sc = scene(1e20);
    sc.has_failure = 1;
    sc.s00 = 1e-3;
    sc.has_fibre = 1;
    sc.fibre_g[0] = 1;
    sc.fibre_c[0] = sc.fibre_c[1] = 1e20;
    sc.fibre_s00[0] = 2e-3;
    sc.fibre_s00[1] = 1e-3;
    p = pair(x, 1, 1);
    CHECK(broken_at(p, &sc, 1.99e-3) == 0, "along g: s = 1.99e-3 < 2e-3 intact");
    CHECK(broken_at(p, &sc, 2.01e-3) == 1, "along g: s = 2.01e-3 > 2e-3 breaks");
    pd_particles_free(p);
    p = pair(y45, 1, 1);
    CHECK(broken_at(p, &sc, 1.49e-3) == 0, "45 degrees: s = 1.49e-3 < 1.5e-3 intact");
    CHECK(broken_at(p, &sc, 1.51e-3) == 1, "45 degrees: s = 1.51e-3 > 1.5e-3 breaks");
    pd_particles_free(p);
    proved(f0, "a bond's own critical stretch (interface, fibre) breaks it exactly above "
               "k min(s0_i, s0_j), k = s00_bond/s00");
}

int main(void)
{
    test_fibre();
    test_materials();
    test_critical_stretch();
    if (failures)
        fprintf(stderr, "test_materials: %d failures\n", failures);
    return failures != 0;
}
