/*
 * passes.c -- the bench's timing of pd-run's PMB bond kernel alone
 * (share/bench.sh, part "passes"): the bond pass of a model, with failure
 * and contact, repeated in one process and timed pass by pass, so that
 * the best pass shows what the kernel does when this shared machine lets
 * it run (as share/stream.c's roofs are the best of their repetitions) and
 * the median what it does in the hour the bench ran.
 *
 *     passes MODEL.h5 THREADS PASSES
 *
 * prints one line: "kernel NAME particles N bonds B best S median S" (B
 * the bonds i < j, S seconds a pass).  The state: the seed's PMB constants
 * (c, s00, alpha of examples/lammps-impact/impact.scene), every particle
 * given a random velocity of up to 0.05 m/s and 5 steps taken, so that
 * every bond is stretched or compressed by about 1e-5 and none breaks;
 * then PASSES evaluations of the bond forces (the model's force with
 * failure: the breaking test, the new s0 and, in the kernel, the contact
 * test of every pair), the first one not timed.  Built by `make
 * share/passes`; links lib/libpd.a.
 */
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "models/model.h"
#include "pd.h"
#include "state/sim.h"

static int by_value(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static int fail(const char *what)
{
    fprintf(stderr, "passes: %s: %s\n", what, pd_errmsg());
    return 1;
}

int main(int argc, char **argv)
{
    if (argc != 4 || atoi(argv[2]) < 1 || atoi(argv[3]) < 2) {
        fprintf(stderr, "usage: passes MODEL.h5 THREADS PASSES (PASSES >= 2)\n");
        return 2;
    }
    const int passes = atoi(argv[3]);
    omp_set_num_threads(atoi(argv[2]));
    pd_file *f = NULL;
    pd_particles *p = NULL;
    pd_bonds *b = NULL;
    if (pd_file_open(argv[1], &f) != PD_OK || pd_read_particles(f, &p) != PD_OK ||
        pd_read_bonds_compact(f, p, &b) != PD_OK)
        return fail(argv[1]);
    pd_file_close(f);
    pd_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.model = PD_MODEL_PMB;
    sc.c = 1.6863e22;
    sc.dt = 1e-7;
    sc.steps = passes + 5;
    sc.has_failure = 1;
    sc.s00 = 0.0005;
    sc.alpha = 0.25;
    sc.has_contact = 1;
    pd_sim *sim = NULL;
    if (pd_sim_new(p, b, &sc, &sim) != PD_OK)
        return fail("the run");
    double *const *v = pd_sim_velocities(sim);
    uint64_t s = 12345;
    for (int64_t i = 0; i < p->n; i++)
        for (int d = 0; d < 3; d++) {
            s = s * 6364136223846793005ULL + 1442695040888963407ULL;
            v[d][i] = 0.05 * (2.0 * (double)(s >> 11) / 9007199254740992.0 - 1.0);
        }
    if (pd_sim_setup(sim) != PD_OK)
        return fail("the set-up");
    for (int k = 0; k < 5; k++)
        if (pd_sim_step(sim) != PD_OK)
            return fail("a step");
    double *t = malloc((size_t)passes * sizeof(double));
    if (t == NULL)
        return fail("memory");
    const pd_effect *force = sim->model->force_failure;
    for (int k = 0; k <= passes; k++) {
        const double t0 = omp_get_wtime();
        if (force->force(sim, NULL) != PD_OK)
            return fail("the bond pass");
        if (k > 0)
            t[k - 1] = omp_get_wtime() - t0;
    }
    qsort(t, (size_t)passes, sizeof(double), by_value);
    printf("kernel %s particles %lld bonds %lld best %.6f median %.6f\n",
           pd_sim_stencil(sim) > 0 ? "stencil" : "list", (long long)p->n,
           (long long)(b->count / 2), t[0], t[passes / 2]);
    free(t);
    pd_sim_free(sim);
    pd_bonds_free(b);
    pd_particles_free(p);
    return 0;
}
