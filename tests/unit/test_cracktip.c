/*
 * test_cracktip -- crack tips, extension, speed and fronts of
 * lib/bonds/cracktip.c.
 *
 * Proves: the lower and upper tips are the smallest and largest current
 * coordinate x + u along the axis among particles with damage strictly
 * above the threshold (NaN and a count of 0 when there is none), and
 * pd_crack_tip is the upper one; the extension is 0 before the first frame
 * with a tip, counted from that frame's tip, positive for growth on both
 * sides, NaN where a later tip is missing; the speed of a tip moving at a
 * constant speed is that speed to rounding for every window and at both
 * ends of the series, a staircase with one step per frame gets its mean
 * slope in the middle, and too few frames or equal times give NaN; the
 * front of a damaged ball inside a lattice block is exactly the ball
 * particles within a horizon of a particle outside it (checked by brute
 * force); the front's distances from a point and from an axis line and its
 * extent along the axis match their definitions on a hand-made ring.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "pd.h"

static void test_tips(void)
{
    int f0 = failures;
    pd_particles *p = pd_particles_new(5);
    if (p == NULL)
        die("particles");
    double x[5] = {0, 1, 2, 3, 4}, u[5] = {0.5, -0.25, 0, 0.125, 10};
    double dmg[5] = {0.31, 0.9, 0.3, 1.0, 0.0};
    double zero[5] = {0};
    for (int i = 0; i < 5; i++) {
        p->x[0][i] = x[i];
        p->x[1][i] = -x[i];
        p->x[2][i] = 0;
    }
    double *uu[3] = {u, zero, zero};
    double lo, hi, tip;
    int64_t n;
    CHECK(pd_crack_tips(p, uu, dmg, 0, 0.3, &lo, &hi, &n) == PD_OK, "tips");
    /* damaged: 0 (at 0.5), 1 (at 0.75), 3 (at 3.125); 2 sits at 0.3 exactly */
    CHECK(n == 3 && lo == 0.5 && hi == 3.125, "x tips %g %g of %lld", lo, hi, (long long)n);
    CHECK(pd_crack_tip(p, uu, dmg, 0, 0.3, &tip, &n) == PD_OK && tip == hi, "tip is upper");
    CHECK(pd_crack_tips(p, NULL, dmg, 1, 0.3, &lo, &hi, &n) == PD_OK && lo == -3 && hi == 0,
          "y tips at reference positions %g %g", lo, hi);
    CHECK(pd_crack_tips(p, uu, dmg, 0, 1.0, &lo, &hi, &n) == PD_OK && isnan(lo) && isnan(hi) &&
              n == 0,
          "nothing above 1: NaN tips");
    CHECK(pd_crack_tips(p, uu, dmg, 3, 0.3, &lo, &hi, &n) == PD_ERR_INVALID, "axis 3 refused");
    CHECK(pd_crack_tips(p, uu, dmg, 0, NAN, &lo, &hi, &n) == PD_ERR_INVALID, "NaN threshold");
    pd_particles_free(p);
    proved(f0, "tips: min and max of x + u over damage > threshold; NaN when none");
}

static void test_extension(void)
{
    int f0 = failures;
    double upper[6] = {NAN, NAN, 2.0, 2.5, NAN, 4.0}, lower[6] = {NAN, NAN, 1.0, 0.5, 0.25, 0};
    double da[6];
    pd_crack_extension(6, upper, +1, da);
    CHECK(da[0] == 0 && da[1] == 0 && da[2] == 0 && da[3] == 0.5 && isnan(da[4]) && da[5] == 2,
          "upper: 0 0 0 0.5 nan 2, got %g %g %g %g %g %g", da[0], da[1], da[2], da[3], da[4],
          da[5]);
    pd_crack_extension(6, lower, -1, da);
    CHECK(da[2] == 0 && !signbit(da[2]) && da[3] == 0.5 && da[4] == 0.75 && da[5] == 1,
          "lower grows positive towards smaller coordinates");
    double none[3] = {NAN, NAN, NAN};
    pd_crack_extension(3, none, +1, da);
    CHECK(da[0] == 0 && da[1] == 0 && da[2] == 0, "no tip anywhere: all 0");
    proved(f0, "extension: 0 before the first tip, counted from it, positive both ways");
}

