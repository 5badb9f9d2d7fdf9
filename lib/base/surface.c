/*
 * surface.c -- a closed triangulated surface as a region (pd-lattice
 * --inside): is a point inside it?
 *
 * The answer is the surface's winding number about the point, counted
 * along the ray from x = -inf to the point: every triangle the ray's line
 * crosses before the point adds -1 or +1 by the sign of its normal's x
 * component, and the point is inside when the sum is not zero.  The test
 * is exact on the triangulation with its points snapped to a grid of 2^30
 * steps across the surface's y-z extent (so about 10^-9 of its size):
 * the line-in-triangle decisions are then integer orientations, exact in
 * 64 bits, and a line through an edge or a vertex is moved off it by the
 * same infinitesimal shift (y + eps, z + eps^2) for every triangle
 * ("simulation of simplicity"), so each edge is decided alike for both of
 * its triangles.  Every line then crosses the closed surface as often
 * inwards as outwards, points on or near facets and nearly degenerate
 * triangles included; only where along x a crossing lies is rounded, which
 * decides points within rounding of a facet.  A point on a facet is
 * inside (the regions are closed sets, as pd-lattice's others): it is
 * inside for one of the four shifts (+-eps, +-eps^2) or has a crossing at
 * itself.
 *
 * Triangles are binned by their y-z bounds on a grid of about one
 * triangle per cell, so a query walks the few triangles over its cell,
 * and the crossings of the last line asked about are kept (per thread),
 * so a lattice's row of sites costs one walk.
 */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "pd.h"

#define QSTEPS (1 << 30) /* snapping grid: differences below 2^31, products below 2^62 */

struct pd_surface {
    long long serial;   /* a number no other surface of the process has  */
    int64_t np, nt;
    double *x;          /* (np,3) points                                    */
    int64_t *q;         /* (np,2) snapped y, z                              */
    int64_t *tri;       /* (nt,3)                                           */
    double lo[3], hi[3];
    double qscale[2];   /* steps per metre in y, z                          */
    int64_t g[2];       /* bins per axis                                    */
    int64_t *bin_start; /* (g[0] g[1] + 1) CSR of the triangles of each bin */
    int64_t *bin_tri;
};

void pd_surface_free(pd_surface *s)
{
    if (s == NULL)
        return;
    free(s->x);
    free(s->q);
    free(s->tri);
    free(s->bin_start);
    free(s->bin_tri);
    free(s);
}

/* ------------------------------------------------ closed and manifold */

typedef struct {
    int64_t lo, hi; /* the edge's points, lo < hi */
    int forward;    /* traversed lo -> hi         */
} edge;

static int edge_cmp(const void *a, const void *b)
{
    const edge *e = a, *f = b;
    if (e->lo != f->lo)
        return e->lo < f->lo ? -1 : 1;
    if (e->hi != f->hi)
        return e->hi < f->hi ? -1 : 1;
    return e->forward - f->forward;
}

/* Every edge in exactly two triangles, once each way. */
static pd_status check_closed(const pd_surface *s)
{
    edge *e = malloc((size_t)s->nt * 3 * sizeof *e);
    if (e == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for a surface of %lld triangles",
                       (long long)s->nt);
    for (int64_t t = 0; t < s->nt; t++)
        for (int k = 0; k < 3; k++) {
            int64_t a = s->tri[3 * t + k], b = s->tri[3 * t + (k + 1) % 3];
            e[3 * t + k] = (edge){a < b ? a : b, a < b ? b : a, a < b};
        }
    int64_t ne = s->nt * 3, boundary = 0, crowded = 0, turned = 0;
    qsort(e, (size_t)ne, sizeof *e, edge_cmp);
    for (int64_t i = 0; i < ne;) {
        int64_t j = i + 1;
        while (j < ne && e[j].lo == e[i].lo && e[j].hi == e[i].hi)
            j++;
        if (j - i == 1)
            boundary++;
        else if (j - i > 2)
            crowded++;
        else if (e[i].forward == e[i + 1].forward)
            turned++;
        i = j;
    }
    free(e);
    if (boundary > 0)
        return pd_fail(PD_ERR_INVALID,
                       "the surface is open: %lld boundary edges (edges of one triangle only)",
                       (long long)boundary);
    if (crowded > 0)
        return pd_fail(PD_ERR_INVALID,
                       "the surface is not manifold: %lld edges of more than two triangles "
                       "(0 boundary edges)",
                       (long long)crowded);
    if (turned > 0)
        return pd_fail(PD_ERR_INVALID,
                       "the surface's triangles are not oriented alike: %lld edges run the same "
                       "way in both their triangles",
                       (long long)turned);
    return PD_OK;
}

