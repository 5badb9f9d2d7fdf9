/*
 * pmb.c -- the prototype microelastic brittle (PMB) bond force, seed 000
 * eqs. 5-7 and Algorithm 5; seed 004 eqs. 20-28.
 *
 * For every intact bond i-j with reference length |xi| and current length
 * r = |y_j - y_i|:
 *   s = (r - |xi|) / |xi|                      bond stretch
 *   f_i += c s nu_ij V_j (y_j - y_i) / r       force density on i
 *   f_j -= c s nu_ji V_i (y_j - y_i) / r       force density on j
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
 * The run keeps each bond once (i < j, "half bonds"), so a bond's stretch,
 * test and state are computed once and its force is added to both ends.
 * Rows are cut into blocks of at least the largest row distance j - i of a
 * bond, so a block writes only to itself and the next block; even blocks run
 * in parallel, then odd blocks.  Every force density is summed in an order
 * fixed by the blocks alone: the result does not depend on the thread count.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>

#include "models/model.h"
#include "models/pmb_rows.h"
#include "stencil/grid.h"

#define PMB_CHUNK 256 /* bonds per vector pass */

/* mu[q] = the state bit of bond c0 + q, q < m (0 or 1): a word at a time,
 * its bits in a loop the compiler vectorizes. */
static inline __attribute__((always_inline)) void chunk_states(const uint64_t *bits, int64_t c0,
                                                               int64_t m, double *mu)
{
    for (int64_t q = 0; q < m;) {
        const int64_t k = c0 + q, take = 64 - (k & 63) < m - q ? 64 - (k & 63) : m - q;
        const uint64_t w = __atomic_load_n(&bits[k >> 6], __ATOMIC_RELAXED) >> (k & 63);
        for (int64_t t = 0; t < take; t++)
            mu[q + t] = (double)((w >> t) & 1);
        q += take;
    }
}

/* The forces of the half bonds of row i (and with `failure` their breaking
 * test and the new s0 of both ends; PD_BONDS_FAILURE_LAWS: each bond's threshold times
 * its kfail, lib/models/materials.c), branch-free so that the arithmetic
 * vectorizes; the scatter to the partners j is a plain loop. */
