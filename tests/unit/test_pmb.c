/*
 * test_pmb -- the PMB bond force (lib/models/pmb.c) seen through the public run
 * interface, against the formulas of seed 000 (eqs. 5-9) and seed 004.
 *
 * Forces are read off the velocities after one velocity-Verlet step with a
 * tiny dt from rest: v = dt/(2 rho) (f^n + f^{n+1}) and f^{n+1} = f^n to
 * far below round-off, so f = rho v / dt.
 *
 * Proves: c = 18 K / (pi delta^4); a stretched pair feels f_i = c s nu V_j
 * along the bond (with nu = 3/4 for a bond in the partial-volume shell) and
 * the pair's forces cancel (sum of V_i f_i = 0); compression repels; under a
 * uniform stretch eps every bond has stretch eps, interior particles feel no
 * net force while surface particles are pulled inward, and the strain
 * energy density of an interior particle, 1/4 sum_j c eps^2 |xi| nu V_j, is
 * 9/2 K eps^2 times the lattice's share of the continuum integral pi
 * delta^4; the stable step is seed 004 eq. 46; with failure a bond breaks
 * only when s > s00 - alpha s_min with s_min the smallest stretch of the
 * particle's bonds (eq. 9, not Algorithm 5's min line), never before the
 * second step (s0 starts at +inf), and carries no force once broken.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "pd.h"


static const double PI = 3.14159265358979323846;
static const double RHO = 2200.0;

static pd_sim *sim_of(const pd_particles *p, const pd_bonds *b, double c, double dt,
                      double s00, double alpha)
{
    pd_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.model = PD_MODEL_PMB;
    sc.c = c;
    sc.dt = dt;
    sc.safety = 1;
    sc.steps = 1;
    if (s00 > 0) {
        sc.has_failure = 1;
        sc.s00 = s00;
        sc.alpha = alpha;
    }
    sc.dt_stable = pd_stable_dt(p, b, &sc);
    pd_sim *sim = NULL;
    if (pd_sim_new(p, b, &sc, &sim) != PD_OK)
        die("pd_sim_new");
    return sim;
}

static pd_bonds *bonds(const pd_particles *p, double horizon)
{
    pd_bonds *b = NULL;
    if (pd_bonds_build(p, horizon, &b) != PD_OK)
        die("bonds");
    return b;
}

static void test_micromodulus(void)
{
    int f0 = failures;
    const double K = 14.9e9, delta = 0.0015001;
    double c = pd_pmb_c_from_bulk(K, delta);
    double want = 18.0 * K / (PI * delta * delta * delta * delta);
    CHECK(fabs(c - want) <= 1e-14 * want, "c = %.17g, expected %.17g", c, want);
    CHECK(fabs(pd_pmb_c_from_bulk(K, 2 * delta) * 16 - c) <= 1e-14 * c, "c scales as delta^-4");
    CHECK(fabs(pd_pmb_c_from_bulk(2 * K, delta) - 2 * c) <= 1e-14 * c, "c scales as K");
    CHECK(PD_PMB_C_FACTOR == 18.0, "the factor 18 of seed 000 eq. 6");
    proved(f0, "micromodulus c = 18 K / (pi delta^4)");
}

/* Two particles on the x axis, spacing h, volumes V0 and V1. */
static pd_particles *pair(double h, double v0, double v1)
{
    pd_particles *p = pd_particles_new(2);
    for (int i = 0; i < 2; i++) {
        p->x[0][i] = i * h;
        p->x[1][i] = p->x[2][i] = 0;
        p->volume[i] = i ? v1 : v0;
        p->density[i] = RHO;
        p->radius[i] = 0.5 * h;
        p->material[i] = 1;
        p->id[i] = i + 1;
    }
    p->spacing = h;
    return p;
}

/* Force densities of one tiny step from rest, f = rho v / dt. */
static void forces_of(pd_sim *sim, const pd_particles *p, double dt, double *f[3])
{
    if (pd_sim_setup(sim) != PD_OK || pd_sim_step(sim) != PD_OK)
        die("step");
    double *const *v = pd_sim_velocities(sim);
    for (int d = 0; d < 3; d++)
        for (int64_t i = 0; i < p->n; i++)
            f[d][i] = p->density[i] * v[d][i] / dt;
}

