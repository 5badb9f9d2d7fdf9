/*
 * test_bonds -- bond families of lib/bonds/bonds.c and cell lists of lib/base/cells.c.
 *
 * Proves: on a simple cubic lattice with delta = 3.0001 dx an interior
 * particle has exactly 122 partners (the integer points with
 * i^2 + j^2 + k^2 <= 9, less the origin); families are sorted, without self,
 * and symmetric with equal lengths; lengths are the reference distances; the
 * partial-volume factor is 1 for |xi| <= delta - r, (delta + r - |xi|)/(2r)
 * beyond, and exactly 1/2 for a bond at exactly the horizon; cell lists give
 * the same families as a brute-force all-pairs search on a perturbed, uneven
 * cloud; the cells' rows (pd_cells_adjacent_rows) hold the points of the
 * adjacent cells in their order, at the grid's corners, edges and inside;
 * the spatial sort is a permutation that keeps ids with positions; state
 * bits start set and count broken bonds.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "pd.h"


/* A box of (m+1)^3 lattice sites of spacing h, origin at 0. */
static pd_particles *cube(int m, double h, double perturb, unsigned long seed)
{
    char spec[128];
    snprintf(spec, sizeof spec, "0,%.17g,0,%.17g,0,%.17g", m * h, m * h, m * h);
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, spec, &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {h, 2200.0, 1, perturb, seed};
    pd_particles *p = NULL;
    if (pd_lattice_make(&r, 1, &lp, &p) != PD_OK)
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

static double dist(const pd_particles *p, int64_t i, int64_t j)
{
    double dx = p->x[0][i] - p->x[0][j], dy = p->x[1][i] - p->x[1][j],
           dz = p->x[2][i] - p->x[2][j];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

/* Position of partner j in the family of i, or -1. */
static int64_t find(const pd_bonds *b, int64_t i, int64_t j)
{
    for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++)
        if (b->neighbor[k] == j)
            return k;
    return -1;
}

/* Families sorted, without self, symmetric with equal length. */
static void check_structure(const pd_particles *p, const pd_bonds *b)
{
    CHECK(b->n == p->n && b->offset[0] == 0 && b->offset[b->n] == b->count, "CSR bounds");
    for (int64_t i = 0; i < b->n; i++)
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            int64_t j = b->neighbor[k];
            CHECK(j != i, "particle %lld bonded to itself", (long long)i);
            CHECK(k == b->offset[i] || b->neighbor[k - 1] < j, "family %lld not sorted",
                  (long long)i);
            int64_t back = find(b, j, i);
            CHECK(back >= 0, "bond %lld-%lld has no reverse", (long long)i, (long long)j);
            if (back >= 0)
                CHECK(b->length[back] == b->length[k], "reverse length differs");
            CHECK(fabs(b->length[k] - dist(p, i, j)) <= 1e-15 * dist(p, i, j),
                  "length is not the distance");
        }
}

static void test_family_sizes(void)
{
    int f0 = failures;
    int expect = 0;
    for (int i = -3; i <= 3; i++)
        for (int j = -3; j <= 3; j++)
            for (int k = -3; k <= 3; k++)
                expect += (i || j || k) && i * i + j * j + k * k <= 9;
    CHECK(expect == 122, "122 lattice points within 3 spacings");
    const double h = 0.0005;
    pd_particles *p = cube(12, h, 0, 1);
    pd_bonds *b = bonds(p, 3.0001 * h);
    check_structure(p, b);
    int64_t interior = 0;
    for (int64_t i = 0; i < p->n; i++) {
        int64_t m = b->offset[i + 1] - b->offset[i];
        int in = 1;
        int64_t want = 0;
        long n[3];
        for (int d = 0; d < 3; d++) {
            n[d] = lround(p->x[d][i] / h);
            in &= n[d] >= 3 && n[d] <= 9;
        }
        /* the same ball clipped by the faces of the cube */
        for (int a = -3; a <= 3; a++)
            for (int c = -3; c <= 3; c++)
                for (int e = -3; e <= 3; e++)
                    want += (a || c || e) && a * a + c * c + e * e <= 9 && n[0] + a >= 0 &&
                            n[0] + a <= 12 && n[1] + c >= 0 && n[1] + c <= 12 && n[2] + e >= 0 &&
                            n[2] + e <= 12;
        CHECK(m == want, "particle %lld: %lld partners, expected %lld", (long long)i,
              (long long)m, (long long)want);
        if (in) {
            interior++;
            CHECK(m == 122, "interior particle %lld has %lld partners", (long long)i,
                  (long long)m);
        }
    }
    CHECK(interior == 343, "7^3 interior particles, got %lld", (long long)interior);
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "delta = 3.0001 dx: interior families have 122 partners, faces clip the ball");
}

