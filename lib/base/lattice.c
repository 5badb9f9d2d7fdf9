/*
 * lattice.c -- particles on a simple cubic lattice inside regions.
 *
 * Sites are n * spacing for integer n along each axis (LAMMPS `lattice sc`,
 * origin at 0), or (n + o) * spacing with a fraction o per axis (LAMMPS
 * `lattice sc ... origin`).  A site belongs to the body when it is inside at least one
 * added region and inside no subtracted region.  Sites are numbered z
 * outermost, then y, then x (the order of LAMMPS create_atoms), so ids match
 * a LAMMPS run of the same region.  Each particle gets volume spacing^3 and
 * node radius spacing/2 (seed 000, "Spatial Discretization" and eq. 15).
 * An optional perturbation moves each site by a uniform random amount in
 * [-A, A] per axis (GSL mt19937), breaking the lattice's symmetry.
 *
 * A plate (dimension 2) is the square lattice (i spacing, j spacing, 0) of
 * the sites where (x, y, 0) is in the body: the regions are cut at z = 0.
 * Each particle stands for a column of the plate's thickness H, volume
 * spacing^2 H; the perturbation stays in the plane.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_rng.h>

#include "base/comm.h"
#include "pd.h"

static int site_in_body(const pd_region *regions, int nregions, const double x[3])
{
    int in = 0;
    for (int r = 0; r < nregions && !in; r++)
        if (!regions[r].subtract && pd_region_inside(&regions[r], x))
            in = 1;
    for (int r = 0; r < nregions && in; r++)
        if (regions[r].subtract && pd_region_inside(&regions[r], x))
            in = 0;
    return in;
}

/* The lattice of pd_lattice_make (plate 0) or of pd_plate_make (plate 1,
 * thickness H). */
static pd_status make(const pd_region *regions, int nregions, const pd_lattice_params *lp,
                      int plate, double thickness, pd_particles **out)
{
    const double h = lp->spacing;
    if (!(h > 0) || !isfinite(h))
        return pd_fail(PD_ERR_INVALID, "spacing must be a positive number");
    if (!(lp->density > 0) || !isfinite(lp->density))
        return pd_fail(PD_ERR_INVALID, "density must be a positive number");
    if (!(lp->perturb >= 0) || !isfinite(lp->perturb))
        return pd_fail(PD_ERR_INVALID, "perturbation must be zero or positive");
    if (plate && (!(thickness > 0) || !isfinite(thickness)))
        return pd_fail(PD_ERR_INVALID, "a plate's thickness must be a positive number");

    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    int nadd = 0;
    for (int r = 0; r < nregions; r++) {
        if (regions[r].subtract)
            continue;
        double a[3], b[3];
        pd_region_bounds(&regions[r], a, b);
        for (int d = 0; d < 3; d++) {
            lo[d] = fmin(lo[d], a[d]);
            hi[d] = fmax(hi[d], b[d]);
        }
        nadd++;
    }
    if (nadd == 0)
        return pd_fail(PD_ERR_INVALID, "no region to fill (give --box, --cylinder, --sphere or --inside)");

    const double *o = lp->origin;
    for (int d = 0; d < 3; d++)
        if (!(o[d] >= 0 && o[d] < 1))
            return pd_fail(PD_ERR_INVALID, "the lattice origin is a fraction of the spacing in "
                           "[0, 1), not %g", o[d]);
    if (plate && o[2] != 0)
        return pd_fail(PD_ERR_INVALID, "a plate's sites are at z = 0: its origin's z is 0");
    int64_t nlo[3], nhi[3];
    double sites = 1;
    for (int d = 0; d < 3; d++) {
        nlo[d] = (int64_t)floor(lo[d] / h - o[d]) - 1;
        nhi[d] = (int64_t)ceil(hi[d] / h - o[d]) + 1;
        sites *= (double)(nhi[d] - nlo[d] + 1);
    }
    if (plate) { /* one layer of sites, at z = 0 */
        sites /= (double)(nhi[2] - nlo[2] + 1);
        nlo[2] = nhi[2] = 0;
    }
    if (sites > 4e9)
        return pd_fail(PD_ERR_NOMEM, "the regions span %.3g lattice sites; spacing too small?",
                       sites);

    /* Count, then fill. */
    int64_t n = 0;
    for (int pass = 0; pass < 2; pass++) {
        pd_particles *p = NULL;
        if (pass == 1) {
            if (n == 0)
                return pd_fail(PD_ERR_INVALID, plate ? "the regions hold no lattice site at z = 0"
                                                     : "the regions hold no lattice site");
            p = pd_particles_new(n);
            if (p == NULL)
                return pd_fail(PD_ERR_NOMEM, "out of memory for %lld particles", (long long)n);
            p->spacing = h;
            p->dimension = plate ? 2 : 3;
            p->thickness = plate ? thickness : 0;
        }
        const double volume = plate ? h * h * thickness : h * h * h;
        int64_t k = 0;
        for (int64_t iz = nlo[2]; iz <= nhi[2]; iz++)
            for (int64_t iy = nlo[1]; iy <= nhi[1]; iy++)
                for (int64_t ix = nlo[0]; ix <= nhi[0]; ix++) {
                    /* (n + 0.0) h is n h, bit for bit: no origin, the sites of before */
                    double x[3] = {((double)ix + o[0]) * h, ((double)iy + o[1]) * h,
                                   ((double)iz + o[2]) * h};
                    if (!site_in_body(regions, nregions, x))
                        continue;
                    if (pass == 1) {
                        for (int d = 0; d < 3; d++)
                            p->x[d][k] = x[d];
                        p->volume[k] = volume;
                        p->density[k] = lp->density;
                        p->radius[k] = 0.5 * h;
                        p->material[k] = lp->material;
                        p->id[k] = k + 1;
                    }
                    k++;
                }
        if (pass == 0) {
            n = k;
            /* position (3), volume, density, radius, id: 8 bytes; material: 4 */
            double bytes = (double)n * (7 * 8 + 4);
            if (bytes > 0.5 * pd_memory_bytes())
                return pd_fail(PD_ERR_NOMEM,
                               "%lld particles would need %.3g GB, more than this machine has",
                               (long long)n, bytes / 1e9);
            continue;
        }
        if (lp->perturb > 0) {
            gsl_rng *rng = gsl_rng_alloc(gsl_rng_mt19937);
            if (rng == NULL) {
                pd_particles_free(p);
                return pd_fail(PD_ERR_NOMEM, "cannot allocate a random number generator");
            }
            gsl_rng_set(rng, lp->seed);
            for (int64_t i = 0; i < n; i++)
                for (int d = 0; d < (plate ? 2 : 3); d++)
                    p->x[d][i] += lp->perturb * (2.0 * gsl_rng_uniform(rng) - 1.0);
            gsl_rng_free(rng);
        }
        *out = p;
    }
    return PD_OK;
}

