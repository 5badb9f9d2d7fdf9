/*
 * series.c -- a run's time series (pd-run --series, /series of the run
 * file): one row of the whole run's figures per sampled step, for the
 * curves a study plots (force against displacement, energies against
 * time) and for the summary of a sweep (pd-series --last).
 *
 * A row holds, in the order of pd_series_columns:
 *   - the step, the time and the energies of the balance (pd_energy);
 *   - the broken bonds, the particles damaged past PD_DAMAGE_THRESHOLD
 *     (pd-damage's count), the largest damage and the lost particles;
 *   - the body's momentum, sum rho_i V_i v_i;
 *   - with --relax, what the load step's relaxation took (pd_relax_info);
 *   - per named set, its particles' mean displacement y - x (lost ones
 *     left out) and the force the boundary conditions apply to them: the
 *     effects' reaction hooks (lib/effects/bc.c), summed in row order;
 *   - per projectile and indenter, its centre, velocity and the force the
 *     body puts on it.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/comm.h"
#include "state/sim.h"

static const char *const fixed[] = {
    "step",          "time",           "kinetic_energy",    "elastic_energy",
    "contact_energy", "released_energy", "lost_energy",     "external_work"};
static const char *const counts[] = {"balance",    "broken_bonds",   "damaged_particles",
                                     "max_damage", "lost_particles", "px",
                                     "py",         "pz"};
static const char *const relax_cols[] = {"relax_iterations", "relax_residual", "relax_load",
                                         "relax_peak_kinetic_energy"};
static const char *const set_cols[] = {"ux", "uy", "uz", "fx", "fy", "fz"};
static const char *const sphere_cols[] = {"x", "y", "z", "vx", "vy", "vz", "fx", "fy", "fz"};

#define COUNT(a) ((int)(sizeof(a) / sizeof(a)[0]))

/* Name column k (when names is not NULL) and return k + 1. */
static int column(char (*names)[PD_SERIES_NAME], int k, const char *prefix, const char *name)
{
    if (names)
        snprintf(names[k], PD_SERIES_NAME, "%s%s%s", prefix ? prefix : "", prefix ? "." : "",
                 name);
    return k + 1;
}

int pd_series_columns(const pd_scene *sc, char (*names)[PD_SERIES_NAME])
{
    int k = 0;
    for (int c = 0; c < COUNT(fixed); c++)
        k = column(names, k, NULL, fixed[c]);
    if (sc->has_projectile)
        k = column(names, k, NULL, "projectile_energy");
    if (sc->damping > 0 && !sc->relax)
        k = column(names, k, NULL, "damped_energy");
    for (int c = 0; c < COUNT(counts); c++)
        k = column(names, k, NULL, counts[c]);
    for (int c = 0; sc->relax && c < COUNT(relax_cols); c++)
        k = column(names, k, NULL, relax_cols[c]);
    for (int s = 0; sc->sets && s < sc->sets->count; s++)
        for (int c = 0; c < COUNT(set_cols); c++)
            k = column(names, k, sc->sets->set[s].name, set_cols[c]);
    for (int c = 0; sc->has_projectile && c < COUNT(sphere_cols); c++)
        k = column(names, k, "projectile", sphere_cols[c]);
    for (int c = 0; sc->has_indenter && c < COUNT(sphere_cols); c++)
        k = column(names, k, "indenter", sphere_cols[c]);
    return k;
}

/* The body's momentum, kg m/s, in fixed chunks (any thread count, any
 * ranks: collective on a piece). */
static pd_status momentum(const pd_sim *sim, double P[3])
{
    double *buf = malloc((size_t)(sim->n > 0 ? sim->n : 1) * 3 * sizeof(double));
    if (sim->piece && pd_comm_or(buf == NULL)) {
        free(buf);
        buf = NULL;
    }
    if (buf == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the momentum");
    const double *rho = sim->p->density, *V = sim->p->volume;
    const double *each[3] = {buf, buf + sim->n, buf + 2 * sim->n};
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++)
        for (int d = 0; d < 3; d++)
            buf[d * sim->n + i] = rho[i] * V[i] * sim->v[d][i];
    pd_sim_sum(sim, each, 3, P);
    free(buf);
    return PD_OK;
}

/* A member's terms of set_figures: its displacement, its r, 1 when it is
 * not lost. */
enum { TERMS = 7 };

static void member_terms(const pd_sim *sim, int64_t i, double *const r[3], double *t)
{
    for (int d = 0; d < 3; d++) {
        t[d] = sim->y[d][i] - sim->p->x[d][i];
        t[3 + d] = r ? r[d][i] : 0.0;
    }
    t[6] = !(sim->lost && sim->lost[i]);
}

/* Per set: the mean displacement of its particles that are not lost
 * (NaN when all are) and the sum of r over all of them, in row order.  A
 * piece's members are summed in the same order, each from its owner's
 * terms (a sum over the ranks of terms that are zero but on one). */
