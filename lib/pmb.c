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

#define PMB_CHUNK 256 /* bonds per vector pass */

/* The forces of the family of particle i (and with `failure` its breaking
 * test and new s0), written branch-free so that it vectorizes.  Returns 1
 * when some bond of i must break: pmb_break_row then clears their bits. */
static inline __attribute__((always_inline)) int pmb_row(const pd_sim *sim, int64_t i,
                                                         const int failure)
{
    const pd_bonds *b = sim->b;
    const double *restrict w = sim->bond_w;
    const double s00 = sim->sc.s00, alpha = sim->sc.alpha;
    const double *restrict y0 = sim->y[0], *restrict y1 = sim->y[1], *restrict y2 = sim->y[2];
    const double *restrict len = b->length;
    const int32_t *restrict nb = b->neighbor;
    const uint64_t *restrict intact = sim->intact;
    const double *restrict s0 = sim->s0;
    const double yi0 = y0[i], yi1 = y1[i], yi2 = y2[i];
    const double s0i_old = failure ? s0[i] : 0;
    double ax = 0, ay = 0, az = 0, s0i = -INFINITY, nbreak = 0;
    /* the state bits of a chunk of the family as 0/1 doubles, so that the
     * arithmetic below runs on contiguous data */
    double mu[PMB_CHUNK];
    for (int64_t c0 = b->offset[i]; c0 < b->offset[i + 1]; c0 += PMB_CHUNK) {
        const int64_t m = b->offset[i + 1] - c0 < PMB_CHUNK ? b->offset[i + 1] - c0 : PMB_CHUNK;
        for (int64_t q = 0; q < m; q++)
            mu[q] = (double)pd_bond_intact(intact, c0 + q);
        for (int64_t q = 0; q < m; q++) {
            const int64_t k = c0 + q;
            const int32_t j = nb[k];
            const double dx = y0[j] - yi0, dy = y1[j] - yi1, dz = y2[j] - yi2;
            const double r = sqrt(dx * dx + dy * dy + dz * dz);
            double dr = r - len[k];
            dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
            const double s = dr / len[k];
            const double fk = w[k] * s * mu[q];
            const double f = r > 0.0 ? fk / r : 0.0;
            ax += f * dx;
            ay += f * dy;
            az += f * dz;
            if (failure) {
                const double thr = fmin(s0i_old, s0[j]);
                nbreak += s > thr ? mu[q] : 0.0;
                s0i = fmax(s0i, mu[q] > 0 ? s00 - alpha * s : -INFINITY);
            }
        }
    }
    sim->f[0][i] += ax;
    sim->f[1][i] += ay;
    sim->f[2][i] += az;
    if (failure) /* no intact bond: s0 stays +inf (DBL_MAX, as LAMMPS) */
        sim->s0_new[i] = s0i > -INFINITY ? s0i : DBL_MAX;
    return nbreak > 0;
}

/* The rows compiled for AVX-512, AVX2 and the baseline, picked at run time. */
PD_VECTOR_CLONES static int pmb_row_elastic(const pd_sim *sim, int64_t i)
{
    return pmb_row(sim, i, 0);
}

PD_VECTOR_CLONES static int pmb_row_failure(const pd_sim *sim, int64_t i)
{
    return pmb_row(sim, i, 1);
}

/* Clear the bits of i's bonds that fail the test s > min(s0_i, s0_j): the
 * same arithmetic as pmb_row, so both copies of a bond agree. */
static void pmb_break_row(const pd_sim *sim, int64_t i)
{
    const pd_bonds *b = sim->b;
    double *const *y = sim->y;
    for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
        if (!pd_bond_intact(sim->intact, k))
            continue;
        const int32_t j = b->neighbor[k];
        const double dx = y[0][j] - y[0][i], dy = y[1][j] - y[1][i], dz = y[2][j] - y[2][i];
        const double r = sqrt(dx * dx + dy * dy + dz * dz);
        double dr = r - b->length[k];
        dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
        if (dr / b->length[k] > fmin(sim->s0[i], sim->s0[j]))
            pd_bond_break(sim->intact, k);
    }
}

static void pmb_kernel(pd_sim *sim, int failure)
{
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++)
        if (failure ? pmb_row_failure(sim, i) : pmb_row_elastic(sim, i))
            pmb_break_row(sim, i);
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