static void test_pair_force(void)
{
    int f0 = failures;
    const double h = 1e-3, V0 = 1e-9, V1 = 2e-9, c = 1e20, dt = 1e-13;
    pd_particles *p = pair(h, V0, V1);
    /* horizon 1.25 h: the bond at h lies in the shell, nu = (1.25+0.5-1)/1 */
    pd_bonds *b = bonds(p, 1.25 * h);
    CHECK(b->count == 2, "one bond, stored twice");
    CHECK(b->vfactor[0] == 0.75 && b->vfactor[1] == 0.75, "nu = 3/4");
    const double eps[2] = {1e-3, -2e-3};
    for (int k = 0; k < 2; k++) {
        pd_sim *sim = sim_of(p, b, c, dt, 0, 0);
        pd_sim_positions(sim)[0][1] = h * (1 + eps[k]);
        double fx[2], fy[2], fz[2], *f[3] = {fx, fy, fz};
        forces_of(sim, p, dt, f);
        double s = (h * (1 + eps[k]) - h) / h;
        double want0 = c * s * 0.75 * V1, want1 = -c * s * 0.75 * V0;
        CHECK(fabs(fx[0] - want0) <= 1e-9 * fabs(want0), "f_0 = %.17g, expected %.17g", fx[0],
              want0);
        CHECK(fabs(fx[1] - want1) <= 1e-9 * fabs(want1), "f_1 = %.17g, expected %.17g", fx[1],
              want1);
        CHECK(fy[0] == 0 && fz[0] == 0 && fy[1] == 0 && fz[1] == 0, "force along the bond");
        CHECK(fabs(V0 * fx[0] + V1 * fx[1]) <= 1e-12 * fabs(V0 * fx[0]),
              "forces do not cancel: %g", V0 * fx[0] + V1 * fx[1]);
        CHECK(k == 0 ? fx[0] > 0 : fx[0] < 0, "stretch attracts, compression repels");
        pd_sim_free(sim);
    }
    /* seed 004 eq. 46: dt < sqrt(2 rho / sum_j V_j nu c/|xi|), smallest over i */
    pd_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.c = c;
    double want = sqrt(2 * RHO / (V1 * 0.75 * c / h));
    double got = pd_stable_dt(p, b, &sc);
    CHECK(fabs(got - want) <= 1e-14 * want, "stable dt %.17g, expected %.17g", got, want);
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "a pair feels f_i = c s nu V_j along the bond, V_i f_i + V_j f_j = 0; eq. 46");
}

