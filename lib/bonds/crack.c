/*
 * crack.c -- pre-cracks: planar cracks made before a run by breaking every
 * bond that crosses them (seed 004: a broken bond is one with mu = 0, and a
 * crack is where bonds are broken).
 *
 * A crack is the closed parallelogram
 *
 *   C = { P + u A + v B : 0 <= u <= 1, 0 <= v <= 1 }
 *
 * with corner P and edge vectors A, B (m), in the plane through P with
 * normal n = A x B.  The signed distance (times |n|) of a point x from the
 * plane is s(x) = n . (x - P).  The reference segment x_i -> x_j of a bond
 * crosses the crack when
 *
 *   1. its endpoints lie on different sides of the plane, where a point with
 *      s(x) >= 0 is on the positive side (the side n points to) and one with
 *      s(x) < 0 on the negative side: a point exactly on the plane counts on
 *      the positive side; and
 *   2. the point where the segment meets the plane, X = x_- + t (x_+ - x_-)
 *      with t = s(x_-) / (s(x_-) - s(x_+)), x_- the endpoint on the negative
 *      side and x_+ the other, lies in C: X - P = u A + v B (the 2x2 normal
 *      equations of the edge vectors) with u, v in [0, 1].
 *
 * The convention of rule 1 makes a crack placed exactly on a lattice plane
 * cut one side consistently: the particles of the plane count on the side n
 * points to, so the bonds cut are those from the plane and beyond it to the
 * particles strictly behind it -- as if the crack lay half a spacing behind
 * the plane (towards -n); swapping A and B moves it to the other side.  For
 * a crack whose normal lies along an axis the side test compares
 * coordinates exactly (the other components of n are zeros).  The edges of
 * C are closed but the crossing point carries rounding: place the edges off
 * the crossing points of lattice bonds (e.g. not at a lattice coordinate or
 * half of one) when the edge must be exact.
 *
 * The test takes the endpoints in an order of its own (negative side
 * first), so it is exactly symmetric: i -> j crosses exactly when j -> i
 * does.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "pd.h"

/* |A x B| below this fraction of |A||B| (the sine of the angle between the
 * edges) makes a crack degenerate: its edges are parallel. */
#define PARALLEL_SINE 1e-9

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

pd_status pd_crack_check(const pd_crack *c, const char *spec)
{
    const char *name = spec ? spec : "crack";
    if (c->through) {
        if (c->a[0] == 0 && c->a[1] == 0)
            return pd_fail(PD_ERR_INVALID, "crack '%s': the segment has zero length", name);
        return PD_OK;
    }
    double n[3];
    cross(c->a, c->b, n);
    double aa = dot(c->a, c->a), bb = dot(c->b, c->b), nn = dot(n, n);
    if (!(aa > 0))
        return pd_fail(PD_ERR_INVALID, "crack '%s': edge A has zero length", name);
    if (!(bb > 0))
        return pd_fail(PD_ERR_INVALID, "crack '%s': edge B has zero length", name);
    if (!isfinite(aa) || !isfinite(bb) || !isfinite(nn))
        return pd_fail(PD_ERR_INVALID, "crack '%s': edges too long", name);
    if (!(sqrt(nn) > PARALLEL_SINE * sqrt(aa) * sqrt(bb)))
        return pd_fail(PD_ERR_INVALID, "crack '%s': edges A and B are parallel", name);
    return PD_OK;
}

pd_status pd_crack_parse(const char *spec, pd_crack *c)
{
    memset(c, 0, sizeof *c);
    double v[9];
    if (strncmp(spec, "rect,", 5) == 0) {
        if (!pd_parse_doubles(spec + 5, v, 9))
            return pd_fail(PD_ERR_INVALID, "crack '%s': expected rect,X,Y,Z,AX,AY,AZ,BX,BY,BZ",
                           spec);
        for (int d = 0; d < 3; d++) {
            c->p[d] = v[d];
            c->a[d] = v[3 + d];
            c->b[d] = v[6 + d];
        }
    } else if (strncmp(spec, "segment,", 8) == 0) {
        if (!pd_parse_doubles(spec + 8, v, 4))
            return pd_fail(PD_ERR_INVALID, "crack '%s': expected segment,X1,Y1,X2,Y2", spec);
        c->through = 1;
        c->p[0] = v[0];
        c->p[1] = v[1];
        c->a[0] = v[2] - v[0];
        c->a[1] = v[3] - v[1];
        if (!isfinite(c->a[0]) || !isfinite(c->a[1]))
            return pd_fail(PD_ERR_INVALID, "crack '%s': the segment is too long", spec);
    } else
        return pd_fail(PD_ERR_INVALID, "crack '%s': expected rect,... or segment,...", spec);
    return pd_crack_check(c, spec);
}

