/*
 * test_plate -- 2-D plates: the square lattice of pd_lattice_make with
 * dimension 2 and the plane-stress PMB constants of lib/models/plate.c.
 *
 * Proves: a plate's sites are (i dx, j dx, 0) where the regions cut at
 * z = 0 hold them, with volume dx^2 H, radius dx/2, dimension 2 and its
 * thickness; a region that does not reach z = 0 gives no plate; a
 * perturbation stays in the plane; an interior family for delta = 3.0001 dx
 * has the 28 partners i^2 + j^2 <= 9; c = 12 K / (pi H delta^3) =
 * 9 E / (pi H delta^3) and s0 = sqrt(4 G0 / (c H delta^4)) =
 * sqrt(4 pi G0 / (9 E delta)), the 3-D K = 2E/3; under a uniform in-plane
 * stretch eps the strain energy density of an interior particle
 * (pd_sim_energy) is E eps^2 / (1 - nu), nu = 1/3, times the lattice's share
 * of the disk integral (exactly), and within 2% of it for delta = 25 dx;
 * the energy of the bonds a straight pre-crack cuts, per unit length and
 * thickness, is G0 times the lattice's share (exactly) and within 3% of G0
 * for delta = 20 dx.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "pd.h"

static const double PI = 3.14159265358979323846;
static const double RHO = 8000.0, E = 192e9, H = 1e-3;

static pd_particles *plate(const char *box, double h, double perturb)
{
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, box, &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {h, RHO, 1, perturb, 1};
    pd_particles *p = NULL;
    if (pd_plate_make(&r, 1, &lp, H, &p) != PD_OK)
        die("lattice");
    return p;
}

static pd_bonds *bonds(const pd_particles *p, double horizon)
{
    pd_bonds *b = NULL;
    if (pd_bonds_build(p, horizon, &b) != PD_OK)
        die("bonds");
    return b;
}

/* Partial-volume factor of seed 000 (DESIGN.md), computed here apart from
 * lib/: nu = (delta + r - |xi|) / (2r) in the outer shell of width r = dx/2. */
static double nu_of(double len, double delta, double h)
{
    return len <= delta - 0.5 * h ? 1 : (delta + 0.5 * h - len) / h;
}

static void test_lattice(void)
{
    int f0 = failures;
    const double h = 0.5e-3;
    /* 0..10 dx in x, 0..6 dx in y, cut at z = 0 */
    pd_particles *p = plate("0,0.005,0,0.003,-0.002,0.0004", h, 0);
    CHECK(p->n == 11 * 7, "%lld sites, expected 77", (long long)p->n);
    CHECK(p->dimension == 2 && p->thickness == H && p->spacing == h, "dimension, thickness");
    for (int64_t i = 0; i < p->n; i++) {
        CHECK(p->x[2][i] == 0, "z = 0");
        CHECK(p->volume[i] == h * h * H && p->radius[i] == 0.5 * h, "volume dx^2 H, radius dx/2");
        CHECK(p->x[0][i] == round(p->x[0][i] / h) * h && p->x[1][i] == round(p->x[1][i] / h) * h,
              "on the lattice");
        CHECK(p->id[i] == i + 1, "ids 1..N");
    }
    pd_particles_free(p);

    /* a box above the plane z = 0 holds no site of a plate */
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, "0,1,0,1,0.1,0.2", &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {0.1, RHO, 1, 0, 1};
    pd_particles *q = NULL;
    CHECK(pd_plate_make(&r, 1, &lp, H, &q) == PD_ERR_INVALID && q == NULL,
          "a region off z = 0: an error");
    CHECK(pd_lattice_make(&r, 1, &lp, &q) == PD_OK && q->n > 0, "the 3-D lattice has sites");
    pd_particles_free(q);
    q = NULL;
    if (pd_region_parse(PD_REGION_BOX, "0,1,0,1,-0.1,0.2", &r) != PD_OK)
        die("region");
    CHECK(pd_plate_make(&r, 1, &lp, 0, &q) == PD_ERR_INVALID && q == NULL,
          "thickness 0: an error");
    CHECK(pd_plate_make(&r, 1, &lp, NAN, &q) == PD_ERR_INVALID && q == NULL,
          "thickness NaN: an error");

    /* a perturbation stays in the plane and within its amplitude */
    p = plate("0,0.005,0,0.003,-0.002,0.0004", h, 0.1 * h);
    for (int64_t i = 0; i < p->n; i++) {
        CHECK(p->x[2][i] == 0, "perturbed site off z = 0");
        for (int d = 0; d < 2; d++) {
            double off = p->x[d][i] - round(p->x[d][i] / h) * h;
            CHECK(fabs(off) <= 0.1 * h, "perturbation %g beyond its amplitude", off);
        }
    }
    pd_particles_free(p);
    proved(f0, "a plate: sites (i dx, j dx, 0) cut at z = 0, volume dx^2 H, in-plane perturbation");
}

