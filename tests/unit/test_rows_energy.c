/*
 * test_rows_energy -- the bond list's energies and damage taken over the
 * half bonds (lib/models/pmb.c's rows_energy, in AVX-512 rows, and
 * lib/bonds/bonds.c's pd_half_damage) against walks of the directed
 * families written here from the formulas.
 *
 * Proves: on a perturbed box (no lattice stencil: the bond list), with
 * bonds breaking and pairs in contact under random velocities, after each
 * of 30 steps, every particle's elastic energy (PMB: 1/4 c s^2 |xi| nu V_i
 * V_j over its intact bonds) and its contact energy over the pairs of its
 * family (1/4 (c_S/delta) (d - r)^2 V_i V_j, seed 000 eqs. 13-15) agree
 * with the families' sums to rounding (1e-12 of the largest); the damage
 * of the half bonds is pd_damage of the directed bits bit for bit; and
 * the energies and damage are the same bits on 1 and 2 threads; and that
 * a run that asks for the energies of every step before taking it
 * (pd_sim_energy_next: the bond pass counts them, pmb_row512's `energy`)
 * has the same energies and damage, bit for bit, as one that does not
 * (a pass of their own, rows_energy).  Where
 * the processor has no AVX-512 (or PD_NO_AVX512 is set) the elastic
 * energies are the families' walk, and the contact of the pairs is the
 * contact list's, not checked here.
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bonds/half.h"
#include "check.h"
#include "models/model.h"
#include "pd.h"
#include "state/sim.h"

static const double H = 1e-3, K = 14.9e9, RHO = 2200.0, DELTA = 3.0001e-3;

/* The particle energies of the directed families: elastic (contact 0) or
 * contact (1), e_i = V_i sum_j (...) V_j. */
static void reference(const pd_sim *sim, int contact, double *e)
{
    const pd_bonds *b = sim->b;
    const uint64_t *intact = pd_sim_intact(sim);
    const double *V = sim->p->volume, *rad = sim->p->radius, c = sim->sc.c;
    const double kc = PD_CONTACT_SCALE * c / b->horizon;
    for (int64_t i = 0; i < sim->n; i++) {
        double sum = 0;
        for (int64_t q = b->offset[i]; q < b->offset[i + 1]; q++) {
            const int32_t j = b->neighbor[q];
            const double dx = sim->y[0][j] - sim->y[0][i], dy = sim->y[1][j] - sim->y[1][i],
                         dz = sim->y[2][j] - sim->y[2][i];
            const double r = sqrt(dx * dx + dy * dy + dz * dz), L = b->length[q];
            if (contact) {
                const double d = fmin(PD_CONTACT_REF_FRAC * L,
                                      PD_CONTACT_RADIUS_FAC * (rad[i] + rad[j]));
                if (r < d)
                    sum += 0.25 * kc * (d - r) * (d - r) * V[j];
            } else if (pd_bond_intact(intact, q)) {
                double dr = r - L;
                dr = fabs(dr) < PD_NEAR_ZERO ? 0.0 : dr;
                const double s = dr / L;
                sum += 0.25 * c * s * s * L * b->vfactor[q] * V[j];
            }
        }
        e[i] = sum * V[i];
    }
}

/* The largest |a - b| over n values, relative to the largest |b|. */
static double rel_diff(const double *a, const double *b, int64_t n)
{
    double d = 0, m = 0;
    for (int64_t i = 0; i < n; i++) {
        d = fmax(d, fabs(a[i] - b[i]));
        m = fmax(m, fabs(b[i]));
    }
    return m > 0 ? d / m : d;
}

/* 30 steps of the box on `threads` threads; the energies and damage of
 * every step into e (elastic, contact, damage: 3 n a step). */