static pd_status set_figures(const pd_sim *sim, int s, double *const r[3], double *out)
{
    const int64_t *rows = sim->set_rows[s];
    const int64_t n = sim->sc.sets->set[s].n;
    const pd_piece *pc = sim->piece;
    double *terms = NULL;
    if (pc) {
        terms = calloc((size_t)(n > 0 ? n : 1) * TERMS, sizeof(double));
        if (pd_comm_or(terms == NULL)) {
            free(terms);
            return pd_fail(PD_ERR_NOMEM, "out of memory for the sets' figures");
        }
        for (int64_t m = 0; m < n; m++)
            if (rows[m] >= pc->own_lo && rows[m] < pc->own_hi)
                member_terms(sim, rows[m], r, terms + TERMS * m);
        pd_comm_add(terms, n * TERMS);
    }
    double u[3] = {0, 0, 0}, F[3] = {0, 0, 0};
    int64_t kept = 0;
    for (int64_t m = 0; m < n; m++) {
        double own[TERMS];
        const double *t = terms ? terms + TERMS * m : own;
        if (terms == NULL)
            member_terms(sim, rows[m], r, own);
        for (int d = 0; d < 3 && r; d++)
            F[d] += t[3 + d];
        if (t[6] == 0)
            continue;
        for (int d = 0; d < 3; d++)
            u[d] += t[d];
        kept++;
    }
    free(terms);
    for (int d = 0; d < 3; d++) {
        out[d] = kept ? u[d] / (double)kept : NAN;
        out[3 + d] = F[d];
    }
    return PD_OK;
}

/* The reactions of every particle, or *r[0] NULL when no effect has one. */
static pd_status reactions(const pd_sim *sim, double *r[3])
{
    r[0] = r[1] = r[2] = NULL;
    int any = 0;
    for (int k = 0; k < sim->neffects; k++)
        any |= sim->effects[k]->reaction != NULL;
    if (!any)
        return PD_OK;
    for (int d = 0; d < 3; d++)
        if ((r[d] = malloc((size_t)(sim->n > 0 ? sim->n : 1) * sizeof(double))) == NULL) {
            for (int e = 0; e < d; e++)
                free(r[e]);
            r[0] = NULL;
            return pd_fail(PD_ERR_NOMEM, "out of memory for the reaction forces");
        }
    pd_sim_reactions(sim, r);
    return PD_OK;
}

void pd_sim_reactions(const pd_sim *sim, double *const r[3])
{
    for (int d = 0; d < 3; d++)
        memset(r[d], 0, (size_t)sim->n * sizeof(double));
    for (int k = 0; k < sim->neffects; k++)
        if (sim->effects[k]->reaction)
            sim->effects[k]->reaction(sim, sim->state[k], r);
}

void pd_sim_indenter_centre(const pd_sim *sim, double c[3])
{
    const pd_scene *sc = &sim->sc;
    if (sc->has_indenter)
        pd_indenter_centre(sc->ind_center, sc->ind_velocity, sim->step, sc->dt, c);
    else
        c[0] = c[1] = c[2] = 0.0;
}

static int sphere(double *row, int k, const double x[3], const double v[3], const double f[3])
{
    for (int d = 0; d < 3; d++) {
        row[k + d] = x[d];
        row[k + 3 + d] = v[d];
        row[k + 6 + d] = f[d];
    }
    return k + 9;
}

pd_status pd_sim_series_row(const pd_sim *sim, const pd_energy *e, double *row)
{
    return pd_sim_series_row_damage(sim, e, NULL, row);
}

pd_status pd_sim_series_row_damage(const pd_sim *sim, const pd_energy *e, const double *damage,
                                   double *row)
{
    const pd_scene *sc = &sim->sc;
    int k = 0;
    row[k++] = (double)sim->step;
    row[k++] = sim->time;
    row[k++] = e->kinetic;
    row[k++] = e->elastic;
    row[k++] = e->contact;
    row[k++] = e->released;
    row[k++] = e->lost;
    row[k++] = e->work;
    if (sc->has_projectile)
        row[k++] = e->projectile;
    if (sc->damping > 0 && !sc->relax)
        row[k++] = e->damped;
    double maxd;
    int64_t damaged;
    pd_status s = damage ? pd_sim_damage_stats_of(sim, damage, PD_DAMAGE_THRESHOLD, &maxd,
                                                  &damaged)
                         : pd_sim_damage_stats(sim, PD_DAMAGE_THRESHOLD, &maxd, &damaged);
    double P[3];
    if (s == PD_OK)
        s = momentum(sim, P);
    double *r[3] = {NULL, NULL, NULL};
    if (s == PD_OK)
        s = reactions(sim, r);
    if (sim->piece && (s = pd_comm_agree(s)) != PD_OK && r[0] != NULL)
        for (int d = 0; d < 3; d++) /* another rank's failure */
            free(r[d]);
    if (s != PD_OK)
        return s;
    row[k++] = pd_energy_total(e);
    row[k++] = (double)pd_sim_broken(sim);
    row[k++] = (double)damaged;
    row[k++] = maxd;
    row[k++] = (double)pd_sim_lost(sim);
    for (int d = 0; d < 3; d++)
        row[k++] = P[d];
    if (sc->relax) {
        row[k++] = (double)sim->relaxed.iterations;
        row[k++] = sim->relaxed.residual;
        row[k++] = sim->relaxed.load;
        row[k++] = sim->relaxed.kinetic_peak;
    }
    for (int set = 0; set < sim->nsets && s == PD_OK; set++, k += 6)
        s = set_figures(sim, set, r[0] ? r : NULL, row + k);
    for (int d = 0; d < 3; d++)
        free(r[d]);
    if (s != PD_OK)
        return s;
    if (sc->has_projectile)
        k = sphere(row, k, sim->proj_x, sim->proj_v, sim->proj_f);
    if (sc->has_indenter) {
        double c[3];
        pd_sim_indenter_centre(sim, c);
        k = sphere(row, k, c, sc->ind_velocity, sim->ind_f);
    }
    return PD_OK;
}
