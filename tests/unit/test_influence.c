/*
 * test_influence -- the ellipsoidal influence function (lib/bonds/influence.c,
 * seed 002 eqs. 6-13) and its use in the LPS model.
 *
 * Proves: the distance of eq. 13 is 1 along u, a along v and b along w
 * (v, w the normals of the rotation convention, by hand for an oblique u),
 * 1/sqrt(1/2 + 1/(2a^2)) half-way between u and v, and the roll swaps v
 * and w at pi/2; several ellipsoids give the largest distance, none gives
 * 1; bad ellipsoids are refused.  In LPS runs: a = b = 1 (a sphere)
 * reproduces the isotropic dilatation, energy and stress (the seed's six
 * digits; in fact to rounding); a scaled U gives bit-identical results;
 * scaling omega by a constant changes neither theta, the energy nor the
 * stress (omega = 1/|xi| against 1 on a nearest-neighbour family, where
 * they differ by the constant 1/h); a uniform stretch still gives theta =
 * 3 eps and W = 9/2 K eps^2 (m normalizes any omega); and a body with u
 * along x is stiffer under a stretch along x than along y.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "pd.h"

static const double RHO = 2200.0, H = 1e-3, K = 14.9e9, G = 6e9;
static const int M = 8; /* particles per edge */

static pd_ellipsoid ell(double ux, double uy, double uz, double a, double b, double roll)
{
    pd_ellipsoid e = {{ux, uy, uz}, a, b, roll, {0}};
    if (pd_ellipsoid_init(&e) != PD_OK)
        die("pd_ellipsoid_init");
    return e;
}

static double dist(const pd_ellipsoid *e, double x, double y, double z)
{
    const double d[3] = {x, y, z};
    return pd_ellipsoid_distance(e, d);
}

static void test_distance(void)
{
    int f0 = failures;
    const double a = 0.5, b = 0.25;
    /* u along x, roll 0: v = e_y, w = e_z */
    pd_ellipsoid e = ell(1, 0, 0, a, b, 0);
    CHECK(fabs(dist(&e, 3, 0, 0) - 1) < 1e-15, "along u: %.17g", dist(&e, 3, 0, 0));
    CHECK(fabs(dist(&e, -1, 0, 0) - 1) < 1e-15, "along -u: %.17g", dist(&e, -1, 0, 0));
    CHECK(fabs(dist(&e, 0, 2, 0) - a) < 1e-15, "along v: %.17g", dist(&e, 0, 2, 0));
    CHECK(fabs(dist(&e, 0, 0, 1) - b) < 1e-15, "along w: %.17g", dist(&e, 0, 0, 1));
    /* 45 deg in x-y: w' = (1, 1, 0)/sqrt 2, d = 1/sqrt(1/2 + 1/(2 a^2)) */
    double want = 1 / sqrt(0.5 + 0.5 / (a * a));
    CHECK(fabs(dist(&e, 1, 1, 0) - want) < 1e-15, "45 deg: %.17g vs %.17g", dist(&e, 1, 1, 0),
          want);
    /* an oblique u = (1,1,1): Y = 45 deg, so v = M_Y e_y = (-1,1,0)/sqrt 2
     * at roll 0 and w = u x v = (-1,-1,2)/sqrt 6 */
    const double s2 = sqrt(2), s3 = sqrt(3), s6 = sqrt(6);
    const double u[3] = {1 / s3, 1 / s3, 1 / s3}, v[3] = {-1 / s2, 1 / s2, 0},
                 w[3] = {-1 / s6, -1 / s6, 2 / s6};
    for (int r = 0; r < 3; r++) {
        const double R = r == 0 ? 0 : r == 1 ? 0.7 : acos(-1.0) / 2;
        pd_ellipsoid o = ell(2, 2, 2, a, b, R);
        /* the roll turns v toward w: v_R = cos R v + sin R w */
        double vr[3], wr[3], h[3];
        for (int d = 0; d < 3; d++) {
            vr[d] = cos(R) * v[d] + sin(R) * w[d];
            wr[d] = -sin(R) * v[d] + cos(R) * w[d];
            h[d] = u[d] + vr[d];
        }
        CHECK(fabs(pd_ellipsoid_distance(&o, u) - 1) < 1e-14, "R %g along u: %.17g", R,
              pd_ellipsoid_distance(&o, u));
        CHECK(fabs(pd_ellipsoid_distance(&o, vr) - a) < 1e-14, "R %g along v_R: %.17g", R,
              pd_ellipsoid_distance(&o, vr));
        CHECK(fabs(pd_ellipsoid_distance(&o, wr) - b) < 1e-14, "R %g along w_R: %.17g", R,
              pd_ellipsoid_distance(&o, wr));
        CHECK(fabs(pd_ellipsoid_distance(&o, h) - want) < 1e-14, "R %g between u, v_R: %.17g",
              R, pd_ellipsoid_distance(&o, h));
        if (r == 2) { /* a quarter roll: the old v gets b, the old w gets a */
            CHECK(fabs(pd_ellipsoid_distance(&o, v) - b) < 1e-14, "roll pi/2, v: %.17g",
                  pd_ellipsoid_distance(&o, v));
            CHECK(fabs(pd_ellipsoid_distance(&o, w) - a) < 1e-14, "roll pi/2, w: %.17g",
                  pd_ellipsoid_distance(&o, w));
        }
    }
    /* u straight up: Y = 0, P = 90 deg, so v = e_y and w = -e_x */
    pd_ellipsoid z = ell(0, 0, 1, a, b, 0);
    CHECK(fabs(dist(&z, 0, 0, 1) - 1) < 1e-15 && fabs(dist(&z, 0, 1, 0) - a) < 1e-15 &&
              fabs(dist(&z, 1, 0, 0) - b) < 1e-15,
          "u = e_z: %.17g %.17g %.17g", dist(&z, 0, 0, 1), dist(&z, 0, 1, 0), dist(&z, 1, 0, 0));
    proved(f0, "eq. 13: 1 along u, a along v, b along w, 45 deg by hand, the roll turns v to w");
}