static void test_uniform_stretch(void)
{
    int f0 = failures;
    const double h = 1e-3, delta = 3.0001e-3, K = 14.9e9, eps = 1e-4, dt = 1e-15;
    const int m = 12;
    char spec[128];
    snprintf(spec, sizeof spec, "0,%.17g,0,%.17g,0,%.17g", m * h, m * h, m * h);
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, spec, &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {h, RHO, 1, 0, 1};
    pd_particles *p = NULL;
    if (pd_lattice_make(&r, 1, &lp, &p) != PD_OK)
        die("lattice");
    pd_bonds *b = bonds(p, delta);
    const double c = pd_pmb_c_from_bulk(K, delta);
    pd_sim *sim = sim_of(p, b, c, dt, 0, 0);
    double *const *y = pd_sim_positions(sim);
    const double mid = 0.5 * m * h;
    for (int d = 0; d < 3; d++)
        for (int64_t i = 0; i < p->n; i++)
            y[d][i] = mid + (1 + eps) * (p->x[d][i] - mid);

    /* every bond has stretch eps */
    double worst = 0;
    for (int64_t i = 0; i < p->n; i++)
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            int64_t j = b->neighbor[k];
            double dx = y[0][j] - y[0][i], dy = y[1][j] - y[1][i], dz = y[2][j] - y[2][i];
            double s = (sqrt(dx * dx + dy * dy + dz * dz) - b->length[k]) / b->length[k];
            worst = fmax(worst, fabs(s - eps));
        }
    CHECK(worst <= 1e-10 * eps, "bond stretch differs from eps by %g", worst);

    /* strain energy density of an interior particle against 9/2 K eps^2
     * times the lattice's share of the continuum integral int |xi| dV = pi
     * delta^4 (computed here from integer points, independently of lib/) */
    double share = 0;
    for (int a = -4; a <= 4; a++)
        for (int e = -4; e <= 4; e++)
            for (int g = -4; g <= 4; g++) {
                double len = h * sqrt((double)(a * a + e * e + g * g));
                if ((a || e || g) && len <= delta) {
                    double nu = len <= delta - 0.5 * h ? 1 : (delta + 0.5 * h - len) / h;
                    share += len * nu * h * h * h;
                }
            }
    share /= PI * pow(delta, 4);
    CHECK(share > 0.85 && share < 0.95, "lattice share %g of pi delta^4", share);

    double *f[3];
    for (int d = 0; d < 3; d++)
        f[d] = malloc((size_t)p->n * sizeof(double));
    forces_of(sim, p, dt, f);
    double scale = 0; /* |force density| of one side of the ball */
    for (int64_t k = b->offset[0]; k < b->offset[1]; k++)
        scale = fmax(scale, c * eps * p->volume[b->neighbor[k]] * b->vfactor[k]);
    /* the library's strain energy density (pd_sim_energy) is the same */
    double *wlib = malloc((size_t)p->n * sizeof(double));
    pd_energy en;
    if (wlib == NULL || pd_sim_energy(sim, &en, wlib) != PD_OK)
        die("pd_sim_energy");
    double wsum = 0;
    for (int64_t i = 0; i < p->n; i++)
        wsum += wlib[i] * p->volume[i];
    CHECK(fabs(wsum - en.elastic) <= 1e-12 * en.elastic, "elastic %g, sum of W V %g", en.elastic,
          wsum);
    int64_t interior = 0, faces = 0;
    for (int64_t i = 0; i < p->n; i++) {
        long n[3];
        int in = 1, on = 0, axis = -1;
        for (int d = 0; d < 3; d++) {
            n[d] = lround(p->x[d][i] / h);
            in &= n[d] >= 3 && n[d] <= m - 3;
            if (n[d] == 0 || n[d] == m) {
                on++;
                axis = d;
            }
        }
        double fn = sqrt(f[0][i] * f[0][i] + f[1][i] * f[1][i] + f[2][i] * f[2][i]);
        if (in) {
            interior++;
            CHECK(fn <= 1e-8 * scale, "interior particle %lld: |f| = %g (scale %g)",
                  (long long)i, fn, scale);
            double w = 0;
            for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++)
                w += 0.25 * c * eps * eps * b->length[k] * b->vfactor[k] *
                     p->volume[b->neighbor[k]];
            double want = 4.5 * K * eps * eps * share;
            CHECK(fabs(w - want) <= 1e-9 * want, "energy density %g, expected %g", w, want);
            CHECK(fabs(wlib[i] - want) <= 1e-9 * want, "pd_sim_energy density %g, expected %g",
                  wlib[i], want);
        }
        if (on == 1) {
            /* a face particle (not on an edge): pulled inward along the normal */
            faces++;
            double outward = n[axis] == 0 ? -1 : 1;
            CHECK(outward * f[axis][i] < -0.1 * scale, "face particle %lld not pulled inward",
                  (long long)i);
        }
    }
    CHECK(interior == 343 && faces == 6 * 11 * 11, "%lld interior, %lld face particles",
          (long long)interior, (long long)faces);
    for (int d = 0; d < 3; d++)
        free(f[d]);
    free(wlib);
    pd_sim_free(sim);
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "uniform stretch: bond stretch eps, no interior force, faces pulled in, "
               "W = 9/2 K eps^2 x lattice share (also from pd_sim_energy)");
}

/* Broken pairs after each of `steps` steps of a pair held at stretch s. */
static void run_failure(double s, double s00, double alpha, int steps, int64_t *broken,
                        double *vx)
{
    const double h = 1e-3, dt = 1e-13;
    pd_particles *p = pair(h, 1e-9, 1e-9);
    pd_bonds *b = bonds(p, 1.5001 * h);
    pd_sim *sim = sim_of(p, b, 1e20, dt, s00, alpha);
    pd_sim_positions(sim)[0][1] = h * (1 + s);
    if (pd_sim_setup(sim) != PD_OK)
        die("setup");
    broken[0] = pd_sim_broken(sim);
    for (int n = 1; n <= steps; n++) {
        if (pd_sim_step(sim) != PD_OK)
            die("step");
        broken[n] = pd_sim_broken(sim);
        vx[n] = pd_sim_velocities(sim)[0][0];
    }
    pd_sim_free(sim);
    pd_bonds_free(b);
    pd_particles_free(p);
}