static inline __attribute__((always_inline)) void pmb_row(pd_sim *sim, int64_t i,
                                                          const pd_bond_mode failure, double *released)
{
    pd_half_bonds *h = &sim->half;
    const double s00 = sim->sc.s00, alpha = sim->sc.alpha;
    const double *restrict y0 = sim->y[0], *restrict y1 = sim->y[1], *restrict y2 = sim->y[2];
    const double *restrict len = h->length, *restrict wij = h->w_ij, *restrict wji = h->w_ji;
    const int32_t *restrict nb = h->neighbor;
    const double *restrict s0 = sim->s0;
    const double *restrict kf = h->kfail;
    double *restrict fx = sim->f[0], *restrict fy = sim->f[1], *restrict fz = sim->f[2];
    double *restrict s0_new = sim->s0_new;
    const double yi0 = y0[i], yi1 = y1[i], yi2 = y2[i];
    const double s0i_old = failure ? s0[i] : 0;
    double ax = 0, ay = 0, az = 0, s0i = -INFINITY;
    double mu[PMB_CHUNK], gx[PMB_CHUNK], gy[PMB_CHUNK], gz[PMB_CHUNK], t[PMB_CHUNK],
        brk[PMB_CHUNK];
    for (int64_t c0 = h->offset[i]; c0 < h->offset[i + 1]; c0 += PMB_CHUNK) {
        const int64_t m = h->offset[i + 1] - c0 < PMB_CHUNK ? h->offset[i + 1] - c0 : PMB_CHUNK;
        chunk_states(h->intact, c0, m, mu);
        for (int64_t q = 0; q < m; q++) {
            const int64_t k = c0 + q;
            const int32_t j = nb[k];
            const double dx = y0[j] - yi0, dy = y1[j] - yi1, dz = y2[j] - yi2;
            const double r = sqrt(dx * dx + dy * dy + dz * dz);
            double dr = r - len[k];
            dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
            const double s = dr / len[k];
            const double fi = r > 0.0 ? wij[k] * s * mu[q] / r : 0.0;
            const double fj = r > 0.0 ? wji[k] * s * mu[q] / r : 0.0;
            ax += fi * dx;
            ay += fi * dy;
            az += fi * dz;
            gx[q] = fj * dx;
            gy[q] = fj * dy;
            gz[q] = fj * dz;
            if (failure) { /* ternaries, not fmin/fmax: they vectorize */
                const double thr = failure == PD_BONDS_FAILURE_LAWS ? kf[k] * (s0i_old < s0[j] ? s0i_old : s0[j])
                                                : s0i_old < s0[j] ? s0i_old : s0[j];
                brk[q] = s > thr ? mu[q] : 0.0;
                t[q] = mu[q] > 0 ? s00 - alpha * s : -INFINITY;
            }
        }
        /* the partners' share, and the per-particle reductions of failure */
        double nbreak = 0;
        for (int64_t q = 0; q < m; q++) {
            const int32_t j = nb[c0 + q];
            fx[j] -= gx[q];
            fy[j] -= gy[q];
            fz[j] -= gz[q];
            if (failure) {
                s0_new[j] = t[q] > s0_new[j] ? t[q] : s0_new[j];
                s0i = t[q] > s0i ? t[q] : s0i;
                nbreak += brk[q];
            }
        }
        if (failure && nbreak > 0)
            for (int64_t q = 0; q < m; q++)
                if (brk[q] > 0 && pd_sim_may_break(sim, i, nb[c0 + q])) {
                    pd_bond_break(h->intact, c0 + q);
                    *released += pmb_bond_energy(sim, i, c0 + q);
                }
    }
    fx[i] += ax;
    fy[i] += ay;
    fz[i] += az;
    if (failure)
        s0_new[i] = s0i > s0_new[i] ? s0i : s0_new[i];
}

/* Rows compiled for AVX-512, AVX2 and the baseline, picked at run time. */
PD_VECTOR_CLONES static void pmb_block_elastic(pd_sim *sim, int64_t lo, int64_t hi)
{
    for (int64_t i = lo; i < hi; i++)
        pmb_row(sim, i, PD_BONDS_ELASTIC, NULL);
}

PD_VECTOR_CLONES static void pmb_block_failure(pd_sim *sim, int64_t lo, int64_t hi,
                                               double *released)
{
    for (int64_t i = lo; i < hi; i++)
        pmb_row(sim, i, PD_BONDS_FAILURE, released);
}

/* The same with each bond's own critical stretch (h->kfail). */
PD_VECTOR_CLONES static void pmb_block_failure_laws(pd_sim *sim, int64_t lo, int64_t hi,
                                                    double *released)
{
    for (int64_t i = lo; i < hi; i++)
        pmb_row(sim, i, PD_BONDS_FAILURE_LAWS, released);
}

/* pmb_rows_energy, in lanes where the run has them (their bits first
 * brought up to the half bonds'). */
static int rows_energy(const pd_sim *sim, double *e, int contact)
{
#if PD_AVX512_KERNELS
    if (sim->half.lanes) {
        pmb_lanes_sync((pd_sim *)sim); /* scratch the run keeps */
        return pmb_rows_energy(sim, e, contact, pmb_lanes_energy_block);
    }
#endif
    return pmb_rows_energy(sim, e, contact, NULL);
}