static void test_volume_factors(void)
{
    int f0 = failures;
    /* spacing 1, horizon exactly 3: bonds of length exactly 3 exist */
    pd_particles *p = cube(8, 1.0, 0, 1);
    pd_bonds *b = bonds(p, 3.0);
    check_structure(p, b);
    const double delta = 3.0, r = 0.5;
    int64_t at = 0, inner = 0, partial = 0;
    for (int64_t k = 0; k < b->count; k++) {
        double len = b->length[k], nu = b->vfactor[k];
        CHECK(len <= delta, "bond longer than the horizon");
        if (len == delta) {
            at++;
            CHECK(nu == 0.5, "nu(delta) = %.17g, expected 1/2", nu);
        } else if (len <= delta - r) {
            inner++;
            CHECK(nu == 1.0, "nu = %.17g inside delta - r", nu);
        } else {
            partial++;
            double want = (delta + r - len) / (2 * r);
            CHECK(fabs(nu - want) <= 1e-15, "nu = %.17g, expected %.17g", nu, want);
            CHECK(nu > 0.5 && nu < 1, "partial nu out of (1/2, 1)");
        }
    }
    CHECK(at > 0 && inner > 0 && partial > 0, "all three kinds of bond present");
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "partial volumes: nu = 1 within delta - r, linear beyond, nu(delta) = 1/2");
}

/* A cloud of n points, denser in one corner, with a simple LCG. */
static pd_particles *cloud(int64_t n, unsigned seed)
{
    pd_particles *p = pd_particles_new(n);
    uint64_t s = seed;
    for (int64_t i = 0; i < n; i++) {
        for (int d = 0; d < 3; d++) {
            s = s * 6364136223846793005ULL + 1442695040888963407ULL;
            double u = (double)(s >> 11) / 9007199254740992.0;
            p->x[d][i] = (d == 0 ? u * u : u) * 2.0 - 0.3;
        }
        p->volume[i] = 1e-3;
        p->density[i] = 1.0;
        p->radius[i] = 0.05;
        p->material[i] = 1;
        p->id[i] = i + 1;
    }
    p->spacing = 0.1;
    return p;
}

static void test_cells_vs_brute_force(void)
{
    int f0 = failures;
    const double horizon = 0.31;
    for (int round = 0; round < 2; round++) {
        pd_particles *p = round == 0 ? cloud(900, 12345) : cube(9, 0.1, 0.03, 9);
        pd_bonds *b = bonds(p, horizon);
        check_structure(p, b);
        int64_t total = 0;
        for (int64_t i = 0; i < p->n; i++) {
            int64_t k = b->offset[i];
            for (int64_t j = 0; j < p->n; j++) {
                if (j == i)
                    continue;
                double dx = p->x[0][i] - p->x[0][j], dy = p->x[1][i] - p->x[1][j],
                       dz = p->x[2][i] - p->x[2][j];
                if (dx * dx + dy * dy + dz * dz <= horizon * horizon) {
                    CHECK(k < b->offset[i + 1] && b->neighbor[k] == j,
                          "particle %lld: partner %lld missing or out of order", (long long)i,
                          (long long)j);
                    k++;
                    total++;
                }
            }
            CHECK(k == b->offset[i + 1], "particle %lld has extra partners", (long long)i);
        }
        CHECK(total == b->count, "bond count %lld, brute force %lld", (long long)b->count,
              (long long)total);
        pd_bonds_free(b);
        pd_particles_free(p);
    }
    proved(f0, "cell lists find exactly the brute-force families (uneven cloud, perturbed lattice)");
}

static void test_state_bits(void)
{
    int f0 = failures;
    pd_particles *p = cube(4, 1.0, 0, 1);
    pd_bonds *b = bonds(p, 2.0001);
    CHECK(pd_bits_count_broken(b->intact, b->count) == 0, "all bonds start intact");
    for (int64_t k = 0; k < b->count; k++)
        CHECK(pd_bond_intact(b->intact, k), "bond %lld not intact", (long long)k);
    int64_t broken = 0;
    for (int64_t k = 0; k < b->count; k += 7) {
        pd_bond_break(b->intact, k);
        pd_bond_break(b->intact, k); /* breaking twice changes nothing */
        broken++;
    }
    CHECK(pd_bits_count_broken(b->intact, b->count) == broken, "count of broken bits");
    for (int64_t k = 0; k < b->count; k++)
        CHECK(pd_bond_intact(b->intact, k) == (k % 7 != 0), "bit %lld", (long long)k);
    CHECK(pd_bits_words(0) == 0 && pd_bits_words(1) == 1 && pd_bits_words(64) == 1 &&
              pd_bits_words(65) == 2,
          "words for a bit count");
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "bond state bits start set; breaking clears exactly one bit; counts agree");
}

