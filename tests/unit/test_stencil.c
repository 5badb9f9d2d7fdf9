/*
 * test_stencil -- bond families as a lattice stencil (lib/bonds/stencil.c).
 *
 * Proves: the families pd_bonds_build gives on a simple cubic lattice with
 * delta = 3.0001 dx are a stencil of the 122 offsets with i^2 + j^2 + k^2
 * <= 9 (28 with i^2 + j^2 <= 9 on a square plate), each with its length
 * |d| dx and partial-volume factor; the stencil expands to the very bits
 * of the lists (offsets, partners, lengths, volume factors), in lattice
 * order and in any other row order; one length changed by one ulp, a
 * perturbed lattice, a sparse body or an empty family list is no stencil;
 * expanding onto particles off the lattice or sharing a site is a format
 * error; pd_bonds_build on a lattice (by its sites) gives the cell lists'
 * bonds bit for bit, in any row order and with a horizon of exactly 3
 * spacings (pairs decided one by one), and the stencil it finds is
 * pd_bonds_find_stencil's.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "pd.h"

static pd_particles *box(const char *spec, double h, double perturb, int plate)
{
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, spec, &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {h, 2200.0, 1, perturb, 7};
    pd_particles *p = NULL;
    pd_status s = plate ? pd_plate_make(&r, 1, &lp, 0.001, &p) : pd_lattice_make(&r, 1, &lp, &p);
    if (s != PD_OK)
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

/* Are the lists of a and b the same, bit for bit? */
static int same_lists(const pd_bonds *a, const pd_bonds *b)
{
    return a->n == b->n && a->count == b->count &&
           memcmp(a->offset, b->offset, (size_t)(a->n + 1) * sizeof(int64_t)) == 0 &&
           memcmp(a->neighbor, b->neighbor, (size_t)a->count * sizeof(int32_t)) == 0 &&
           memcmp(a->length, b->length, (size_t)a->count * sizeof(double)) == 0 &&
           memcmp(a->vfactor, b->vfactor, (size_t)a->count * sizeof(double)) == 0 &&
           memcmp(a->intact, b->intact, (size_t)pd_bits_words(a->count) * 8) == 0;
}

static int same_stencil(const pd_stencil *a, const pd_stencil *b)
{
    if (a == NULL || b == NULL)
        return a == b;
    return a->nk == b->nk && memcmp(a->d, b->d, (size_t)a->nk * sizeof *a->d) == 0 &&
           memcmp(a->length, b->length, (size_t)a->nk * sizeof(double)) == 0 &&
           memcmp(a->vfactor, b->vfactor, (size_t)a->nk * sizeof(double)) == 0 &&
           memcmp(a->origin, b->origin, sizeof a->origin) == 0 && a->spacing == b->spacing;
}

/* Do the lattice's and the cell lists' builds give the same bits?  (The
 * cell lists serve when the spacing puts the particles off the lattice.) */
static int same_as_cells(pd_particles *p, double horizon)
{
    pd_bonds *a = bonds(p, horizon), *c = NULL;
    const double h = p->spacing;
    p->spacing = 0.7 * h;
    if (pd_bonds_build_lattice(p, horizon, 1, &c) != PD_OK || c != NULL)
        die("off the lattice");
    c = bonds(p, horizon);
    p->spacing = h;
    int same = same_lists(a, c) && c->stencil == NULL;
    pd_bonds_free(a);
    pd_bonds_free(c);
    return same;
}

/* The stencil of p's families with this horizon (NULL: none), and its
 * expansion compared with the lists. */
static pd_stencil *stencil_of(const pd_particles *p, double horizon, int *expands)
{
    pd_bonds *b = bonds(p, horizon), *e = NULL;
    pd_stencil *built = b->stencil;
    b->stencil = NULL;
    if (pd_bonds_find_stencil(p, b) != PD_OK)
        die("find");
    CHECK(same_stencil(built, b->stencil), "the build's stencil is pd_bonds_find_stencil's");
    pd_stencil_free(built);
    pd_stencil *st = b->stencil;
    b->stencil = NULL;
    *expands = 0;
    if (st && pd_bonds_expand(p, st, horizon, &e) == PD_OK) {
        *expands = same_lists(b, e);
        pd_bonds_free(e);
    }
    pd_bonds_free(b);
    return st;
}

