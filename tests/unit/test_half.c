/*
 * test_half -- the half bonds of a run (lib/bonds/half.c): their state
 * expanded back into the directed bits of the file's families.
 *
 * Proves: pd_half_expand gives, for every directed bond i-j, the state of
 * the half bond min(i,j)-max(i,j) (found by its partner, one by one), on
 * 1, 2, 3 and 7 threads, for rows in lattice order and shuffled (the rows'
 * span then near N), with every bond intact, none, and a fixed pseudo-random
 * third broken; and pd_half_set_state of the expanded bits gives the half
 * bits back.
 */
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "bonds/half.h"
#include "check.h"
#include "pd.h"

static pd_particles *box(double h)
{
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, "0,0.0061,0,0.0041,0,0.0031", &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {h, 2200.0, 1, 0.0, 7};
    pd_particles *p = NULL;
    if (pd_lattice_make(&r, 1, &lp, &p) != PD_OK)
        die("lattice");
    return p;
}

/* The directed bits the half bonds mean, one bond at a time. */
static void expected(const pd_half_bonds *h, const pd_bonds *b, uint64_t *bits)
{
    memset(bits, 0, (size_t)pd_bits_words(b->count) * sizeof(uint64_t));
    for (int64_t i = 0; i < b->n; i++)
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            int64_t j = b->neighbor[k];
            int64_t q = pd_half_find(h, j < i ? j : i, j < i ? i : j);
            if (q < 0)
                die("a directed bond without its half bond");
            if (pd_bond_intact(h->intact, q))
                bits[k >> 6] |= UINT64_C(1) << (k & 63);
        }
}

static void check_body(pd_particles *p, const char *order)
{
    pd_bonds *b = NULL;
    if (pd_bonds_build(p, 3.0001 * 0.001, &b) != PD_OK)
        die("bonds");
    pd_half_bonds h;
    memset(&h, 0, sizeof h);
    if (pd_half_build(b, &h) != PD_OK)
        die("half bonds");
    const size_t words = (size_t)pd_bits_words(b->count);
    uint64_t *want = malloc(words * sizeof(uint64_t)), *got = malloc(words * sizeof(uint64_t));
    uint64_t *back = malloc((words + 1) * sizeof(uint64_t));
    if (!want || !got || !back)
        die("memory");
    int before = failures;
    for (int pattern = 0; pattern < 3; pattern++) {
        const size_t hw = (size_t)pd_bits_words(h.count);
        for (size_t w = 0; w < hw; w++)
            h.intact[w] = pattern == 0 ? ~UINT64_C(0) : 0;
        if (pattern == 2)
            for (int64_t q = 0; q < h.count; q++)
                if ((uint64_t)q * 2654435761u % 3 != 0)
                    h.intact[q >> 6] |= UINT64_C(1) << (q & 63);
        if (h.count % 64) /* no bits past the last bond */
            h.intact[hw - 1] &= (UINT64_C(1) << (h.count % 64)) - 1;
        memcpy(back, h.intact, hw * sizeof(uint64_t));
        expected(&h, b, want);
        const int threads[] = {1, 2, 3, 7};
        for (int t = 0; t < 4; t++) {
            omp_set_num_threads(threads[t]);
            memset(got, 0xa5, words * sizeof(uint64_t));
            pd_half_expand(&h, b, got);
            CHECK(memcmp(got, want, words * sizeof(uint64_t)) == 0,
                  "%s, pattern %d, %d threads: the expanded bits differ", order, pattern,
                  threads[t]);
        }
        pd_half_set_state(&h, b, got);
        CHECK(memcmp(h.intact, back, hw * sizeof(uint64_t)) == 0,
              "%s, pattern %d: the expanded bits do not give the half bits back", order,
              pattern);
    }
    char what[160];
    snprintf(what, sizeof what,
             "rows %s (%lld bonds, rows' span %lld): the half bonds expand to the directed "
             "bits on 1, 2, 3 and 7 threads, and back",
             order, (long long)b->count, (long long)h.block);
    proved(before, what);
    free(want);
    free(got);
    free(back);
    pd_half_free(&h);
    pd_bonds_free(b);
}

int main(void)
{
    pd_particles *p = box(0.001);
    check_body(p, "in lattice order");
    shuffle_rows(p);
    check_body(p, "shuffled");
    pd_particles_free(p);
    return failures ? 1 : 0;
}
