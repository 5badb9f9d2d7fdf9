/*
 * grid_bits.c -- the directed bond bits of the file's families (a frame's
 * /frames/N/state, the restart's) and the particles' damage (a frame's, a
 * status line's, a series row's) read off the stencil's masks, without a
 * walk of the bond lists (grid.c explains the stencil).
 *
 * In grid order (no permutation) the family of particle g, sorted by
 * partner as the file holds it, is sorted by offset too: its partners at
 * the negative offsets -d_k first, k descending (d_k ascends with k in
 * (outer, mid, inner)), then those at d_k, k ascending.  Which offsets g
 * has is fixed by the body: bit k of `pos` (g has a partner at d_k) and
 * bit 63 - k of `neg` (at -d_k: the bits reversed, so that k descending
 * is place ascending).  The state of g's bond at d_k is bit k of g's mask;
 * that at -d_k is bit k of the partner's mask, gathered into bit 63 - k
 * of g's `mirror` word by a walk of the segments, once: from then on each
 * break clears its bit in the mirror as in the mask (grid_break), until
 * the masks are made again from the half bonds.  A row of the file is
 * then the mirror's bits at `neg` followed by the mask's bits at `pos`,
 * each packed in place order: two bit gathers (one instruction each with
 * BMI2) per particle instead of a lookup per bond.  A particle's damage
 * needs only the count of its intact bonds: two popcounts.
 */
#include <stdlib.h>
#include <string.h>

#include "stencil/grid_impl.h"

/* The bits of x at the places set in m, packed from bit 0 up in the order
 * of the places (pext, where the processor has BMI2). */
static inline uint64_t gather(uint64_t x, uint64_t m)
{
    uint64_t r = 0;
    for (int c = 0; m; c++, m &= m - 1)
        r |= (uint64_t)((x & m & -m) != 0) << c;
    return r;
}

/* A writer of consecutive bits into words: the first and the last word it
 * touches may be shared with the writers of the ranges beside it, and
 * are or-ed in atomically; the others are stored whole. */
typedef struct {
    uint64_t *out;
    int64_t w, first; /* the word being filled, the first one            */
    uint64_t cur;     /* its bits so far                                  */
    int fill;         /* how many (the next bit's place)                  */
} bit_writer;

static inline void put_word(bit_writer *bw, int last)
{
    if (bw->w == bw->first || last)
        __atomic_fetch_or(&bw->out[bw->w], bw->cur, __ATOMIC_RELAXED);
    else
        bw->out[bw->w] = bw->cur;
}

/* Append the low nbits (<= 64) of v (no bit above them set). */
static inline void put_bits(bit_writer *bw, uint64_t v, int nbits)
{
    if (nbits == 0)
        return;
    bw->cur |= v << bw->fill;
    if (bw->fill + nbits < 64) {
        bw->fill += nbits;
        return;
    }
    put_word(bw, 0);
    const int spill = bw->fill + nbits - 64; /* bits of v left for the next word */
    bw->cur = spill ? v >> (nbits - spill) : 0;
    bw->w++;
    bw->fill = spill;
}

/* pos and neg of every particle (once); 0 when the families are not the
 * stencil's rows (a count differs), -1 out of memory. */
static int offsets_of_rows(pd_grid *G, const pd_bonds *b)
{
    const int64_t n = G->n;
    G->pos = calloc((size_t)(n > 0 ? n : 1), sizeof(uint64_t));
    G->neg = calloc((size_t)(n > 0 ? n : 1), sizeof(uint64_t));
    if (G->pos == NULL || G->neg == NULL)
        return -1;
    for (int64_t s = 0; s < G->nseg; s++) {
        const grid_seg *sg = &G->seg[s];
        const uint64_t bit = UINT64_C(1) << sg->k, rev = UINT64_C(1) << (63 - sg->k);
        for (int64_t g = sg->lo; g < sg->hi; g++) {
            G->pos[g] |= bit;
            G->neg[g + sg->shift] |= rev;
        }
    }
    for (int64_t g = 0; g < n; g++)
        if (__builtin_popcountll(G->pos[g]) + __builtin_popcountll(G->neg[g]) !=
            b->offset[g + 1] - b->offset[g])
            return 0;
    return 1;
}

/* The rows of particles [g0, g1) into intact, gather_fn the bit gather. */
#define GRID_ROWS(name, attr, gather_fn)                                                        \
    attr static void name(const pd_grid *G, const pd_bonds *b, uint64_t *intact, int64_t g0,  \
                          int64_t g1)                                                         \
    {                                                                                         \
        bit_writer bw = {.out = intact, .w = b->offset[g0] >> 6, .first = b->offset[g0] >> 6, \
                         .fill = (int)(b->offset[g0] & 63)};                                  \
        for (int64_t g = g0; g < g1; g++) {                                                   \
            put_bits(&bw, gather_fn(G->mirror[g], G->neg[g]),                                 \
                     __builtin_popcountll(G->neg[g]));                                        \
            put_bits(&bw, gather_fn(G->mask[g], G->pos[g]), __builtin_popcountll(G->pos[g])); \
        }                                                                                     \
        if (bw.fill > 0)                                                                      \
            put_word(&bw, 1);                                                                 \
    }
GRID_ROWS(rows_plain, , gather)
#if PD_AVX512_KERNELS /* x86-64 with GCC or clang: pext where the processor has it */
GRID_ROWS(rows_bmi2, __attribute__((target("bmi2,popcnt"))), _pext_u64)
#endif