void pd_half_contact_energy(const pd_sim *sim, double *e)
{
    if (!sim->half.contact || rows_energy(sim, e, 1))
        return;
    const pd_bonds *b = sim->b;
    const double k = PD_CONTACT_SCALE * sim->sc.c / b->horizon;
    const double *V = sim->p->volume, *rad = sim->p->radius;
    double *const *y = sim->y;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        if (sim->lost && sim->lost[i])
            continue;
        double sum = 0;
        for (int64_t q = b->offset[i]; q < b->offset[i + 1]; q++) {
            const int32_t j = b->neighbor[q];
            if (sim->lost && sim->lost[j])
                continue;
            const double dx = y[0][j] - y[0][i], dy = y[1][j] - y[1][i], dz = y[2][j] - y[2][i];
            const double r2 = dx * dx + dy * dy + dz * dz;
            const double d0 = PD_CONTACT_REF_FRAC * b->length[q],
                         d1 = PD_CONTACT_RADIUS_FAC * (rad[i] + rad[j]);
            const double d = d0 < d1 ? d0 : d1; /* fmin, inlined */
            if (!(r2 < d * d)) /* most pairs: no square root */
                continue;
            const double r = sqrt(r2);
            if (r < d)
                sum += 0.25 * k * (d - r) * (d - r) * V[j];
        }
        e[i] += sum * V[i];
    }
}

double pd_half_contact_cap(const pd_particles *p)
{
    double rmin = INFINITY, rmax = 0;
    for (int64_t i = 0; i < p->n; i++) {
        rmin = fmin(rmin, p->radius[i]);
        rmax = fmax(rmax, p->radius[i]);
    }
    rmin = -pd_body_max(p, -rmin); /* a window: over the ranks */
    rmax = pd_body_max(p, rmax);
    return rmin == rmax ? PD_CONTACT_RADIUS_FAC * (rmax + rmax) : INFINITY;
}

/* Does this run take the AVX-512 rows (lib/models/pmb_rows.c: where the
 * processor has AVX-512 F, VL and DQ and PD_NO_AVX512 is not set; any
 * other build or processor walks pmb_row)?  Then h->pack is there. */
