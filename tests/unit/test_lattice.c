/*
 * test_lattice -- regions and lattices of lib/base/region.c and lib/base/lattice.c.
 *
 * Proves: regions are closed sets (a point on a face, on the cylinder's
 * mantle or on the sphere is inside, a point just outward is not); the
 * cylinder's C1,C2 are the other two coordinates in x,y,z order; malformed
 * specs are refused; lattice sites are n*spacing inside the union of the
 * added regions and outside every subtracted one, counted against direct
 * enumeration (11^3 for a closed box, 123 for a ball of radius 3 spacings);
 * no site appears twice in a union; ids are 1..N in z, y, x order; every
 * particle has volume h^3 and radius h/2; a perturbation stays within its
 * amplitude and is reproducible by seed; an empty body is an error.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "pd.h"

static pd_region region(pd_region_kind kind, const char *spec)
{
    pd_region r;
    pd_status s = pd_region_parse(kind, spec, &r);
    if (s != PD_OK) {
        fprintf(stderr, "cannot parse '%s': %s\n", spec, pd_errmsg());
        exit(1);
    }
    return r;
}

static int inside(const pd_region *r, double x, double y, double z)
{
    double p[3] = {x, y, z};
    return pd_region_inside(r, p);
}

static void test_box(void)
{
    int f0 = failures;
    pd_region b = region(PD_REGION_BOX, "-1,2,0,3,0.5,4");
    CHECK(inside(&b, -1, 0, 0.5) && inside(&b, 2, 3, 4), "corners are inside");
    CHECK(inside(&b, 0, 1.5, 4), "a point on a face is inside");
    CHECK(!inside(&b, nextafter(-1, -2), 1, 1), "just below xlo is outside");
    CHECK(!inside(&b, 0, nextafter(3, 4), 1), "just above yhi is outside");
    CHECK(!inside(&b, 0, 1, nextafter(4, 5)), "just above zhi is outside");
    double lo[3], hi[3];
    pd_region_bounds(&b, lo, hi);
    CHECK(lo[0] == -1 && hi[0] == 2 && lo[1] == 0 && hi[1] == 3 && lo[2] == 0.5 && hi[2] == 4,
          "box bounds");
    proved(f0, "a box is closed: faces and corners inside, the next double outside");
}

static void test_cylinder(void)
{
    int f0 = failures;
    /* axis z, centre (x,y) = (1,2), R = 5: (1+3, 2+4) is at exactly 5 */
    pd_region z = region(PD_REGION_CYLINDER, "z,1,2,5,0,10");
    CHECK(z.axis == 2, "axis z");
    CHECK(inside(&z, 4, 6, 5), "a point on the mantle is inside");
    CHECK(inside(&z, 1, 2, 0) && inside(&z, 1, 2, 10), "end faces are inside");
    CHECK(!inside(&z, 1, 2, nextafter(10, 11)), "beyond the end is outside");
    CHECK(!inside(&z, 4 + 1e-12, 6, 5), "just outside the mantle is outside");
    /* axis y: C1 is x, C2 is z (LAMMPS region cylinder) */
    pd_region y = region(PD_REGION_CYLINDER, "y,1,2,5,-3,0");
    CHECK(y.axis == 1, "axis y");
    CHECK(inside(&y, 6, -1, 2) && inside(&y, 1, -3, 7), "y axis: C1 is x, C2 is z");
    CHECK(!inside(&y, 1, -1, -3.01), "y axis: outside in z");
    CHECK(!inside(&y, 1, 0.5, 2), "y axis: beyond HI");
    /* axis x: C1 is y, C2 is z */
    pd_region x = region(PD_REGION_CYLINDER, "x,1,2,5,0,1");
    CHECK(inside(&x, 0.5, 6, 2) && inside(&x, 0.5, 1, 7), "x axis: C1 is y, C2 is z");
    CHECK(!inside(&x, 0.5, 1, 7.01), "x axis: outside the mantle");
    double lo[3], hi[3];
    pd_region_bounds(&y, lo, hi);
    CHECK(lo[0] == -4 && hi[0] == 6 && lo[1] == -3 && hi[1] == 0 && lo[2] == -3 && hi[2] == 7,
          "cylinder y bounds: x in [-4,6], y in [-3,0], z in [-3,7]");
    proved(f0, "a cylinder is closed; C1,C2 are the other axes in x,y,z order");
}

