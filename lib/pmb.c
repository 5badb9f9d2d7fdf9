/*
 * pmb.c -- the prototype microelastic brittle (PMB) bond force, seed 000
 * eqs. 5-7 and Algorithm 5; seed 004 eqs. 20-28.
 *
 * For every intact bond i-j with reference length |xi| and current length
 * r = |y_j - y_i|:
 *   s = (r - |xi|) / |xi|                      bond stretch
 *   f_i += c s nu V_j (y_j - y_i) / r          force density on i
 * with dr = r - |xi| set to 0 when |dr| < eps_machine (seed 000, "A
 * Numerical Example"), and no force when r = 0.
 *
 * Failure (seed 000 eqs. 8-9, seed 004 eq. 28): a bond breaks when
 * s > min(s0_i, s0_j), with s0 of the *previous* step; after the test,
 *   s0_i(new) = s00 - alpha s_min = max over i's intact bonds of (s00 - alpha s)
 * (DESIGN.md: eq. 9, not Algorithm 5's min line).  s0 starts at +inf, so no
 * bond breaks before the first step's forces are known, and a bond that
 * breaks still carries its force in the step it breaks (LAMMPS peri/pmb).
 * Bonds never heal.
 *
 * Both directed copies of a bond see bitwise the same stretch and the same
 * min(s0_i, s0_j), so they break together.
 */
#include <float.h>
#include <math.h>

#include "sim.h"

/* Bond forces, and with `failure` the breaking test and the new s0. */
static inline void pmb_kernel(pd_sim *sim, int failure)
{
    const pd_bonds *b = sim->b;
    const double *V = sim->p->volume;
    const double c = sim->sc.c, s00 = sim->sc.s00, alpha = sim->sc.alpha;
    double *const *y = sim->y;
    double *restrict fx = sim->f[0], *restrict fy = sim->f[1], *restrict fz = sim->f[2];
    const double *s0 = sim->s0;
    double *s0_new = sim->s0_new;
    uint64_t *intact = sim->intact;

#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        const double yi0 = y[0][i], yi1 = y[1][i], yi2 = y[2][i];
        double ax = 0, ay = 0, az = 0;
        double s0i = DBL_MAX;
        int first = 1;
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            if (!pd_bond_intact(intact, k))
                continue;
            const int32_t j = b->neighbor[k];
            const double dx = y[0][j] - yi0, dy = y[1][j] - yi1, dz = y[2][j] - yi2;
            const double r = sqrt(dx * dx + dy * dy + dz * dz);
            double dr = r - b->length[k];
            if (fabs(dr) < PD_NEAR_ZERO)
                dr = 0.0;
            const double s = dr / b->length[k];
            const double fk = c * V[j] * b->vfactor[k] * s;
            if (r > 0.0) {
                const double q = fk / r;
                ax += q * dx;
                ay += q * dy;
                az += q * dz;
            }
            if (failure) {
                if (s > fmin(s0[i], s0[j]))
                    pd_bond_break(intact, k);
                const double t = s00 - alpha * s;
                s0i = first ? t : fmax(s0i, t);
                first = 0;
            }
        }
        fx[i] += ax;
        fy[i] += ay;
        fz[i] += az;
        if (failure)
            s0_new[i] = s0i;
    }
}

static pd_status pmb_force(pd_sim *sim, void *state)
{
    (void)state;
    pmb_kernel(sim, 0);
    return PD_OK;
}

static pd_status pmb_failure_force(pd_sim *sim, void *state)
{
    (void)state;
    if (sim->setup) {
        /* the initial state: forces only; s0 stays +inf (seed 000,
         * "Breaking Bonds": no bond breaks before the second step) */
        pmb_kernel(sim, 0);
        return PD_OK;
    }
    pmb_kernel(sim, 1);
    double *t = sim->s0;
    sim->s0 = sim->s0_new;
    sim->s0_new = t;
    return PD_OK;
}

const pd_effect pd_effect_pmb = {"pmb", PD_T_BONDS, NULL, pmb_force, NULL};
const pd_effect pd_effect_pmb_failure = {"pmb+failure", PD_T_BONDS, NULL, pmb_failure_force,
                                         NULL};

double pd_stable_dt(const pd_particles *p, const pd_bonds *b, const pd_scene *s)
{
    /* seed 004 eq. 46: dt < sqrt(2 rho_i / sum_p V_p C_ip), C_ip = c/|xi|
     * for PMB (|df/deta| of f = c s), here with the partial volume nu V_p
     * that the discrete force uses; the smallest over all particles. */
    double best = INFINITY;
    for (int64_t i = 0; i < b->n; i++) {
        double sum = 0;
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++)
            sum += p->volume[b->neighbor[k]] * b->vfactor[k] * s->c / b->length[k];
        if (sum > 0)
            best = fmin(best, sqrt(2.0 * p->density[i] / sum));
    }
    return best;
}

double pd_pmb_c_from_bulk(double bulk_modulus, double horizon)
{
    const double pi = 3.14159265358979323846;
    return PD_PMB_C_FACTOR * bulk_modulus / (pi * pow(horizon, 4));
}