static pd_status pmb_rows_init(pd_sim *sim)
{
#if PD_AVX512_KERNELS
    pd_half_bonds *h = &sim->half;
    if (h->pack || !__builtin_cpu_supports("avx512f") || !__builtin_cpu_supports("avx512vl") ||
        !__builtin_cpu_supports("avx512dq") || getenv("PD_NO_AVX512"))
        return PD_OK;
    size_t bytes = (size_t)(sim->n > 0 ? sim->n : 1) * 8 * sizeof(double);
    if ((h->pack = aligned_alloc(64, bytes)) == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the bond list's rows");
    if (!sim->sc.has_contact) {
        pmb_lanes_build(sim);
        return PD_OK;
    }
    /* the rows take the contact of the half bonds' pairs; the contact list
     * the others, which started at least `gap` apart (the horizon, unless
     * the families leave out a closer pair) */
    pd_status s = pd_half_gap(h, sim->b, sim->p, &h->gap);
    if (s != PD_OK)
        return s;
    h->contact_cap = pd_half_contact_cap(sim->p);
    h->contact = 1;
    pmb_lanes_build(sim);
#else
    (void)sim;
#endif
    return PD_OK;
}

/* A block of the bond pass (pmb_walk_blocks): its rows' forces, and with
 * failure their breaks and released energy. */
typedef struct {
    pd_sim *sim;
    pd_bond_mode failure;
    int energy;
} pmb_pass;

static void pmb_block(const pd_sim *csim, int64_t blk, int64_t lo, int64_t hi, void *ctx)
{
    const pmb_pass *ps = ctx;
    pd_sim *sim = ps->sim; /* csim, writable */
    (void)csim;
    pd_half_bonds *h = &sim->half;
    if (ps->failure)
        h->released[blk] = 0;
#if PD_AVX512_KERNELS
    if (h->lanes) {
        pmb_lanes_block(sim, blk, lo, ps->failure, ps->energy, &h->released[blk]);
        return;
    }
    if (h->pack) {
        pmb_rows_block(sim, lo, hi, ps->failure, ps->energy, &h->released[blk]);
        return;
    }
#endif
    if (ps->failure == PD_BONDS_FAILURE_LAWS)
        pmb_block_failure_laws(sim, lo, hi, &h->released[blk]);
    else if (ps->failure)
        pmb_block_failure(sim, lo, hi, &h->released[blk]);
    else
        pmb_block_elastic(sim, lo, hi);
}

static void pmb_blocks(pd_sim *sim, pd_bond_mode failure, int energy)
{
    pmb_pass ps = {sim, failure, energy};
    pmb_walk_blocks(sim, pmb_block, &ps);
}

static void pmb_kernel(pd_sim *sim, pd_bond_mode failure)
{
    const pd_half_bonds *h = &sim->half;
    double *restrict pk = h->pack;
    /* failure's bookkeeping outside the fused loop (the s0_new reset and
     * finish, the released-energy sum) goes to its own timer, taken out of
     * the bonds' one that pd_sim_compute_forces charges the whole call to;
     * the rows' copy in and out, which does the reset and finish too, is
     * the bonds' */
    double tf = 0, t0;
    if (pk) /* the rows' copy: positions and s0, forces 0 and new s0 -inf */
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < sim->n; i++) {
            double *p = pk + 8 * i;
            p[0] = sim->y[0][i];
            p[1] = sim->y[1][i];
            p[2] = sim->y[2][i];
            p[3] = failure ? sim->s0[i] : 0.0;
            p[4] = p[5] = p[6] = 0.0;
            p[7] = -INFINITY;
        }
    else if (failure) {
        t0 = pd_wtime();
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < sim->n; i++)
            sim->s0_new[i] = -INFINITY;
        tf += pd_wtime() - t0;
    }
    const int energy = pmb_rows_count(sim);
    pmb_lanes_sync(sim); /* the lanes' bits, where the half bonds' moved on */
    pmb_blocks(sim, !failure ? PD_BONDS_ELASTIC : h->kfail ? PD_BONDS_FAILURE_LAWS : failure,
               energy);
    if (energy) { /* the step's energies, counted */
        sim->half.energy_ok = 1;
        sim->half.energy_step = sim->step;
        sim->half.energy_epoch = h->epoch;
    }
    if (pk) /* the rows' forces added to the step's, and their new s0 */
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < sim->n; i++) {
            const double *p = pk + 8 * i + 4;
            sim->f[0][i] += p[0];
            sim->f[1][i] += p[1];
            sim->f[2][i] += p[2];
            if (failure) /* no intact bond: +inf (DBL_MAX, as LAMMPS) */
                sim->s0_new[i] = p[3] == -INFINITY ? DBL_MAX : p[3];
        }
    if (!failure)
        return;
    t0 = pd_wtime();
    if (!pk)
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < sim->n; i++) /* no intact bond: +inf (DBL_MAX, as LAMMPS) */
            if (sim->s0_new[i] == -INFINITY)
                sim->s0_new[i] = DBL_MAX;
    pd_sim_add_released(sim, h->released, h->nblocks); /* in block order: any thread count */
    tf += pd_wtime() - t0;
    sim->timers[PD_T_FAILURE] += tf;
    sim->timers[PD_T_BONDS] -= tf;
}

static pd_status pmb_force(pd_sim *sim, void *state)
{
    (void)state;
    if (sim->grid)
        return pd_grid_pmb(sim, PD_BONDS_ELASTIC);
    pmb_kernel(sim, PD_BONDS_ELASTIC);
    return PD_OK;
}

static pd_status pmb_failure_force(pd_sim *sim, void *state)
{
    (void)state;
    if (sim->setup) {
        /* the initial state: forces only; s0 stays +inf (seed 000,
         * "Breaking Bonds": no bond breaks before the second step) */
        if (sim->grid)
            return pd_grid_pmb(sim, PD_BONDS_ELASTIC);
        pmb_kernel(sim, PD_BONDS_ELASTIC);
        return PD_OK;
    }
    if (sim->grid) {
        pd_status st = pd_grid_pmb(sim, PD_BONDS_FAILURE);
        if (st != PD_OK)
            return st;
    } else
        pmb_kernel(sim, PD_BONDS_FAILURE);
    double *t = sim->s0;
    sim->s0 = sim->s0_new;
    sim->s0_new = t;
    sim->intact_stale = 1;
    return PD_OK;
}