static void test_sphere(void)
{
    int f0 = failures;
    pd_region s = region(PD_REGION_SPHERE, "1,1,1,5");
    CHECK(inside(&s, 4, 5, 1) && inside(&s, 1, 1, -4), "points at exactly R are inside");
    CHECK(!inside(&s, 4 + 1e-12, 5, 1), "just outside is outside");
    CHECK(inside(&s, 1, 1, 1), "the centre is inside");
    proved(f0, "a sphere is closed");
}

static void test_parse_errors(void)
{
    int f0 = failures;
    pd_region r;
    const struct {
        pd_region_kind kind;
        const char *spec;
    } bad[] = {
        {PD_REGION_BOX, "0,1,0,1,0"},      {PD_REGION_BOX, "1,0,0,1,0,1"},
        {PD_REGION_BOX, "0,1,0,1,0,1,2"},  {PD_REGION_BOX, "0,1,,0,1,0"},
        {PD_REGION_BOX, "0,1,0,1,0,nan"},  {PD_REGION_BOX, "a,1,0,1,0,1"},
        {PD_REGION_CYLINDER, "w,0,0,1,0,1"}, {PD_REGION_CYLINDER, "z,0,0,0,0,1"},
        {PD_REGION_CYLINDER, "z,0,0,1,2,1"}, {PD_REGION_CYLINDER, "zz,0,0,1,0,1"},
        {PD_REGION_SPHERE, "0,0,0,-1"},    {PD_REGION_SPHERE, "0,0,0"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++)
        CHECK(pd_region_parse(bad[k].kind, bad[k].spec, &r) == PD_ERR_INVALID,
              "'%s' should be refused", bad[k].spec);
    CHECK(pd_region_parse_tagged("cone,1,2", &r) == PD_ERR_INVALID, "unknown kind refused");
    CHECK(pd_region_parse_tagged("sphere,0,0,0,1", &r) == PD_OK && r.kind == PD_REGION_SPHERE,
          "tagged sphere parsed");
    CHECK(pd_region_parse_tagged("box,0,1,0,1,0,1", &r) == PD_OK && r.kind == PD_REGION_BOX,
          "tagged box parsed");
    proved(f0, "malformed region specs are refused with PD_ERR_INVALID");
}

static pd_particles *lattice(const pd_region *r, int n, double h, double perturb,
                             unsigned long seed)
{
    pd_lattice_params lp = {h, 2200.0, 7, perturb, seed};
    pd_particles *p = NULL;
    pd_status s = pd_lattice_make(r, n, &lp, &p);
    if (s != PD_OK) {
        fprintf(stderr, "pd_lattice_make: %s\n", pd_errmsg());
        exit(1);
    }
    return p;
}

/* Number of integer points (i,j,k) with i^2+j^2+k^2 <= m2. */
static int64_t ball_points(int m2)
{
    int64_t count = 0;
    for (int i = -10; i <= 10; i++)
        for (int j = -10; j <= 10; j++)
            for (int k = -10; k <= 10; k++)
                count += i * i + j * j + k * k <= m2;
    return count;
}

static void test_counts(void)
{
    int f0 = failures;
    pd_region box = region(PD_REGION_BOX, "0,10,0,10,0,10");
    pd_particles *p = lattice(&box, 1, 1.0, 0, 1);
    CHECK(p->n == 1331, "closed box 0..10: %lld sites, expected 11^3", (long long)p->n);
    pd_particles_free(p);

    /* spacing 0.5 so that every coordinate is exact */
    pd_region ball = region(PD_REGION_SPHERE, "1,1,1,1.5");
    p = lattice(&ball, 1, 0.5, 0, 1);
    CHECK(ball_points(9) == 123, "123 integer points within radius 3");
    CHECK(p->n == 123, "ball of radius 3 spacings: %lld sites, expected 123", (long long)p->n);
    pd_particles_free(p);

    /* cylinder along z, radius 3 spacings around a site, 5 layers */
    pd_region cyl = region(PD_REGION_CYLINDER, "z,0.5,-1,1.5,0,2");
    p = lattice(&cyl, 1, 0.5, 0, 1);
    int64_t disc = 0;
    for (int i = -5; i <= 5; i++)
        for (int j = -5; j <= 5; j++)
            disc += i * i + j * j <= 9;
    CHECK(disc == 29, "29 integer points in a disc of radius 3");
    CHECK(p->n == 5 * disc, "cylinder: %lld sites, expected %lld", (long long)p->n,
          (long long)(5 * disc));
    pd_particles_free(p);
    proved(f0, "site counts equal direct enumeration (box 1331, ball 123, cylinder 5 x 29)");
}

static void test_union_subtract(void)
{
    int f0 = failures;
    pd_region r[3];
    r[0] = region(PD_REGION_BOX, "0,3,0,2,0,2");
    r[1] = region(PD_REGION_BOX, "1.5,4.5,1,4,0,2");
    pd_particles *p = lattice(r, 2, 0.5, 0, 1);
    /* 7x5x5 + 7x7x5 - 4x3x5 */
    CHECK(p->n == 175 + 245 - 60, "union: %lld sites, expected 360", (long long)p->n);
    int dup = 0;
    for (int64_t i = 0; i < p->n; i++)
        for (int64_t j = i + 1; j < p->n; j++)
            dup += p->x[0][i] == p->x[0][j] && p->x[1][i] == p->x[1][j] &&
                   p->x[2][i] == p->x[2][j];
    CHECK(dup == 0, "union has %d duplicate sites", dup);
    pd_particles_free(p);

    /* a box minus a ball of radius 3 spacings around one of its sites */
    r[0] = region(PD_REGION_BOX, "0,5,0,5,0,5");
    r[1] = region(PD_REGION_SPHERE, "2.5,2.5,2.5,1.5");
    r[1].subtract = 1;
    p = lattice(r, 2, 0.5, 0, 1);
    CHECK(p->n == 1331 - 123, "box minus ball: %lld sites, expected 1208", (long long)p->n);
    for (int64_t i = 0; i < p->n; i++) {
        double x[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
        CHECK(!pd_region_inside(&r[1], x), "site %lld inside the subtracted ball", (long long)i);
    }
    pd_particles_free(p);

    /* the subtracted region wins over every added one */
    r[2] = region(PD_REGION_BOX, "0,5,0,5,0,5");
    r[2].subtract = 1;
    pd_lattice_params lp = {0.5, 1.0, 1, 0, 1};
    pd_particles *q = NULL;
    CHECK(pd_lattice_make(r, 3, &lp, &q) == PD_ERR_INVALID && q == NULL,
          "everything subtracted: an error, no particles");
    proved(f0, "a union holds each site once; --subtract removes exactly its sites");
}

static void test_particles(void)
{
    int f0 = failures;
    const double h = 0.0007;
    pd_region r = region(PD_REGION_SPHERE, "0.001,0.002,0.003,0.0035");
    pd_particles *p = lattice(&r, 1, h, 0, 1);
    CHECK(p->n > 100, "a few hundred sites");
    CHECK(p->spacing == h && p->dimension == 3, "spacing and dimension recorded");
    for (int64_t i = 0; i < p->n; i++) {
        CHECK(p->id[i] == i + 1, "id %lld at row %lld", (long long)p->id[i], (long long)i);
        CHECK(p->volume[i] == h * h * h, "volume h^3");
        CHECK(p->radius[i] == 0.5 * h, "radius h/2");
        CHECK(p->density[i] == 2200.0 && p->material[i] == 7, "density and material");
        for (int d = 0; d < 3; d++) {
            double n = round(p->x[d][i] / h);
            CHECK(p->x[d][i] == n * h, "site on the lattice");
        }
        double x[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
        CHECK(pd_region_inside(&r, x), "site inside its region");
        if (i > 0) {
            /* z outermost, then y, then x (LAMMPS create_atoms) */
            int later = p->x[2][i] > p->x[2][i - 1] ||
                        (p->x[2][i] == p->x[2][i - 1] &&
                         (p->x[1][i] > p->x[1][i - 1] ||
                          (p->x[1][i] == p->x[1][i - 1] && p->x[0][i] > p->x[0][i - 1])));
            CHECK(later, "row %lld out of z, y, x order", (long long)i);
        }
    }
    pd_particles_free(p);
    proved(f0, "ids 1..N in z,y,x order; volume h^3, radius h/2, on the lattice, inside");
}

static void test_perturb(void)
{
    int f0 = failures;
    const double h = 0.001, A = 0.0002;
    pd_region r = region(PD_REGION_BOX, "0,0.01,0,0.01,0,0.01");
    pd_particles *p0 = lattice(&r, 1, h, 0, 1);
    pd_particles *a = lattice(&r, 1, h, A, 42);
    pd_particles *b = lattice(&r, 1, h, A, 42);
    pd_particles *c = lattice(&r, 1, h, A, 43);
    CHECK(a->n == p0->n && b->n == p0->n && c->n == p0->n, "perturbation keeps the count");
    double maxd[3] = {0, 0, 0};
    int64_t same_ab = 0, same_ac = 0;
    for (int64_t i = 0; i < p0->n; i++) {
        int eq_ab = 1, eq_ac = 1;
        for (int d = 0; d < 3; d++) {
            double dd = fabs(a->x[d][i] - p0->x[d][i]);
            CHECK(dd <= A, "moved by %g > A", dd);
            maxd[d] = fmax(maxd[d], dd);
            eq_ab &= a->x[d][i] == b->x[d][i];
            eq_ac &= a->x[d][i] == c->x[d][i];
        }
        same_ab += eq_ab;
        same_ac += eq_ac;
        CHECK(a->id[i] == p0->id[i], "ids unchanged by the perturbation");
    }
    for (int d = 0; d < 3; d++)
        CHECK(maxd[d] > 0.9 * A, "axis %d hardly perturbed (%g)", d, maxd[d]);
    CHECK(same_ab == p0->n, "same seed, same positions");
    CHECK(same_ac == 0, "different seeds, %lld equal sites", (long long)same_ac);
    pd_particles_free(p0);
    pd_particles_free(a);
    pd_particles_free(b);
    pd_particles_free(c);
    proved(f0, "perturbation: within [-A,A] per axis, reproducible by seed, seed-dependent");
}

static void test_errors(void)
{
    int f0 = failures;
    pd_region r = region(PD_REGION_BOX, "0.2,0.8,0.2,0.8,0.2,0.8");
    pd_lattice_params lp = {1.0, 1.0, 1, 0, 1};
    pd_particles *p = NULL;
    CHECK(pd_lattice_make(&r, 1, &lp, &p) == PD_ERR_INVALID && p == NULL,
          "a box between sites: error");
    CHECK(strstr(pd_errmsg(), "no lattice site") != NULL, "message: %s", pd_errmsg());
    pd_lattice_params bad[] = {
        {0, 1, 1, 0, 1}, {-1, 1, 1, 0, 1}, {NAN, 1, 1, 0, 1}, {INFINITY, 1, 1, 0, 1},
        {1, 0, 1, 0, 1}, {1, -1, 1, 0, 1}, {1, NAN, 1, 0, 1}, {1, 1, 1, -1, 1},
    };
    pd_region big = region(PD_REGION_BOX, "0,3,0,3,0,3");
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        p = NULL;
        CHECK(pd_lattice_make(&big, 1, &bad[k], &p) == PD_ERR_INVALID && p == NULL,
              "bad parameters %zu accepted", k);
    }
    CHECK(pd_lattice_make(&big, 0, &lp, &p) == PD_ERR_INVALID, "no region: error");
    proved(f0, "empty bodies and bad spacing, density or perturbation are errors");
}

int main(void)
{
    test_box();
    test_cylinder();
    test_sphere();
    test_parse_errors();
    test_counts();
    test_union_subtract();
    test_particles();
    test_perturb();
    test_errors();
    if (failures)
        fprintf(stderr, "test_lattice: %d failures\n", failures);
    return failures != 0;
}