static void test_speed(void)
{
    int f0 = failures;
    enum { N = 9 };
    double t[N], a[N], v[N];
    const double c = 1300.0; /* m/s, the seed's maximum crack speed */
    for (int k = 0; k < N; k++) {
        t[k] = 1e-6 * k * (1 + 0.1 * k); /* unevenly spaced frames */
        a[k] = 1e-3 + c * t[k];
    }
    for (int w = 1; w <= 10; w++) {
        CHECK(pd_crack_speed(N, t, a, w, v) == PD_OK, "speed");
        for (int k = 0; k < N; k++)
            CHECK(fabs(v[k] - c) <= 1e-9 * c, "window %d frame %d: %.17g", w, k, v[k]);
    }
    /* a staircase: one step of h per frame dt = slope h/dt everywhere */
    double h = 2.5e-4, dt = 1e-7;
    for (int k = 0; k < N; k++) {
        t[k] = k * dt;
        a[k] = h * (k / 2); /* steps every other frame: mean slope h/(2 dt) */
    }
    CHECK(pd_crack_speed(N, t, a, 2, v) == PD_OK, "staircase");
    for (int k = 2; k < N - 2; k++)
        CHECK(fabs(v[k] - h / (2 * dt)) <= 0.2 * h / (2 * dt), "staircase frame %d: %g", k, v[k]);
    /* NaN in the data leaves those frames out */
    for (int k = 0; k < N; k++) {
        t[k] = k * dt;
        a[k] = c * t[k];
    }
    a[4] = NAN;
    CHECK(pd_crack_speed(N, t, a, 1, v) == PD_OK, "with a NaN");
    CHECK(isnan(v[4]) && fabs(v[3] - c) <= 1e-9 * c && fabs(v[5] - c) <= 1e-9 * c,
          "NaN frame: NaN speed, its neighbours fit the rest");
    double one[1] = {0}, tt[2] = {1, 1}, aa[2] = {0, 1};
    CHECK(pd_crack_speed(1, one, one, 2, v) == PD_OK && isnan(v[0]), "one frame: NaN");
    CHECK(pd_crack_speed(2, tt, aa, 2, v) == PD_OK && isnan(v[0]) && isnan(v[1]),
          "equal times: NaN");
    CHECK(pd_crack_speed(2, tt, aa, 0, v) == PD_ERR_INVALID, "window 0 refused");
    proved(f0, "speed: least-squares slope, exact for a constant speed, NaN without data");
}

static void test_front(void)
{
    int f0 = failures;
    const double h = 1e-3, delta = 2.0001 * h;
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, "0,0.0101,0,0.0101,0,0.0101", &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {h, 2200, 1, 0, 1};
    pd_particles *p = NULL;
    pd_bonds *b = NULL;
    if (pd_lattice_make(&r, 1, &lp, &p) != PD_OK || pd_bonds_build(p, delta, &b) != PD_OK)
        die("model");
    const double c[3] = {5 * h, 5 * h, 5 * h}, R = 3.2 * h;
    double *d = malloc((size_t)p->n * sizeof(double));
    uint8_t *front = malloc((size_t)p->n);
    for (int64_t i = 0; i < p->n; i++) {
        double r2 = 0;
        for (int k = 0; k < 3; k++)
            r2 += (p->x[k][i] - c[k]) * (p->x[k][i] - c[k]);
        d[i] = r2 <= R * R ? 0.35 + 0.5 * (double)(i % 3) / 3 : 0.2 * (double)(i % 2);
    }
    int64_t nfront, want = 0, bad = 0;
    CHECK(pd_crack_front(p, b, d, 0.3, front, &nfront) == PD_OK, "front");
    for (int64_t i = 0; i < p->n; i++) {
        int on = 0;
        for (int64_t j = 0; j < p->n && d[i] > 0.3 && !on; j++) {
            double r2 = 0;
            for (int k = 0; k < 3; k++)
                r2 += (p->x[k][i] - p->x[k][j]) * (p->x[k][i] - p->x[k][j]);
            on = j != i && r2 <= delta * delta && !(d[j] > 0.3);
        }
        want += on;
        bad += on != front[i];
    }
    CHECK(bad == 0 && nfront == want && want > 0, "front %lld, brute force %lld, %lld differ",
          (long long)nfront, (long long)want, (long long)bad);
    /* a ring of 4 points around the z axis through c, at two heights */
    pd_particles *q = pd_particles_new(6);
    if (q == NULL)
        die("particles");
    double ring[6][3] = {{8, 5, 1}, {5, 9, 2}, {2, 5, 3}, {5, 1, 4}, {5, 5, 0}, {9, 9, 9}};
    uint8_t fl[6] = {1, 1, 1, 1, 0, 0};
    for (int i = 0; i < 6; i++)
        for (int k = 0; k < 3; k++)
            q->x[k][i] = ring[i][k] * h;
    pd_crack_front_info fi;
    CHECK(pd_crack_front_stats(q, NULL, fl, c, 2, 1, &fi) == PD_OK, "stats");
    CHECK(fi.n == 4 && fabs(fi.r_max - 4 * h) < 1e-15 && fabs(fi.r_mean - 3.5 * h) < 1e-15 &&
              fabs(fi.lo - 1 * h) < 1e-15 && fabs(fi.hi - 4 * h) < 1e-15,
          "ring from the axis: %g %g %g %g", fi.r_max, fi.r_mean, fi.lo, fi.hi);
    CHECK(pd_crack_front_stats(q, NULL, fl, c, 2, 0, &fi) == PD_OK &&
              fabs(fi.r_max - 5 * h) < 1e-15 &&
              fabs(fi.r_mean - (5 + 5 + sqrt(13) + sqrt(17)) / 4 * h) < 1e-15,
          "from the point: |(3,0,-4)| = |(0,4,-3)| = 5 h the largest, got %g", fi.r_max);
    memset(fl, 0, sizeof fl);
    CHECK(pd_crack_front_stats(q, NULL, fl, c, 2, 1, &fi) == PD_OK && fi.n == 0 &&
              isnan(fi.r_max) && isnan(fi.lo),
          "empty front: NaN");
    free(d);
    free(front);
    pd_particles_free(q);
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "front: damaged particles with an undamaged family member; ring measures");
}

int main(void)
{
    test_tips();
    test_extension();
    test_speed();
    test_front();
    return failures ? 1 : 0;
}