/* The rows readable off the masks (pos, neg and the mirror's array made
 * on first use) and the mirror holding the masks' bits: 1, else 0. */
static int mirror_of_masks(const pd_sim *sim)
{
    pd_grid *G = sim->grid;
    const pd_bonds *b = sim->b;
    if (G == NULL || G->perm || G->words != 1 || G->epoch != sim->half.epoch || G->rows < 0)
        return 0;
    if (G->rows == 0) {
        int r = offsets_of_rows(G, b);
        G->mirror = r > 0 ? malloc((size_t)(G->n > 0 ? G->n : 1) * sizeof(uint64_t)) : NULL;
        G->rows = r > 0 && G->mirror ? 1 : -1;
        if (G->rows < 0)
            return 0;
    }
    if (G->mirror_ok) /* kept by every break since (grid_break) */
        return 1;
    const int64_t n = G->n;
    uint64_t *restrict mirror = G->mirror;
    const uint64_t *restrict mask = G->mask;
    memset(mirror, 0, (size_t)n * sizeof(uint64_t));
    /* the partners' bits at -d_k, block by block: a block's segments reach
     * only into itself and the next one, so even blocks, then odd ones */
    for (int phase = 0; phase < 2; phase++) {
#pragma omp parallel
        for (int64_t blk = phase; blk < G->nblocks; blk += 2) {
            if (!grid_mine(G, blk))
                continue;
            for (int64_t si = block_seg0(G, blk); si < block_seg0(G, blk + 1); si++) {
                const grid_seg *sg = &G->seg[si];
                const int k = sg->k, up = 63 - k;
                const int64_t lo = sg->lo, hi = sg->hi, shift = sg->shift;
#pragma omp simd
                for (int64_t g = lo; g < hi; g++)
                    mirror[g + shift] |= ((mask[g] >> k) & 1) << up;
            }
        }
    }
    G->mirror_ok = 1;
    return 1;
}

int pd_grid_directed_bits(const pd_sim *sim, uint64_t *intact)
{
    if (!mirror_of_masks(sim))
        return 0;
    const pd_grid *G = sim->grid;
    const pd_bonds *b = sim->b;
    const int64_t n = G->n;
    memset(intact, 0, (size_t)pd_bits_words(b->count) * sizeof(uint64_t));
#pragma omp parallel
    {
        int64_t g0, g1;
        pd_thread_share(n, &g0, &g1);
        if (g0 < g1 && b->offset[g1] > b->offset[g0]) {
#if PD_AVX512_KERNELS
            if (__builtin_cpu_supports("bmi2") && __builtin_cpu_supports("popcnt"))
                rows_bmi2(G, b, intact, g0, g1);
            else
#endif
                rows_plain(G, b, intact, g0, g1);
        }
    }
    return 1;
}

/* The damage of rows [g0, g1) into damage (NULL: not kept), the largest
 * and the count above threshold: a row's intact bonds are its mirror's
 * bits at neg and its mask's at pos, sum[m] the volume of m bonds (popcnt
 * through the clones). */
PD_VECTOR_CLONES static void counted_rows(const pd_grid *G, const int64_t *off, const double *sum,
                                          int64_t g0, int64_t g1, double threshold,
                                          double *damage, double *dmax, int64_t *above)
{
    double m = 0;
    int64_t count = 0;
    for (int64_t g = g0; g < g1; g++) {
        const int64_t all = off[g + 1] - off[g];
        const int kept = __builtin_popcountll(G->mirror[g] & G->neg[g]) +
                         __builtin_popcountll(G->mask[g] & G->pos[g]);
        const double d = all > 0 ? 1.0 - sum[kept] / sum[all] : 0.0;
        if (damage)
            damage[g] = d;
        m = d > m ? d : m;
        count += d > threshold;
    }
    *dmax = m;
    *above = count;
}

int grid_volume_sums(pd_grid *G, const pd_sim *sim)
{
    if (G->vsum_ok == 0) {
        const double *V = sim->p->volume;
        const int64_t n = G->n, *off = sim->b->offset;
        int uniform = 1;
        for (int64_t i = 1; i < n && uniform; i++) /* pd_damage's figures need equal volumes */
            uniform = V[i] == V[0];
        int64_t longest = 0;
        for (int64_t i = 0; i < n; i++)
            longest = off[i + 1] - off[i] > longest ? off[i + 1] - off[i] : longest;
        G->vsum = uniform ? malloc((size_t)(longest + 1) * sizeof(double)) : NULL;
        G->vsum_ok = G->vsum ? 1 : -1;
        for (int64_t m = 0; G->vsum && m <= longest; m++)
            G->vsum[m] = m == 0 ? 0.0 : G->vsum[m - 1] + V[0];
    }
    return G->vsum_ok > 0;
}

int pd_grid_damage_counted(const pd_sim *sim, double threshold, double *damage,
                           double *max_damage, int64_t *above)
{
    if (sim->piece || !mirror_of_masks(sim) || !grid_volume_sums(sim->grid, sim))
        return 0; /* a piece's rows at its edges lack the bonds beyond them */
    const pd_grid *G = sim->grid;
    double m = 0;
    int64_t count = 0;
#pragma omp parallel reduction(max : m) reduction(+ : count)
    {
        int64_t g0, g1, c;
        double t;
        pd_thread_share(G->n, &g0, &g1);
        counted_rows(G, sim->b->offset, G->vsum, g0, g1, threshold, damage, &t, &c);
        m = t > m ? t : m;
        count += c;
    }
    if (max_damage)
        *max_damage = m;
    if (above)
        *above = count;
    return 1;
}
