/*
 * relax.c -- quasi-static loading by adaptive dynamic relaxation (pd-run
 * --relax; B. Kilic and E. Madenci, "An adaptive dynamic relaxation method
 * for quasi-static simulations using the peridynamic theory", Theor. Appl.
 * Fract. Mech. 53 (2010)).
 *
 * Each step of the run is a load step: its time t_n = n dt sets the loads
 * (the prescribed motions at their offset P(t_n), the body forces b(t_n),
 * the indenter at its centre of t_n), and the body is relaxed to the
 * static state under them.  Relaxation integrates the damped fictitious
 * dynamics  rho u'' + c rho u' = f(u)  from rest by central differences of
 * step h (sc.relax_dt, safety x the stable step, so that the fictitious
 * density is the body's own):
 *     v^{1/2}   = h f^0 / (2 rho)
 *     v^{k+1/2} = ((2 - c_k h) v^{k-1/2} + 2 h f^k / rho) / (2 + c_k h)
 *     y^{k+1}   = y^k + h v^{k+1/2}
 * on the free components; the held ones stay at x + P(t_n), at rest.  The
 * damping c_k is adapted at every iteration to the critical damping of the
 * lowest mode, twice the square root of the Rayleigh quotient of the
 * diagonal local stiffness,
 *     K_ii = -(f_i^k - f_i^{k-1}) / (rho_i h v_i^{k-1/2}),
 *     c_k  = 2 sqrt(u^T K u / u^T u),  u = y^k - x  (0 unless positive),
 * or is the C of --damping when one is given (plain dynamic relaxation).
 * Bonds do not break while the body relaxes (its transient would break
 * them: the held layer jumps by the load's increment at the first
 * iteration); the breaking test is taken on the relaxed state and, while
 * it breaks bonds, the body is relaxed again from there (each time from
 * rest), so that a crack runs as far as the load step drives it.
 * A load step is relaxed when the residual, the norm of the net force on
 * the free particles, sqrt(sum over free components of (V_i f_i)^2), N,
 * is at most sc.relax_tolerance times the load: the norm of the loads
 * (the reactions of the held sets and the body forces, particle by
 * particle, and the force on the indenter), but no less than the norm of
 * the forces K PD_PENALTY_STRAIN V_i^(2/3) of a negligible stress on every
 * particle (a scene without loads, a bar cut through).
 *
 * The work of the loads is the trapezoid over the load steps,
 *     W += sum_i (R_i^{n-1} + R_i^n)/2 . (y_i^n - y_i^{n-1})
 *          - (F^{n-1} + F^n)/2 . (c^n - c^{n-1})
 * (R the reactions, F the force on the indenter, c its centre), exact for
 * a linear body: elastic + released - work is then what the relaxation
 * dissipated.  Every sum is taken in fixed chunks, the same bits at any
 * thread count; a load step starts from its state's forces evaluated again,
 * so that a restart (positions and bonds kept) goes on bit for bit.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/comm.h"
#include "state/sim.h"

enum { RESIDUAL, LOAD, QUOTIENT, NORM, KINETIC, NBUF };

struct pd_relax {
    double *y0[3];    /* positions at the end of the last load step, m    */
    double *r0[3];    /* the reactions there, N                           */
    double *r[3];     /* the reactions now, N                             */
    double *fprev[3]; /* forces of the iteration before, N/m^3            */
    double *term[NBUF]; /* each particle's term of the sums               */
    double floor;     /* the least load a residual is measured against, N */
};

static void relax_free(struct pd_relax *r)
{
    if (r == NULL)
        return;
    for (int d = 0; d < 3; d++) {
        free(r->y0[d]);
        free(r->r0[d]);
        free(r->r[d]);
        free(r->fprev[d]);
    }
    for (int k = 0; k < NBUF; k++)
        free(r->term[k]);
    free(r);
}

static pd_status relax_new(const pd_sim *sim, struct pd_relax **out)
{
    struct pd_relax *r = calloc(1, sizeof *r);
    const size_t bytes = (size_t)(sim->n > 0 ? sim->n : 1) * sizeof(double);
    int ok = r != NULL;
    for (int d = 0; d < 3 && ok; d++)
        ok = (r->y0[d] = malloc(bytes)) && (r->r0[d] = malloc(bytes)) &&
             (r->r[d] = malloc(bytes)) && (r->fprev[d] = malloc(bytes));
    for (int k = 0; k < NBUF && ok; k++)
        ok = (r->term[k] = malloc(bytes)) != NULL;
    if (!ok) {
        relax_free(r);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the relaxation");
    }
    /* the floor: a stress of K PD_PENALTY_STRAIN on each particle's face,
     * the norm of K s V_i^(2/3) (a body whose load vanished, a bar cut
     * through, is at rest once its residual is below that) */
    double k = sim->sc.bulk_modulus;
    if (!(k > 0)) /* c given: c is linear in K */
        k = sim->sc.c / pd_pmb_c_for(sim->p, 1.0, sim->b->horizon);
    /* in row order (a piece of a body on MPI ranks: its own rows, on from
     * the ranks below) */
    const int64_t lo = sim->piece ? sim->piece->own_lo : 0, hi = sim->piece ? sim->piece->own_hi : sim->n;
    double sum = sim->piece ? pd_comm_chain_in() : 0.0;
    for (int64_t i = lo; i < hi; i++) {
        const double f = k * PD_PENALTY_STRAIN * pow(sim->p->volume[i], 2.0 / 3.0);
        sum += f * f;
    }
    if (sim->piece)
        sum = pd_comm_chain_out(sum);
    r->floor = sqrt(sum);
    *out = r;
    return PD_OK;
}

