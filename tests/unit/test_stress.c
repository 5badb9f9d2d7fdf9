/*
 * test_stress -- the peridynamic stress (pd_sim_stress, seed 003 eq. 7 read
 * per particle: sigma_i = 1/2 sum_j V_j f_ij (x) xi_ij) of PMB and LPS.
 *
 * Proves, for the interior particle of a 15^3 block (delta = 3 spacings):
 *   - under a uniform isotropic stretch eps, sigma = 3 K eps s I, where s
 *     is the lattice's share of the continuum integral of |xi| over the
 *     horizon (pi delta^4), computed here from integer points and not by
 *     lib/ (0.90 at delta = 3 spacings): the continuum value 3 K eps of a
 *     PMB solid times the stiffness the lattice has; no shear, von Mises 0
 *     (a first Piola-Kirchhoff stress: the reference xi, so no 1 + eps);
 *   - under a uniaxial stretch eps along x (y and z held), sigma_yy / sigma_xx
 *     is lambda / (lambda + 2 mu) = 1/3 for PMB (nu = 1/4, lambda = mu)
 *     within 0.05 (the cubic lattice's anisotropy: 0.367 measured), and the sum of V_i sigma_i over the
 *     body is the virial of its bonds, sum over bonds of F (x) xi;
 *   - a rigid rotation gives no stress, and the stress tensor is the same at
 *     1 and 2 threads (each row its own sum);
 *   - for LPS (K, G), delta = 4 spacings, the continuum values within 2%: an
 *     isotropic stretch gives 3 K eps I, a uniaxial one sigma_xx =
 *     (K + 4G/3) eps and sigma_yy = (K - 2G/3) eps.
 */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "pd.h"

static const double PI = 3.14159265358979323846;
static const double H = 1e-3;           /* spacing, m        */
static const double DELTA = 3.0001e-3;  /* horizon, m        */
static const double K = 14.9e9;         /* bulk modulus, Pa  */
static const double G = 8.0e9;          /* shear modulus of the LPS solid, Pa */
enum { SIDE = 15 };

static pd_particles *block(void)
{
    pd_region r = {.kind = PD_REGION_BOX,
                   .p = {-0.5 * H, (SIDE - 0.5) * H, -0.5 * H, (SIDE - 0.5) * H, -0.5 * H,
                         (SIDE - 0.5) * H}};
    pd_lattice_params lp = {.spacing = H, .density = 2200, .material = 1, .seed = 1};
    pd_particles *p = NULL;
    if (pd_lattice_make(&r, 1, &lp, &p) != PD_OK)
        die("lattice");
    return p;
}

static pd_sim *sim_model(const pd_particles *p, const pd_bonds *b, pd_model_kind model)
{
    pd_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.model = model;
    sc.bulk_modulus = K;
    sc.shear_modulus = G;
    sc.c = pd_pmb_c_from_bulk(K, DELTA);
    sc.dt = 1e-9;
    sc.safety = 1;
    sc.steps = 1;
    sc.dt_stable = pd_stable_dt(p, b, &sc);
    pd_sim *sim = NULL;
    if (pd_sim_new(p, b, &sc, &sim) != PD_OK)
        die("pd_sim_new");
    return sim;
}

static pd_sim *sim_of(const pd_particles *p, const pd_bonds *b)
{
    return sim_model(p, b, PD_MODEL_PMB);
}

/* Deform the positions: y = F x. */
static void deform(pd_sim *sim, const pd_particles *p, const double F[9])
{
    double *const *y = pd_sim_positions(sim);
    for (int64_t i = 0; i < p->n; i++)
        for (int a = 0; a < 3; a++)
            y[a][i] = F[3 * a] * p->x[0][i] + F[3 * a + 1] * p->x[1][i] + F[3 * a + 2] * p->x[2][i];
}

/* The row of the particle at the block's centre. */
static int64_t centre(const pd_particles *p)
{
    const double c = (SIDE / 2) * H;
    for (int64_t i = 0; i < p->n; i++)
        if (fabs(p->x[0][i] - c) < 1e-9 && fabs(p->x[1][i] - c) < 1e-9 &&
            fabs(p->x[2][i] - c) < 1e-9)
            return i;
    return -1;
}

/* The lattice's share of the continuum integral of |xi| over the horizon,
 * pi delta^4, with the partial volumes (DESIGN.md), from integer points. */
static double lattice_share(void)
{
    double share = 0;
    for (int a = -4; a <= 4; a++)
        for (int e = -4; e <= 4; e++)
            for (int g = -4; g <= 4; g++) {
                double len = H * sqrt((double)(a * a + e * e + g * g));
                if ((a || e || g) && len <= DELTA) {
                    double nu = len <= DELTA - 0.5 * H ? 1 : (DELTA + 0.5 * H - len) / H;
                    share += len * nu * H * H * H;
                }
            }
    return share / (PI * pow(DELTA, 4));
}

