/*
 * test_crack -- pre-cracks of lib/bonds/crack.c: the crossing predicate of a
 * reference segment and a parallelogram crack, parsing, and the pre-crack
 * of built bonds.
 *
 * Proves: a segment crosses the crack exactly when its endpoints are on
 * different sides of the plane and it meets the plane inside the closed
 * parallelogram (corners and edges included, just outside excluded); an
 * endpoint exactly on the plane counts on the side n = A x B points to, so
 * swapping A and B moves such a segment across; a segment in the plane or
 * parallel to it never crosses; the predicate is exactly symmetric in its
 * endpoints on random segments; degenerate specs (zero edge, parallel
 * edges, zero-length segment, wrong field count) are refused and good ones
 * give the parallelogram they name; on a lattice, a plane across the whole
 * section breaks exactly the pairs with endpoints on both sides, on both
 * directed copies, with the pre-crack bits a subset of the broken ones; a
 * crack exactly on a lattice plane cuts like one half a spacing behind it
 * (towards -n); a segment through the thickness equals the rect that
 * spans the section; a crack that crosses no bond leaves precrack NULL.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "pd.h"

static pd_crack rect(double px, double py, double pz, double ax, double ay, double az, double bx,
                     double by, double bz)
{
    pd_crack c = {{px, py, pz}, {ax, ay, az}, {bx, by, bz}, 0};
    return c;
}

static int crosses(const pd_crack *c, double x0, double x1, double x2, double y0, double y1,
                   double y2)
{
    double x[3] = {x0, x1, x2}, y[3] = {y0, y1, y2};
    return pd_crack_crosses(c, x, y);
}

static void test_predicate(void)
{
    int f0 = failures;
    /* the unit square in z = 0, normal A x B = +z */
    pd_crack c = rect(0, 0, 0, 1, 0, 0, 0, 1, 0);
    CHECK(crosses(&c, 0.5, 0.5, -1, 0.5, 0.5, 1), "through the middle");
    CHECK(crosses(&c, 0.2, 0.3, 1, 0.6, 0.7, -2), "oblique, downwards");
    CHECK(!crosses(&c, 0.5, 0.5, 1, 0.5, 0.5, 2), "both above");
    CHECK(!crosses(&c, 0.5, 0.5, -1, 0.5, 0.5, -2), "both below");
    CHECK(!crosses(&c, 1.5, 0.5, -1, 1.5, 0.5, 1), "meets the plane beyond edge u = 1");
    CHECK(!crosses(&c, 0.5, -0.1, -1, 0.5, -0.1, 1), "meets the plane before edge v = 0");
    CHECK(!crosses(&c, 0.9, 0.5, -1, 1.3, 0.5, 1), "oblique, meets the plane at u = 1.1");
    CHECK(crosses(&c, 0.75, 0.5, -1, 1.25, 0.5, 1), "oblique, meets the plane at u = 1");
    /* closed: the corners and edges belong to the crack */
    CHECK(crosses(&c, 0, 0, -1, 0, 0, 1), "at the corner P");
    CHECK(crosses(&c, 1, 1, -1, 1, 1, 1), "at the corner P + A + B");
    CHECK(crosses(&c, 1, 0.5, -1, 1, 0.5, 1), "on the edge u = 1");
    /* in the plane, or parallel to it: never */
    CHECK(!crosses(&c, 0.1, 0.1, 0, 0.9, 0.9, 0), "in the plane");
    CHECK(!crosses(&c, 0.1, 0.1, 0.5, 0.9, 0.9, 0.5), "parallel");
    /* an endpoint on the plane counts on the positive side (z >= 0) */
    CHECK(crosses(&c, 0.5, 0.5, 0, 0.5, 0.5, -1), "from the plane to below");
    CHECK(crosses(&c, 0.5, 0.5, -1, 0.5, 0.5, 0), "from below to the plane");
    CHECK(!crosses(&c, 0.5, 0.5, 0, 0.5, 0.5, 1), "from the plane to above");
    /* swapped edges: normal -z, the plane joins the side below */
    pd_crack s = rect(0, 0, 0, 0, 1, 0, 1, 0, 0);
    CHECK(!crosses(&s, 0.5, 0.5, 0, 0.5, 0.5, -1), "swapped: from the plane to below");
    CHECK(crosses(&s, 0.5, 0.5, 0, 0.5, 0.5, 1), "swapped: from the plane to above");
    CHECK(crosses(&s, 0.5, 0.5, -1, 0.5, 0.5, 1), "swapped: through the middle");
    /* an oblique parallelogram: corner (1,2,3), A = (2,0,1), B = (0,3,0) */
    pd_crack o = rect(1, 2, 3, 2, 0, 1, 0, 3, 0);
    double mid[3] = {1 + 1 + 0, 2 + 1.5, 3 + 0.5}; /* P + A/2 + B/2 */
    double n[3] = {-3, 0, 6};                      /* A x B */
    CHECK(crosses(&o, mid[0] - 0.1 * n[0], mid[1], mid[2] - 0.1 * n[2], mid[0] + 0.1 * n[0],
                  mid[1], mid[2] + 0.1 * n[2]),
          "oblique crack, through its centre");
    CHECK(!crosses(&o, mid[0] - 0.1 * n[0], mid[1] + 2, mid[2] - 0.1 * n[2], mid[0] + 0.1 * n[0],
                   mid[1] + 2, mid[2] + 0.1 * n[2]),
          "oblique crack, beyond edge B");
    proved(f0, "crossing: opposite sides and inside the closed parallelogram; plane on the "
               "+n side");
}