static void test_sort(void)
{
    int f0 = failures;
    pd_particles *p = cube(10, 0.001, 0.0002, 3);
    pd_particles *q = cube(10, 0.001, 0.0002, 3);
    if (pd_particles_sort_spatial(q, 0.0030001) != PD_OK)
        die("sort");
    CHECK(q->n == p->n, "same count");
    int moved = 0;
    char *seen = calloc((size_t)p->n, 1);
    for (int64_t i = 0; i < q->n; i++) {
        int64_t src = q->id[i] - 1;
        CHECK(src >= 0 && src < p->n && !seen[src], "ids are a permutation");
        if (src < 0 || src >= p->n || seen[src])
            continue;
        seen[src] = 1;
        moved += src != i;
        for (int d = 0; d < 3; d++)
            CHECK(q->x[d][i] == p->x[d][src], "position left its id");
        CHECK(q->volume[i] == p->volume[src] && q->radius[i] == p->radius[src], "fields travel");
    }
    CHECK(moved > 0, "the sort changed the order");
    /* the bonds of the sorted set are the same pairs, by id */
    pd_bonds *a = bonds(p, 0.0030001), *b = bonds(q, 0.0030001);
    CHECK(a->count == b->count, "same bond count after sorting");
    for (int64_t i = 0; i < q->n; i++) {
        int64_t src = q->id[i] - 1;
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++)
            CHECK(find(a, src, q->id[b->neighbor[k]] - 1) >= 0, "pair lost by sorting");
    }
    free(seen);
    pd_bonds_free(a);
    pd_bonds_free(b);
    pd_particles_free(p);
    pd_particles_free(q);
    proved(f0, "the spatial sort is a permutation keeping ids with particles; same pairs");
}

static void test_errors(void)
{
    int f0 = failures;
    pd_particles *p = cube(2, 1.0, 0, 1);
    pd_bonds *b = NULL;
    CHECK(pd_bonds_build(p, 0, &b) == PD_ERR_INVALID && b == NULL, "zero horizon refused");
    CHECK(pd_bonds_build(p, -1, &b) == PD_ERR_INVALID, "negative horizon refused");
    CHECK(pd_bonds_build(p, NAN, &b) == PD_ERR_INVALID, "NaN horizon refused");
    CHECK(pd_bonds_build(p, INFINITY, &b) == PD_ERR_INVALID, "infinite horizon refused");
    pd_particles_free(p);
    pd_bonds_free(NULL);
    proved(f0, "bad horizons are refused; free accepts NULL");
}

/* The rows of index runs hold the points of pd_cells_adjacent's cells, in
 * its order, for points all over (and beyond) an uneven cloud's grid. */
static void test_cell_rows(void)
{
    int f0 = failures;
    enum { N = 3000 };
    double *x[3];
    for (int d = 0; d < 3; d++)
        if ((x[d] = malloc(N * sizeof(double))) == NULL)
            die("memory");
    uint64_t s = 12345;
    for (int i = 0; i < N; i++)
        for (int d = 0; d < 3; d++) {
            s = s * 6364136223846793005ULL + 1442695040888963407ULL;
            x[d][i] = (d + 1) * 0.01 * (double)(s >> 11) / 9007199254740992.0;
        }
    pd_cells c;
    if (pd_cells_build(&c, N, x, 0.0013) != PD_OK)
        die("cells");
    int bad = 0, probes = 0;
    for (int q = 0; q < 2000; q++) {
        double at[3];
        for (int d = 0; d < 3; d++) {
            s = s * 6364136223846793005ULL + 1442695040888963407ULL;
            at[d] = (d + 1) * 0.012 * (double)(s >> 11) / 9007199254740992.0 - 0.001;
        }
        int64_t cells[27], lo[9], hi[9], first[9], home[3];
        int width, around[9], dx0;
        const int nc = pd_cells_adjacent(&c, at, cells), nr = pd_cells_adjacent_rows(&c, at, lo, hi);
        /* the runs: the same rows, each of its width's cells, at the
         * offsets they say from the point's cell */
        pd_cells_locate(&c, at, home);
        const int home_id = (int)((home[2] * c.dim[1] + home[1]) * c.dim[0] + home[0]);
        bad += pd_cells_adjacent_runs(&c, at, first, &width, around, &dx0) != nr;
        for (int r = 0; r < nr; r++) {
            const int64_t want_first = home_id + ((around[r] / 3 - 1) * c.dim[1] +
                                                  (around[r] % 3 - 1)) * c.dim[0] + dx0;
            bad += first[r] != want_first || c.start[first[r]] != lo[r] ||
                   c.start[first[r] + width] != hi[r];
        }
        int64_t want[27 * 64], got[27 * 64], nw = 0, ng = 0;
        for (int k = 0; k < nc; k++)
            for (int64_t e = c.start[cells[k]]; e < c.start[cells[k] + 1] && nw < 27 * 64; e++)
                want[nw++] = e;
        for (int r = 0; r < nr; r++)
            for (int64_t e = lo[r]; e < hi[r] && ng < 27 * 64; e++)
                got[ng++] = e;
        bad += nw != ng || memcmp(want, got, (size_t)nw * sizeof(int64_t)) != 0;
        probes += nw > 0;
    }
    CHECK(bad == 0, "%d of 2000 probes: the rows are not the adjacent cells' points", bad);
    CHECK(probes > 1500, "only %d probes met points", probes);
    pd_cells_free(&c);
    for (int d = 0; d < 3; d++)
        free(x[d]);
    proved(f0, "the cells' rows and runs hold the adjacent cells' points in their order");
}

