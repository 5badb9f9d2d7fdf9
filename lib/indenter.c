/*
 * indenter.c -- a spherical indenter moving at constant velocity (LAMMPS
 * `fix indent ... sphere`, used by the seed 000 impact example).
 *
 * Centre c(t) = c0 + t v, with t = n dt at step n.  Every particle inside
 * the sphere (r = |y_i - c| < R) feels the repulsive force density
 *   f_i += K (R - r)^2 (y_i - c) / r,
 * which is what fix indent adds to the force of a peri particle (whose
 * "force" is a force density, so K has units N/m^5).  The sphere is rigid
 * and does not feel the body: see --projectile (a later issue) for that.
 */
#include <math.h>

#include "sim.h"

static pd_status indenter_force(pd_sim *sim, void *state)
{
    (void)state;
    const pd_scene *s = &sim->sc;
    /* the same evaluation order as the LAMMPS example: y0 + (step*dt)*v */
    const double t = (double)sim->step * s->dt;
    const double c0 = s->ind_center[0] + t * s->ind_velocity[0];
    const double c1 = s->ind_center[1] + t * s->ind_velocity[1];
    const double c2 = s->ind_center[2] + t * s->ind_velocity[2];
    const double R = s->ind_radius, K = s->ind_k;
    double *const *y = sim->y;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        const double dx = y[0][i] - c0, dy = y[1][i] - c1, dz = y[2][i] - c2;
        const double r2 = dx * dx + dy * dy + dz * dz;
        if (r2 >= R * R)
            continue;
        const double r = sqrt(r2);
        const double dr = r - R;
        if (dr >= 0.0 || r <= 0.0)
            continue;
        const double fmag = K * dr * dr;
        sim->f[0][i] += dx * fmag / r;
        sim->f[1][i] += dy * fmag / r;
        sim->f[2][i] += dz * fmag / r;
    }
    return PD_OK;
}

const pd_effect pd_effect_indenter = {"indenter", PD_T_INDENTER, NULL, indenter_force, NULL};