/* xorshift64*: a fixed sequence of doubles in [0, 1). */
static double next_uniform(uint64_t *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (double)((*s * UINT64_C(2685821657736338717)) >> 11) * 0x1.0p-53;
}

static void test_symmetric(void)
{
    int f0 = failures;
    uint64_t seed = 12345;
    pd_crack c = rect(0.1, -0.2, 0.05, 0.7, 0.3, -0.2, -0.1, 0.5, 0.9);
    int hits = 0;
    for (int k = 0; k < 200000; k++) {
        double x[3], y[3];
        for (int d = 0; d < 3; d++) {
            x[d] = 2 * next_uniform(&seed) - 0.5;
            y[d] = x[d] + 0.6 * (next_uniform(&seed) - 0.5);
        }
        int a = pd_crack_crosses(&c, x, y), b = pd_crack_crosses(&c, y, x);
        CHECK(a == b, "crosses(x,y) = %d but crosses(y,x) = %d", a, b);
        hits += a;
    }
    CHECK(hits > 1000, "the random segments cross the crack (%d)", hits);
    proved(f0, "the predicate is exactly symmetric in its endpoints");
}

static void test_parse(void)
{
    int f0 = failures;
    pd_crack c;
    CHECK(pd_crack_parse("rect,1,2,3,4,5,6,7,8,10", &c) == PD_OK, "rect: %s", pd_errmsg());
    CHECK(c.p[0] == 1 && c.p[2] == 3 && c.a[1] == 5 && c.b[2] == 10 && !c.through, "rect fields");
    CHECK(pd_crack_parse("segment,0.001,0.002,0.004,0.006", &c) == PD_OK, "segment: %s",
          pd_errmsg());
    CHECK(c.through && c.p[0] == 0.001 && c.p[1] == 0.002 && c.a[0] == 0.004 - 0.001 &&
              c.a[1] == 0.006 - 0.002 && c.a[2] == 0,
          "segment fields");
    static const char *bad[] = {
        "rect,0,0,0,0,0,0,0,1,0",      /* zero edge A        */
        "rect,0,0,0,1,0,0,0,0,0",      /* zero edge B        */
        "rect,0,0,0,1,2,3,2,4,6",      /* parallel edges     */
        "rect,0,0,0,1,2,3,-1,-2,-3",   /* antiparallel edges */
        "rect,0,0,0,1,0,0,0,1",        /* 8 numbers          */
        "rect,0,0,0,1,0,0,0,1,0,0",    /* 10 numbers         */
        "rect,0,0,0,1,0,0,0,1,nan",    /* not finite         */
        "segment,1,2,1,2",             /* zero length        */
        "segment,1,2,3",               /* 3 numbers          */
        "line,0,0,1,1",                /* unknown kind       */
        "rect",                        /* nothing            */
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        pd_status s = pd_crack_parse(bad[k], &c);
        CHECK(s == PD_ERR_INVALID, "'%s' accepted", bad[k]);
        CHECK(strstr(pd_errmsg(), bad[k]) != NULL, "message '%s' does not name '%s'",
              pd_errmsg(), bad[k]);
    }
    proved(f0, "parse: rect and segment; degenerate and malformed specs refused");
}

/* Lattice of (mx+1) x (my+1) x (mz+1) sites of spacing h at the origin,
 * bonds within 3.0001 h. */
static void model(int mx, int my, int mz, double h, pd_particles **pp, pd_bonds **bp)
{
    char spec[160];
    snprintf(spec, sizeof spec, "0,%.17g,0,%.17g,0,%.17g", (mx + 0.1) * h, (my + 0.1) * h,
             (mz + 0.1) * h);
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, spec, &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {h, 2200, 1, 0, 1};
    if (pd_lattice_make(&r, 1, &lp, pp) != PD_OK || pd_bonds_build(*pp, 3.0001 * h, bp) != PD_OK)
        die("model");
}

/* The set of pre-cracked bonds as a bit string, for comparisons. */
static int same_bits(const uint64_t *a, const uint64_t *b, int64_t count)
{
    for (int64_t k = 0; k < count; k++)
        if (pd_bond_intact(a, k) != pd_bond_intact(b, k))
            return 0;
    return 1;
}

static pd_bonds *cracked(int mx, int my, int mz, double h, const pd_crack *c, int64_t *pairs,
                         pd_particles **pp)
{
    pd_bonds *b;
    model(mx, my, mz, h, pp, &b);
    if (pd_bonds_precrack(*pp, b, c, 1, pairs) != PD_OK)
        die("precrack");
    return b;
}