/* The parallelogram of a crack given through the thickness: the segment's
 * plane from the lowest z of the particles less a margin to the highest
 * plus the margin.  Any bond's crossing point lies within the particles' z
 * range; the margin keeps rounding inside. */
static pd_crack span_z(const pd_crack *c, const pd_particles *p, double margin)
{
    pd_crack out = *c;
    double lo = INFINITY, hi = -INFINITY;
    for (int64_t i = 0; i < p->n; i++) {
        lo = p->x[2][i] < lo ? p->x[2][i] : lo;
        hi = p->x[2][i] > hi ? p->x[2][i] : hi;
    }
    if (p->n == 0)
        lo = hi = 0;
    out.through = 0;
    out.p[2] = lo - margin;
    out.a[2] = 0;
    out.b[0] = out.b[1] = 0;
    out.b[2] = hi - lo + 2 * margin;
    return out;
}

/* The plane of a crack, ready for many tests: normal and Gram matrix. */
typedef struct {
    double p[3], a[3], b[3], n[3];
    double aa, ab, bb, det;
} plane;

static plane plane_of(const pd_crack *c)
{
    plane q;
    memcpy(q.p, c->p, sizeof q.p);
    memcpy(q.a, c->a, sizeof q.a);
    memcpy(q.b, c->b, sizeof q.b);
    cross(c->a, c->b, q.n);
    q.aa = dot(c->a, c->a);
    q.ab = dot(c->a, c->b);
    q.bb = dot(c->b, c->b);
    q.det = q.aa * q.bb - q.ab * q.ab;
    return q;
}

/* s(x) = n . (x - P) */
static double side_value(const plane *q, const double x[3])
{
    double d[3] = {x[0] - q->p[0], x[1] - q->p[1], x[2] - q->p[2]};
    return dot(q->n, d);
}

/* Rule 2 for a segment whose endpoints are on different sides: xm on the
 * negative side (sm < 0), xp on the positive side (sp >= 0). */
static int meets_inside(const plane *q, const double xm[3], double sm, const double xp[3],
                        double sp)
{
    double t = sm / (sm - sp), d[3];
    for (int k = 0; k < 3; k++)
        d[k] = xm[k] + t * (xp[k] - xm[k]) - q->p[k];
    double da = dot(d, q->a), db = dot(d, q->b);
    double u = (q->bb * da - q->ab * db) / q->det, v = (q->aa * db - q->ab * da) / q->det;
    return u >= 0 && u <= 1 && v >= 0 && v <= 1;
}

static int crosses(const plane *q, const double x[3], double sx, const double y[3], double sy)
{
    int px = sx >= 0, py = sy >= 0;
    if (px == py)
        return 0;
    return px ? meets_inside(q, y, sy, x, sx) : meets_inside(q, x, sx, y, sy);
}

int pd_crack_crosses(const pd_crack *c, const double x[3], const double y[3])
{
    plane q = plane_of(c);
    return crosses(&q, x, side_value(&q, x), y, side_value(&q, y));
}

/* Set bit b (atomically: rows are done in parallel and each sets the bit
 * of its bond's mirror in another row). */
static void set_bit(uint64_t *bits, int64_t b)
{
    __atomic_fetch_or(&bits[b >> 6], UINT64_C(1) << (b & 63), __ATOMIC_RELAXED);
}