static void test_cube(void)
{
    int before = failures, expands = 0;
    const double h = 0.001, delta = 3.0001 * h;
    pd_particles *p = box("0,0.008,0,0.006,0,0.005", h, 0, 0);
    CHECK(same_as_cells(p, delta), "the lattice's build is the cell lists'");
    CHECK(same_as_cells(p, 3.0 * h), "horizon 3 dx: the lattice's build is the cell lists'");
    pd_stencil *st = stencil_of(p, delta, &expands);
    CHECK(st != NULL, "a box lattice's families are a stencil");
    if (st) {
        CHECK(st->nk == 122, "the stencil has %d offsets, not 122", st->nk);
        CHECK(expands, "the stencil expands to the lists bit for bit");
        for (int k = 0; k < st->nk; k++) {
            const int32_t *d = st->d[k];
            double len = h * sqrt((double)(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
            CHECK(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= 9, "offset %d outside", k);
            CHECK(fabs(st->length[k] - len) <= 1e-12 * len, "offset %d: length %g not %g", k,
                  st->length[k], len);
            CHECK(st->vfactor[k] == pd_partial_volume(st->length[k], delta, 0.5 * h),
                  "offset %d: volume factor", k);
            CHECK(k == 0 || d[2] > st->d[k - 1][2] ||
                      (d[2] == st->d[k - 1][2] && (d[1] > st->d[k - 1][1] ||
                                                   (d[1] == st->d[k - 1][1] && d[0] > st->d[k - 1][0]))),
                  "offsets sorted by (z, y, x) at %d", k);
        }
        CHECK(st->spacing == h && st->origin[0] == 0 && st->origin[2] == 0, "lattice");
    }
    pd_stencil_free(st);
    /* the rows in lattice order, then shuffled: both expand bit for bit */
    if (pd_particles_sort_spatial(p, delta) != PD_OK)
        die("sort");
    st = stencil_of(p, delta, &expands);
    CHECK(st && expands, "in lattice order the stencil expands to the lists");
    pd_stencil_free(st);
    shuffle_rows(p);
    st = stencil_of(p, delta, &expands);
    CHECK(st && expands, "in shuffled order the stencil expands to the lists");
    CHECK(same_as_cells(p, delta), "shuffled: the lattice's build is the cell lists'");
    CHECK(same_as_cells(p, 3.0 * h), "shuffled, horizon 3 dx: the lattice's build is the cells'");
    CHECK(same_as_cells(p, 1.7 * h), "shuffled, horizon 1.7 dx: the lattice's build is the cells'");
    /* expanding onto particles off the lattice, or two at one site */
    if (st) {
        pd_bonds *e = NULL;
        double x0 = p->x[0][5];
        p->x[0][5] += 0.3 * h;
        CHECK(pd_bonds_expand(p, st, delta, &e) == PD_ERR_FORMAT && e == NULL &&
                  strstr(pd_errmsg(), "off the lattice"),
              "a particle off the lattice: %s", pd_errmsg());
        p->x[0][5] = p->x[0][6];
        p->x[1][5] = p->x[1][6];
        p->x[2][5] = p->x[2][6];
        CHECK(pd_bonds_expand(p, st, delta, &e) == PD_ERR_FORMAT && e == NULL &&
                  strstr(pd_errmsg(), "shares its lattice site"),
              "two particles at one site: %s", pd_errmsg());
        p->x[0][5] = x0;
    }
    pd_stencil_free(st);
    pd_particles_free(p);
    proved(before, "a lattice box's families are the stencil of 122 offsets, built by the sites "
                   "as by cell lists and expanded bit for bit in any row order; off-lattice or "
                   "shared sites are format errors");
}

static void test_plate(void)
{
    int before = failures, expands = 0;
    const double h = 0.001;
    pd_particles *p = box("0,0.02,0,0.01,-1,1", h, 0, 1);
    CHECK(same_as_cells(p, 3.0001 * h), "a plate: the lattice's build is the cell lists'");
    pd_stencil *st = stencil_of(p, 3.0001 * h, &expands);
    CHECK(st && st->nk == 28 && expands, "a plate's stencil has %d offsets, not 28",
          st ? st->nk : -1);
    for (int k = 0; st && k < st->nk; k++)
        CHECK(st->d[k][2] == 0, "a plate's offset %d leaves the plane", k);
    pd_stencil_free(st);
    pd_particles_free(p);
    proved(before, "a square plate's families are the stencil of 28 offsets");
}

static void test_not_stencils(void)
{
    int before = failures, expands = 0;
    const double h = 0.001, delta = 3.0001 * h;
    /* one length one ulp off: the lists are not the stencil's bits */
    pd_particles *p = box("0,0.006,0,0.006,0,0.006", h, 0, 0);
    pd_bonds *b = bonds(p, delta);
    b->length[17] = nextafter(b->length[17], INFINITY);
    CHECK(pd_bonds_find_stencil(p, b) == PD_OK && b->stencil == NULL,
          "a length one ulp off is no stencil");
    pd_bonds_free(b);
    pd_particles_free(p);
    /* a perturbed lattice */
    p = box("0,0.006,0,0.006,0,0.006", h, 1e-5, 0);
    pd_stencil *st = stencil_of(p, delta, &expands);
    CHECK(st == NULL, "a perturbed lattice is no stencil");
    pd_stencil_free(st);
    pd_particles_free(p);
    /* a sparse body: two small cubes far apart */
    pd_region r[2];
    if (pd_region_parse(PD_REGION_BOX, "0,0.004,0,0.004,0,0.004", &r[0]) != PD_OK ||
        pd_region_parse(PD_REGION_BOX, "0.2,0.204,0.2,0.204,0.2,0.204", &r[1]) != PD_OK)
        die("regions");
    pd_lattice_params lp = {h, 2200.0, 1, 0, 7};
    if (pd_lattice_make(r, 2, &lp, &p) != PD_OK)
        die("lattice");
    st = stencil_of(p, delta, &expands);
    CHECK(st == NULL, "a sparse body keeps its lists");
    pd_stencil_free(st);
    /* no bonds at all */
    b = bonds(p, 0.5 * h);
    CHECK(b->count == 0 && pd_bonds_find_stencil(p, b) == PD_OK && b->stencil == NULL,
          "no bonds, no stencil");
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(before, "one ulp off, a perturbed lattice, a sparse body or no bonds: no stencil");
}

int main(void)
{
    test_cube();
    test_plate();
    test_not_stencils();
    return failures ? 1 : 0;
}