static void test_family(void)
{
    int f0 = failures;
    const double h = 0.5e-3;
    pd_particles *p = plate("-0.005,0.005,-0.005,0.005,0,0", h, 0);
    pd_bonds *b = bonds(p, 3.0001 * h);
    int64_t interior = 0;
    for (int64_t i = 0; i < p->n; i++) {
        if (fabs(p->x[0][i]) > 7 * h || fabs(p->x[1][i]) > 7 * h)
            continue;
        interior++;
        int64_t size = b->offset[i + 1] - b->offset[i];
        CHECK(size == 28, "interior family of %lld, expected 28", (long long)size);
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            int64_t j = b->neighbor[k];
            long di = lround((p->x[0][j] - p->x[0][i]) / h);
            long dj = lround((p->x[1][j] - p->x[1][i]) / h);
            CHECK(di * di + dj * dj <= 9 && p->x[2][j] == 0, "partner (%ld, %ld)", di, dj);
        }
    }
    CHECK(interior == 15 * 15, "%lld interior particles", (long long)interior);
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "delta = 3.0001 dx: 28 partners i^2 + j^2 <= 9 in the plane");
}

static void test_constants(void)
{
    int f0 = failures;
    const double delta = 1.6e-3, g0 = 250.0;
    const double K = pd_pmb_bulk_from_youngs(E, 2);
    CHECK(fabs(K - 0.75 * E) <= 1e-15 * E, "2-D K = 3E/4 = E/(2(1 - 1/3))");
    CHECK(fabs(pd_pmb_bulk_from_youngs(E, 3) - 2.0 * E / 3.0) <= 1e-15 * E, "3-D K = 2E/3");
    double c = pd_pmb_c_from_bulk_2d(K, delta, H);
    double lit = 9.0 * E / (PI * H * pow(delta, 3)); /* Ha & Bobaru 2010 */
    CHECK(fabs(c - lit) <= 1e-14 * lit, "c = %.17g, literature %.17g", c, lit);
    double s0 = pd_pmb_s0_from_energy_2d(g0, c, delta, H);
    double s0lit = sqrt(4.0 * PI * g0 / (9.0 * E * delta));
    CHECK(fabs(s0 - s0lit) <= 1e-14 * s0lit, "s0 = %.17g, literature %.17g", s0, s0lit);
    /* picked by the particles' dimension */
    pd_particles *p = plate("0,0.001,0,0.001,0,0", 0.5e-3, 0);
    CHECK(pd_pmb_c_for(p, K, delta) == c && pd_pmb_s0_for(p, g0, c, delta) == s0, "2-D picked");
    p->dimension = 3;
    CHECK(pd_pmb_c_for(p, K, delta) == pd_pmb_c_from_bulk(K, delta) &&
              pd_pmb_s0_for(p, g0, c, delta) == pd_pmb_s0_from_energy(g0, c, delta),
          "3-D picked");
    pd_particles_free(p);
    proved(f0, "plane stress: c = 12K/(pi H delta^3) = 9E/(pi H delta^3), "
               "s0 = sqrt(4 pi G0/(9 E delta)); 3-D K = 2E/3");
}

/* Strain energy density of the particle nearest the origin of a plate
 * [-m dx, m dx]^2, delta = (m + 1e-4) dx, stretched by eps in the plane, from
 * pd_sim_energy; *share gets the lattice's share of the disk integral
 * int |xi| dA = 2 pi delta^3 / 3 (from integer points, apart from lib/). */
static double stretched_energy(int m, double eps, double *share)
{
    const double h = 1e-4, delta = (m + 1e-4) * h;
    char spec[128];
    snprintf(spec, sizeof spec, "%.17g,%.17g,%.17g,%.17g,0,0", -m * h, m * h, -m * h, m * h);
    pd_particles *p = plate(spec, h, 0);
    pd_bonds *b = bonds(p, delta);
    pd_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.model = PD_MODEL_PMB;
    sc.c = pd_pmb_c_for(p, pd_pmb_bulk_from_youngs(E, 2), delta);
    sc.safety = 1;
    sc.dt = 1e-12;
    sc.steps = 1;
    sc.dt_stable = pd_stable_dt(p, b, &sc);
    pd_sim *sim = NULL;
    if (pd_sim_new(p, b, &sc, &sim) != PD_OK)
        die("pd_sim_new");
    double *const *y = pd_sim_positions(sim);
    int64_t centre = -1;
    for (int64_t i = 0; i < p->n; i++) {
        for (int d = 0; d < 2; d++)
            y[d][i] = (1 + eps) * p->x[d][i];
        if (p->x[0][i] == 0 && p->x[1][i] == 0)
            centre = i;
    }
    double *w = malloc((size_t)p->n * sizeof(double));
    pd_energy en;
    if (w == NULL || centre < 0 || pd_sim_energy(sim, &en, w) != PD_OK)
        die("energy");
    double wc = w[centre];
    CHECK(b->offset[centre + 1] - b->offset[centre] > 3 * m * m, "a whole family");
    double sum = 0;
    for (int a = -m - 1; a <= m + 1; a++)
        for (int e = -m - 1; e <= m + 1; e++) {
            double len = h * sqrt((double)(a * a + e * e));
            if ((a || e) && len <= delta)
                sum += len * nu_of(len, delta, h) * h * h;
        }
    *share = sum / (2.0 * PI * pow(delta, 3) / 3.0);
    free(w);
    pd_sim_free(sim);
    pd_bonds_free(b);
    pd_particles_free(p);
    return wc;
}