pd_status pd_lattice_make(const pd_region *regions, int nregions, const pd_lattice_params *lp,
                          pd_particles **out)
{
    return make(regions, nregions, lp, 0, 0, out);
}

pd_status pd_plate_make(const pd_region *regions, int nregions, const pd_lattice_params *lp,
                        double thickness, pd_particles **out)
{
    return make(regions, nregions, lp, 1, thickness, out);
}

/* ------------------------------------------------------- lattice order */

/* The lattice coordinate along axis d of every particle, round((x - lo) /
 * h), into c (when not NULL); 0 when a particle is farther than
 * PD_LATTICE_TOL spacings from its site or the coordinate leaves int32. */
static int lattice_axis(const pd_particles *p, int d, double lo, double h, int32_t *c)
{
    for (int64_t i = 0; i < p->n; i++) {
        double u = (p->x[d][i] - lo) / h, r = nearbyint(u);
        if (!(fabs(u - r) <= PD_LATTICE_TOL) || !(fabs(r) < 1e9))
            return 0;
        if (c)
            c[i] = (int32_t)r;
    }
    return 1;
}

int pd_lattice_coords(const pd_particles *p, int axis[3], int32_t *lc[3])
{
    const double h = p->spacing;
    if (!(h > 0) || (p->n == 0 && !p->window))
        return 0;
    double lo[3], hi[3];
    pd_body_bounds(p, lo, hi); /* a window: the whole body's (collective) */
    for (int d = 0; d < 3; d++)
        if (!isfinite(lo[d]) || !isfinite(hi[d]) || (hi[d] - lo[d]) / h > 1e9)
            return 0;
    /* inner: the longest extent; outer: the next; mid: the shortest (ties
     * by axis number) */
    int ord[3] = {0, 1, 2};
    for (int a = 0; a < 3; a++)
        for (int b = a + 1; b < 3; b++)
            if (hi[ord[b]] - lo[ord[b]] > hi[ord[a]] - lo[ord[a]]) {
                int t = ord[a];
                ord[a] = ord[b];
                ord[b] = t;
            }
    axis[0] = ord[0];
    axis[1] = ord[2];
    axis[2] = ord[1];
    for (int a = 0; a < 3; a++)
        if (!lattice_axis(p, axis[a], lo[axis[a]], h, lc ? lc[a] : NULL))
            return 0;
    return 1;
}