static void test_several(void)
{
    int f0 = failures;
    pd_ellipsoid two[2] = {ell(1, 0, 0, 0.5, 0.5, 0), ell(0, 1, 0, 0.5, 0.5, 0)};
    const double dx[3] = {1, 0, 0}, dy[3] = {0, 1, 0}, dz[3] = {0, 0, 1}, d21[3] = {2, 1, 0};
    CHECK(pd_ellipsoids_factor(two, 2, dx) == 1 && pd_ellipsoids_factor(two, 2, dy) == 1,
          "both preferred directions keep the full weight");
    CHECK(fabs(pd_ellipsoids_factor(two, 2, dz) - 0.5) < 1e-15, "across both: %.17g",
          pd_ellipsoids_factor(two, 2, dz));
    /* (2,1,0)/sqrt 5: the first gives 1/sqrt(4/5 + 4/5), the second
     * 1/sqrt(1/5 + 16/5); the larger wins */
    const double want = 1 / sqrt(1.6);
    CHECK(fabs(pd_ellipsoids_factor(two, 2, d21) - want) < 1e-15, "(2,1,0): %.17g vs %.17g",
          pd_ellipsoids_factor(two, 2, d21), want);
    CHECK(fabs(pd_ellipsoid_distance(&two[1], d21) - 1 / sqrt(3.4)) < 1e-15, "second: %.17g",
          pd_ellipsoid_distance(&two[1], d21));
    CHECK(pd_ellipsoids_factor(two, 0, d21) == 1, "no ellipsoid: isotropic");
    pd_ellipsoid e;
    const char *bad[] = {"1,0,0,0,0.5,0", "0,0,0,1,1,0", "1,0,0,1.5,1,0", "1,0,0,1,1",
                         "1,0,0,1,1,0,7", "1,0,0,1,1,x", "1,0,0,1,-0.5,0", "", NULL};
    for (int k = 0; bad[k]; k++)
        CHECK(pd_ellipsoid_parse(bad[k], &e) == PD_ERR_INVALID, "'%s' accepted", bad[k]);
    CHECK(pd_ellipsoid_parse("0,2,0,0.5,1,0.25", &e) == PD_OK && e.u[1] == 2 && e.a == 0.5 &&
              e.b == 1 && e.roll == 0.25,
          "a good ellipsoid: %s", pd_errmsg());
    proved(f0, "several ellipsoids: the largest distance; none: 1; bad ones refused");
}

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

/* What an LPS run sees at positions y = x + displacement: theta, the
 * energy density and the stress of every particle. */
typedef struct {
    double *theta, *w, *s;
    double total;
} look;

enum { STRETCH_X, STRETCH_Y, STRETCH_ALL, WOBBLE };