/* ------------------------------------------------ exact orientations */

static int sign64(int64_t v)
{
    return (v > 0) - (v < 0);
}

/* The side of the directed edge a -> b (snapped y, z) that p lies on,
 * +1 left, -1 right, after the shift p + (sy eps, sz eps^2) (sy, sz = +-1);
 * 0 only when a and b coincide.  Computed in one order of the two points,
 * so that the edge's two triangles, which run it both ways, get opposite
 * answers.  *on is set when p lies on the edge's line, unshifted. */
static int side(const int64_t *a, const int64_t *b, const int64_t *p, int sy, int sz, int *on)
{
    int swap = a[0] > b[0] || (a[0] == b[0] && a[1] > b[1]);
    const int64_t *u = swap ? b : a, *v = swap ? a : b;
    int64_t dy = v[0] - u[0], dz = v[1] - u[1];
    int s = sign64(dy * (p[1] - u[1]) - dz * (p[0] - u[0]));
    if (s == 0) {
        *on = 1;
        s = dz != 0 ? -sign64(dz) * sy : sign64(dy) * sz;
    }
    return swap ? -s : s;
}

static int64_t orient(const int64_t *a, const int64_t *b, const int64_t *p)
{
    return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
}

static int64_t snap(double v, double lo, double scale)
{
    double t = nearbyint((v - lo) * scale);
    return t < 0 ? -1 : t > QSTEPS ? (int64_t)QSTEPS + 1 : (int64_t)t;
}

/* The bin of a snapped coordinate on axis a. */
static int64_t bin_of(const pd_surface *s, int a, int64_t q)
{
    int64_t b = q * s->g[a] / ((int64_t)QSTEPS + 1);
    return b < 0 ? 0 : b >= s->g[a] ? s->g[a] - 1 : b;
}