static void test_isotropic(const pd_particles *p, const pd_bonds *b)
{
    int f0 = failures;
    const double eps = 1e-3;
    pd_sim *sim = sim_of(p, b);
    const double F[9] = {1 + eps, 0, 0, 0, 1 + eps, 0, 0, 0, 1 + eps};
    deform(sim, p, F);
    double *s = malloc((size_t)p->n * 9 * sizeof(double));
    if (s == NULL || pd_sim_stress(sim, s) != PD_OK)
        die("stress");
    int64_t i = centre(p);
    CHECK(i >= 0, "the centre particle");
    const double share = lattice_share();
    const double want = 3 * K * eps * share;
    const double *si = s + 9 * i;
    for (int a = 0; a < 3; a++)
        for (int d = 0; d < 3; d++) {
            double w = a == d ? want : 0;
            CHECK(fabs(si[3 * a + d] - w) <= 1e-9 * want, "sigma_%d%d = %.9g, expected %.9g", a,
                  d, si[3 * a + d], w);
        }
    CHECK(pd_von_mises(si) <= 1e-9 * want, "von Mises %g under isotropic stretch",
          pd_von_mises(si));
    CHECK(fabs(si[0] / share - 3 * K * eps) <= 1e-9 * 3 * K * eps,
          "the continuum value 3 K eps of PMB, times the lattice share %.4f", share);
    printf("   isotropic stretch %g: sigma %.6g Pa = %.4f x 3 K eps (lattice share %.4f)\n", eps,
           si[0], si[0] / (3 * K * eps), share);
    free(s);
    pd_sim_free(sim);
    proved(f0, "isotropic stretch: sigma = 3 K eps I times the lattice share");
}

static void test_uniaxial(const pd_particles *p, const pd_bonds *b)
{
    int f0 = failures;
    const double eps = 1e-4;
    pd_sim *sim = sim_of(p, b);
    const double F[9] = {1 + eps, 0, 0, 0, 1, 0, 0, 0, 1};
    deform(sim, p, F);
    double *s = malloc((size_t)p->n * 9 * sizeof(double));
    if (s == NULL || pd_sim_stress(sim, s) != PD_OK)
        die("stress");
    const double *si = s + 9 * centre(p);
    double ratio = si[4] / si[0];
    CHECK(fabs(si[4] - si[8]) <= 1e-9 * si[0], "sigma_yy = sigma_zz");
    CHECK(fabs(ratio - 1.0 / 3.0) < 0.05, "sigma_yy / sigma_xx = %.4f, PMB continuum 1/3", ratio);
    CHECK(fabs(si[1]) + fabs(si[2]) + fabs(si[5]) <= 1e-9 * si[0], "no shear");
    /* the continuum: sigma_xx = (lambda + 2 mu) eps = 9/5 K eps (nu = 1/4),
     * times the lattice's share */
    double want = 1.8 * K * eps * lattice_share();
    CHECK(fabs(si[0] - want) < 0.05 * want, "sigma_xx %.6g, continuum x share %.6g", si[0], want);
    printf("   uniaxial stretch %g: sigma_xx %.6g Pa, sigma_yy/sigma_xx %.4f\n", eps, si[0], ratio);

    /* the virial: sum_i V_i sigma_i = sum over bonds (each once) of F (x) xi,
     * with F = c s nu V_i V_j along the bond (equal volumes: nu symmetric) */
    const double c = pd_pmb_c_from_bulk(K, DELTA);
    double total = 0, bonds = 0;
    double *const *y = pd_sim_positions(sim);
    for (int64_t i = 0; i < p->n; i++) {
        total += p->volume[i] * s[9 * i];
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            int64_t j = b->neighbor[k];
            if (j < i)
                continue;
            double e[3], r = 0;
            for (int d = 0; d < 3; d++) {
                e[d] = y[d][j] - y[d][i];
                r += e[d] * e[d];
            }
            r = sqrt(r);
            double st = (r - b->length[k]) / b->length[k];
            bonds += c * st * b->vfactor[k] * p->volume[i] * p->volume[j] * e[0] / r *
                     (p->x[0][j] - p->x[0][i]);
        }
    }
    CHECK(fabs(total - bonds) <= 1e-9 * fabs(bonds), "sum V sigma_xx %.12g, bond virial %.12g",
          total, bonds);
    free(s);
    pd_sim_free(sim);
    proved(f0, "uniaxial stretch: sigma_yy/sigma_xx = 1/3; the body's sum is the bond virial");
}