/* A cell list rebuilt into the arrays of the one before (pd_cells_rebuild_except)
 * is the list a fresh build gives, for clouds that grow and shrink and with
 * points skipped; its full cells are those that hold points, ascending, and
 * each cell's points are in ascending order. */
static void test_cells_rebuild(void)
{
    int f0 = failures;
    enum { N = 4000 };
    double *x[3];
    uint8_t *skip = malloc(N);
    for (int d = 0; d < 3; d++)
        if ((x[d] = malloc(N * sizeof(double))) == NULL || skip == NULL)
            die("memory");
    uint64_t s = 777;
    pd_cells r;
    memset(&r, 0, sizeof r);
    int bad = 0, sorted = 0, fulls = 0;
    const double spread[5] = {0.01, 0.05, 0.002, 0.2, 0.01};
    for (int round = 0; round < 5; round++) {
        const int64_t n = round == 2 ? N / 3 : N;
        for (int64_t i = 0; i < n; i++) {
            for (int d = 0; d < 3; d++) {
                s = s * 6364136223846793005ULL + 1442695040888963407ULL;
                x[d][i] = spread[round] * (d + 1) * (double)(s >> 11) / 9007199254740992.0;
            }
            skip[i] = round == 4 && i % 7 == 3;
        }
        pd_cells c;
        if (pd_cells_build_except(&c, n, x, 0.0011, skip) != PD_OK ||
            pd_cells_rebuild_except(&r, n, x, 0.0011, skip) != PD_OK)
            die("cells");
        const int64_t ncell = c.dim[0] * c.dim[1] * c.dim[2];
        bad += r.dim[0] != c.dim[0] || r.dim[1] != c.dim[1] || r.dim[2] != c.dim[2] ||
               r.size != c.size ||
               memcmp(r.start, c.start, (size_t)(ncell + 1) * sizeof(int64_t)) != 0 ||
               memcmp(r.index, c.index, (size_t)c.start[ncell] * sizeof(int32_t)) != 0;
        int64_t f = 0;
        for (int64_t k = 0; k < ncell; k++) {
            if (c.start[k + 1] > c.start[k])
                fulls += f >= c.nfull || c.full[f++] != k;
            for (int64_t e = c.start[k] + 1; e < c.start[k + 1]; e++)
                sorted += c.index[e - 1] >= c.index[e];
        }
        fulls += f != c.nfull || r.nfull != c.nfull;
        int64_t kept = 0;
        for (int64_t i = 0; i < n; i++)
            kept += !skip[i];
        bad += c.start[ncell] != kept;
        pd_cells_free(&c);
    }
    CHECK(bad == 0, "%d of 5 rebuilds differ from a fresh build", bad);
    CHECK(fulls == 0, "%d errors in the lists of full cells", fulls);
    CHECK(sorted == 0, "%d cells' points out of order", sorted);
    pd_cells_free(&r);
    CHECK(r.start == NULL && r.start_room == 0, "pd_cells_free leaves arrays behind");
    for (int d = 0; d < 3; d++)
        free(x[d]);
    free(skip);
    proved(f0, "a cell list rebuilt into its arrays is a fresh build's; its full cells ascend");
}

int main(void)
{
    test_family_sizes();
    test_cell_rows();
    test_volume_factors();
    test_cells_vs_brute_force();
    test_cells_rebuild();
    test_state_bits();
    test_sort();
    test_errors();
    if (failures)
        fprintf(stderr, "test_bonds: %d failures\n", failures);
    return failures != 0;
}
