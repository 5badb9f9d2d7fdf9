/*
 * bonds.c -- bond families within the horizon (seed 000 eq. 11), stored as
 * CSR: the family of particle i is neighbor[offset[i] .. offset[i+1]), sorted
 * by partner.  Every bond i-j appears in both families (directed storage), so
 * each particle sums its own forces without write conflicts.
 *
 * Per bond: the reference length |xi| and the partial-volume factor
 *   nu = 1                              |xi| <= delta - r_j
 *   nu = (delta + r_j - |xi|) / (2 r_j)  delta - r_j < |xi| <= delta
 * (seed 000, "Modification to the Particle Volume"; nu(delta) = 1/2), and
 * the state mu as one bit (seed 004: "a bit variable to store values of mu").
 * Bonds broken before the run by a pre-crack (crack.c) carry a second bit,
 * so that damage can be shown with or without them.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "pd.h"

int64_t pd_bits_words(int64_t count)
{
    return (count + 63) / 64;
}

pd_bonds *pd_bonds_alloc(int64_t n, int64_t count)
{
    pd_bonds *b = calloc(1, sizeof *b);
    if (b == NULL)
        return NULL;
    b->n = n;
    b->count = count;
    size_t m = count > 0 ? (size_t)count : 1;
    b->offset = calloc((size_t)n + 1, sizeof(int64_t));
    b->neighbor = malloc(m * sizeof(int32_t));
    b->length = malloc(m * sizeof(double));
    b->vfactor = malloc(m * sizeof(double));
    b->intact = calloc((size_t)pd_bits_words(count) + 1, sizeof(uint64_t));
    if (!b->offset || !b->neighbor || !b->length || !b->vfactor || !b->intact) {
        pd_bonds_free(b);
        return NULL;
    }
    return b;
}

void pd_bonds_free(pd_bonds *b)
{
    if (b == NULL)
        return;
    free(b->offset);
    free(b->neighbor);
    free(b->length);
    free(b->vfactor);
    free(b->intact);
    free(b->precrack);
    pd_stencil_free(b->stencil);
    free(b);
}

int64_t pd_bits_count_broken(const uint64_t *bits, int64_t count)
{
    int64_t intact = 0, words = count / 64;
    for (int64_t w = 0; w < words; w++)
        intact += __builtin_popcountll(bits[w]);
    for (int64_t b = words * 64; b < count; b++)
        intact += pd_bond_intact(bits, b);
    return count - intact;
}

int64_t pd_bits_count_broken_except(const uint64_t *bits, const uint64_t *skip, int64_t count)
{
    if (skip == NULL)
        return pd_bits_count_broken(bits, count);
    int64_t broken = 0, words = count / 64;
    for (int64_t w = 0; w < words; w++)
        broken += __builtin_popcountll(~bits[w] & ~skip[w]);
    for (int64_t b = words * 64; b < count; b++)
        broken += !pd_bond_intact(bits, b) && !pd_bond_intact(skip, b);
    return broken;
}

double pd_partial_volume(double len, double horizon, double r)
{
    if (len <= horizon - r)
        return 1.0;
    return (horizon + r - len) / (2.0 * r);
}

/* Visit the partners of i within the horizon: count them (out == NULL) or
 * write them (unsorted) into out[]. */
static int64_t family(const pd_particles *p, const pd_cells *c, int64_t i, double horizon,
                      int32_t *out)
{
    const double cut2 = horizon * horizon;
    double xi[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
    int64_t cells[27];
    int ncells = pd_cells_adjacent(c, xi, cells);
    int64_t m = 0;
    for (int q = 0; q < ncells; q++)
        for (int64_t e = c->start[cells[q]]; e < c->start[cells[q] + 1]; e++) {
            int32_t j = c->index[e];
            if (j == i)
                continue;
            /* the same arithmetic as LAMMPS fix PERI_NEIGH, so that pairs at
             * exactly the horizon are decided alike */
            double dx = xi[0] - p->x[0][j], dy = xi[1] - p->x[1][j], dz = xi[2] - p->x[2][j];
            double rsq = dx * dx + dy * dy + dz * dz;
            if (rsq <= cut2) {
                if (out)
                    out[m] = j;
                m++;
            }
        }
    return m;
}

static int cmp_int32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

pd_status pd_bonds_build(const pd_particles *p, double horizon, pd_bonds **out)
{
    if (!(horizon > 0) || !isfinite(horizon))
        return pd_fail(PD_ERR_INVALID, "horizon must be a positive number");
    if (p->n >= INT32_MAX)
        return pd_fail(PD_ERR_INVALID, "too many particles for one process (%lld)",
                       (long long)p->n);
    pd_status ls = pd_bonds_build_lattice(p, horizon, 1, out);
    if (ls != PD_OK || *out)
        return ls;
    pd_cells c;
    pd_status st = pd_cells_build(&c, p->n, p->x, horizon);
    if (st != PD_OK)
        return st;
    int64_t n = p->n;
    int64_t *count = malloc((size_t)(n + 1) * sizeof(int64_t));
    if (count == NULL) {
        pd_cells_free(&c);
        return pd_fail(PD_ERR_NOMEM, "out of memory for bond counts");
    }
#pragma omp parallel for schedule(dynamic, 1024)
    for (int64_t i = 0; i < n; i++)
        count[i] = family(p, &c, i, horizon, NULL);
    int64_t total = 0;
    for (int64_t i = 0; i < n; i++)
        total += count[i];
    pd_bonds *b = pd_bonds_alloc(n, total);
    if (b == NULL) {
        free(count);
        pd_cells_free(&c);
        return pd_fail(PD_ERR_NOMEM, "out of memory for %lld bonds", (long long)total);
    }
    b->horizon = horizon;
    for (int64_t i = 0; i < n; i++)
        b->offset[i + 1] = b->offset[i] + count[i];
    free(count);
#pragma omp parallel for schedule(dynamic, 1024)
    for (int64_t i = 0; i < n; i++) {
        int32_t *nb = b->neighbor + b->offset[i];
        int64_t m = family(p, &c, i, horizon, nb);
        qsort(nb, (size_t)m, sizeof *nb, cmp_int32);
        for (int64_t q = 0; q < m; q++) {
            int64_t k = b->offset[i] + q, j = nb[q];
            double dx = p->x[0][i] - p->x[0][j], dy = p->x[1][i] - p->x[1][j],
                   dz = p->x[2][i] - p->x[2][j];
            b->length[k] = sqrt(dx * dx + dy * dy + dz * dz);
            b->vfactor[k] = pd_partial_volume(b->length[k], horizon, p->radius[j]);
        }
    }
    pd_cells_free(&c);
    /* two particles at one place: no bond direction, no stretch */
    for (int64_t i = 0; i < n; i++)
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++)
            if (b->length[k] == 0) {
                int64_t j = b->neighbor[k];
                pd_bonds_free(b);
                return pd_fail(PD_ERR_INVALID,
                               "particles %lld and %lld (ids %lld and %lld) are at the same "
                               "position (%g, %g, %g) m",
                               (long long)i, (long long)j, (long long)p->id[i],
                               (long long)p->id[j], p->x[0][i], p->x[1][i], p->x[2][i]);
            }
    memset(b->intact, 0xff, (size_t)pd_bits_words(total) * sizeof(uint64_t));
    *out = b;
    return PD_OK;
}

