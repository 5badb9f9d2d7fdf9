/*
 * test_grid -- the lattice test and lattice order of lib/stencil/grid.c, on which
 * pd-bonds sorts and pd-run's stencil kernel rests.
 *
 * Proves: a pd-lattice body is on its lattice, with the axes ordered inner
 * (the longest extent), mid (the shortest), outer; its coordinates are the
 * integer sites; a perturbed body, one shifted by a third of a spacing on
 * one particle, and one without a spacing are not on a lattice; the lattice
 * order sorts by (outer, mid, inner), is a permutation, and is the identity
 * after pd_particles_sort_spatial; a plate (2-D) is on its lattice too.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "check.h"
#include "pd.h"

static pd_particles *box(const char *spec, double h, double perturb, int plate)
{
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, spec, &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {.spacing = h, .density = 2200, .material = 1, .perturb = perturb,
                            .seed = 1};
    pd_particles *p;
    pd_status s = plate ? pd_plate_make(&r, 1, &lp, 0.001, &p) : pd_lattice_make(&r, 1, &lp, &p);
    if (s != PD_OK)
        die("lattice");
    return p;
}

static void test_coords(void)
{
    int f0 = failures;
    /* 9 x 4 x 6 sites: x longest (inner), y shortest (mid), z outer */
    pd_particles *p = box("0,0.008,0,0.003,0,0.005", 0.001, 0, 0);
    CHECK(p->n == 9 * 4 * 6, "%lld sites", (long long)p->n);
    int axis[3];
    int32_t *lc[3];
    for (int a = 0; a < 3; a++)
        lc[a] = malloc((size_t)p->n * sizeof(int32_t));
    CHECK(pd_lattice_coords(p, axis, lc) == 1, "a pd-lattice body is on its lattice");
    CHECK(axis[0] == 0 && axis[1] == 1 && axis[2] == 2, "axes %d %d %d", axis[0], axis[1],
          axis[2]);
    int exact = 1;
    for (int64_t i = 0; i < p->n; i++)
        for (int a = 0; a < 3; a++)
            exact &= fabs(p->x[axis[a]][i] - 0.001 * lc[a][i]) < 1e-12;
    CHECK(exact, "the coordinates are the sites");
    /* one particle a third of a spacing off: not a lattice */
    p->x[1][5] += 0.001 / 3;
    CHECK(pd_lattice_coords(p, axis, NULL) == 0, "a site off the lattice is seen");
    p->x[1][5] -= 0.001 / 3;
    p->spacing = 0;
    CHECK(pd_lattice_coords(p, axis, NULL) == 0, "no spacing, no lattice");
    for (int a = 0; a < 3; a++)
        free(lc[a]);
    pd_particles_free(p);
    pd_particles *q = box("0,0.008,0,0.003,0,0.005", 0.001, 2e-4, 0);
    CHECK(pd_lattice_coords(q, axis, NULL) == 0, "a perturbed body is not on a lattice");
    pd_particles_free(q);
    proved(f0, "the lattice test: sites, axes, and what is not a lattice");
}

static void test_order(void)
{
    int f0 = failures;
    pd_particles *p = box("0,0.004,0,0.009,0,0.002", 0.001, 0, 0); /* y inner, x outer, z mid */
    int64_t *order;
    if (pd_lattice_order(p, &order) != PD_OK || order == NULL)
        die("order");
    int axis[3];
    pd_lattice_coords(p, axis, NULL);
    CHECK(axis[0] == 1 && axis[1] == 2 && axis[2] == 0, "axes %d %d %d", axis[0], axis[1],
          axis[2]);
    int sorted = 1, perm = 1;
    char *seen = calloc((size_t)p->n, 1);
    for (int64_t g = 0; g < p->n; g++) {
        perm &= order[g] >= 0 && order[g] < p->n && !seen[order[g]];
        if (order[g] >= 0 && order[g] < p->n)
            seen[order[g]] = 1;
        if (g > 0) {
            const int64_t a = order[g - 1], b = order[g];
            double ka[3], kb[3];
            for (int d = 0; d < 3; d++) {
                ka[d] = p->x[axis[2 - d]][a];
                kb[d] = p->x[axis[2 - d]][b];
            }
            sorted &= ka[0] < kb[0] || (ka[0] == kb[0] && (ka[1] < kb[1] ||
                                                            (ka[1] == kb[1] && ka[2] < kb[2])));
        }
    }
    CHECK(perm, "the order is a permutation");
    CHECK(sorted, "sorted by (outer, mid, inner)");
    free(seen);
    free(order);
    if (pd_particles_sort_spatial(p, 0.003) != PD_OK || pd_lattice_order(p, &order) != PD_OK)
        die("sort");
    int identity = 1;
    for (int64_t g = 0; g < p->n; g++)
        identity &= order[g] == g;
    CHECK(identity, "after pd_particles_sort_spatial the lattice order is the identity");
    free(order);
    pd_particles_free(p);
    pd_particles *q = box("0,0.01,0,0.005,-1,1", 0.001, 0, 1);
    CHECK(pd_lattice_coords(q, axis, NULL) == 1 && axis[0] == 0 && axis[1] == 2 && axis[2] == 1,
          "a plate is on its lattice, inner x, outer y");
    pd_particles_free(q);
    proved(f0, "the lattice order, and pd-bonds' sort into it");
}

int main(void)
{
    test_coords();
    test_order();
    return failures != 0;
}
