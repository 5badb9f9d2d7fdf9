/*
 * bonds.c -- bond families within the horizon (seed 000 eq. 11), stored as
 * CSR (built by build.c, or expanded from a lattice stencil by stencil.c):
 * the family of particle i is neighbor[offset[i] .. offset[i+1]), sorted
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

#include "bonds/half.h"
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
    pd_bond_sites_free(b->sites);
    free(b);
}

pd_stencil *pd_stencil_alloc(int nk)
{
    pd_stencil *st = calloc(1, sizeof *st);
    if (st == NULL)
        return NULL;
    size_t m = nk > 0 ? (size_t)nk : 1;
    st->nk = nk;
    st->d = malloc(m * sizeof *st->d);
    st->length = malloc(m * sizeof(double));
    st->vfactor = malloc(m * sizeof(double));
    if (!st->d || !st->length || !st->vfactor) {
        pd_stencil_free(st);
        return NULL;
    }
    return st;
}

void pd_stencil_free(pd_stencil *st)
{
    if (st == NULL)
        return;
    free(st->d);
    free(st->length);
    free(st->vfactor);
    free(st);
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

/* The bits of `bits` set among [lo, hi), and with `skip` those whose bit
 * in skip is clear.  (popcnt: where the processor has it, through the
 * clones of counted_damage.) */
static inline __attribute__((always_inline)) int64_t bits_in(const uint64_t *bits,
                                                            const uint64_t *skip, int64_t lo,
                                                            int64_t hi)
{
    int64_t c = 0;
    while (lo < hi) {
        const int64_t w = lo >> 6, end = (w + 1) * 64 < hi ? (w + 1) * 64 : hi;
        uint64_t m = ~UINT64_C(0) << (lo & 63);
        if (end & 63 && end == hi)
            m &= (UINT64_C(1) << (end & 63)) - 1;
        uint64_t x = (bits ? bits[w] : ~UINT64_C(0)) & m;
        if (skip)
            x &= ~skip[w];
        c += __builtin_popcountll(x);
        lo = end;
    }
    return c;
}

/* Hot loops are compiled for AVX-512, AVX2 and the baseline (as
 * lib/state/sim.h's PD_VECTOR_CLONES): here for popcnt. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(PD_NO_CLONES)
#define BONDS_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define BONDS_CLONES
#endif

/* The damage of rows [i0, i1) from their counts of bits, table[m] the sum
 * of m volumes. */
BONDS_CLONES static void counted_damage(const pd_bonds *b, const uint64_t *intact,
                                        const uint64_t *skip, const double *table, int64_t i0,
                                        int64_t i1, double *damage)
{
    for (int64_t i = i0; i < i1; i++) {
        const double all = table[bits_in(NULL, skip, b->offset[i], b->offset[i + 1])];
        const double kept = table[bits_in(intact, skip, b->offset[i], b->offset[i + 1])];
        damage[i] = all > 0 ? 1.0 - kept / all : 0.0;
    }
}

/* When all volumes are equal, the running sums V, V + V, ... up to the
 * largest family (table[m], the sum of m volumes in family order); else,
 * or out of memory, NULL. */
static double *volume_sums(const pd_particles *p, const pd_bonds *b)
{
    int uniform = b->n > 0;
    for (int64_t i = 1; i < p->n && uniform; i++)
        uniform = p->volume[i] == p->volume[0];
    int64_t longest = 0;
    for (int64_t i = 0; i < b->n && uniform; i++)
        longest = b->offset[i + 1] - b->offset[i] > longest ? b->offset[i + 1] - b->offset[i]
                                                            : longest;
    double *table = uniform ? malloc((size_t)(longest + 1) * sizeof(double)) : NULL;
    if (table) {
        table[0] = 0;
        for (int64_t m = 1; m <= longest; m++)
            table[m] = table[m - 1] + p->volume[0];
    }
    return table;
}

/* Damage (seed 000 eq. 10) over the bonds whose bit in `skip` is clear
 * (skip NULL: every bond).  The sums of V_j run in family order; when all
 * volumes are equal, a sum of m of them is the m-th of the running sums
 * V, V + V, ... (table[m], added in that very order), so the bits are
 * counted instead of walking the partners: the same damage, bit for bit,
 * without reading the neighbour lists. */