static look measure(const pd_particles *p, const pd_bonds *b, pd_influence inf,
                    const pd_ellipsoid *el, int nel, int how, double eps)
{
    pd_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.model = PD_MODEL_LPS;
    sc.bulk_modulus = K;
    sc.shear_modulus = G;
    sc.influence = inf;
    sc.c = pd_pmb_c_from_bulk(K, b->horizon);
    sc.dt = 1e-15;
    sc.safety = 1;
    sc.steps = 1;
    sc.nellipsoids = nel;
    for (int k = 0; k < nel; k++)
        sc.ellipsoid[k] = el[k];
    sc.dt_stable = pd_stable_dt(p, b, &sc);
    pd_sim *sim = NULL;
    if (pd_sim_new(p, b, &sc, &sim) != PD_OK)
        die("pd_sim_new");
    double *const *y = pd_sim_positions(sim);
    for (int64_t i = 0; i < p->n; i++)
        for (int d = 0; d < 3; d++) {
            double u = 0;
            if (how == STRETCH_ALL || (how == STRETCH_X && d == 0) || (how == STRETCH_Y && d == 1))
                u = eps * p->x[d][i];
            else if (how == WOBBLE) /* a smooth, non-affine displacement */
                u = eps * H * sin(0.7 * (double)i + 1.3 * d);
            y[d][i] = p->x[d][i] + u;
        }
    look l;
    l.theta = malloc((size_t)p->n * sizeof(double));
    l.w = malloc((size_t)p->n * sizeof(double));
    l.s = calloc((size_t)p->n * 9, sizeof(double));
    pd_energy e;
    if (pd_sim_dilatation(sim, l.theta) != PD_OK || pd_sim_energy(sim, &e, l.w) != PD_OK ||
        pd_sim_stress(sim, l.s) != PD_OK)
        die("measure");
    l.total = e.elastic;
    pd_sim_free(sim);
    return l;
}

static void look_free(look *l)
{
    free(l->theta);
    free(l->w);
    free(l->s);
}

/* The largest difference of a and b relative to the largest |a|, over
 * theta, energy and stress. */
static double rel_diff(const look *a, const look *b, int64_t n)
{
    double dt = 0, st = 0, dw = 0, sw = 0, ds = 0, ss = 0;
    for (int64_t i = 0; i < n; i++) {
        dt = fmax(dt, fabs(a->theta[i] - b->theta[i]));
        st = fmax(st, fabs(a->theta[i]));
        dw = fmax(dw, fabs(a->w[i] - b->w[i]));
        sw = fmax(sw, fabs(a->w[i]));
        for (int q = 0; q < 9; q++) {
            ds = fmax(ds, fabs(a->s[9 * i + q] - b->s[9 * i + q]));
            ss = fmax(ss, fabs(a->s[9 * i + q]));
        }
    }
    return fmax(dt / st, fmax(dw / sw, ds / ss));
}

static int same_bits(const look *a, const look *b, int64_t n)
{
    return memcmp(a->theta, b->theta, (size_t)n * sizeof(double)) == 0 &&
           memcmp(a->w, b->w, (size_t)n * sizeof(double)) == 0 &&
           memcmp(a->s, b->s, (size_t)n * 9 * sizeof(double)) == 0;
}