/* Does the relaxation move component a of particle i? */
static inline int moves(const pd_sim *sim, int64_t i, int a)
{
    return !(sim->held && (sim->held[i] >> a & 1)) && !(sim->lost && sim->lost[i]);
}

/* The sums of one iteration, each over the particles in fixed chunks:
 * the squares of the residual and of the loads, the Rayleigh quotient's
 * numerator and denominator (`quotient`: after the first iteration), and
 * the kinetic energy. */
static void sums(const pd_sim *sim, struct pd_relax *R, int quotient, double out[NBUF])
{
    const double h = sim->sc.relax_dt;
    const double *rho = sim->p->density, *V = sim->p->volume;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        double t[NBUF] = {0, 0, 0, 0, 0};
        for (int a = 0; a < 3; a++) {
            const double f = sim->f[a][i], v = sim->v[a][i], r = R->r[a][i];
            t[LOAD] += r * r;
            t[KINETIC] += v * v;
            if (!moves(sim, i, a))
                continue;
            t[RESIDUAL] += (V[i] * f) * (V[i] * f);
            const double u = sim->y[a][i] - sim->p->x[a][i];
            t[NORM] += u * u;
            if (quotient && v != 0) {
                const double k = -(f - R->fprev[a][i]) / (rho[i] * h * v);
                t[QUOTIENT] += u * k * u;
            }
        }
        t[KINETIC] *= 0.5 * rho[i] * V[i];
        for (int k = 0; k < NBUF; k++)
            R->term[k][i] = t[k];
    }
    pd_sim_sum(sim, (const double *const *)R->term, NBUF, out); /* over the ranks too */
}

/* One iteration's move of the free components with damping c (`first`:
 * the start from rest, v^{1/2} = h f / (2 rho)); f is kept as fprev. */
static void move(pd_sim *sim, struct pd_relax *R, double c, int first)
{
    const double h = sim->sc.relax_dt, a0 = 2.0 - c * h, a1 = 1.0 / (2.0 + c * h);
    const double *rho = sim->p->density;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++)
        for (int a = 0; a < 3; a++) {
            const double f = sim->f[a][i];
            R->fprev[a][i] = f;
            if (!moves(sim, i, a))
                continue;
            double *v = &sim->v[a][i];
            *v = first ? 0.5 * h * f / rho[i] : (a0 * *v + 2.0 * h * f / rho[i]) * a1;
            sim->y[a][i] += h * *v;
        }
}

/* The forces at the current positions (a piece of a body on MPI ranks:
 * its ghosts' positions first, and its ghosts at rest after). */
static pd_status forces(pd_sim *sim)
{
    if (sim->piece)
        pd_piece_halo(sim);
    pd_status s = pd_sim_compute_forces(sim);
    if (sim->piece)
        pd_piece_ghosts_rest(sim);
    return s;
}

/* Relax from rest under the current loads until the residual is within
 * the tolerance; *total counts the load step's iterations. */
static pd_status iterate(pd_sim *sim, struct pd_relax *R, pd_relax_info *info, int64_t *total)
{
    const pd_scene *sc = &sim->sc;
    const double tol = sc->relax_tolerance;
    for (int d = 0; d < 3; d++)
        memset(sim->v[d], 0, (size_t)sim->n * sizeof(double));
    for (int64_t k = 0;; k++, ++*total) {
        double t0 = pd_wtime();
        pd_sim_reactions(sim, R->r);
        double sum[NBUF];
        sums(sim, R, k > 0, sum);
        const double *F = sim->ind_f;
        info->residual = sqrt(sum[RESIDUAL]);
        info->load = sqrt(sum[LOAD] + F[0] * F[0] + F[1] * F[1] + F[2] * F[2]);
        info->kinetic = sum[KINETIC];
        info->kinetic_peak = fmax(info->kinetic_peak, sum[KINETIC]);
        info->iterations = *total;
        if (!isfinite(info->residual) || !isfinite(sum[KINETIC]))
            return pd_fail(PD_ERR_UNSTABLE,
                           "the relaxation of load step %lld is not finite at iteration %lld",
                           (long long)sim->step, (long long)*total);
        const double ref = fmax(info->load, R->floor);
        if (info->residual <= tol * ref)
            return PD_OK;
        if (*total == sc->relax_iterations)
            return pd_fail(PD_ERR_UNSTABLE,
                           "load step %lld is not relaxed after %lld iterations: the residual "
                           "force %.3g N is %.3g times the load %.3g N, above --relax-tolerance "
                           "%g; give more --relax-iterations or smaller load steps",
                           (long long)sim->step, (long long)*total, info->residual,
                           info->residual / ref, ref, tol);
        double c = 0;
        if (sc->damping > 0)
            c = sc->damping;
        else if (k > 0 && sum[QUOTIENT] > 0 && sum[NORM] > 0)
            c = 2.0 * sqrt(sum[QUOTIENT] / sum[NORM]);
        move(sim, R, c, k == 0);
        sim->timers[PD_T_INTEGRATE] += pd_wtime() - t0;
        pd_status s = forces(sim);
        if (s != PD_OK)
            return s;
    }
}

