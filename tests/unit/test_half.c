/*
 * test_half -- the half bonds of a run (lib/bonds/half.c): their state
 * expanded back into the directed bits of the file's families.
 *
 * Proves: pd_half_expand gives, for every directed bond i-j, the state of
 * the half bond min(i,j)-max(i,j) (found by its partner, one by one), on
 * 1, 2, 3 and 7 threads, for rows in lattice order and shuffled (the rows'
 * span then near N), with every bond intact, none, and a fixed pseudo-random
 * third broken; and pd_half_set_state of the expanded bits gives the half
 * bits back.  And pd_half_gap, the closest pair that is not a bond: on a
 * perturbed body whose families are pd-bonds's, the horizon; with the
 * horizon raised over the families (the pairs between the two left out),
 * the closest of those, as a search of every pair finds it.
 */
#include <math.h>
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

/* The closest pair i < j that is not a half bond, below `cap`: every pair. */
static double brute_gap(const pd_half_bonds *h, const pd_particles *p, double cap)
{
    double best = cap;
    for (int64_t i = 0; i < p->n; i++)
        for (int64_t j = i + 1; j < p->n; j++) {
            const double dx = p->x[0][j] - p->x[0][i], dy = p->x[1][j] - p->x[1][i],
                         dz = p->x[2][j] - p->x[2][i];
            const double d = sqrt(dx * dx + dy * dy + dz * dz);
            if (d < best && pd_half_find(h, i, j) < 0)
                best = d;
        }
    return best;
}

static void check_gap(void)
{
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, "0,0.0061,0,0.0041,0,0.0031", &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {.spacing = 0.001, .density = 2200.0, .material = 1,
                            .perturb = 1e-4, .seed = 11};
    pd_particles *p = NULL;
    pd_bonds *b = NULL;
    if (pd_lattice_make(&r, 1, &lp, &p) != PD_OK || pd_bonds_build(p, 3.0001e-3, &b) != PD_OK)
        die("perturbed body");
    pd_half_bonds h;
    memset(&h, 0, sizeof h);
    if (pd_half_build(b, &h) != PD_OK)
        die("half bonds");
    double gap = 0;
    CHECK(pd_half_gap(&h, b, p, &gap) == PD_OK && gap == b->horizon,
          "pd-bonds's families: the gap is the horizon (%.17g, not %.17g)", b->horizon, gap);
    CHECK(brute_gap(&h, p, b->horizon) == b->horizon,
          "no pair within the horizon is left out of pd-bonds's families");
    b->horizon = 3.4e-3; /* the pairs between 3.0001 and 3.4 mm: not bonds */
    const double want = brute_gap(&h, p, b->horizon);
    CHECK(want > 3.0001e-3 && want < 3.4e-3, "the raised horizon leaves pairs out (%g)", want);
    CHECK(pd_half_gap(&h, b, p, &gap) == PD_OK && gap == want,
          "families short of the horizon: the closest pair left out, %.17g (found %.17g)", want,
          gap);
    printf("ok: pd_half_gap: the horizon for pd-bonds's families, else the closest pair left out "
           "(%.6g m)\n", gap);
    pd_half_free(&h);
    pd_bonds_free(b);
    pd_particles_free(p);
}

int main(void)
{
    check_gap();
    pd_particles *p = box(0.001);
    check_body(p, "in lattice order");
    shuffle_rows(p);
    check_body(p, "shuffled");
    pd_particles_free(p);
    return failures ? 1 : 0;
}
