/*
 * cracktip.c -- crack tips, crack fronts, crack extension and crack speed.
 *
 * Seed 004 (Silling & Askari 2005) §5 defines the tip as "the maximum value
 * of x_1 among all nodes i such that phi_i > phi_0", phi the damage of eq.
 * (21) and phi_0 = 0.3, and plots the crack growth distance Delta a(t)
 * (Fig. 7), whose slope is the crack speed (about 1300 m/s there).  Here the
 * coordinate is any axis, taken at the current positions y = x + u (the
 * reference positions when u is not given), and the threshold is a
 * parameter.  A centre crack has two tips, the largest (upper) and the
 * smallest (lower) coordinate; a crack in a 3-D body has a front, the
 * outline of the damaged zone.  With a lattice a tip moves in steps of the
 * spacing, as the seed's Fig. 7 shows; the speed is therefore the slope of
 * a least-squares line through a window of frames, not a bare difference.
 */
#include <gsl/gsl_fit.h>
#include <math.h>
#include <stdlib.h>

#include "pd.h"

static pd_status check_args(int axis, double threshold)
{
    if (axis < 0 || axis > 2)
        return pd_fail(PD_ERR_INVALID, "crack tip axis %d is not 0, 1 or 2", axis);
    if (!isfinite(threshold))
        return pd_fail(PD_ERR_INVALID, "crack tip damage threshold must be finite");
    return PD_OK;
}

pd_status pd_crack_tips(const pd_particles *p, double *const u[3], const double *damage, int axis,
                        double threshold, double *lower, double *upper, int64_t *ndamaged)
{
    *lower = *upper = NAN;
    *ndamaged = 0;
    pd_status s = check_args(axis, threshold);
    if (s != PD_OK)
        return s;
    const double *x = p->x[axis];
    const double *ua = u ? u[axis] : NULL;
    double min = INFINITY, max = -INFINITY;
    int64_t count = 0;
#pragma omp parallel for schedule(static) reduction(min : min) reduction(max : max) \
    reduction(+ : count)
    for (int64_t i = 0; i < p->n; i++) {
        if (!(damage[i] > threshold))
            continue;
        double y = ua ? x[i] + ua[i] : x[i];
        count++;
        if (y > max)
            max = y;
        if (y < min)
            min = y;
    }
    *ndamaged = count;
    if (count) {
        *lower = min;
        *upper = max;
    }
    return PD_OK;
}

pd_status pd_crack_tip(const pd_particles *p, double *const u[3], const double *damage, int axis,
                       double threshold, double *tip, int64_t *ndamaged)
{
    double lower;
    return pd_crack_tips(p, u, damage, axis, threshold, &lower, tip, ndamaged);
}

void pd_crack_extension(int64_t n, const double *tip, int sign, double *da)
{
    int64_t first = 0;
    while (first < n && !isfinite(tip[first]))
        first++;
    for (int64_t k = 0; k < n; k++) {
        if (k < first)
            da[k] = 0.0; /* no crack yet: nothing has grown */
        else if (!isfinite(tip[k]))
            da[k] = NAN;
        else
            da[k] = sign > 0 ? tip[k] - tip[first] : tip[first] - tip[k]; /* no -0 */
    }
}

