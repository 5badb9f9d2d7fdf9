/*
 * test_grid_bits -- the file's directed bond bits read off the stencil's
 * masks (lib/stencil/grid_bits.c) against the half bonds' expansion
 * (lib/bonds/half.c).
 *
 * Proves: on a disk (runs of many lengths, partners at many shifts) and a
 * box in lattice order, with bonds breaking under random velocities, the
 * directed bits pd_sim_intact gives after every step are those of
 * pd_half_expand bit for bit, on 1, 2 and 3 threads, and are read off the
 * masks (the grid says it can); so is the damage pd_sim_damage gives,
 * pd_damage's of the expansion to the bit, and the largest damage and the
 * count above 0.3 of pd_sim_damage_stats.  The masks' mirror is made
 * once and then kept by each break, so the breaks of every kernel are
 * checked: PMB and LPS, in AVX-512 tiles (where the processor has them)
 * and in the portable segment walk.  On shuffled rows and with more than
 * 64 half-stencil offsets (delta = 4.01 h) the grid declines and the bits
 * are the expansion's.
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bonds/half.h"
#include "check.h"
#include "pd.h"
#include "state/sim.h"
#include "stencil/grid.h"

static const double H = 1e-3, K = 14.9e9, RHO = 2200.0;

static pd_particles *body(int kind, int shuffled, double delta)
{
    pd_region r;
    pd_status s = kind == 0 ? pd_region_parse(PD_REGION_CYLINDER, "y,0,0,0.0061,0,0.0025", &r)
                            : pd_region_parse(PD_REGION_BOX, "0,0.0195,0,0.0055,0,0.0045", &r);
    if (s != PD_OK)
        die("region");
    pd_lattice_params lp = {H, RHO, 1, 0.0, 11};
    pd_particles *p = NULL;
    if (pd_lattice_make(&r, 1, &lp, &p) != PD_OK ||
        pd_particles_sort_spatial(p, delta) != PD_OK)
        die("lattice");
    if (shuffled)
        shuffle_rows(p);
    return p;
}

static void check_body(int kind, int shuffled, double delta, int threads, pd_model_kind model,
                       int tiles)
{
    int f0 = failures;
    omp_set_num_threads(threads);
    if (tiles)
        unsetenv("PD_NO_AVX512");
    else
        setenv("PD_NO_AVX512", "1", 1);
    pd_particles *p = body(kind, shuffled, delta);
    pd_bonds *b = NULL;
    if (pd_bonds_build(p, delta, &b) != PD_OK)
        die("bonds");
    pd_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.model = model;
    sc.bulk_modulus = K;
    sc.shear_modulus = 8e9;
    sc.influence = PD_INFLUENCE_INV_R;
    sc.c = pd_pmb_c_from_bulk(K, b->horizon);
    sc.safety = 0.8;
    sc.dt_stable = pd_stable_dt(p, b, &sc);
    sc.dt = sc.safety * sc.dt_stable;
    sc.steps = 30;
    sc.has_failure = 1;
    sc.s00 = 0.0005;
    sc.alpha = 0.25;
    pd_sim *sim = NULL;
    if (pd_sim_new(p, b, &sc, &sim) != PD_OK)
        die("pd_sim_new");
    double *const *v = pd_sim_velocities(sim);
    for (int64_t i = 0; i < p->n; i++) {
        uint64_t s = (uint64_t)llround(p->x[0][i] / H + 100) * 1000003u +
                     (uint64_t)llround(p->x[1][i] / H + 100) * 10007u +
                     (uint64_t)llround(p->x[2][i] / H + 100);
        for (int d = 0; d < 3; d++) {
            s = s * 6364136223846793005ULL + 1442695040888963407ULL;
            v[d][i] = 6.0 * (2.0 * (double)(s >> 11) / 9007199254740992.0 - 1.0);
        }
    }
    if (pd_sim_setup(sim) != PD_OK)
        die("setup");
    CHECK(pd_sim_stencil(sim) > 0, "the body is walked as a stencil");
    const size_t words = (size_t)pd_bits_words(b->count);
    uint64_t *want = malloc(words * sizeof(uint64_t));
    double *dmg = malloc((size_t)p->n * sizeof(double)), *dwant = malloc((size_t)p->n * sizeof(double));
    if (want == NULL || dmg == NULL || dwant == NULL)
        die("memory");
    int differ = 0, read_off = 0, ddiffer = 0, sdiffer = 0;
    for (int step = 0; step < 30; step++) {
        if (pd_sim_step(sim) != PD_OK)
            die("step");
        const uint64_t *got = pd_sim_intact(sim);
        read_off += sim->grid && pd_grid_directed_bits(sim, want);
        pd_half_expand(&sim->half, b, want);
        differ += memcmp(got, want, words * sizeof(uint64_t)) != 0;
        pd_sim_damage(sim, dmg);
        pd_damage(p, b, want, dwant);
        ddiffer += memcmp(dmg, dwant, (size_t)p->n * sizeof(double)) != 0;
        double most = 0, got_most = -1;
        int64_t above = 0, got_above = -1;
        for (int64_t i = 0; i < p->n; i++) {
            most = dwant[i] > most ? dwant[i] : most;
            above += dwant[i] > 0.3;
        }
        if (pd_sim_damage_stats(sim, 0.3, &got_most, &got_above) != PD_OK)
            die("damage stats");
        sdiffer += memcmp(&most, &got_most, sizeof most) != 0 || above != got_above;
    }
    const int expect = !shuffled && delta < 4 * H;
    CHECK(differ == 0, "%d steps' bits differ from the half bonds' expansion", differ);
    CHECK(ddiffer == 0, "%d steps' damage differs from pd_damage's of the expansion", ddiffer);
    CHECK(sdiffer == 0, "%d steps' largest damage or count above 0.3 differ from pd_damage's",
          sdiffer);
    CHECK(read_off == (expect ? 30 : 0), "the masks were read %d times of 30", read_off);
    CHECK(pd_sim_broken(sim) > 0, "bonds should break at 6 m/s");
    char what[200];
    snprintf(what, sizeof what,
             "%s %s%s%s, delta %.2f h, %d thread%s: the directed bits and the damage %s are "
             "the half bonds' (%lld broken of %lld)",
             model == PD_MODEL_LPS ? "LPS" : "PMB", tiles ? "tiles, " : "",
             kind == 0 ? "disk" : "box", shuffled ? " shuffled" : "", delta / H, threads,
             threads > 1 ? "s" : "", expect ? "read off the masks" : "(expanded)",
             (long long)pd_sim_broken(sim), (long long)b->count / 2);
    proved(f0, what);
    free(want);
    free(dmg);
    free(dwant);
    pd_sim_free(sim);
    pd_bonds_free(b);
    pd_particles_free(p);
}

int main(void)
{
    for (int threads = 1; threads <= 3; threads++) {
        check_body(0, 0, 3.0001 * H, threads, PD_MODEL_PMB, 0);
        check_body(1, 0, 3.0001 * H, threads, PD_MODEL_PMB, 0);
    }
    /* each kernel keeps the mirror through its own breaks */
    const int tiles = __builtin_cpu_supports("avx512f") != 0;
    for (int t = 0; t <= tiles; t++) {
        check_body(0, 0, 3.0001 * H, 2, PD_MODEL_PMB, t);
        check_body(0, 0, 3.0001 * H, 2, PD_MODEL_LPS, t);
        check_body(1, 0, 3.0001 * H, 2, PD_MODEL_LPS, t);
    }
    check_body(0, 1, 3.0001 * H, 2, PD_MODEL_PMB, 0);
    check_body(1, 0, 4.01 * H, 2, PD_MODEL_PMB, 0);
    return failures ? 1 : 0;
}