/* The copy j -> i of bond k = i -> j: families are sorted by partner. */
static int64_t mirror(const pd_bonds *b, int64_t i, int64_t j)
{
    int64_t lo = b->offset[j], hi = b->offset[j + 1];
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (b->neighbor[mid] < i)
            lo = mid + 1;
        else
            hi = mid;
    }
    return (lo < b->offset[j + 1] && b->neighbor[lo] == i) ? lo : -1;
}

/* pd_bonds_precrack over the families of rows [lo, hi): `mirrored`, each
 * pair from its lower row, both its bonds at once (the whole body); else
 * each bond from its own row (a part of the body, whose partners' families
 * may be another's), the pair decided from its lower row's side alike. */
static pd_status precrack(const pd_particles *p, pd_bonds *b, const pd_crack *cracks,
                          int ncracks, int64_t *counts, int64_t lo, int64_t hi, int mirrored)
{
    if (p->n != b->n)
        return pd_fail(PD_ERR_INVALID, "pre-crack: %lld particles but bonds of %lld",
                       (long long)p->n, (long long)b->n);
    for (int c = 0; c < ncracks; c++) {
        pd_status st = pd_crack_check(&cracks[c], NULL);
        if (st != PD_OK)
            return st;
    }
    int64_t n = p->n, words = pd_bits_words(b->count);
    double *s = malloc((size_t)(n > 0 ? n : 1) * sizeof(double));
    uint64_t *bits = b->precrack;
    if (bits == NULL)
        bits = calloc((size_t)words + 1, sizeof(uint64_t));
    if (s == NULL || bits == NULL) {
        free(s);
        if (bits != b->precrack)
            free(bits);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the pre-crack");
    }
    pd_status st = PD_OK;
    int64_t any = 0;
    for (int c = 0; c < ncracks && st == PD_OK; c++) {
        double margin = b->horizon > 0 ? b->horizon : 1.0;
        pd_crack whole = cracks[c].through ? span_z(&cracks[c], p, margin) : cracks[c];
        plane q = plane_of(&whole);
        int64_t pairs = 0, bad = -1;
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < n; i++) {
            double x[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
            s[i] = side_value(&q, x);
        }
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : pairs) reduction(max : bad)
        for (int64_t i = lo; i < hi; i++) {
            for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
                int64_t j = b->neighbor[k];
                /* each pair from its lower row a, where both sides are known
                 * to differ */
                const int64_t a = i < j ? i : j, e = i < j ? j : i;
                if ((mirrored && j <= i) || (s[a] >= 0) == (s[e] >= 0))
                    continue;
                double x[3] = {p->x[0][a], p->x[1][a], p->x[2][a]};
                double y[3] = {p->x[0][e], p->x[1][e], p->x[2][e]};
                if (!crosses(&q, x, s[a], y, s[e]))
                    continue;
                if (!mirrored) { /* this bond; its mirror is its own row's */
                    pd_bond_break(b->intact, k);
                    set_bit(bits, k);
                    pairs += j > i;
                    continue;
                }
                int64_t m = mirror(b, i, j);
                if (m < 0) {
                    bad = i;
                    continue;
                }
                pd_bond_break(b->intact, k);
                pd_bond_break(b->intact, m);
                set_bit(bits, k);
                set_bit(bits, m);
                pairs++;
            }
        }
        if (bad >= 0)
            st = pd_fail(PD_ERR_INVALID, "pre-crack: the family of particle %lld is not symmetric",
                         (long long)bad);
        if (counts)
            counts[c] = pairs;
        any += pairs;
    }
    free(s);
    if (b->precrack == NULL && (any > 0 || !mirrored) && st == PD_OK)
        b->precrack = bits; /* a part's: kept, the body's may have some */
    else if (bits != b->precrack)
        free(bits);
    return st;
}

pd_status pd_bonds_precrack(const pd_particles *p, pd_bonds *b, const pd_crack *cracks,
                            int ncracks, int64_t *counts)
{
    return precrack(p, b, cracks, ncracks, counts, 0, p->n, 1);
}

pd_status pd_bonds_precrack_rows(const pd_particles *p, pd_bonds *b, const pd_crack *cracks,
                                 int ncracks, int64_t lo, int64_t hi, int64_t *counts)
{
    return precrack(p, b, cracks, ncracks, counts, lo, hi, 0);
}