/* Damage (seed 000 eq. 10) over the bonds whose bit in `skip` is clear
 * (skip NULL: every bond). */
static void damage_over(const pd_particles *p, const pd_bonds *b, const uint64_t *intact,
                        const uint64_t *skip, double *damage)
{
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < b->n; i++) {
        double all = 0, kept = 0;
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            if (skip && pd_bond_intact(skip, k))
                continue;
            double v = p->volume[b->neighbor[k]];
            all += v;
            if (pd_bond_intact(intact, k))
                kept += v;
        }
        damage[i] = all > 0 ? 1.0 - kept / all : 0.0;
    }
}

void pd_damage(const pd_particles *p, const pd_bonds *b, const uint64_t *intact, double *damage)
{
    damage_over(p, b, intact, NULL, damage);
}

void pd_damage_no_precrack(const pd_particles *p, const pd_bonds *b, const uint64_t *intact,
                           double *damage)
{
    damage_over(p, b, intact, b->precrack, damage);
}

typedef struct {
    uint64_t key;
    int64_t index;
} sort_item;

static int cmp_item(const void *a, const void *b)
{
    const sort_item *x = a, *y = b;
    if (x->key != y->key)
        return (x->key > y->key) - (x->key < y->key);
    return (x->index > y->index) - (x->index < y->index);
}

pd_status pd_particles_sort_spatial(pd_particles *p, double cell)
{
    int64_t n = p->n;
    int64_t *order;
    pd_status st = pd_lattice_order(p, &order);
    if (st != PD_OK)
        return st;
    pd_cells c = {0};
    if (order == NULL && (st = pd_cells_build(&c, n, p->x, cell)) != PD_OK)
        return st;
    sort_item *items = malloc((size_t)(n > 0 ? n : 1) * sizeof *items);
    pd_particles *q = pd_particles_new(n);
    if (items == NULL || q == NULL) {
        free(items);
        free(order);
        pd_particles_free(q);
        pd_cells_free(&c);
        return pd_fail(PD_ERR_NOMEM, "out of memory sorting particles");
    }
    if (order) { /* a lattice: its own order */
        for (int64_t i = 0; i < n; i++)
            items[i].index = order[i];
        free(order);
    } else {
        /* the longest axis outermost: slabs across it are the thinnest */
        int outer = 0;
        for (int d = 1; d < 3; d++)
            if (c.dim[d] > c.dim[outer])
                outer = d;
        int mid = (outer + 1) % 3, inner = (outer + 2) % 3;
        if (c.dim[inner] > c.dim[mid]) {
            int t = mid;
            mid = inner;
            inner = t;
        }
        for (int64_t i = 0; i < n; i++) {
            double x[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
            int64_t k[3];
            pd_cells_locate(&c, x, k);
            items[i].key = (uint64_t)((k[outer] * c.dim[mid] + k[mid]) * c.dim[inner] + k[inner]);
            items[i].index = i;
        }
        pd_cells_free(&c);
        qsort(items, (size_t)n, sizeof *items, cmp_item);
    }
    for (int64_t i = 0; i < n; i++) {
        int64_t s = items[i].index;
        for (int d = 0; d < 3; d++)
            q->x[d][i] = p->x[d][s];
        q->volume[i] = p->volume[s];
        q->density[i] = p->density[s];
        q->radius[i] = p->radius[s];
        q->material[i] = p->material[s];
        q->id[i] = p->id[s];
    }
    free(items);
    /* swap storage */
    pd_particles tmp = *p;
    for (int d = 0; d < 3; d++)
        p->x[d] = q->x[d];
    p->volume = q->volume;
    p->density = q->density;
    p->radius = q->radius;
    p->material = q->material;
    p->id = q->id;
    for (int d = 0; d < 3; d++)
        q->x[d] = tmp.x[d];
    q->volume = tmp.volume;
    q->density = tmp.density;
    q->radius = tmp.radius;
    q->material = tmp.material;
    q->id = tmp.id;
    pd_particles_free(q);
    return PD_OK;
}