static pd_status build_bins(pd_surface *s)
{
    int64_t side_bins = (int64_t)ceil(sqrt((double)s->nt));
    for (int a = 0; a < 2; a++)
        s->g[a] = side_bins < 1 ? 1 : side_bins > 4096 ? 4096 : side_bins;
    int64_t nb = s->g[0] * s->g[1];
    s->bin_start = calloc((size_t)nb + 1, sizeof *s->bin_start);
    if (s->bin_start == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for a surface's bins");
    for (int pass = 0; pass < 2; pass++) {
        for (int64_t t = 0; t < s->nt; t++) {
            int64_t blo[2], bhi[2];
            for (int a = 0; a < 2; a++) {
                int64_t lo = INT64_MAX, hi = INT64_MIN;
                for (int k = 0; k < 3; k++) {
                    int64_t q = s->q[2 * s->tri[3 * t + k] + a];
                    lo = q < lo ? q : lo;
                    hi = q > hi ? q : hi;
                }
                blo[a] = bin_of(s, a, lo);
                bhi[a] = bin_of(s, a, hi);
            }
            for (int64_t by = blo[0]; by <= bhi[0]; by++)
                for (int64_t bz = blo[1]; bz <= bhi[1]; bz++) {
                    int64_t b = by * s->g[1] + bz;
                    if (pass == 0)
                        s->bin_start[b + 1]++;
                    else
                        s->bin_tri[s->bin_start[b]++] = t;
                }
        }
        if (pass == 0) {
            for (int64_t b = 0; b < nb; b++)
                s->bin_start[b + 1] += s->bin_start[b];
            s->bin_tri = malloc((size_t)(s->bin_start[nb] ? s->bin_start[nb] : 1) *
                                sizeof *s->bin_tri);
            if (s->bin_tri == NULL)
                return pd_fail(PD_ERR_NOMEM, "out of memory for a surface's bins");
        } else {
            /* the fill moved each start to the next bin's: move back */
            for (int64_t b = nb; b > 0; b--)
                s->bin_start[b] = s->bin_start[b - 1];
            s->bin_start[0] = 0;
        }
    }
    return PD_OK;
}

pd_status pd_surface_new(int64_t np, const double *points, int64_t nt, const int64_t *tri,
                         pd_surface **out)
{
    *out = NULL;
    if (nt < 4 || np < 4)
        return pd_fail(PD_ERR_INVALID, "a closed surface needs at least 4 triangles, not %lld",
                       (long long)nt);
    for (int64_t t = 0; t < nt; t++) {
        for (int k = 0; k < 3; k++)
            if (tri[3 * t + k] < 0 || tri[3 * t + k] >= np)
                return pd_fail(PD_ERR_INVALID, "triangle %lld names point %lld of %lld",
                               (long long)t, (long long)tri[3 * t + k], (long long)np);
        if (tri[3 * t] == tri[3 * t + 1] || tri[3 * t + 1] == tri[3 * t + 2] ||
            tri[3 * t + 2] == tri[3 * t])
            return pd_fail(PD_ERR_INVALID, "triangle %lld repeats a point", (long long)t);
    }
    for (int64_t i = 0; i < 3 * np; i++)
        if (!isfinite(points[i]))
            return pd_fail(PD_ERR_INVALID, "surface point %lld is not finite", (long long)(i / 3));
    static atomic_llong made;
    pd_surface *s = calloc(1, sizeof *s);
    if (s == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for a surface");
    s->serial = atomic_fetch_add(&made, 1) + 1;
    s->np = np;
    s->nt = nt;
    s->x = malloc((size_t)np * 3 * sizeof *s->x);
    s->q = malloc((size_t)np * 2 * sizeof *s->q);
    s->tri = malloc((size_t)nt * 3 * sizeof *s->tri);
    if (s->x == NULL || s->q == NULL || s->tri == NULL) {
        pd_surface_free(s);
        return pd_fail(PD_ERR_NOMEM, "out of memory for a surface of %lld triangles",
                       (long long)nt);
    }
    memcpy(s->x, points, (size_t)np * 3 * sizeof *s->x);
    memcpy(s->tri, tri, (size_t)nt * 3 * sizeof *s->tri);
    pd_status st = check_closed(s);
    if (st != PD_OK) {
        pd_surface_free(s);
        return st;
    }
    for (int d = 0; d < 3; d++) {
        s->lo[d] = INFINITY;
        s->hi[d] = -INFINITY;
    }
    /* the bounds of the points the triangles use (all of them, once closed) */
    for (int64_t t = 0; t < 3 * nt; t++)
        for (int d = 0; d < 3; d++) {
            double v = points[3 * tri[t] + d];
            s->lo[d] = v < s->lo[d] ? v : s->lo[d];
            s->hi[d] = v > s->hi[d] ? v : s->hi[d];
        }
    for (int a = 0; a < 2; a++) {
        double ext = s->hi[a + 1] - s->lo[a + 1];
        if (!(ext > 0)) {
            pd_surface_free(s);
            return pd_fail(PD_ERR_INVALID, "the surface is flat: it encloses no volume");
        }
        s->qscale[a] = QSTEPS / ext;
    }
    for (int64_t i = 0; i < np; i++)
        for (int a = 0; a < 2; a++)
            s->q[2 * i + a] = snap(points[3 * i + a + 1], s->lo[a + 1], s->qscale[a]);
    if ((st = build_bins(s)) != PD_OK) {
        pd_surface_free(s);
        return st;
    }
    *out = s;
    return PD_OK;
}

/* The crossings of the line through p (snapped y, z; shifted by
 * (sy eps, sz eps^2)) with the surface: where along x, and -1 entering
 * (a normal with negative x), +1 leaving.  Returns their number, at most
 * `cap` kept; *on is set when p lies on the line of a triangle's side.
 * With x, also the winding numbers about x of every crossing before x
 * (*strict) and before or at x (*closed), kept or not. */
static int crossings(const pd_surface *s, const int64_t p[2], int sy, int sz, double *at,
                     int *sign, int cap, int *on, const double *x, int *strict, int *closed)
{
    int64_t b = bin_of(s, 0, p[0]) * s->g[1] + bin_of(s, 1, p[1]);
    int n = 0;
    for (int64_t k = s->bin_start[b]; k < s->bin_start[b + 1]; k++) {
        const int64_t *t = s->tri + 3 * s->bin_tri[k];
        const int64_t *qa = s->q + 2 * t[0], *qb = s->q + 2 * t[1], *qc = s->q + 2 * t[2];
        int sa = side(qb, qc, p, sy, sz, on), sb = side(qc, qa, p, sy, sz, on),
            sc = side(qa, qb, p, sy, sz, on);
        if (sa == 0 || sa != sb || sb != sc)
            continue;
        int64_t area = orient(qa, qb, qc);
        if (area == 0)
            continue; /* cannot be crossed: its three sides never agree */
        /* where the line crosses it, from the barycentric weights */
        const double *xa = s->x + 3 * t[0], *xb = s->x + 3 * t[1], *xc = s->x + 3 * t[2];
        double wb = (double)orient(qc, qa, p) / (double)area,
               wc = (double)orient(qa, qb, p) / (double)area;
        const double cross = xa[0] + (wb * (xb[0] - xa[0]) + wc * (xc[0] - xa[0]));
        if (n < cap) {
            at[n] = cross;
            sign[n] = sa;
        }
        if (x) {
            *strict -= cross < *x ? sa : 0;
            *closed -= cross <= *x ? sa : 0;
        }
        n++;
    }
    return n;
}

/* The crossings of the last line asked about, per thread: a lattice asks
 * along its rows, so one line serves a row of sites. */
#define ROW_CAP 1024
static _Thread_local struct {
    long long serial; /* the surface's (not its address, which another may reuse) */
    int64_t p[2];
    int known; /* shifts whose crossings are kept */
    int on;
    int n[4];
    double at[4][ROW_CAP];
    int sign[4][ROW_CAP];
} row;

/* Is x beyond a crossing that leaves it with a winding number, counting a
 * crossing at x itself (closed) or not (strict)? */
static int winds(const double *at, const int *sign, int n, double x)
{
    int strict = 0, closed = 0;
    for (int c = 0; c < n; c++) {
        strict -= at[c] < x ? sign[c] : 0;
        closed -= at[c] <= x ? sign[c] : 0;
    }
    return strict != 0 || closed != 0;
}

int pd_surface_inside(const pd_surface *s, const double x[3])
{
    for (int d = 0; d < 3; d++)
        if (!(x[d] >= s->lo[d] && x[d] <= s->hi[d]))
            return 0;
    const int64_t p[2] = {snap(x[1], s->lo[1], s->qscale[0]), snap(x[2], s->lo[2], s->qscale[1])};
    if (row.serial != s->serial || row.p[0] != p[0] || row.p[1] != p[1]) {
        row.serial = s->serial;
        row.p[0] = p[0];
        row.p[1] = p[1];
        row.known = row.on = 0;
    }
    /* A point on the surface is inside (a closed set): along x, a crossing
     * at the point counts, and across the line a point on a side is
     * shifted each of the four ways. */
    static const int shifts[4][2] = {{1, 1}, {-1, 1}, {1, -1}, {-1, -1}};
    for (int k = 0; k < 4; k++) {
        int in;
        if (k >= row.known) {
            row.n[k] = crossings(s, p, shifts[k][0], shifts[k][1], row.at[k], row.sign[k],
                                 ROW_CAP, &row.on, NULL, NULL, NULL);
            row.known = k + 1;
        }
        if (row.n[k] <= ROW_CAP)
            in = winds(row.at[k], row.sign[k], row.n[k], x[0]);
        else { /* more than a row keeps: counted for this site alone */
            int on = 0, strict = 0, closed = 0;
            crossings(s, p, shifts[k][0], shifts[k][1], NULL, NULL, 0, &on, x, &strict, &closed);
            in = strict != 0 || closed != 0;
        }
        if (in)
            return 1;
        if (!row.on)
            return 0;
    }
    return 0;
}

void pd_surface_bounds(const pd_surface *s, double lo[3], double hi[3])
{
    for (int d = 0; d < 3; d++) {
        lo[d] = s->lo[d];
        hi[d] = s->hi[d];
    }
}

int64_t pd_surface_triangles(const pd_surface *s)
{
    return s->nt;
}

double pd_surface_volume(const pd_surface *s)
{
    double v = 0;
    for (int64_t t = 0; t < s->nt; t++) {
        const double *a = s->x + 3 * s->tri[3 * t], *b = s->x + 3 * s->tri[3 * t + 1],
                     *c = s->x + 3 * s->tri[3 * t + 2];
        v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
              a[2] * (b[0] * c[1] - b[1] * c[0])) /
             6;
    }
    return v;
}
