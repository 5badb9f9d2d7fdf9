/*
 * test_eps -- the elastic-plastic solid (--model eps, lib/models/lps.c).
 *
 * Proves: below yield EPS is LPS (the same force density to rounding at a
 * deformed, perturbed state, surface particles included: the symmetric
 * state-based pair form of EPS is Algorithm 2 rearranged); under a
 * monotonic simple shear the interior shear stress rises with slope ~G,
 * then stays on a plateau at the von Mises yield stress in shear, Y/sqrt3
 * (the yield value psi_0 = 5/2 Y^2 I/m^2 is calibrated to it), within 5%;
 * unloading is elastic with the loading slope, and the stress reaches zero
 * at a residual (plastic) shear gamma_max - tau_y/G_el, as the continuum
 * elastic-perfectly-plastic solid.
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
static const double K = 14.9e9, G = 6e9, Y = 2e7;

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

static pd_sim *model_sim(const pd_particles *p, const pd_bonds *b, pd_model_kind model, double y)
{
    pd_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.model = model;
    sc.bulk_modulus = K;
    sc.shear_modulus = G;
    sc.yield_stress = y;
    sc.c = pd_pmb_c_from_bulk(K, b->horizon);
    sc.dt = 1e-8;
    sc.safety = 1;
    sc.steps = 1;
    sc.dt_stable = pd_stable_dt(p, b, &sc);
    pd_sim *sim = NULL;
    if (pd_sim_new(p, b, &sc, &sim) != PD_OK)
        die("pd_sim_new");
    return sim;
}

/* One force evaluation (advancing the plastic extensions), forces zeroed
 * first. */
static void evaluate(pd_sim *sim)
{
    for (int d = 0; d < 3; d++)
        memset(sim->f[d], 0, (size_t)sim->n * sizeof(double));
    if (sim->effects[0]->force(sim, sim->state[0]) != PD_OK)
        die("force");
}

static void test_below_yield(const pd_particles *p, const pd_bonds *b)
{
    int f0 = failures;
    pd_sim *lps = model_sim(p, b, PD_MODEL_LPS, 0), *eps = model_sim(p, b, PD_MODEL_EPS, 1e30);
    unsigned seed = 7;
    for (int64_t i = 0; i < p->n; i++)
        for (int d = 0; d < 3; d++) {
            seed = seed * 1103515245u + 12345u;
            const double u = 1e-6 * ((double)(seed >> 8) / 16777216.0 - 0.5) +
                             (d == 0 ? 3e-4 * p->x[2][i] : d == 2 ? 1e-4 * p->x[2][i] : 0);
            lps->y[d][i] = eps->y[d][i] = p->x[d][i] + u;
        }
    evaluate(lps);
    evaluate(eps);
    double fbig = 0, dmax = 0;
    for (int d = 0; d < 3; d++)
        for (int64_t i = 0; i < p->n; i++) {
            fbig = fmax(fbig, fabs(lps->f[d][i]));
            dmax = fmax(dmax, fabs(lps->f[d][i] - eps->f[d][i]));
        }
    CHECK(fbig > 0 && dmax <= 1e-12 * fbig, "EPS - LPS force %.3g of %.3g", dmax, fbig);
    printf("  below yield: max |f_eps - f_lps| / max |f| = %.2g\n", dmax / fbig);
    pd_sim_free(lps);
    pd_sim_free(eps);
    proved(f0, "below yield EPS is LPS to rounding (perturbed shear, surfaces too)");
}

/* The mean interior shear stress (s_xz + s_zx)/2, Pa. */
static double interior_shear(const pd_particles *p, pd_sim *sim, double *st)
{
    if (pd_sim_stress(sim, st) != PD_OK)
        die("stress");
    double sum = 0;
    int cnt = 0;
    for (int64_t i = 0; i < p->n; i++)
        if (interior(p, i)) {
            sum += 0.5 * (st[9 * i + 2] + st[9 * i + 6]);
            cnt++;
        }
    return sum / cnt;
}

static void shear_to(const pd_particles *p, pd_sim *sim, double gamma)
{
    for (int64_t i = 0; i < p->n; i++)
        sim->y[0][i] = p->x[0][i] + gamma * p->x[2][i];
    evaluate(sim);
}

static void test_shear_plateau(const pd_particles *p, const pd_bonds *b)
{
    int f0 = failures;
    pd_sim *sim = model_sim(p, b, PD_MODEL_EPS, Y);
    double *st = malloc((size_t)p->n * 9 * sizeof(double));
    const double ty = Y / sqrt(3.0), gy = ty / G, dg = gy / 20;
    const int nload = 100; /* to 5 gamma_y */
    shear_to(p, sim, dg);
    const double g_el = interior_shear(p, sim, st) / dg; /* elastic slope */
    double s = 0, smin = INFINITY, smax = 0;
    for (int n = 2; n <= nload; n++) {
        shear_to(p, sim, n * dg);
        s = interior_shear(p, sim, st);
        if (n * dg >= 2 * gy) { /* well past yield: the plateau */
            smin = fmin(smin, s);
            smax = fmax(smax, s);
        }
    }
    const double gmax = nload * dg, plateau = s;
    CHECK(fabs(g_el / G - 1) <= 0.1, "elastic slope %.4g vs G %.4g", g_el, G);
    CHECK(fabs(plateau / ty - 1) <= 0.05, "plateau %.6g vs Y/sqrt3 %.6g", plateau, ty);
    CHECK(smax - smin <= 1e-3 * ty, "plateau varies by %.3g of %.3g", smax - smin, ty);
    /* unload: elastic, down to zero stress */
    double g = gmax, prev = plateau, g0 = NAN;
    shear_to(p, sim, g - dg);
    const double g_un = (plateau - interior_shear(p, sim, st)) / dg;
    CHECK(fabs(g_un / g_el - 1) <= 1e-3, "unloading slope %.6g vs loading %.6g", g_un, g_el);
    for (g = gmax - dg; g > -gmax; g -= dg / 4) {
        shear_to(p, sim, g);
        s = interior_shear(p, sim, st);
        if (s <= 0) {
            g0 = g + (dg / 4) * (-s) / (prev - s); /* linear between the two */
            break;
        }
        prev = s;
    }
    const double want = gmax - plateau / g_el;
    CHECK(isfinite(g0) && fabs(g0 / want - 1) <= 0.02, "residual shear %.6g, gamma_max - "
          "tau/G_el %.6g", g0, want);
    printf("  shear: G_el/G %.4f, plateau/(Y/sqrt3) %.4f, unloading slope/loading %.6f, residual "
           "shear %.4g (gamma_y %.4g, expected %.4g)\n",
           g_el / G, plateau / ty, g_un / g_el, g0, gy, want);
    free(st);
    pd_sim_free(sim);
    proved(f0, "monotonic shear: plateau at Y/sqrt3, elastic unloading, residual plastic shear");
}

int main(void)
{
    pd_particles *p = cube();
    pd_bonds *b = NULL;
    if (pd_bonds_build(p, DELTA, &b) != PD_OK)
        die("bonds");
    test_below_yield(p, b);
    test_shear_plateau(p, b);
    pd_bonds_free(b);
    pd_particles_free(p);
    return failures != 0;
}
