/*
 * half.c -- the bonds of a run, each stored once (i < j): the half bonds
 * every kernel walks (lib/models/pmb.c's bond list, lib/stencil/ and
 * lib/models/lps.c through their state bits), built from the file's
 * directed families, and their state kept in step with the directed bits.
 */
#include <stdlib.h>

#include "bonds/half.h"

static int64_t lower_bound(const int32_t *v, int64_t lo, int64_t hi, int32_t key)
{
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (v[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

void pd_half_free(pd_half_bonds *h)
{
    if (h == NULL)
        return;
    free(h->offset);
    free(h->neighbor);
    free(h->length);
    if (h->w_ji != h->w_ij)
        free(h->w_ji);
    free(h->w_ij);
    free(h->intact);
    free(h->released);
    free(h->cursor);
    free(h->kfail);
}

pd_status pd_half_build(const pd_bonds *b, pd_half_bonds *h)
{
    int64_t n = b->n, count = 0;
    h->n = n;
    h->offset = malloc((size_t)(n + 1) * sizeof(int64_t));
    h->cursor = malloc((size_t)(n > 0 ? n : 1) * sizeof(int64_t));
    if (h->offset == NULL || h->cursor == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the bonds of the run");
    h->offset[0] = 0;
    int64_t span = 1;
    for (int64_t i = 0; i < n; i++) {
        int64_t first = lower_bound(b->neighbor, b->offset[i], b->offset[i + 1], (int32_t)i + 1);
        count += b->offset[i + 1] - first;
        h->offset[i + 1] = count;
        if (b->offset[i + 1] > first) {
            int64_t d = b->neighbor[b->offset[i + 1] - 1] - i;
            span = d > span ? d : span;
        }
    }
    h->count = count;
    size_t m = (size_t)(count > 0 ? count : 1);
    h->neighbor = malloc(m * sizeof(int32_t));
    h->intact = calloc((size_t)pd_bits_words(count) + 1, sizeof(uint64_t));
    if (!h->neighbor || !h->intact)
        return pd_fail(PD_ERR_NOMEM, "out of memory for %lld bonds", (long long)count);
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++) {
        int64_t k = b->offset[i + 1] - (h->offset[i + 1] - h->offset[i]);
        for (int64_t q = h->offset[i]; q < h->offset[i + 1]; q++, k++)
            h->neighbor[q] = b->neighbor[k];
    }
    pd_half_set_state(h, b, b->intact);
    h->block = span;
    h->nblocks = (n + span - 1) / span;
    h->released = calloc((size_t)(h->nblocks > 0 ? h->nblocks : 1), sizeof(double));
    if (h->released == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the bonds of the run");
    return PD_OK;
}

void pd_half_set_state(pd_half_bonds *h, const pd_bonds *b, const uint64_t *intact)
{
    h->epoch++;
    /* a half bond i-j (j > i) takes the bit of its copy in i's family */
    for (int64_t w = 0; w < pd_bits_words(h->count); w++)
        h->intact[w] = 0;
    for (int64_t i = 0; i < h->n; i++) {
        int64_t q = h->offset[i];
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++)
            if (b->neighbor[k] > i) {
                if (pd_bond_intact(intact, k))
                    h->intact[q >> 6] |= UINT64_C(1) << (q & 63);
                q++;
            }
    }
}

int64_t pd_half_find(const pd_half_bonds *h, int64_t i, int64_t j)
{
    int64_t q = lower_bound(h->neighbor, h->offset[i], h->offset[i + 1], (int32_t)j);
    return q < h->offset[i + 1] && h->neighbor[q] == j ? q : -1;
}

void pd_half_break_all(pd_half_bonds *h, const pd_bonds *b, int64_t i)
{
    h->epoch++;
    for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
        int32_t j = b->neighbor[k];
        int64_t q = pd_half_find(h, j < i ? j : i, j < i ? i : j);
        if (q >= 0)
            pd_bond_break(h->intact, q);
    }
}

void pd_half_expand(pd_half_bonds *h, const pd_bonds *b, uint64_t *intact)
{
    /* Row i meets its bonds to j < i in ascending i for each j, so a cursor
     * per row walks the half bonds of j in order. */
    for (int64_t i = 0; i < h->n; i++)
        h->cursor[i] = h->offset[i];
    int64_t words = pd_bits_words(b->count);
    for (int64_t w = 0; w < words; w++)
        intact[w] = 0;
    for (int64_t i = 0; i < h->n; i++) {
        int64_t own = h->offset[i];
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            int32_t j = b->neighbor[k];
            int64_t q = j < i ? h->cursor[j]++ : own++;
            if (pd_bond_intact(h->intact, q))
                intact[k >> 6] |= UINT64_C(1) << (k & 63);
        }
    }
}