/* sum_j 1/4 c s^2 |xi| nu V_j over the intact bonds of family F of
 * particle i, branch-free (a broken bond times 0) so that it vectorizes. */
PD_VECTOR_CLONES static double family_energy(const pd_family *F, const uint64_t *intact,
                                             double *const *y, const double *V, double c,
                                             int64_t i)
{
    double sum = 0, mu[PMB_CHUNK];
    for (int64_t c0 = 0; c0 < F->n; c0 += PMB_CHUNK) {
        const int64_t m = F->n - c0 < PMB_CHUNK ? F->n - c0 : PMB_CHUNK;
        chunk_states(intact, F->first + c0, m, mu);
        for (int64_t t = 0; t < m; t++) {
            const int32_t j = F->j[c0 + t];
            const double L = F->length[c0 + t];
            const double dx = y[0][j] - y[0][i], dy = y[1][j] - y[1][i], dz = y[2][j] - y[2][i];
            double dr = sqrt(dx * dx + dy * dy + dz * dz) - L;
            dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
            const double s = dr / L;
            sum += mu[t] * (0.25 * c * s * s * L * F->vfactor[c0 + t] * V[j]);
        }
    }
    return sum;
}

/* The bonds' energy, half of each bond to each end (directed bonds, each
 * row its own sum): e_i += sum_j 1/4 c s^2 |xi| nu_ij V_i V_j. */
static void pmb_energy_uniform(const pd_sim *sim, void *state, double *e)
{
    (void)state;
    const pd_bonds *b = sim->b;
    const uint64_t *intact = pd_sim_intact(sim);
    const double *V = sim->p->volume, c = sim->sc.c;
    double *const *y = sim->y;
#pragma omp parallel
    {
        pd_family_buf fb = {0};
        pd_family F;
#pragma omp for schedule(static)
        for (int64_t i = 0; i < sim->n; i++) {
            if (pd_family_get(b, sim->p, i, &fb, &F) != 0) {
                e[i] = NAN; /* out of memory: never a wrong number */
                continue;
            }
            e[i] += family_energy(&F, intact, y, V, c, i) * V[i];
        }
        pd_family_buf_free(&fb);
    }
}

/* The static virial of each particle's intact bonds (pd_sim_stress):
 * s_i += 1/2 sum_j V_j f_ij (x) xi_ij with f_ij = c s nu_ij (y_j - y_i)/r,
 * the force density bond j puts on i per unit volume of j.  Directed
 * bonds, each row its own sum: the same at any thread count. */
static void pmb_stress_uniform(const pd_sim *sim, void *state, double *out)
{
    (void)state;
    const pd_bonds *b = sim->b;
    const uint64_t *intact = pd_sim_intact(sim);
    const double *V = sim->p->volume, c = sim->sc.c;
    double *const *y = sim->y;
    double *const *x = sim->p->x;
#pragma omp parallel
    {
        pd_family_buf fb = {0};
        pd_family F;
#pragma omp for schedule(static)
        for (int64_t i = 0; i < sim->n; i++) {
            double sum[9] = {0};
            if (pd_family_get(b, sim->p, i, &fb, &F) != 0)
                for (int m = 0; m < 9; m++) /* out of memory: never a wrong number */
                    sum[m] = NAN;
            for (int64_t t = 0; t < F.n; t++) {
                if (!pd_bond_intact(intact, F.first + t))
                    continue;
                const int32_t j = F.j[t];
                const double e[3] = {y[0][j] - y[0][i], y[1][j] - y[1][i], y[2][j] - y[2][i]};
                const double r = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
                double dr = r - F.length[t];
                dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
                if (r <= 0.0)
                    continue;
                const double f = 0.5 * c * (dr / F.length[t]) * F.vfactor[t] * V[j] / r;
                const double xi[3] = {x[0][j] - x[0][i], x[1][j] - x[1][i], x[2][j] - x[2][i]};
                for (int a = 0; a < 3; a++)
                    for (int d = 0; d < 3; d++)
                        sum[3 * a + d] += f * e[a] * xi[d];
            }
            for (int m = 0; m < 9; m++)
                out[9 * i + m] += sum[m];
        }
        pd_family_buf_free(&fb);
    }
}