static void test_lps(const pd_particles *p, const pd_bonds *b, const pd_bonds *nn)
{
    int f0 = failures;
    const int64_t n = p->n;
    const double eps = 1e-4;
    /* a sphere (a = b = 1) is the isotropic influence */
    look iso = measure(p, b, PD_INFLUENCE_INV_R, NULL, 0, WOBBLE, eps);
    pd_ellipsoid sph[2] = {ell(0.3, -1, 2, 1, 1, 0.4), ell(1, 0, 0, 1, 1, 0)};
    look s1 = measure(p, b, PD_INFLUENCE_INV_R, sph, 2, WOBBLE, eps);
    const double dsph = rel_diff(&iso, &s1, n);
    CHECK(dsph < 1e-6, "a = b = 1 vs isotropic: %.3g (the seed: six digits)", dsph);
    CHECK(dsph < 1e-13, "a = b = 1 vs isotropic: %.3g (rounding)", dsph);
    printf("  a = b = 1 against isotropic: largest relative difference %.2g\n", dsph);
    /* the same ellipsoid with U scaled: bit for bit */
    pd_ellipsoid e1 = ell(1, 1, 0, 0.5, 0.7, 0.3), e2 = ell(2, 2, 0, 0.5, 0.7, 0.3),
                 e3 = ell(3, 3, 0, 0.5, 0.7, 0.3);
    look a1 = measure(p, b, PD_INFLUENCE_INV_R, &e1, 1, WOBBLE, eps);
    look a2 = measure(p, b, PD_INFLUENCE_INV_R, &e2, 1, WOBBLE, eps);
    look a3 = measure(p, b, PD_INFLUENCE_INV_R, &e3, 1, WOBBLE, eps);
    CHECK(same_bits(&a1, &a2, n), "U and 2U differ");
    const double d3 = rel_diff(&a1, &a3, n);
    CHECK(d3 < 1e-13, "U and 3U: %.3g", d3);
    CHECK(rel_diff(&iso, &a1, n) > 1e-3, "the ellipsoid changes nothing: %.3g",
          rel_diff(&iso, &a1, n));
    printf("  U against 3U: largest relative difference %.2g\n", d3);
    /* omega times a constant: 1/|xi| = (1/h) 1 on nearest-neighbour bonds */
    look c1 = measure(p, nn, PD_INFLUENCE_INV_R, &e1, 1, WOBBLE, eps);
    look c2 = measure(p, nn, PD_INFLUENCE_ONE, &e1, 1, WOBBLE, eps);
    const double dc = rel_diff(&c1, &c2, n);
    CHECK(dc < 1e-13, "omega vs omega h: %.3g", dc);
    printf("  omega against a constant times omega: largest relative difference %.2g\n", dc);
    look *all[] = {&iso, &s1, &a1, &a2, &a3, &c1, &c2};
    for (int k = 0; k < 7; k++)
        look_free(all[k]);
    proved(f0, "LPS: a sphere is isotropic; a scaled U and a scaled omega change nothing");

    f0 = failures;
    /* a uniform stretch: m normalizes any omega */
    pd_ellipsoid two[2] = {ell(1, 1, 0, 0.3, 0.6, 0.2), ell(0, 0, 1, 0.5, 0.5, 0)};
    look u = measure(p, b, PD_INFLUENCE_INV_R, two, 2, STRETCH_ALL, eps);
    const double want = 4.5 * K * eps * eps;
    for (int64_t i = 0; i < n; i++) {
        CHECK(fabs(u.theta[i] - 3 * eps) <= 1e-9 * eps, "theta[%lld] = %.17g", (long long)i,
              u.theta[i]);
        CHECK(fabs(u.w[i] - want) <= 1e-6 * want, "W[%lld] = %.17g vs %.17g", (long long)i,
              u.w[i], want);
    }
    look_free(&u);
    /* u along x, a = b = 1/2: stiffer along x than along y; isotropic equal */
    pd_ellipsoid ex = ell(1, 0, 0, 0.5, 0.5, 0);
    look ix = measure(p, b, PD_INFLUENCE_INV_R, NULL, 0, STRETCH_X, eps);
    look iy = measure(p, b, PD_INFLUENCE_INV_R, NULL, 0, STRETCH_Y, eps);
    look ax = measure(p, b, PD_INFLUENCE_INV_R, &ex, 1, STRETCH_X, eps);
    look ay = measure(p, b, PD_INFLUENCE_INV_R, &ex, 1, STRETCH_Y, eps);
    double sxx = 0, syy = 0;
    for (int64_t i = 0; i < n; i++) {
        sxx += ax.s[9 * i + 0];
        syy += ay.s[9 * i + 4];
    }
    CHECK(fabs(ix.total / iy.total - 1) < 1e-9, "isotropic: W_x / W_y = %.12g",
          ix.total / iy.total);
    CHECK(ax.total > 1.05 * ay.total, "W along u %.6g vs across %.6g", ax.total, ay.total);
    CHECK(sxx > 1.05 * syy, "sum s_xx along u %.6g vs s_yy across %.6g", sxx, syy);
    printf("  uniaxial stretch, u = e_x, a = b = 1/2: W_x/W_y = %.4f, s_xx/s_yy = %.4f "
           "(isotropic %.4f)\n",
           ax.total / ay.total, sxx / syy, ix.total / iy.total);
    look *st[] = {&ix, &iy, &ax, &ay};
    for (int k = 0; k < 4; k++)
        look_free(st[k]);
    proved(f0, "LPS: uniform stretch theta = 3 eps, W = 9/2 K eps^2; stiffer along u than across");
}

int main(void)
{
    test_distance();
    test_several();
    pd_particles *p = cube();
    pd_bonds *b = NULL, *nn = NULL;
    if (pd_bonds_build(p, 3.0001e-3, &b) != PD_OK || pd_bonds_build(p, 1.01e-3, &nn) != PD_OK)
        die("bonds");
    test_lps(p, b, nn);
    pd_bonds_free(b);
    pd_bonds_free(nn);
    pd_particles_free(p);
    return failures != 0;
}
