/*
 * grid_lps.c -- LPS on the stencil (grid.c explains it): the dilatation
 * theta of Algorithm 4, the pair forces of Algorithm 2 and, with failure,
 * the breaking test and the new s0, for bodies in lattice order whose
 * influence function depends on |xi| alone.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>

#include "stencil/grid_impl.h"

/* LPS on the stencil (lib/models/lps.c; omega a function of |xi|, so per offset;
 * the particles in lattice order, so lib/models/lps.c's arrays need no copies).
 * The arithmetic of each bond is lps.c's theta_row and force_row, product
 * for product; each bond is computed once and added to both ends (the pair
 * force t_ij of Algorithm 2 is symmetric: equal volumes, nu_ij = nu_ji). */

/* Algorithm 4's term omega |xi| e nu V of bond g-j (0 when broken), added
 * to the sums of both ends (the bonds of a block whose partner is cut or
 * above, grid_cut); with `energy` also omega e e nu V (energy_row's sum)
 * to sq. */
#define GRID_THETA_BODY                                                                        \
    do {                                                                                       \
        const int64_t j = g + shift;                                                           \
        const double mu = (mask[g * W] & bit) ? 1.0 : 0.0;                                     \
        const double dx = y0[j] - y0[g], dy = y1[j] - y1[g], dz = y2[j] - y2[g];               \
        const double r = sqrt(dx * dx + dy * dy + dz * dz);                                    \
        double e = r - len;                                                                    \
        e = fabs(e) < PD_NEAR_ZERO ? 0.0 : e;                                                  \
        const double c = mu * (oml * e * V * nu);                                              \
        sum[g] += c;                                                                           \
        sum[j] += c;                                                                           \
        if (energy) {                                                                          \
            const double q = mu * (om * e * e * V * nu);                                       \
            sq[g] += q;                                                                        \
            sq[j] += q;                                                                        \
        }                                                                                      \
    } while (0)

/* The dilatation sums of one block's bonds, and with `energy` the
 * energy's sums of squared extensions. */
static inline __attribute__((always_inline)) void
theta_walk(const pd_grid *G, int64_t blk, const grid_arrays *A, double *sum, double *sq, double V,
           const int energy)
{
    const double *restrict y0 = A->y0, *restrict y1 = A->y1, *restrict y2 = A->y2;
    const int W = G->words;
    const int64_t cut = grid_cut(G, blk);
    for (int64_t si = block_seg0(G, blk); si < block_seg0(G, blk + 1); si++) {
        const grid_seg *sg = &G->seg[si];
        const int k = sg->k;
        const uint64_t bit = UINT64_C(1) << (k & 63);
        const uint64_t *restrict mask = G->mask + (k >> 6);
        const int64_t shift = sg->shift, lo = grid_seg_lo(sg, cut, 0);
        const double len = G->len[k], om = G->omega[k], oml = om * len, nu = G->nu[k];
        if (shift >= GRID_SAFE) {
#pragma omp simd safelen(GRID_SAFE)
            for (int64_t g = lo; g < sg->hi; g++)
                GRID_THETA_BODY;
        } else
            for (int64_t g = lo; g < sg->hi; g++)
                GRID_THETA_BODY;
    }
}

PD_VECTOR_CLONES static void lps_theta_block(const pd_grid *G, int64_t blk, const grid_arrays *A,
                                             double *sum, double V)
{
    theta_walk(G, blk, A, sum, NULL, V, 0);
}

/* The pair force of bond g-j (Algorithm 2), its force on g and -it on j,
 * and with failure the test and the new s0 of both ends (as seg_bonds).
 * With ta = theta/m and tb = 1/m of each particle (pd_grid.theta_m and
 * inv_m, computed once a step) and per offset c1 = (3K - 5G) V nu omega
 * |xi| and c2 = 15 G V nu omega,
 *   t = c1 (ta_g + ta_j) + c2 (tb_g + tb_j) e,
 * force_row's t with its products regrouped (equal to rounding). */
