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

#include "effects/effect.h"

/* The centre at the current step. */
static void centre(const pd_sim *sim, double c[3])
{
    const pd_scene *s = &sim->sc;
    pd_indenter_centre(s->ind_center, s->ind_velocity, sim->step, s->dt, c);
}

/* The sphere's force density on particle i (not lost), added to sim->f and
 * into f; 0 when the sphere does not touch it. */
static inline int push_row(pd_sim *sim, const double c[3], double R, double K, int64_t i,
                           double f[3])
{
    double *const *y = sim->y;
    const double dx = y[0][i] - c[0], dy = y[1][i] - c[1], dz = y[2][i] - c[2];
    const double r2 = dx * dx + dy * dy + dz * dz;
    if (r2 >= R * R || (sim->lost && sim->lost[i]))
        return 0;
    const double r = sqrt(r2);
    const double dr = r - R;
    if (dr >= 0.0 || r <= 0.0)
        return 0;
    const double fmag = K * dr * dr;
    f[0] = dx * fmag / r, f[1] = dy * fmag / r, f[2] = dz * fmag / r;
    sim->f[0][i] += f[0];
    sim->f[1][i] += f[1];
    sim->f[2][i] += f[2];
    return 1;
}

void pd_sphere_push(pd_sim *sim, const double c[3], double R, double K, double F[3])
{
    const double *V = sim->p->volume;
    const int64_t n = sim->n, nchunks = (n + PD_SUM_CHUNK - 1) / PD_SUM_CHUNK;
    F[0] = F[1] = F[2] = 0;
    if (sim->piece) { /* a piece of the body: its own rows' V_i f_i, summed over the ranks */
        double *w[3] = {sim->piece->sum3, sim->piece->sum3 + n, sim->piece->sum3 + 2 * n};
        const int64_t own_lo = sim->piece->own_lo, own_hi = sim->piece->own_hi;
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < n; i++) {
            double f[3];
            w[0][i] = w[1][i] = w[2][i] = 0;
            if (push_row(sim, c, R, K, i, f) && i >= own_lo && i < own_hi)
                for (int d = 0; d < 3; d++)
                    w[d][i] = V[i] * f[d];
        }
        pd_sim_sum(sim, (const double *const *)w, 3, F);
        return;
    }
    for (int64_t g = 0; g < nchunks; g += 64) {
        const int64_t m = nchunks - g < 64 ? nchunks - g : 64;
        double part[64][3];
#pragma omp parallel for schedule(static)
        for (int64_t ch = 0; ch < m; ch++) {
            const int64_t lo = (g + ch) * PD_SUM_CHUNK;
            const int64_t hi = lo + PD_SUM_CHUNK < n ? lo + PD_SUM_CHUNK : n;
            double sx = 0, sy = 0, sz = 0;
            for (int64_t i = lo; i < hi; i++) {
                double f[3];
                if (!push_row(sim, c, R, K, i, f))
                    continue;
                sx += V[i] * f[0];
                sy += V[i] * f[1];
                sz += V[i] * f[2];
            }
            part[ch][0] = sx;
            part[ch][1] = sy;
            part[ch][2] = sz;
        }
        for (int64_t ch = 0; ch < m; ch++)
            for (int d = 0; d < 3; d++)
                F[d] += part[ch][d];
    }
}

void pd_sphere_energy(const pd_sim *sim, const double c[3], double R, double K, double *e)
{
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        const double dx = sim->y[0][i] - c[0], dy = sim->y[1][i] - c[1], dz = sim->y[2][i] - c[2];
        const double r = sqrt(dx * dx + dy * dy + dz * dz);
        if (r < R && !(sim->lost && sim->lost[i]))
            e[i] += sim->p->volume[i] * K * (R - r) * (R - r) * (R - r) / 3.0;
    }
}

/* Forces, and the power the moving sphere puts in: its potential
 * U = sum V_i K (R - r)^3 / 3 depends on time through c(t), and
 * dU/dt = v . sum V_i f_i (pd_energy.work integrates it). */
static pd_status indenter_force(pd_sim *sim, void *state)
{
    (void)state;
    const pd_scene *s = &sim->sc;
    double c[3], F[3];
    centre(sim, c);
    pd_sphere_push(sim, c, s->ind_radius, s->ind_k, F);
    for (int d = 0; d < 3; d++)
        sim->ind_f[d] = -F[d];
    sim->power += s->ind_velocity[0] * F[0] + s->ind_velocity[1] * F[1] +
                  s->ind_velocity[2] * F[2];
    return PD_OK;
}

/* The sphere's penalty energy, V_i K (R - r)^3 / 3 (fix indent's). */
static void indenter_energy(const pd_sim *sim, void *state, double *e)
{
    (void)state;
    double c[3];
    centre(sim, c);
    pd_sphere_energy(sim, c, sim->sc.ind_radius, sim->sc.ind_k, e);
}

static int indenter_declared(const pd_scene *s)
{
    return s->has_indenter;
}

const pd_effect pd_effect_indenter = {
    .name = "indenter", .timer = PD_T_INDENTER, .force = indenter_force,
    .energy = indenter_energy, .kind = PD_ENERGY_CONTACT, .declared = indenter_declared};
