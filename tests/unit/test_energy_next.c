/*
 * test_energy_next -- the energies counted in the bond pass
 * (pd_sim_energy_next, lib/stencil/grid_pmb.c) against those of a pass of
 * their own (lib/stencil/grid_energy.c).
 *
 * Proves: on the lattice stencil, with failure and contact (bonds breaking
 * and pairs in contact) and without, with the particles in lattice order
 * and shuffled (the kernel then walks grid-order copies), on 1 and 2
 * threads, a run that asks for the energies of every step before taking it
 * has at every step the same energies (every field of pd_energy) and the
 * same strain energy density, bit for bit, as one that does not, and the
 * same trajectory; that the bond pass did count them (the stencil's
 * counted energies are those of the step); and that a step not asked for
 * leaves nothing counted.  Both in the AVX-512 tiles, where a processor
 * has them (the run that does not ask counts them in a pass of the tiles'
 * order, grid_tile_energies), and in the segment walk (PD_NO_AVX512).
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "pd.h"
#include "stencil/grid_impl.h"

static const double H = 1e-3, K = 14.9e9, RHO = 2200.0;

/* A 20 x 6 x 5 block (runs of 20 along x: shifts below and above the
 * kernel's GRID_SAFE) and its bonds, delta = 3.0001 h. */
static void model(int shuffled, pd_particles **pp, pd_bonds **bp)
{
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, "0,0.0195,0,0.0055,0,0.0045", &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {H, RHO, 1, 0.0, 11};
    if (pd_lattice_make(&r, 1, &lp, pp) != PD_OK)
        die("lattice");
    pd_particles *p = *pp;
    if (pd_particles_sort_spatial(p, 3.0001 * H) != PD_OK) /* lattice order */
        die("sort");
    if (shuffled)
        shuffle_rows(p);
    if (pd_bonds_build(p, 3.0001 * H, bp) != PD_OK)
        die("bonds");
}

static pd_sim *start(const pd_particles *p, const pd_bonds *b, int failure)
{
    pd_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.model = PD_MODEL_PMB;
    sc.c = pd_pmb_c_from_bulk(K, b->horizon);
    sc.bulk_modulus = K;
    sc.safety = 0.8;
    sc.dt_stable = pd_stable_dt(p, b, &sc);
    sc.dt = sc.safety * sc.dt_stable;
    sc.steps = 60;
    if (failure) {
        sc.has_failure = 1;
        sc.s00 = 0.0005;
        sc.alpha = 0.25;
        sc.has_contact = 1;
        sc.contact_skin = 0.5 * H;
    }
    pd_sim *sim = NULL;
    if (pd_sim_new(p, b, &sc, &sim) != PD_OK)
        die("pd_sim_new");
    double *const *v = pd_sim_velocities(sim);
    for (int64_t i = 0; i < p->n; i++) { /* 40 m/s at random, by position */
        uint64_t s = (uint64_t)llround(p->x[0][i] / H) * 1000003u +
                     (uint64_t)llround(p->x[1][i] / H) * 10007u + (uint64_t)llround(p->x[2][i] / H);
        for (int d = 0; d < 3; d++) {
            s = s * 6364136223846793005ULL + 1442695040888963407ULL;
            v[d][i] = 40.0 * (2.0 * (double)(s >> 11) / 9007199254740992.0 - 1.0);
        }
    }
    return sim;
}

static int same(const void *a, const void *b, size_t bytes)
{
    return memcmp(a, b, bytes) == 0;
}

static void run_pair(int tiles, int shuffled, int failure, int threads)
{
    int f0 = failures;
    omp_set_num_threads(threads);
    pd_particles *p;
    pd_bonds *b;
    model(shuffled, &p, &b);
    pd_sim *asked = start(p, b, failure), *plain = start(p, b, failure);
    CHECK(pd_sim_stencil(asked) > 0, "the block is walked as a stencil");
    CHECK(pd_grid_tiles(asked->grid) == tiles && pd_grid_tiles(plain->grid) == tiles,
          "the rows should %sbe walked in tiles", tiles ? "" : "not ");
    CHECK((asked->grid->perm != NULL) == shuffled, "grid-order copies only when shuffled");
    if (pd_sim_setup(asked) != PD_OK || pd_sim_setup(plain) != PD_OK)
        die("setup");
    const size_t n = (size_t)p->n;
    double *da = malloc(n * sizeof(double)), *dp = malloc(n * sizeof(double));
    if (!da || !dp)
        die("memory");
    int counted = 0, bad = 0;
    double contact = 0;
    for (int step = 1; step <= 60; step++) {
        const int ask = step % 7 != 3; /* and now and then not */
        if (ask)
            pd_sim_energy_next(asked);
        if (pd_sim_step(asked) != PD_OK || pd_sim_step(plain) != PD_OK)
            die("step");
        const pd_grid *G = asked->grid;
        const int ok = G->energy_ok && G->energy_step == pd_sim_stepno(asked);
        counted += ok;
        if (ok != ask)
            bad++;
        pd_energy ea, ep;
        if (pd_sim_energy(asked, &ea, da) != PD_OK || pd_sim_energy(plain, &ep, dp) != PD_OK)
            die("energy");
        contact = fmax(contact, ea.contact);
        CHECK(same(&ea, &ep, sizeof ea) && same(da, dp, n * sizeof(double)),
              "step %d: the energies differ (elastic %.17g against %.17g, contact %.17g "
              "against %.17g)",
              step, ea.elastic, ep.elastic, ea.contact, ep.contact);
    }
    CHECK(bad == 0, "%d steps counted the energies when not asked, or not when asked", bad);
    CHECK(counted > 40, "only %d steps counted the energies", counted);
    double *const *ya = pd_sim_positions(asked), *const *yp = pd_sim_positions(plain);
    for (int d = 0; d < 3; d++)
        CHECK(same(ya[d], yp[d], n * sizeof(double)), "the trajectories differ");
    if (failure) {
        CHECK(pd_sim_broken(asked) > 0, "bonds should break at 40 m/s");
        CHECK(pd_sim_broken(asked) == pd_sim_broken(plain), "the broken bonds differ");
        CHECK(contact > 0, "pairs should come into contact at 40 m/s");
    }
    char what[200];
    snprintf(what, sizeof what,
             "%s, %s, %s, %d thread%s: the energies counted in the bond pass are a pass's own, "
             "bit for bit (%lld broken bonds)",
             tiles ? "AVX-512 tiles" : "segments", shuffled ? "shuffled" : "lattice order",
             failure ? "failure and contact" : "elastic", threads, threads > 1 ? "s" : "",
             (long long)pd_sim_broken(asked));
    proved(f0, what);
    free(da);
    free(dp);
    pd_sim_free(asked);
    pd_sim_free(plain);
    pd_bonds_free(b);
    pd_particles_free(p);
}

int main(void)
{
    const int avx512 = __builtin_cpu_supports("avx512f") != 0;
    if (!avx512)
        printf("# no AVX-512 on this processor: the segment walk only\n");
    for (int tiles = avx512; tiles >= 0; tiles--) {
        if (tiles)
            unsetenv("PD_NO_AVX512");
        else
            setenv("PD_NO_AVX512", "1", 1);
        for (int shuffled = 0; shuffled < 2; shuffled++)
            for (int failure = 0; failure < 2; failure++)
                for (int threads = 1; threads <= 2; threads++)
                    run_pair(tiles, shuffled, failure, threads);
    }
    return failures ? 1 : 0;
}
