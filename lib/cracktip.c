/*
 * cracktip.c -- the position of a crack tip.
 *
 * Seed 004 (Silling & Askari 2005) §5 defines it as "the maximum value of
 * x_1 among all nodes i such that phi_i > phi_0", phi the damage of eq. (21)
 * and phi_0 = 0.3.  Here the coordinate is any axis, taken at the current
 * positions y = x + u (the reference positions when u is not given), and
 * the threshold is a parameter.  With a lattice the tip moves in steps of
 * the spacing, as the seed's Fig. 7 shows.
 */
#include <math.h>

#include "pd.h"

pd_status pd_crack_tip(const pd_particles *p, double *const u[3], const double *damage, int axis,
                       double threshold, double *tip, int64_t *ndamaged)
{
    *tip = NAN;
    *ndamaged = 0;
    if (axis < 0 || axis > 2)
        return pd_fail(PD_ERR_INVALID, "crack tip axis %d is not 0, 1 or 2", axis);
    if (!isfinite(threshold))
        return pd_fail(PD_ERR_INVALID, "crack tip damage threshold must be finite");
    const double *x = p->x[axis];
    const double *ua = u ? u[axis] : NULL;
    double max = -INFINITY;
    int64_t count = 0;
#pragma omp parallel for schedule(static) reduction(max : max) reduction(+ : count)
    for (int64_t i = 0; i < p->n; i++) {
        if (!(damage[i] > threshold))
            continue;
        double y = ua ? x[i] + ua[i] : x[i];
        count++;
        if (y > max)
            max = y;
    }
    *ndamaged = count;
    *tip = count ? max : NAN;
    return PD_OK;
}