#define GRID_LPS_BODY                                                                          \
    do {                                                                                       \
        const int64_t g = c0 + q, j = g + shift;                                               \
        const double mu = (mask[g * W] & bit) ? 1.0 : 0.0;                                     \
        const double dx = y0[j] - y0[g], dy = y1[j] - y1[g], dz = y2[j] - y2[g];               \
        const double r = sqrt(dx * dx + dy * dy + dz * dz);                                    \
        double e = r - len;                                                                    \
        e = fabs(e) < PD_NEAR_ZERO ? 0.0 : e;                                                  \
        const double t = c1 * (ta[g] + ta[j]) + c2 * (tb[g] + tb[j]) * e;                     \
        const double fb = r > 0.0 ? mu * t / r : 0.0;                                          \
        f0[g] += dx * fb;                                                                      \
        f1[g] += dy * fb;                                                                      \
        f2[g] += dz * fb;                                                                      \
        f0[j] -= dx * fb;                                                                      \
        f1[j] -= dy * fb;                                                                      \
        f2[j] -= dz * fb;                                                                      \
        near += r < dc ? 1.0 : 0.0;                                                            \
        if (failure) {                                                                         \
            const double s = e * il;                                                           \
            const double thr = s0[g] < s0[j] ? s0[g] : s0[j];                                  \
            brk[q] = s > thr ? mu : 0.0;                                                       \
            nbreak += brk[q];                                                                  \
            const double tt = mu > 0 ? s00 - (alpha * s) : -INFINITY;                          \
            s0n[g] = tt > s0n[g] ? tt : s0n[g];                                                \
            s0n[j] = tt > s0n[j] ? tt : s0n[j];                                                \
        }                                                                                      \
    } while (0)

#define GRID_LPS_BLOCK(name, with_failure)                                                     \
    PD_VECTOR_CLONES static int name(pd_grid *G, int64_t blk, const grid_arrays *A,            \
                                     const double *restrict ta, const double *restrict tb,     \
                                     double V, double dil, double shear)                       \
    {                                                                                          \
        const int W = G->words, failure = with_failure;                                        \
        const double *restrict y0 = A->y0, *restrict y1 = A->y1, *restrict y2 = A->y2;         \
        const double *restrict s0 = A->s0;                                                     \
        double *f0 = A->f0, *f1 = A->f1, *f2 = A->f2, *s0n = A->s0n;                           \
        const double s00 = A->s00, alpha = A->alpha;                                           \
        const int64_t cut = grid_cut(G, blk);                                                  \
        double brk[GRID_CHUNK];                                                                \
        for (int64_t si = block_seg0(G, blk); si < block_seg0(G, blk + 1); si++) {             \
            const grid_seg *sg = &G->seg[si];                                                  \
            const int k = sg->k;                                                               \
            const uint64_t bit = UINT64_C(1) << (k & 63);                                      \
            const uint64_t *restrict mask = G->mask + (k >> 6);                                \
            const int64_t shift = sg->shift;                                                   \
            const double len = G->len[k], il = G->inv_len[k], dc = G->dc[k];                   \
            const double c1 = dil * V * G->nu[k] * G->omega[k] * len,                          \
                         c2 = PD_LPS_SHEAR_FACTOR * shear * V * G->nu[k] * G->omega[k];        \
            for (int64_t c0 = grid_seg_lo(sg, cut, 0); c0 < sg->hi; c0 += GRID_CHUNK) {        \
                const int64_t n = sg->hi - c0 < GRID_CHUNK ? sg->hi - c0 : GRID_CHUNK;         \
                double nbreak = 0, near = 0;                                                   \
                if (shift >= GRID_SAFE) {                                                      \
                    _Pragma("omp simd reduction(+ : nbreak, near) safelen(16)")               \
                    for (int64_t q = 0; q < n; q++)                                            \
                        GRID_LPS_BODY;                                                         \
                } else                                                                         \
                    for (int64_t q = 0; q < n; q++)                                            \
                        GRID_LPS_BODY;                                                         \
                if (G->cmask && near > 0)                                                      \
                    seg_contact(G, sg, A, c0, n, W);                                           \
                if (failure && nbreak > 0)                                                     \
                    for (int64_t q = 0; q < n; q++)                                            \
                        if (brk[q] > 0 && grid_may_break(G, c0 + q, c0 + q + shift)) {        \
                            G->mask[(c0 + q) * W + (k >> 6)] &= ~bit;                          \
                            if (record_break(&G->breaks[blk], c0 + q, k, c0 + q + shift))      \
                                return -1;                                                     \
                        }                                                                      \
            }                                                                                  \
        }                                                                                      \
        return 0;                                                                              \
    }
GRID_LPS_BLOCK(lps_force_block_0, 0)
GRID_LPS_BLOCK(lps_force_block_1, 1)

/* Of one block's intact bonds (with their partner cut or above), both
 * ends: th += omega |xi| e nu V and sq += omega e e nu V (energy_row's). */
PD_VECTOR_CLONES static void lps_energy_block(const pd_grid *G, int64_t blk, const grid_arrays *A,
                                              double *th, double *sq, double V)
{
    theta_walk(G, blk, A, th, sq, V, 1);
}