/* The same two with each bond's own c (lib/models/materials.c), apart so that a
 * scene without laws keeps the loops above bit for bit. */
static void pmb_energy_laws(const pd_sim *sim, double *e)
{
    const pd_bonds *b = sim->b;
    const uint64_t *intact = pd_sim_intact(sim);
    const double *V = sim->p->volume;
    double *const *y = sim->y;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        double sum = 0;
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            if (!pd_bond_intact(intact, k))
                continue;
            const int32_t j = b->neighbor[k];
            const double dx = y[0][j] - y[0][i], dy = y[1][j] - y[1][i], dz = y[2][j] - y[2][i];
            double dr = sqrt(dx * dx + dy * dy + dz * dz) - b->length[k];
            dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
            const double s = dr / b->length[k];
            double c, s00;
            pd_bond_law_of(sim->p, &sim->sc, i, j, &c, &s00);
            sum += 0.25 * c * s * s * b->length[k] * b->vfactor[k] * V[j];
        }
        e[i] += sum * V[i];
    }
}

static void pmb_stress_laws(const pd_sim *sim, double *out)
{
    const pd_bonds *b = sim->b;
    const uint64_t *intact = pd_sim_intact(sim);
    const double *V = sim->p->volume;
    double *const *y = sim->y;
    double *const *x = sim->p->x;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        double sum[9] = {0};
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            if (!pd_bond_intact(intact, k))
                continue;
            const int32_t j = b->neighbor[k];
            const double e[3] = {y[0][j] - y[0][i], y[1][j] - y[1][i], y[2][j] - y[2][i]};
            const double r = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
            double dr = r - b->length[k];
            dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
            if (r <= 0.0)
                continue;
            double c, s00;
            pd_bond_law_of(sim->p, &sim->sc, i, j, &c, &s00);
            const double f = 0.5 * c * (dr / b->length[k]) * b->vfactor[k] * V[j] / r;
            const double xi[3] = {x[0][j] - x[0][i], x[1][j] - x[1][i], x[2][j] - x[2][i]};
            for (int a = 0; a < 3; a++)
                for (int d = 0; d < 3; d++)
                    sum[3 * a + d] += f * e[a] * xi[d];
        }
        for (int m = 0; m < 9; m++)
            out[9 * i + m] += sum[m];
    }
}

static void pmb_energy(const pd_sim *sim, void *state, double *e)
{
    if (sim->grid)
        pd_grid_pmb_energy(sim, e);
    else if (pd_scene_has_laws(&sim->sc))
        pmb_energy_laws(sim, e);
    else if (!rows_energy(sim, e, 0))
        pmb_energy_uniform(sim, state, e);
}

static void pmb_stress(const pd_sim *sim, void *state, double *out)
{
    if (pd_scene_has_laws(&sim->sc))
        pmb_stress_laws(sim, out);
    else
        pmb_stress_uniform(sim, state, out);
}

/* The bond list's lengths and weights where the lattice stencil does not
 * walk the bonds, each bond's own c and failure factor with laws. */
static pd_status pmb_init(pd_sim *sim, void **state)
{
    (void)state;
    pd_status s = pd_scene_has_laws(&sim->sc) ? pd_bond_laws_check(sim->p, &sim->sc) : PD_OK;
    if (s == PD_OK && !sim->grid)
        s = pd_half_weights(sim->p, sim->b, sim->sc.c, &sim->half);
    if (s == PD_OK && !sim->grid && pd_scene_has_laws(&sim->sc))
        s = pd_half_laws(sim->p, sim->b, &sim->sc, &sim->half);
    if (s == PD_OK && !sim->grid)
        s = pmb_rows_init(sim);
    return s;
}