static void test_rotation_threads(const pd_particles *p, const pd_bonds *b)
{
    int f0 = failures;
    const double t = 0.3, co = cos(t), si = sin(t);
    pd_sim *sim = sim_of(p, b);
    const double R[9] = {co, -si, 0, si, co, 0, 0, 0, 1};
    deform(sim, p, R);
    size_t bytes = (size_t)p->n * 9 * sizeof(double);
    double *s = malloc(bytes), *s1 = malloc(bytes);
    if (s == NULL || s1 == NULL || pd_sim_stress(sim, s) != PD_OK)
        die("stress");
    double worst = 0;
    for (int64_t k = 0; k < p->n * 9; k++)
        worst = fmax(worst, fabs(s[k]));
    /* round-off of the rotated lengths against |xi|: a stretch of ~1e-13 */
    CHECK(worst < 1e-9 * K, "a rigid rotation gives stress up to %g Pa", worst);
    const double F[9] = {1.001, 2e-4, 0, -1e-4, 0.999, 3e-4, 0, 1e-4, 1.002};
    deform(sim, p, F);
    omp_set_num_threads(1);
    pd_sim_stress(sim, s1);
    omp_set_num_threads(2);
    pd_sim_stress(sim, s);
    CHECK(memcmp(s, s1, bytes) == 0, "the same stress at 1 and 2 threads");
    free(s);
    free(s1);
    pd_sim_free(sim);
    proved(f0, "a rigid rotation gives no stress; the same at any thread count");
}

/* LPS normalizes its bond sums by the weighted volume m, so the lattice's
 * share cancels: the continuum values hold at interior particles, up to the
 * cubic lattice's anisotropy in the fourth moments of the family: at
 * delta = 3 spacings sum w xi_x^4/|xi|^2 nu V is 0.961 of its isotropic
 * value m/5 (sigma_xx 3.7% low), at 4 spacings 0.989; so a horizon of
 * 4 spacings here. */
static void test_lps(const pd_particles *p, const pd_bonds *b)
{
    int f0 = failures;
    double *s = malloc((size_t)p->n * 9 * sizeof(double));
    if (s == NULL)
        die("memory");
    const double eps = 1e-4;
    const double iso[9] = {1 + eps, 0, 0, 0, 1 + eps, 0, 0, 0, 1 + eps};
    const double uni[9] = {1 + eps, 0, 0, 0, 1, 0, 0, 0, 1};
    const double *F[2] = {iso, uni};
    for (int c = 0; c < 2; c++) {
        pd_sim *sim = sim_model(p, b, PD_MODEL_LPS);
        deform(sim, p, F[c]);
        if (pd_sim_stress(sim, s) != PD_OK)
            die("stress");
        const double *si = s + 9 * centre(p);
        if (c == 0) {
            const double want = 3 * K * eps;
            for (int a = 0; a < 3; a++)
                CHECK(fabs(si[4 * a] - want) <= 0.02 * want, "LPS sigma_%d%d %.6g, 3 K eps %.6g",
                      a, a, si[4 * a], want);
            printf("   LPS isotropic stretch: sigma %.6g Pa = %.4f x 3 K eps\n", si[0],
                   si[0] / want);
        } else {
            const double xx = (K + 4 * G / 3) * eps, yy = (K - 2 * G / 3) * eps;
            CHECK(fabs(si[0] - xx) <= 0.02 * xx, "LPS sigma_xx %.6g, (K + 4G/3) eps %.6g", si[0],
                  xx);
            CHECK(fabs(si[4] - yy) <= 0.02 * xx, "LPS sigma_yy %.6g, (K - 2G/3) eps %.6g", si[4],
                  yy);
            printf("   LPS uniaxial stretch: sigma_xx %.6g Pa = %.4f x (K + 4G/3) eps, "
                   "sigma_yy %.4f x (K - 2G/3) eps\n",
                   si[0], si[0] / xx, si[4] / yy);
        }
        pd_sim_free(sim);
    }
    free(s);
    proved(f0, "LPS: sigma = 3 K eps I (isotropic), sigma_xx = (K + 4G/3) eps (uniaxial), 2%");
}

int main(void)
{
    pd_particles *p = block();
    pd_bonds *b = NULL;
    if (pd_bonds_build(p, DELTA, &b) != PD_OK)
        die("bonds");
    test_isotropic(p, b);
    test_uniaxial(p, b);
    test_rotation_threads(p, b);
    pd_bonds *b4 = NULL; /* LPS: delta = 4 spacings, see test_lps */
    if (pd_bonds_build(p, 4.0001 * H, &b4) != PD_OK)
        die("bonds");
    test_lps(p, b4);
    pd_bonds_free(b4);
    pd_bonds_free(b);
    pd_particles_free(p);
    return failures ? 1 : 0;
}