pd_status pd_crack_speed(int64_t n, const double *time, const double *da, int window,
                         double *speed)
{
    if (window < 1)
        return pd_fail(PD_ERR_INVALID, "crack speed window %d is not at least 1", window);
    int64_t cap = 2 * (int64_t)window + 1 < n ? 2 * (int64_t)window + 1 : n;
    double *t = malloc((size_t)(cap > 0 ? cap : 1) * sizeof *t);
    double *a = malloc((size_t)(cap > 0 ? cap : 1) * sizeof *a);
    if (t == NULL || a == NULL) {
        free(t);
        free(a);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    for (int64_t k = 0; k < n; k++) {
        int m = 0;
        int64_t lo = k - window > 0 ? k - window : 0;
        int64_t hi = k + window < n - 1 ? k + window : n - 1;
        for (int64_t j = lo; j <= hi; j++)
            if (isfinite(time[j]) && isfinite(da[j])) {
                t[m] = time[j];
                a[m] = da[j];
                m++;
            }
        speed[k] = NAN;
        if (m < 2 || !isfinite(da[k]))
            continue;
        /* the slope of the least-squares line a = c0 + c1 t; NaN when the
         * times are all equal (GSL divides by their variance) */
        double c0, c1, cov00, cov01, cov11, sumsq;
        gsl_fit_linear(t, 1, a, 1, (size_t)m, &c0, &c1, &cov00, &cov01, &cov11, &sumsq);
        speed[k] = isfinite(c1) ? c1 : NAN;
    }
    free(t);
    free(a);
    return PD_OK;
}

pd_status pd_crack_front(const pd_particles *p, const pd_bonds *b, const double *damage,
                         double threshold, uint8_t *front, int64_t *nfront)
{
    *nfront = 0;
    if (!isfinite(threshold))
        return pd_fail(PD_ERR_INVALID, "crack front damage threshold must be finite");
    if (b == NULL || b->n != p->n)
        return pd_fail(PD_ERR_INVALID, "crack front needs the bonds of the particles");
    int64_t count = 0;
#pragma omp parallel for schedule(static) reduction(+ : count)
    for (int64_t i = 0; i < p->n; i++) {
        uint8_t on = 0;
        if (damage[i] > threshold)
            for (int64_t k = b->offset[i]; k < b->offset[i + 1] && !on; k++)
                on = !(damage[b->neighbor[k]] > threshold);
        front[i] = on;
        count += on;
    }
    *nfront = count;
    return PD_OK;
}

pd_status pd_crack_front_stats(const pd_particles *p, double *const u[3], const uint8_t *front,
                               const double center[3], int axis, int from_axis,
                               pd_crack_front_info *fi)
{
    fi->n = 0;
    fi->r_max = fi->r_mean = fi->lo = fi->hi = NAN;
    if (axis < 0 || axis > 2)
        return pd_fail(PD_ERR_INVALID, "crack front axis %d is not 0, 1 or 2", axis);
    double rmax = -INFINITY, rsum = 0, lo = INFINITY, hi = -INFINITY;
    int64_t count = 0;
    /* serial: the mean's rounding must not depend on the thread count */
    for (int64_t i = 0; i < p->n; i++) {
        if (!front[i])
            continue;
        double r2 = 0, ya = 0;
        for (int d = 0; d < 3; d++) {
            double y = u ? p->x[d][i] + u[d][i] : p->x[d][i];
            if (d == axis)
                ya = y;
            if (d != axis || !from_axis)
                r2 += (y - center[d]) * (y - center[d]);
        }
        double r = sqrt(r2);
        count++;
        rsum += r;
        if (r > rmax)
            rmax = r;
        if (ya < lo)
            lo = ya;
        if (ya > hi)
            hi = ya;
    }
    fi->n = count;
    if (count) {
        fi->r_max = rmax;
        fi->r_mean = rsum / (double)count;
        fi->lo = lo;
        fi->hi = hi;
    }
    return PD_OK;
}

pd_status pd_crack_connected(const pd_particles *p, const pd_bonds *b, const double *damage,
                             double threshold, uint8_t *keep, int64_t *nkept)
{
    *nkept = 0;
    if (b == NULL || b->n != p->n)
        return pd_fail(PD_ERR_INVALID, "the damaged cluster needs the bonds of the particles");
    if (b->precrack == NULL)
        return pd_fail(PD_ERR_INVALID,
                       "the body has no pre-crack (pd-bonds --crack) for a cluster to grow from");
    int64_t *queue = malloc((size_t)(p->n > 0 ? p->n : 1) * sizeof *queue);
    if (queue == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for %lld particles", (long long)p->n);
    int64_t head = 0, tail = 0;
    /* keep: 1 allowed and not reached, 2 reached; the pre-cracked first */
    for (int64_t i = 0; i < p->n; i++) {
        if (!(keep[i] && damage[i] > threshold)) {
            keep[i] = 0;
            continue;
        }
        int cracked = 0;
        for (int64_t k = b->offset[i]; k < b->offset[i + 1] && !cracked; k++)
            cracked = (int)((b->precrack[k >> 6] >> (k & 63)) & 1);
        if (cracked) {
            keep[i] = 2;
            queue[tail++] = i;
        }
    }
    while (head < tail) { /* breadth first through damaged neighbours */
        const int64_t i = queue[head++];
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            const int64_t j = b->neighbor[k];
            if (keep[j] == 1) {
                keep[j] = 2;
                queue[tail++] = j;
            }
        }
    }
    for (int64_t i = 0; i < p->n; i++)
        keep[i] = keep[i] == 2;
    free(queue);
    *nkept = tail;
    return PD_OK;
}