/*
 * Four particles in a line, bonded to their nearest neighbours only: the
 * middle bond 1-2 stretched by sa, the outer bonds 0-1 and 2-3 compressed by
 * sb < 0.  Eq. 9 gives particles 1 and 2 s0 = s00 - alpha s_min = s00 -
 * alpha sb, so the middle bond breaks only for sa > s00 + alpha |sb|;
 * Algorithm 5's min line (s0 = s00 - alpha s_max) would break it for
 * sa > s00 / (1 + alpha).  Broken pairs after 4 steps.
 */
static int64_t chain_broken(double sa, double sb, double s00, double alpha)
{
    const double h = 1e-3, dt = 1e-13;
    pd_particles *p = pd_particles_new(4);
    for (int i = 0; i < 4; i++) {
        p->x[0][i] = i * h;
        p->x[1][i] = p->x[2][i] = 0;
        p->volume[i] = h * h * h;
        p->density[i] = RHO;
        p->radius[i] = 0.5 * h;
        p->material[i] = 1;
        p->id[i] = i + 1;
    }
    p->spacing = h;
    pd_bonds *b = bonds(p, 1.2 * h);
    if (b->count != 6)
        die("the chain should have 3 bonds");
    pd_sim *sim = sim_of(p, b, 1e20, dt, s00, alpha);
    double *yx = pd_sim_positions(sim)[0];
    yx[1] = h;
    yx[2] = h + h * (1 + sa);
    yx[0] = yx[1] - h * (1 + sb);
    yx[3] = yx[2] + h * (1 + sb);
    if (pd_sim_setup(sim) != PD_OK)
        die("setup");
    for (int n = 0; n < 4; n++)
        if (pd_sim_step(sim) != PD_OK)
            die("step");
    int64_t broken = pd_sim_broken(sim);
    pd_sim_free(sim);
    pd_bonds_free(b);
    pd_particles_free(p);
    return broken;
}

static void test_failure(void)
{
    int f0 = failures;
    int64_t broken[6];
    double vx[6];
    /* s00 = 1e-3, alpha = 0.25: one bond breaks when s > s00 - alpha s,
     * i.e. s > 8e-4 (eq. 9) */
    run_failure(8.5e-4, 1e-3, 0.25, 5, broken, vx);
    CHECK(broken[0] == 0 && broken[1] == 0, "broken before the second step (s0 starts at +inf)");
    CHECK(broken[2] == 1, "s = 8.5e-4 > s00 - alpha s: broken at step 2 (%lld)",
          (long long)broken[2]);
    CHECK(broken[5] == 1, "a broken bond stays broken");
    CHECK(vx[4] == vx[3] && vx[5] == vx[4], "a broken bond carries no force");
    CHECK(vx[2] > 0, "the bond pulled before it broke");
    run_failure(7.5e-4, 1e-3, 0.25, 5, broken, vx);
    CHECK(broken[5] == 0, "s = 7.5e-4 < s00 - alpha s: intact");
    run_failure(9.9e-4, 1e-3, 0.0, 5, broken, vx);
    CHECK(broken[5] == 0, "alpha = 0: s = 9.9e-4 < s00 stays intact");
    run_failure(1.01e-3, 1e-3, 0.0, 5, broken, vx);
    CHECK(broken[1] == 0 && broken[2] == 1, "alpha = 0: s > s00 breaks at step 2");
    run_failure(-5e-3, 1e-3, 0.25, 5, broken, vx);
    CHECK(broken[5] == 0, "compression never breaks a bond");
    /* s00 = 1e-3, alpha = 0.25, sb = -2e-3: eq. 9 threshold 1.5e-3 */
    CHECK(chain_broken(1.2e-3, -2e-3, 1e-3, 0.25) == 0,
          "sa = 1.2e-3 < s00 - alpha s_min: intact (Algorithm 5's line would break it)");
    CHECK(chain_broken(1.6e-3, -2e-3, 1e-3, 0.25) == 1, "sa = 1.6e-3 > s00 - alpha s_min: broken");
    proved(f0, "failure: s > s00 - alpha s_min breaks (eq. 9, s_min the smallest stretch) from "
               "the second step on, for good");
}

int main(void)
{
    test_micromodulus();
    test_pair_force();
    test_uniform_stretch();
    test_failure();
    if (failures)
        fprintf(stderr, "test_pmb: %d failures\n", failures);
    return failures != 0;
}