int pd_grid_lps_energy(const pd_sim *sim, const double *m, double *e)
{
    pd_grid *G = sim->grid;
    if (G == NULL || G->omega == NULL || G->perm)
        return 0;
    if (G->epoch != sim->half.epoch) { /* the masks of the bonds of now */
        pd_grid_sync((pd_sim *)sim, G);
        if (G->status != PD_OK)
            return 0;
    }
    const int64_t n = G->n;
    double *th = calloc((size_t)(n > 0 ? n : 1), sizeof(double));
    double *sq = calloc((size_t)(n > 0 ? n : 1), sizeof(double));
    if (th == NULL || sq == NULL) {
        free(th);
        free(sq);
        return 0;
    }
    const double V = sim->p->volume[0], K = sim->sc.bulk_modulus, Gs = sim->sc.shear_modulus;
    const grid_arrays A = {.y0 = sim->y[0], .y1 = sim->y[1], .y2 = sim->y[2]};
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel
        for (int64_t blk = grid_walk0(G, phase); blk < G->walk; blk += 2)
            if (grid_mine(G, blk))
                lps_energy_block(G, blk, &A, th, sq, V);
    }
    /* energy_row's: V_i ((K/2 - 5G/6) theta^2 + 15G/2 sum / m_i) */
    const double *Vi = sim->p->volume;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++) {
        if (m[i] == 0.0)
            continue;
        const double t = (PD_LPS_DILATATION / m[i]) * th[i];
        e[i] += Vi[i] * ((0.5 * K - 5.0 * Gs / 6.0) * t * t +
                         0.5 * PD_LPS_SHEAR_FACTOR * Gs / m[i] * sq[i]);
    }
    free(th);
    free(sq);
    return 1;
}

pd_status pd_grid_lps(pd_sim *sim, const double *m, double *theta, pd_bond_mode failure,
                      void (*mark)(void *ctx, int64_t i, int64_t j), void *ctx)
{
    pd_grid *G = sim->grid;
    const int64_t n = G->n;
    if (G->epoch != sim->half.epoch) {
        pd_grid_sync(sim, G);
        if (G->status != PD_OK)
            return G->status;
    }
    const double V = sim->p->volume[0];
    const double dil = PD_LPS_PAIR_FACTOR(sim->sc.bulk_modulus, sim->sc.shear_modulus);
    grid_arrays A = {.y0 = sim->y[0], .y1 = sim->y[1], .y2 = sim->y[2], .f0 = sim->f[0],
                     .f1 = sim->f[1], .f2 = sim->f[2], .s0 = sim->s0, .s0n = sim->s0_new,
                     .s00 = sim->sc.s00, .alpha = sim->sc.alpha};
    /* theta (Algorithm 4): the sums over the bonds, then 3/m_i */
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++)
        theta[i] = 0.0;
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel
        for (int64_t blk = grid_walk0(G, phase); blk < G->walk; blk += 2)
            if (grid_mine(G, blk))
                lps_theta_block(G, blk, &A, theta, V);
    }
    double *ta = G->theta_m, *tb = G->inv_m;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++)
        theta[i] = m[i] != 0.0 ? (PD_LPS_DILATATION / m[i]) * theta[i] : 0.0;
    if (sim->piece) /* the ghosts' theta from their owners (theirs lack bonds) */
        pd_piece_exchange(sim, &theta, 1);
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++) {
        ta[i] = m[i] != 0.0 ? theta[i] / m[i] : 0.0;
        tb[i] = m[i] != 0.0 ? 1.0 / m[i] : 0.0;
        if (failure)
            sim->s0_new[i] = -INFINITY;
    }
    /* the forces (Algorithm 2) and the breaking test */
    int bad = 0;
    for (int64_t blk = 0; blk < G->nblocks; blk++)
        G->breaks[blk].n = 0;
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel reduction(| : bad)
        for (int64_t blk = grid_walk0(G, phase); blk < G->walk; blk += 2)
            if (grid_mine(G, blk))
                bad |= (failure ? lps_force_block_1 : lps_force_block_0)(
                           G, blk, &A, ta, tb, V, dil, sim->sc.shear_modulus) != 0;
    }
    if (bad)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the broken bonds of a step");
    if (!failure)
        return PD_OK;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++) /* no intact bond: +inf (DBL_MAX, as LAMMPS) */
        if (sim->s0_new[i] == -INFINITY)
            sim->s0_new[i] = DBL_MAX;
    for (int64_t blk = 0; blk < G->nblocks; blk++)
        for (int64_t e = 0; e < G->breaks[blk].n; e++)
            mark(ctx, G->breaks[blk].g[e], G->breaks[blk].j[e]);
    return PD_OK;
}
