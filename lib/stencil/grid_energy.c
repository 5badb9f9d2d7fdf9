/*
 * grid_energy.c -- what the stencil counts besides the forces (grid.c
 * explains it): the bonds' elastic energy and the contact energy of the
 * stencil pairs per particle, and the largest damage.
 */
#include <math.h>
#include <stdlib.h>

#include "stencil/grid_impl.h"

/* The energy of the stencil pairs, half of each pair to each end: with
 * `contact`, e_i += 1/4 (c_S/delta) (d_k - r)^2 V_i V_j over the contact
 * pairs closer than d_k (lib/effects/contact.c's), else e_i += 1/4 c s^2 |xi| nu
 * V_i V_j over the intact bonds (lib/models/pmb.c's pmb_energy).  Even blocks,
 * then odd ones, so that no two threads add to one particle. */
static inline __attribute__((always_inline)) void
seg_energy(const pd_sim *sim, const pd_grid *G, const grid_seg *sg, int64_t cut, double *e,
           const int contact)
{
    const double V = sim->p->volume[0];
    const int W = G->words, k = sg->k;
    const uint64_t bit = UINT64_C(1) << (k & 63);
    const uint64_t *bits = (contact ? G->cmask : G->mask) + (k >> 6);
    const double L = G->len[k], iL = G->inv_len[k], dc = G->dc[k];
    const double c = grid_energy_c(G, k, V, contact);
    const double *restrict y0 = sim->y[0], *restrict y1 = sim->y[1], *restrict y2 = sim->y[2];
    const int64_t shift = sg->shift, lo = grid_seg_lo(sg, cut, 0);
    if (G->perm == NULL && shift >= GRID_SAFE) { /* the two ends never share a vector */
#pragma omp simd safelen(GRID_SAFE)
        for (int64_t g = lo; g < sg->hi; g++) {
            const int64_t j = g + shift;
            const double dx = y0[j] - y0[g], dy = y1[j] - y1[g], dz = y2[j] - y2[g];
            const double r2 = dx * dx + dy * dy + dz * dz;
            const double x = (bits[g * W] & bit) ? grid_pair_energy(contact, r2, sqrt(r2), c, L, iL, dc) : 0.0;
            e[g] += x;
            e[j] += x;
        }
        return;
    }
    for (int64_t g = lo; g < sg->hi; g++) {
        if (!(bits[g * W] & bit))
            continue;
        const int64_t i = G->perm ? G->perm[g] : g;
        const int64_t j = G->perm ? G->perm[g + shift] : g + shift;
        const double dx = y0[j] - y0[i], dy = y1[j] - y1[i], dz = y2[j] - y2[i];
        const double r2 = dx * dx + dy * dy + dz * dz;
        if (contact && !(r2 < dc * dc)) /* the most, no square root */
            continue;
        const double x = grid_pair_energy(contact, r2, sqrt(r2), c, L, iL, dc);
        e[i] += x;
        e[j] += x;
    }
}

/* The pairs of one block whose partner is cut or above (grid_cut; the
 * vector loop where the particles are in grid order and the two ends of a
 * segment's lanes never meet). */
PD_VECTOR_CLONES static void block_energy(const pd_sim *sim, int64_t blk, double *e, int contact)
{
    const pd_grid *G = sim->grid;
    const int64_t cut = grid_cut(G, blk);
    for (int64_t si = block_seg0(G, blk); si < block_seg0(G, blk + 1); si++)
        if (contact)
            seg_energy(sim, G, &G->seg[si], cut, e, 1);
        else
            seg_energy(sim, G, &G->seg[si], cut, e, 0);
}

static void pair_energy(const pd_sim *sim, double *e, const int contact)
{
    const pd_grid *G = sim->grid;
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel
        for (int64_t blk = grid_walk0(G, phase); blk < G->walk; blk += 2)
            if (grid_mine(G, blk))
                block_energy(sim, blk, e, contact);
    }
}

int pd_grid_damage(const pd_sim *sim, double threshold, double *max_damage, int64_t *above)
{
    const pd_grid *G = sim->grid;
    if (G == NULL || G->epoch != sim->half.epoch)
        return 0;
    /* off the masks' mirror, kept by every break (grid_bits.c): popcounts */
    if (pd_grid_damage_counted(sim, threshold, NULL, max_damage, above))
        return 1;
    const int64_t n = G->n;
    const int W = G->words;
    if (!grid_volume_sums(sim->grid, sim)) /* pd_damage's figures need equal volumes */
        return 0;
    const int64_t *off = sim->b->offset;
    const double *sum = G->vsum;
    int32_t *kept = calloc((size_t)(n > 0 ? n : 1), sizeof(int32_t));
    if (kept == NULL)
        return 0;
    /* the intact bonds of each particle, both ends of each (even blocks,
     * then odd ones: no two threads count into one particle) */
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel
        for (int64_t blk = phase; blk < G->nblocks; blk += 2) {
            if (!grid_mine(G, blk))
                continue;
            for (int64_t si = block_seg0(G, blk); si < block_seg0(G, blk + 1); si++) {
                const grid_seg *sg = &G->seg[si];
                const int k = sg->k;
                const uint64_t bit = UINT64_C(1) << (k & 63);
                for (int64_t g = sg->lo; g < sg->hi; g++) {
                    const int32_t m = (G->mask[g * W + (k >> 6)] & bit) != 0;
                    kept[g] += m;
                    kept[g + sg->shift] += m;
                }
            }
        }
    }
    /* equal volumes: damage = 1 - intact / family, the family counting
     * every bond of the file, to the bit as pd_damage */
    double dmax = 0;
    int64_t count = 0;
#pragma omp parallel for schedule(static) reduction(max : dmax) reduction(+ : count)
    for (int64_t g = 0; g < n; g++) {
        const int64_t i = G->perm ? G->perm[g] : g;
        const int64_t all = off[i + 1] - off[i];
        const double d = all > 0 ? 1.0 - sum[kept[g]] / sum[all] : 0.0;
        dmax = d > dmax ? d : dmax;
        count += d > threshold;
    }
    free(kept);
    *max_damage = dmax;
    *above = count;
    return 1;
}

/* Are the energies the last bond pass counted those of now? */
static int counted(const pd_sim *sim)
{
    const pd_grid *G = sim->grid;
    return G->energy_ok && G->energy_step == sim->step && G->energy_epoch == sim->half.epoch;
}

/* e[i] += the counted energy of particle i (grid order through perm). */
static void add_counted(const pd_grid *G, const double *eg, double *e)
{
#pragma omp parallel for schedule(static)
    for (int64_t g = 0; g < G->n; g++)
        e[G->perm ? G->perm[g] : g] += eg[g];
}

/* In tiles the bond pass sums the energies in an order of its own, which
 * a pass of the pairs does not follow: the energies of a step the bond
 * pass did not count are counted as it counts them (grid_tile_energies). */
void pd_grid_contact_energy(const pd_sim *sim, double *e)
{
    if (sim->grid == NULL || sim->grid->cmask == NULL)
        return;
    if ((counted(sim) || grid_tile_energies(sim)) && sim->grid->ec)
        add_counted(sim->grid, sim->grid->ec, e);
    else
        pair_energy(sim, e, 1);
}

void pd_grid_pmb_energy(const pd_sim *sim, double *e)
{
    if (counted(sim) || grid_tile_energies(sim))
        add_counted(sim->grid, sim->grid->eb, e);
    else
        pair_energy(sim, e, 0);
}