const pd_effect pd_effect_pmb = {
    .name = "pmb", .timer = PD_T_BONDS, .init = pmb_init, .force = pmb_force,
    .energy = pmb_energy, .kind = PD_ENERGY_ELASTIC, .stress = pmb_stress};
const pd_effect pd_effect_pmb_failure = {
    .name = "pmb+failure", .timer = PD_T_BONDS, .init = pmb_init, .force = pmb_failure_force,
    .energy = pmb_energy, .kind = PD_ENERGY_ELASTIC, .stress = pmb_stress};

/* pd_bond_stiffness with the caller's buffer: a compact family goes
 * through arrays too, so that the compiler's vectorized sum (VEC_CFLAGS)
 * is the lists' own. */
static double stiffness(const pd_particles *p, const pd_bonds *b, double c, int64_t i,
                        pd_family_buf *fb)
{
    pd_family F;
    if (pd_family_get(b, p, i, fb, &F) != 0)
        return NAN;
    double sum = 0;
    for (int64_t t = 0; t < F.n; t++)
        sum += p->volume[F.j[t]] * F.vfactor[t] * c / F.length[t];
    return sum;
}

double pd_bond_stiffness(const pd_particles *p, const pd_bonds *b, double c, int64_t i)
{
    pd_family_buf fb = {0};
    const double sum = stiffness(p, b, c, i, &fb);
    pd_family_buf_free(&fb);
    return sum;
}

static double pmb_stable_dt(const pd_particles *p, const pd_bonds *b, const pd_scene *s)
{
    /* seed 004 eq. 46: dt < sqrt(2 rho_i / sum_p V_p C_ip), C_ip = c/|xi|
     * for PMB (|df/deta| of f = c s), here with the partial volume nu V_p
     * that the discrete force uses; the smallest over all particles. */
    double best = INFINITY;
    int bad = 0; /* a buffer out of memory: NaN, never a wrong step */
#pragma omp parallel reduction(min : best) reduction(| : bad)
    {
        pd_family_buf fb = {0};
#pragma omp for schedule(static) /* each particle's own sum; min in any order */
        for (int64_t i = 0; i < b->n; i++) {
            double sum = pd_scene_has_laws(s) ? pd_bond_stiffness_laws(p, b, s, i)
                                              : stiffness(p, b, s->c, i, &fb);
            bad |= isnan(sum);
            if (sum > 0)
                best = fmin(best, sqrt(2.0 * p->density[i] / sum));
        }
        pd_family_buf_free(&fb);
    }
    return bad ? NAN : best;
}

/* One c and s00 for every bond: the lattice stencil's PMB kernels. */
static pd_stencil_kind pmb_stencil(const pd_scene *s)
{
    return pd_scene_has_laws(s) ? PD_STENCIL_NONE : PD_STENCIL_PMB;
}

static const char *const pmb_takes[] = {"--c", "--bulk-modulus", "--youngs-modulus",
                                        "--failure-energy", "--material", "--interface",
                                        "--fibre", NULL};

const pd_model pd_model_pmb = {
    .name = "pmb", .kind = PD_MODEL_PMB, .force = &pd_effect_pmb,
    .force_failure = &pd_effect_pmb_failure, .stable_dt = pmb_stable_dt, .stencil = pmb_stencil,
    .takes = pmb_takes, .fields = PD_FIELD_ENERGY | PD_FIELD_STRESS};

double pd_pmb_c_from_bulk(double bulk_modulus, double horizon)
{
    const double pi = 3.14159265358979323846;
    return PD_PMB_C_FACTOR * bulk_modulus / (pi * pow(horizon, 4));
}

double pd_pmb_s0_from_energy(double g0, double c, double horizon)
{
    const double pi = 3.14159265358979323846;
    return sqrt(10.0 * g0 / (pi * c * pow(horizon, 5)));
}