static void run(const pd_particles *p, const pd_bonds *b, int threads, int ask, double *out,
                int *rows, int64_t *broken, int64_t *touching)
{
    omp_set_num_threads(threads);
    pd_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.model = PD_MODEL_PMB;
    sc.c = pd_pmb_c_from_bulk(K, b->horizon);
    sc.safety = 0.8;
    sc.dt_stable = pd_stable_dt(p, b, &sc);
    sc.dt = sc.safety * sc.dt_stable;
    sc.steps = 30;
    sc.has_failure = 1;
    sc.s00 = 0.0005;
    sc.alpha = 0.25;
    sc.has_contact = 1;
    pd_sim *sim = NULL;
    if (pd_sim_new(p, b, &sc, &sim) != PD_OK)
        die("pd_sim_new");
    double *const *v = pd_sim_velocities(sim);
    uint64_t s = 88172645463325252ULL;
    for (int64_t i = 0; i < p->n; i++)
        for (int d = 0; d < 3; d++) {
            s = s * 6364136223846793005ULL + 1442695040888963407ULL;
            v[d][i] = 40.0 * (2.0 * (double)(s >> 11) / 9007199254740992.0 - 1.0);
        }
    if (pd_sim_setup(sim) != PD_OK)
        die("setup");
    CHECK(pd_sim_stencil(sim) == 0, "a perturbed box is walked as a bond list");
    *rows = sim->half.pack != NULL;
    const int64_t n = p->n;
    double *want = malloc((size_t)n * sizeof(double));
    if (want == NULL)
        die("memory");
    *touching = 0;
    int counted = 0;
    for (int step = 0; step < 30; step++) {
        if (ask)
            pd_sim_energy_next(sim);
        if (pd_sim_step(sim) != PD_OK)
            die("step");
        counted += sim->half.energy_ok && sim->half.energy_step == sim->step;
        double *e = out + (size_t)step * 3 * n;
        memset(e, 0, (size_t)2 * n * sizeof(double));
        sim->model->force_failure->energy(sim, NULL, e);
        pd_half_contact_energy(sim, e + n);
        reference(sim, 0, want);
        CHECK(rel_diff(e, want, n) < 1e-12, "step %d: elastic energies off by %.2g", step,
              rel_diff(e, want, n));
        reference(sim, 1, want);
        if (sim->half.contact) /* else the contact list holds these pairs */
            CHECK(rel_diff(e + n, want, n) < 1e-12, "step %d: contact energies off by %.2g",
                  step, rel_diff(e + n, want, n));
        for (int64_t i = 0; i < n; i++)
            *touching += want[i] > 0;
        if (!pd_half_damage(p, b, &sim->half, e + 2 * n))
            die("pd_half_damage declined a whole body of equal volumes");
        pd_damage(p, b, pd_sim_intact(sim), want);
        CHECK(memcmp(e + 2 * n, want, (size_t)n * sizeof(double)) == 0,
              "step %d: the half bonds' damage is not pd_damage's", step);
    }
    CHECK(counted == (ask && *rows ? 30 : 0), "the bond pass counted the energies of %d steps",
          counted);
    *broken = pd_sim_broken(sim);
    free(want);
    pd_sim_free(sim);
}

int main(void)
{
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, "0,0.0195,0,0.0055,0,0.0045", &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {.spacing = H, .density = RHO, .material = 1, .perturb = 0.1 * H,
                            .seed = 11};
    pd_particles *p = NULL;
    if (pd_lattice_make(&r, 1, &lp, &p) != PD_OK || pd_particles_sort_spatial(p, DELTA) != PD_OK)
        die("lattice");
    pd_bonds *b = NULL;
    if (pd_bonds_build(p, DELTA, &b) != PD_OK)
        die("bonds");
    const size_t each = (size_t)30 * 3 * (size_t)p->n;
    double *one = malloc(each * sizeof(double)), *two = malloc(each * sizeof(double));
    double *asked = malloc(each * sizeof(double));
    if (!one || !two || !asked)
        die("memory");
    int f0 = failures, rows1, rows2, rows3;
    int64_t broken1, broken2, broken3, touching1, touching2, touching3;
    run(p, b, 1, 0, one, &rows1, &broken1, &touching1);
    run(p, b, 2, 0, two, &rows2, &broken2, &touching2);
    run(p, b, 2, 1, asked, &rows3, &broken3, &touching3);
    CHECK(broken1 > 0 && touching1 > 0, "bonds should break (%lld) and pairs touch (%lld)",
          (long long)broken1, (long long)touching1);
    CHECK(memcmp(one, two, each * sizeof(double)) == 0 && broken1 == broken2,
          "1 and 2 threads give other bits");
    CHECK(memcmp(two, asked, each * sizeof(double)) == 0 && broken2 == broken3,
          "the energies the bond pass counted are not those of a pass of their own");
    char what[400];
    snprintf(what, sizeof what,
             "perturbed box, %lld particles, 30 steps (%lld bonds broken, %lld particle-steps in "
             "contact): energies %s agree with the families' to 1e-12 and, counted in the bond "
             "pass, are those of a pass of their own bit for bit; the half bonds' damage is "
             "pd_damage's; 1 and 2 threads the same bits",
             (long long)p->n, (long long)broken1, (long long)touching1,
             rows1 ? "in AVX-512 rows" : "(no AVX-512 here: the families' walk)");
    proved(f0, what);
    free(one);
    free(two);
    free(asked);
    pd_bonds_free(b);
    pd_particles_free(p);
    return failures ? 1 : 0;
}
