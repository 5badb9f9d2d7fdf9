/*
 * impact.c -- a scene of pd set up and run through pd.h alone, as a
 * program of a user's own would: a glass block on the lattice, bonded
 * within the horizon, hit by a rigid sphere, with bond failure and contact
 * (seed 000's impact example, small).  It does what the pipeline
 *
 *   pd-lattice --box 0,0.01,0,0.01,0,0.004 --spacing 0.0005 --density 2200 -o lattice.h5
 *   pd-bonds --horizon 0.0015001 lattice.h5 -o model.h5
 *   pd-run --bulk-modulus 14.9e9 --failure 0.0005,0.25 --contact \
 *          --projectile sphere,0.005,0.005,0.0055,0.0015,0.005,0,0,-100 \
 *          --steps 200 --every 50 model.h5 -o run.h5
 *
 * does, and writes the same run file, bit for bit but for the history:
 * the programs are glue over these calls.
 *
 * Usage: impact [RUN.h5 [SPACING]] (default run.h5); prints the energy
 * balance at each frame, and on stderr the threads and what the steps
 * cost, as pd-run's log does.  With a spacing (m), the same block at that
 * spacing, for `make convergence`: the horizon 3.0002 spacings (m = 3, as
 * 0.0015001 is at 0.5 mm), the fracture energy of the 0.5 mm block held
 * (s00 from G0, seed 004 eq. 27), and the run to END_TIME, where the 0.5
 * mm block's 200 steps end, in the fewest equal steps of at most 0.8 of
 * the stable step (pd-run --failure-energy, --time).
 */
#include <stdio.h>
#include <stdlib.h>

#include <omp.h>

#include <pd.h>

#define SPACING 0.0005   /* m                                         */
#define HORIZON 0.0015001 /* m: just above 3 spacings (DESIGN.md)     */
#define M_SWEEP 3.0002   /* the horizon of a spacing given, / spacing */
#define END_TIME 2.3e-5  /* s: 200 steps at 0.5 mm end at 2.3008e-5  */

static int fail(const char *what)
{
    fprintf(stderr, "impact: error: %s: %s\n", what, pd_errmsg());
    return 1;
}

int main(int argc, char **argv)
{
    const char *path = argc > 1 ? argv[1] : "run.h5";
    const int sweep = argc > 2;
    double spacing = SPACING, horizon = HORIZON;
    char *end = NULL;
    if (sweep)
        spacing = strtod(argv[2], &end);
    if (argc > 3 || (sweep && (end == argv[2] || *end != '\0' || !(spacing > 0)))) {
        fprintf(stderr, "usage: impact [RUN.h5 [SPACING]]\n");
        return 2;
    }
    if (sweep)
        horizon = M_SWEEP * spacing;
    pd_h5_debug(0);

    /* the body: a box of sites on the simple cubic lattice, in the
     * order pd-bonds keeps (lattice order), and its families */
    pd_region box;
    pd_particles *p = NULL;
    pd_bonds *b = NULL;
    const pd_lattice_params lp = {.spacing = spacing, .density = 2200, .material = 1, .seed = 1};
    if (pd_region_parse(PD_REGION_BOX, "0,0.01,0,0.01,0,0.004", &box) != PD_OK ||
        pd_lattice_make(&box, 1, &lp, &p) != PD_OK)
        return fail("the lattice");
    if (pd_particles_sort_spatial(p, horizon) != PD_OK || pd_bonds_build(p, horizon, &b) != PD_OK)
        return fail("the bonds");

    /* the scene as a user says it, then resolved against the body */
    pd_scene_spec spec = {0};
    pd_scene *sc = &spec.sc;
    sc->model = PD_MODEL_PMB;
    sc->bulk_modulus = 14.9e9; /* Pa: c = 18 K / (pi delta^4)          */
    spec.has_k = 1;
    sc->has_failure = 1;       /* s0 = 0.0005 - 0.25 s_min             */
    sc->s00 = 0.0005;
    sc->alpha = 0.25;
    sc->has_contact = 1;
    sc->has_projectile = 1;    /* 1.5 mm, 5 g, at 100 m/s down z       */
    const double centre[3] = {0.005, 0.005, 0.0055}, velocity[3] = {0, 0, -100};
    for (int d = 0; d < 3; d++) {
        sc->proj_center[d] = centre[d];
        sc->proj_velocity[d] = velocity[d];
    }
    sc->proj_radius = 0.0015;
    sc->proj_mass = 0.005;
    sc->safety = 0.8;          /* dt = 0.8 x the stable step           */
    sc->steps = 200;
    sc->every = 50;
    sc->series = 20;           /* a row of the time series every 20    */
    sc->threads = omp_get_max_threads();
    if (sweep) {               /* G0 of s00 = 0.0005 at delta = 1.5 mm: */
        spec.has_g0 = 1;       /* 9 K delta s00^2 / 5                   */
        spec.g0 = 9 * 14.9e9 * 0.0015 * 0.0005 * 0.0005 / 5;
        spec.has_time = 1;
        spec.end_time = END_TIME;
    }
    if (pd_scene_resolve(&spec, p, b, "the block") != PD_OK)
        return fail("the scene");

    /* the run and its file: frames laid out, then published */
    pd_sim *sim = NULL;
    pd_file *f = NULL;
    char *text = pd_scene_text(sc);
    if (text == NULL || pd_sim_new(p, b, sc, &sim) != PD_OK)
        return fail("the run");
    if (pd_file_create(path, &f) != PD_OK ||
        pd_run_file_start(f, 0, NULL, p, b, NULL, sc, pd_sim_effects(sim), "impact", text, 0) !=
            PD_OK)
        return fail(path);
    fprintf(stderr, "impact: %d threads\n", sc->threads);
    const double t0 = omp_get_wtime();
    pd_status s = pd_sim_setup(sim);
    for (int64_t n = 0; n <= sc->steps && s == PD_OK; n++) {
        if (n > 0)
            s = pd_sim_step(sim);
        pd_energy e;
        if (s == PD_OK && pd_frame_at(sc, n) &&
            (s = pd_run_file_frame(f, sim, sc->fields, &e)) == PD_OK)
            printf("step %3lld  t %.4e s  kinetic %.6e J  projectile %.6e J  released %.6e J  "
                   "balance %.6e J  broken %lld\n",
                   (long long)n, pd_sim_time(sim), e.kinetic, e.projectile, e.released,
                   pd_energy_total(&e), (long long)pd_sim_broken(sim));
        else if (s == PD_OK && pd_run_file_sample_due(f, n) && /* the series' row alone */
                 (s = pd_sim_energy(sim, &e, NULL)) == PD_OK)
            s = pd_run_file_sample(f, sim, &e);
    }
    const double wall = omp_get_wtime() - t0;
    if (s == PD_OK)
        fprintf(stderr, "impact: %lld steps in %.3f s (%.3g bond updates/s)\n",
                (long long)sc->steps, wall,
                wall > 0 ? (double)b->count * (double)sc->steps / wall : 0.0);
    if (s == PD_OK)
        s = pd_file_close(f);
    else
        pd_file_abort(f);
    int rc = s == PD_OK ? 0 : fail("the run");
    free(text);
    pd_sim_free(sim);
    pd_bonds_free(b);
    pd_particles_free(p);
    return rc;
}