int pd_lattice_sites(const pd_particles *p, const double origin[3], double h, int32_t *c[3])
{
    if (!(h > 0) || !isfinite(h) || p->n == 0)
        return 0;
    for (int d = 0; d < 3; d++)
        if (!isfinite(origin[d]) || !lattice_axis(p, d, origin[d], h, c ? c[d] : NULL))
            return 0;
    return 1;
}

typedef struct {
    int64_t g;
    int32_t c[3];
} order_item;

static int cmp_order(const void *a, const void *b)
{
    const order_item *x = a, *y = b;
    for (int d = 2; d >= 0; d--)
        if (x->c[d] != y->c[d])
            return (x->c[d] > y->c[d]) - (x->c[d] < y->c[d]);
    return (x->g > y->g) - (x->g < y->g);
}

int64_t *pd_lattice_sort(int64_t n, int32_t *const lc[3])
{
    order_item *it = malloc((size_t)(n > 0 ? n : 1) * sizeof *it);
    int64_t *o = malloc((size_t)(n > 0 ? n : 1) * sizeof *o);
    if (it && o) {
        for (int64_t i = 0; i < n; i++) {
            it[i].g = i;
            for (int d = 0; d < 3; d++)
                it[i].c[d] = lc[d][i];
        }
        qsort(it, (size_t)n, sizeof *it, cmp_order);
        for (int64_t g = 0; g < n; g++)
            o[g] = it[g].g;
    } else {
        free(o);
        o = NULL;
    }
    free(it);
    return o;
}

pd_status pd_lattice_order(const pd_particles *p, int64_t **order)
{
    *order = NULL;
    int axis[3];
    int32_t *lc[3] = {NULL, NULL, NULL};
    for (int d = 0; d < 3; d++)
        lc[d] = malloc((size_t)(p->n > 0 ? p->n : 1) * sizeof(int32_t));
    pd_status s = PD_OK;
    if (!lc[0] || !lc[1] || !lc[2])
        s = pd_fail(PD_ERR_NOMEM, "out of memory ordering the lattice");
    else if (pd_lattice_coords(p, axis, lc) && (*order = pd_lattice_sort(p->n, lc)) == NULL)
        s = pd_fail(PD_ERR_NOMEM, "out of memory ordering the lattice");
    for (int d = 0; d < 3; d++)
        free(lc[d]);
    return s;
}

int pd_region_rounding(const pd_region *r, double h, const double origin[3], const char *what,
                       char *text, size_t len)
{
    double face[6];
    int axis[6], upper[6], nf = 0;
    if (r->kind == PD_REGION_BOX)
        for (int k = 0; k < 6; k++) {
            face[nf] = r->p[k];
            axis[nf] = k / 2;
            upper[nf++] = k % 2;
        }
    else if (r->kind == PD_REGION_CYLINDER)
        for (int k = 0; k < 2; k++) {
            face[nf] = r->p[3 + k];
            axis[nf] = r->axis;
            upper[nf++] = k;
        }
    int found = 0, more = 0;
    for (int k = 0; k < nf; k++) {
        const double o = origin[axis[k]];
        const double n = nearbyint(face[k] / h - o), site = (n + o) * h;
        const double off = fabs(site - face[k]) / h;
        if (site == face[k] || !(off < PD_LATTICE_ROUNDING))
            continue;
        if (found++) {
            more++;
            continue;
        }
        const int in = upper[k] ? site <= face[k] : site >= face[k];
        const double out = face[k] + (upper[k] ? -0.5 : 0.5) * h,
                     keep = face[k] + (upper[k] ? 0.5 : -0.5) * h;
        snprintf(text, len,
                 "%s: its face %c = %g lies %.2g spacings from the lattice plane %c = %.15g x "
                 "%g = %.17g, whose sites rounding puts %s; to say which you mean, give the "
                 "face half a spacing away (%g keeps them, %g leaves them out)",
                 what, 'x' + axis[k], face[k], off, 'x' + axis[k], n + o, h, site,
                 in ? "inside" : "outside", keep, out);
    }
    if (more) {
        size_t used = strlen(text);
        snprintf(text + used, len - used, "; %d more face%s like it", more, more > 1 ? "s" : "");
    }
    return found > 0;
}

void pd_lattice_block_starts(const int32_t *outer, int64_t i0, int64_t i1, int64_t lo, int thick,
                             int64_t nb, int64_t *start)
{
    memset(start, 0, (size_t)(nb + 1) * sizeof(int64_t));
    for (int64_t i = i0; i < i1; i++) /* the rows below each block's first plane */
        start[(outer[i] - lo) / thick + 1]++;
    pd_comm_add_int(start, nb + 1);
    for (int64_t k = 1; k <= nb; k++)
        start[k] += start[k - 1];
}