static void test_lattice(void)
{
    int f0 = failures;
    const double h = 1e-3;
    pd_particles *p;
    int64_t pairs = -1;
    /* the plane x = 4.5 h across the whole y-z section, normal +x */
    pd_crack c = rect(4.5 * h, -h, -h, 0, 8 * h, 0, 0, 0, 8 * h);
    pd_bonds *b = cracked(9, 6, 6, h, &c, &pairs, &p);
    int64_t across = 0;
    for (int64_t i = 0; i < p->n; i++)
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            int64_t j = b->neighbor[k];
            int cut = (p->x[0][i] < 4.5 * h) != (p->x[0][j] < 4.5 * h);
            across += cut;
            CHECK(pd_bond_intact(b->intact, k) == !cut, "bond %lld-%lld", (long long)i,
                  (long long)j);
        }
    CHECK(b->precrack != NULL, "precrack allocated");
    CHECK(pairs * 2 == across && across > 0, "pairs %lld, directed bonds across %lld",
          (long long)pairs, (long long)across);
    CHECK(pd_bits_count_broken(b->intact, b->count) == across, "only the bonds across broken");
    /* precrack = the complement of intact here; bits past count clear */
    for (int64_t k = 0; k < b->count; k++)
        CHECK(pd_bond_intact(b->precrack, k) == !pd_bond_intact(b->intact, k), "bit %lld",
              (long long)k);
    CHECK(pd_bits_count_broken_except(b->intact, b->precrack, b->count) == 0,
          "no broken bond outside the pre-crack");

    /* exactly on the lattice plane x = 5 h: like 4.5 h with normal +x ... */
    pd_particles *q;
    int64_t pairs5;
    pd_crack on = rect(5 * h, -h, -h, 0, 8 * h, 0, 0, 0, 8 * h);
    pd_bonds *b5 = cracked(9, 6, 6, h, &on, &pairs5, &q);
    CHECK(pairs5 == pairs && same_bits(b5->precrack, b->precrack, b->count),
          "on the plane x = 5h, normal +x: as at 4.5h");
    pd_bonds_free(b5);
    pd_particles_free(q);
    /* ... and like 5.5 h with normal -x */
    pd_crack on_swapped = rect(5 * h, -h, -h, 0, 0, 8 * h, 0, 8 * h, 0);
    pd_crack at55 = rect(5.5 * h, -h, -h, 0, 8 * h, 0, 0, 0, 8 * h);
    int64_t pa, pb;
    pd_particles *q1, *q2;
    pd_bonds *ba = cracked(9, 6, 6, h, &on_swapped, &pa, &q1);
    pd_bonds *bb = cracked(9, 6, 6, h, &at55, &pb, &q2);
    CHECK(pa == pb && same_bits(ba->precrack, bb->precrack, ba->count),
          "on the plane x = 5h, normal -x: as at 5.5h");
    pd_bonds_free(ba);
    pd_bonds_free(bb);
    pd_particles_free(q1);
    pd_particles_free(q2);

    /* a segment through the thickness equals the rect spanning it */
    pd_crack seg;
    if (pd_crack_parse("segment,0.0045,-0.001,0.0045,0.0043", &seg) != PD_OK)
        die("segment");
    pd_crack half = rect(4.5 * h, -h, -h, 0, 5.3 * h, 0, 0, 0, 8 * h);
    int64_t ps, ph;
    pd_bonds *bs = cracked(9, 6, 6, h, &seg, &ps, &q1);
    pd_bonds *bh = cracked(9, 6, 6, h, &half, &ph, &q2);
    CHECK(ps == ph && ps > 0 && ps < pairs && same_bits(bs->precrack, bh->precrack, bs->count),
          "segment = rect (%lld, %lld pairs)", (long long)ps, (long long)ph);
    CHECK(same_bits(bs->intact, bh->intact, bs->count), "segment = rect: the same intact bits");
    pd_bonds_free(bs);
    pd_bonds_free(bh);
    pd_particles_free(q1);
    pd_particles_free(q2);

    /* a crack away from the body crosses nothing: no pre-crack at all */
    pd_crack away = rect(0.5, 0, 0, 0, 1, 0, 0, 0, 1);
    int64_t none = -1;
    pd_bonds *bn = cracked(4, 4, 4, h, &away, &none, &q1);
    CHECK(none == 0 && bn->precrack == NULL, "no crossing: precrack stays NULL");
    CHECK(pd_bits_count_broken(bn->intact, bn->count) == 0, "no crossing: all intact");
    pd_bonds_free(bn);
    pd_particles_free(q1);

    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "lattice: the pairs across broken on both copies, marked as pre-crack; "
               "on-plane convention; segment = rect");
}

int main(void)
{
    test_predicate();
    test_symmetric();
    test_parse();
    test_lattice();
    if (failures)
        fprintf(stderr, "test_crack: %d failures\n", failures);
    return failures != 0;
}