/* The load step with the bonds held elastic while the body relaxes
 * (sim->setup: the kernels' forces without the breaking test), then the
 * breaking test on the relaxed state and, while it breaks bonds, the
 * relaxation again from there. */
static pd_status load_step(pd_sim *sim, struct pd_relax *R, pd_relax_info *info, double F0[3],
                           double c0[3])
{
    const pd_scene *sc = &sim->sc;
    double t0 = pd_wtime();
    pd_status s = forces(sim); /* the state the step starts from */
    if (s != PD_OK)
        return s;
    pd_sim_reactions(sim, R->r0);
    memcpy(F0, sim->ind_f, 3 * sizeof(double));
    pd_sim_indenter_centre(sim, c0);
    for (int d = 0; d < 3; d++)
        memcpy(R->y0[d], sim->y[d], (size_t)sim->n * sizeof(double));
    sim->step++; /* the loads of the new time */
    sim->time = (double)sim->step * sc->dt;
    if ((s = pd_sim_constrain(sim, PD_PHASE_SETUP)) != PD_OK)
        return s;
    sim->timers[PD_T_INTEGRATE] += pd_wtime() - t0;
    if ((s = forces(sim)) != PD_OK)
        return s;
    memset(info, 0, sizeof *info);
    for (int64_t total = 0;;) {
        if ((s = iterate(sim, R, info, &total)) != PD_OK || !sc->has_failure)
            return s;
        const int64_t broken = pd_sim_broken(sim);
        sim->setup = 0;
        s = forces(sim);
        sim->setup = 1;
        int more = pd_sim_broken(sim) != broken; /* a piece: on some rank */
        if (sim->piece)
            more = pd_comm_or(more);
        if (s != PD_OK || !more)
            return s;
        info->rounds++;
        /* the forces without the bonds just broken (the breaking pass
         * still had them), to relax from */
        if ((s = forces(sim)) != PD_OK)
            return s;
    }
}

pd_status pd_sim_relax(pd_sim *sim, pd_relax_info *info)
{
    const pd_scene *sc = &sim->sc;
    if (!(sc->relax_dt > 0) || !(sc->relax_tolerance > 0))
        return pd_fail(PD_ERR_INVALID, "the scene is not quasi-static (pd_scene_resolve of a "
                       "scene with relax sets its step and tolerance)");
    pd_status s = sim->relax ? PD_OK : relax_new(sim, &sim->relax);
    if (s != PD_OK)
        return s;
    sim->relax_free = relax_free; /* pd_sim_free's, without a call back up here */
    struct pd_relax *R = sim->relax;
    sim->energy_next = 0; /* wanted of the end: pd_sim_energy takes its own pass */
    sim->f_zeroed = 0;
    double F0[3], c0[3];
    sim->setup = 1;
    s = load_step(sim, R, info, F0, c0);
    sim->setup = 0;
    if (s != PD_OK)
        return s;
    double t0 = pd_wtime();
    /* the loads' work over the step: R->r is that of the relaxed state */
    double c1[3], dc = 0;
    pd_sim_indenter_centre(sim, c1);
    for (int d = 0; d < 3; d++)
        dc -= 0.5 * (F0[d] + sim->ind_f[d]) * (c1[d] - c0[d]);
    double *w = R->term[0];
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        double t = 0;
        for (int a = 0; a < 3; a++)
            t += 0.5 * (R->r0[a][i] + R->r[a][i]) * (sim->y[a][i] - R->y0[a][i]);
        w[i] = t;
    }
    double wsum;
    pd_sim_sum(sim, (const double *const *)&w, 1, &wsum);
    sim->work += wsum + dc;
    sim->relaxed = *info;
    sim->timers[PD_T_INTEGRATE] += pd_wtime() - t0;
    return PD_OK;
}