static void damage_over(const pd_particles *p, const pd_bonds *b, const uint64_t *intact,
                        const uint64_t *skip, double *damage)
{
    double *table = volume_sums(p, b);
    if (table) {
#pragma omp parallel
        {
            int64_t i0, i1;
            pd_thread_share(b->n, &i0, &i1);
            counted_damage(b, intact, skip, table, i0, i1, damage);
        }
        free(table);
        return;
    }
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < b->n; i++) {
        double all = 0, kept = 0;
        pd_bond_iter it;
        for (pd_family_start_partners(b, p, i, &it); pd_family_next(&it);) {
            const int64_t k = it.q;
            if (skip && pd_bond_intact(skip, k))
                continue;
            double v = p->volume[it.j];
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

/* kept[i] and kept[j] += 1 for each intact half bond i-j of rows [lo, hi)
 * (popcnt and tzcnt through the clones). */
BONDS_CLONES static void count_intact(const pd_half_bonds *h, int64_t lo, int64_t hi, int32_t *kept)
{
    for (int64_t i = lo; i < hi; i++)
        for (int64_t q = h->offset[i]; q < h->offset[i + 1];) {
            const int64_t end = ((q >> 6) + 1) * 64 < h->offset[i + 1] ? ((q >> 6) + 1) * 64
                                                                       : h->offset[i + 1];
            uint64_t w = h->intact[q >> 6] >> (q & 63);
            if (end - q < 64)
                w &= (UINT64_C(1) << (end - q)) - 1;
            kept[i] += __builtin_popcountll(w);
            for (; w; w &= w - 1)
                kept[h->neighbor[q + __builtin_ctzll(w)]]++;
            q = end;
        }
}

int pd_half_damage(const pd_particles *p, const pd_bonds *b, const pd_half_bonds *h,
                   double *damage)
{
    if (!b->offset || h->n != b->n || h->walk != h->nblocks || h->walk_lo != 0)
        return 0; /* no lists, or a piece of a body */
    double *table = volume_sums(p, b);
    int32_t *kept = table ? calloc((size_t)(b->n > 0 ? b->n : 1), sizeof(int32_t)) : NULL;
    if (kept == NULL) {
        free(table);
        return 0;
    }
    /* even blocks, then odd ones: a block's partners are in it or the next */
    for (int phase = 0; phase < 2; phase++)
#pragma omp parallel for schedule(static)
        for (int64_t blk = phase; blk < h->nblocks; blk += 2)
            count_intact(h, blk * h->block,
                         (blk + 1) * h->block < b->n ? (blk + 1) * h->block : b->n, kept);
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < b->n; i++) {
        const double all = table[b->offset[i + 1] - b->offset[i]];
        damage[i] = all > 0 ? 1.0 - table[kept[i]] / all : 0.0;
    }
    free(kept);
    free(table);
    return 1;
}

/* The root of x; each step on the way points x at its grandparent
 * (path halving).  parent[x] <= x holds throughout. */
static int64_t piece_root(int64_t *parent, int64_t x)
{
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

pd_status pd_fragments(const pd_particles *p, const pd_bonds *b, const uint64_t *intact,
                       int64_t *pieces, double *largest)
{
    const int64_t n = b->n;
    int64_t *parent = malloc((size_t)(n > 0 ? n : 1) * sizeof *parent);
    double *volume = malloc((size_t)(n > 0 ? n : 1) * sizeof *volume);
    if (parent == NULL || volume == NULL) {
        free(parent);
        free(volume);
        return pd_fail(PD_ERR_NOMEM, "out of memory finding the fragments");
    }
    for (int64_t i = 0; i < n; i++)
        parent[i] = i;
    /* union by the smaller root: a root is the first particle of its piece */
    for (int64_t i = 0; i < n; i++) {
        pd_bond_iter it;
        for (pd_family_start_partners(b, p, i, &it); pd_family_next(&it);) {
            if (it.j <= i || !pd_bond_intact(intact, it.q))
                continue; /* each bond once, from its lower end */
            int64_t ri = piece_root(parent, i), rj = piece_root(parent, it.j);
            if (ri < rj)
                parent[rj] = ri;
            else if (rj < ri)
                parent[ri] = rj;
        }
    }
    /* ascending, parent[x] < x already holds its piece's number: number
     * the roots in order and give every other particle its parent's */
    int64_t count = 0;
    double most = 0;
    for (int64_t i = 0; i < n; i++) {
        if (parent[i] == i) {
            volume[count] = 0;
            parent[i] = count++;
        } else {
            parent[i] = parent[parent[i]];
        }
        volume[parent[i]] += p->volume[i];
    }
    for (int64_t k = 0; k < count; k++)
        most = volume[k] > most ? volume[k] : most;
    free(parent);
    free(volume);
    *pieces = count;
    *largest = most;
    return PD_OK;
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