static void test_energy(void)
{
    int f0 = failures;
    const double eps = 1e-4, nu = 1.0 / 3.0;
    const double want = E * eps * eps / (1.0 - nu); /* plane stress, sxx = syy = E eps/(1-nu) */
    double share;
    double w3 = stretched_energy(3, eps, &share);
    CHECK(fabs(w3 - want * share) <= 1e-9 * want, "delta = 3 dx: W %g, expected %g x %g", w3, want,
          share);
    double w25 = stretched_energy(25, eps, &share);
    CHECK(fabs(w25 - want * share) <= 1e-9 * want, "delta = 25 dx: W %g, expected %g x %g", w25,
          want, share);
    CHECK(fabs(w25 / want - 1) <= 0.02, "delta = 25 dx: W/W_continuum = %.4f", w25 / want);
    printf("# W / (E eps^2/(1-nu)): %.4f at delta = 3 dx, %.4f at delta = 25 dx\n", w3 / want,
           w25 / want);
    proved(f0, "in-plane stretch: W = E eps^2/(1-nu) (nu = 1/3) x lattice share; within 2% at "
               "delta = 25 dx");
}

static void test_fracture_energy(void)
{
    int f0 = failures;
    /* the line y = dx/2 between two rows, cut by a pre-crack; the bonds
     * whose lower end has x in the window [20 dx, 40 dx) hold the energy of
     * 20 dx of crack, all their partners being inside the plate */
    const int m = 20;
    const double h = 1e-4, delta = (m + 1e-4) * h, g0 = 1000.0;
    char spec[128];
    snprintf(spec, sizeof spec, "0,%.17g,%.17g,%.17g,0,0", 60 * h, -(m + 1) * h, (m + 2) * h);
    pd_particles *p = plate(spec, h, 0);
    pd_bonds *b = bonds(p, delta);
    const double c = pd_pmb_c_for(p, pd_pmb_bulk_from_youngs(E, 2), delta);
    const double s0 = pd_pmb_s0_for(p, g0, c, delta);
    pd_crack cr;
    snprintf(spec, sizeof spec, "segment,%.17g,%.17g,%.17g,%.17g", -h, 0.5 * h, 61 * h, 0.5 * h);
    if (pd_crack_parse(spec, &cr) != PD_OK || pd_bonds_precrack(p, b, &cr, 1, NULL) != PD_OK)
        die("precrack");
    double energy = 0;
    for (int64_t i = 0; i < p->n; i++)
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            int64_t j = b->neighbor[k], lo = p->x[1][i] < p->x[1][j] ? i : j;
            if (j < i || !pd_bond_intact(b->precrack, k))
                continue;
            double xl = p->x[0][lo] / h;
            if (xl >= 19.5 && xl < 39.5)
                energy += 0.5 * c * s0 * s0 * b->length[k] * b->vfactor[k] * p->volume[i] *
                          p->volume[j];
        }
    double g = energy / (20 * h * H);
    /* the lattice's share of int_0^delta xi^3 dxi = delta^4/4, per column */
    double sum = 0;
    for (int k = 0; k <= m; k++)
        for (int a = -m - 1; a <= m + 1; a++)
            for (int e = k + 1; e <= k + m + 1; e++) {
                double len = h * sqrt((double)(a * a + e * e));
                if (len <= delta)
                    sum += len * nu_of(len, delta, h);
            }
    double share = 0.5 * sum * h * h * h / (pow(delta, 4) / 4.0);
    CHECK(fabs(g - g0 * share) <= 1e-9 * g0, "G %g, expected %g x share %g", g, g0, share);
    CHECK(fabs(g / g0 - 1) <= 0.03, "G/G0 = %.4f", g / g0);
    printf("# bonds across a line: G/G0 = %.4f at delta = 20 dx\n", g / g0);
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "the bonds across a crack line hold G0 per unit area (lattice share; within 3% at "
               "delta = 20 dx)");
}

int main(void)
{
    test_lattice();
    test_family();
    test_constants();
    test_energy();
    test_fracture_energy();
    if (failures)
        fprintf(stderr, "test_plate: %d failures\n", failures);
    return failures != 0;
}
