/*
 * bc.c -- boundary conditions on particle sets (seed 004 §2: a load on a
 * surface is a body force in a layer of thickness delta; a prescribed
 * velocity or displacement is held in a layer).  Two effects:
 *
 * body-force: f_i += b(t) e_a for i in the set (a force density, N/m^3).
 *   Its work over step n -> n+1 is the trapezoid over the displacement,
 *     dW = sum_i V_i (b(t_n) + b(t_{n+1}))/2 (y_{n+1} - y_n)_a,
 *   with y_{n+1} - y_n = dt v^{n+1/2} (the velocity at the force
 *   evaluation); for a free particle under a constant b this is exactly
 *   velocity Verlet's change of kinetic energy.
 *
 * prescribed-motion: the a-component of y and v of the set held to
 *     velocity-bc:      y = x + G(t), v = g(t)
 *     displacement-bc:  y = x + g(t), v = g'(t)
 *   (P(t) = the prescribed offset, U(t) = the prescribed velocity).  In the
 *   step (lib/run/sim.c): after the first half kick v = (P_{n+1} - P_n)/dt (so
 *   that the drift lands on it), after the drift y = x + P_{n+1} exactly,
 *   after the second half kick v = U_{n+1}.  The body's forces f on a held
 *   component are then balanced by the reaction R_i = V_i (rho_i a_i - f_i).
 *   Its work, the energy the prescribed motion puts into the body, is
 *   taken in the discrete form that velocity Verlet's own balance has
 *   (kinetic change = trapezoid of f over the displacement):
 *     dW = sum_i [1/2 rho_i V_i (U_{n+1}^2 - U_n^2)
 *                 - V_i (f_i^n + f_i^{n+1})/2 (P_{n+1} - P_n)],
 *   so that kinetic + elastic - work stays constant to the integrator's
 *   error, jumps of the velocity (square pulses) included.
 *
 * Reactions (the time series' SET.fx, ...): the force a condition applies
 * to a particle, N.  Under a body force V_i b(t).  On a held component
 * the force that, with the body's f_i, gives the prescribed acceleration:
 *   R_i = V_i (rho_i a_i - f_i),
 *   a_i = g'(t) for velocity-bc, 0 for displacement-bc (a piecewise linear
 *   g has no second derivative between its corners), and 0 in a relaxed
 *   state (pd-run --relax: at rest),
 * at the state of the step (after its forces).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/comm.h"
#include "effects/effect.h"

const char *pd_bc_option(pd_bc_kind kind)
{
    return kind == PD_BC_VELOCITY       ? "velocity-bc"
           : kind == PD_BC_DISPLACEMENT ? "displacement-bc"
                                        : "body-force";
}

pd_status pd_bc_parse(pd_bc_kind kind, const char *spec, pd_bc *bc)
{
    memset(bc, 0, sizeof *bc);
    bc->kind = kind;
    const char *c1 = strchr(spec, ',');
    if (c1 == NULL || c1 == spec || (size_t)(c1 - spec) >= PD_SET_NAME_MAX ||
        !strchr("xyz", c1[1]) || c1[1] == '\0' || c1[2] != ',' || c1[3] == '\0')
        return pd_fail(PD_ERR_INVALID, "--%s '%s': expected SET,AXIS,PROFILE with AXIS x, y or z",
                       pd_bc_option(kind), spec);
    memcpy(bc->set, spec, (size_t)(c1 - spec));
    bc->set[c1 - spec] = '\0';
    if (!pd_set_name_ok(bc->set))
        return pd_fail(PD_ERR_INVALID, "--%s '%s': '%s' is not a set name", pd_bc_option(kind),
                       spec, bc->set);
    bc->axis = c1[1] - 'x';
    pd_status s = pd_profile_parse(c1 + 3, &bc->profile);
    if (s != PD_OK) {
        char why[512]; /* the message is rewritten in place */
        snprintf(why, sizeof why, "%s", pd_errmsg());
        return pd_fail(s, "--%s %s: %s", pd_bc_option(kind), bc->set, why);
    }
    return PD_OK;
}

/* The conditions of one effect with their rows. */
typedef struct {
    const pd_bc *bc;
    int64_t n;
    int64_t *rows; /* a piece of a body on MPI ranks: -1 for a member beyond it */
    double *fprev; /* prescribed: f of the held component at step n, N/m^3 */
    double *terms; /* a piece: each member's term of the work, from its owner */
} cond;

typedef struct {
    int count;
    cond *c;
} bc_state;

static void bc_free(void *state)
{
    bc_state *st = state;
    if (st == NULL)
        return;
    for (int k = 0; k < st->count; k++) {
        free(st->c[k].rows);
        free(st->c[k].fprev);
        free(st->c[k].terms);
    }
    free(st->c);
    free(st);
}

static int prescribed(const pd_bc *bc)
{
    return bc->kind != PD_BC_BODY_FORCE;
}

/* The conditions of the scene that `want` picks, with their rows. */
static pd_status bc_init(pd_sim *sim, void **state, int want_prescribed)
{
    const pd_scene *sc = &sim->sc;
    bc_state *st = calloc(1, sizeof *st);
    *state = NULL;
    if (st == NULL || (st->c = calloc((size_t)sc->nbc, sizeof(cond))) == NULL) {
        free(st);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the boundary conditions");
    }
    *state = st;
    for (int k = 0; k < sc->nbc; k++) {
        const pd_bc *bc = &sc->bc[k];
        if (prescribed(bc) != want_prescribed)
            continue;
        const pd_set *set = pd_sets_find(sc->sets, bc->set);
        if (set == NULL)
            return pd_fail(PD_ERR_INVALID,
                           "--%s: the model has no set '%s' (pd-lattice --set names them)",
                           pd_bc_option(bc->kind), bc->set);
        cond *c = &st->c[st->count++];
        c->bc = bc;
        c->n = set->n;
        pd_status s = sim->piece ? pd_set_rows_present(set, sim->p, &c->rows)
                                 : pd_set_rows(set, sim->p, &c->rows);
        if (s == PD_OK && sim->piece &&
            (c->terms = malloc((size_t)(c->n > 0 ? c->n : 1) * sizeof(double))) == NULL)
            s = pd_fail(PD_ERR_NOMEM, "out of memory for the boundary conditions");
        if (s != PD_OK)
            return s;
        if (want_prescribed && (c->fprev = calloc((size_t)c->n, sizeof(double))) == NULL)
            return pd_fail(PD_ERR_NOMEM, "out of memory for the boundary conditions");
    }
    if (!want_prescribed)
        return PD_OK;
    /* one prescribed motion per particle and axis */
    int *owner = calloc((size_t)sim->n * 3, sizeof(int));
    if (owner == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the boundary conditions");
    pd_status s = PD_OK;
    for (int k = 0; k < st->count && s == PD_OK; k++) {
        const cond *c = &st->c[k];
        for (int64_t m = 0; m < c->n && s == PD_OK; m++) {
            if (c->rows[m] < 0) /* beyond a piece */
                continue;
            int *o = &owner[3 * c->rows[m] + c->bc->axis];
            if (*o) {
                const pd_bc *a = st->c[*o - 1].bc;
                s = pd_fail(PD_ERR_INVALID,
                            "--%s %s and --%s %s both prescribe the %c motion of particle id "
                            "%lld",
                            pd_bc_option(a->kind), a->set, pd_bc_option(c->bc->kind), c->bc->set,
                            'x' + c->bc->axis, (long long)sim->p->id[c->rows[m]]);
            }
            *o = k + 1;
        }
    }
    /* the held components, for the relaxation (lib/run/relax.c) */
    if (s == PD_OK && (sim->held = calloc((size_t)sim->n, 1)) == NULL)
        s = pd_fail(PD_ERR_NOMEM, "out of memory for the boundary conditions");
    for (int64_t i = 0; s == PD_OK && i < sim->n; i++)
        for (int a = 0; a < 3; a++)
            sim->held[i] |= (uint8_t)((owner[3 * i + a] != 0) << a);
    free(owner);
    return s;
}

/* The sum of a condition's terms in its members' order, on a piece of a
 * body on MPI ranks: each member's from the rank that owns it (terms[m],
 * 0 elsewhere and for the lost), summed over the ranks exactly, then in
 * order, as one rank sums them. */
static double member_sum(const pd_sim *sim, const cond *c)
{
    pd_comm_add(c->terms, c->n);
    double sum = 0;
    for (int64_t m = 0; m < c->n; m++)
        sum += c->terms[m];
    (void)sim;
    return sum;
}

/* Is row i (>= 0) of a piece its own? */
static inline int own_row(const pd_sim *sim, int64_t i)
{
    return i >= sim->piece->own_lo && i < sim->piece->own_hi;
}

/* ------------------------------------------------------------ body force */

/* bc_init, leaving no state behind on failure. */
static pd_status init_or_free(pd_sim *sim, void **state, int want_prescribed)
{
    pd_status s = bc_init(sim, state, want_prescribed);
    if (s != PD_OK) {
        bc_free(*state);
        *state = NULL;
    }
    return s;
}

static pd_status body_init(pd_sim *sim, void **state)
{
    return init_or_free(sim, state, 0);
}

static pd_status body_force(pd_sim *sim, void *state)
{
    const bc_state *st = state;
    const double t = sim->time, dt = sim->sc.dt, tprev = (double)(sim->step - 1) * dt;
    const uint8_t *lost = sim->lost;
    const double *V = sim->p->volume;
    double work = 0;
    for (int k = 0; k < st->count; k++) {
        const cond *c = &st->c[k];
        const int a = c->bc->axis;
        const double b = pd_profile_value(&c->bc->profile, t);
        const double bmid = 0.5 * (pd_profile_value(&c->bc->profile, tprev) + b);
        double sum = 0; /* in row order: the same at any thread count */
        if (c->terms)
            memset(c->terms, 0, (size_t)c->n * sizeof(double));
        for (int64_t m = 0; m < c->n; m++) {
            const int64_t i = c->rows[m];
            if (i < 0 || (lost && lost[i]))
                continue;
            sim->f[a][i] += b;
            if (!c->terms)
                sum += V[i] * sim->v[a][i];
            else if (own_row(sim, i))
                c->terms[m] = V[i] * sim->v[a][i];
        }
        if (c->terms) /* a piece: over the ranks */
            sum = member_sum(sim, c);
        work += bmid * sum * dt;
    }
    if (!sim->setup && !sim->sc.relax) /* the relaxation books its own */
        sim->work += work;
    return PD_OK;
}

/* Does the scene hold a condition of the kind (body forces) or of the
 * other kinds (prescribed motion)? */
static int has_bc(const pd_scene *s, int body)
{
    for (int k = 0; k < s->nbc; k++)
        if ((s->bc[k].kind == PD_BC_BODY_FORCE) == body)
            return 1;
    return 0;
}

static int body_declared(const pd_scene *s)
{
    return has_bc(s, 1);
}

static void body_reaction(const pd_sim *sim, void *state, double *const r[3])
{
    const bc_state *st = state;
    for (int k = 0; k < st->count; k++) {
        const cond *c = &st->c[k];
        const double b = pd_profile_value(&c->bc->profile, sim->time);
        for (int64_t m = 0; m < c->n; m++) {
            const int64_t i = c->rows[m];
            if (i >= 0 && !(sim->lost && sim->lost[i]))
                r[c->bc->axis][i] += sim->p->volume[i] * b;
        }
    }
}

const pd_effect pd_effect_body_force = {
    .name = "body-force", .timer = PD_T_INTEGRATE, .init = body_init, .force = body_force,
    .free = bc_free, .declared = body_declared, .reaction = body_reaction};

/* ------------------------------------------------------------ prescribed motion */

/* The prescribed offset P(t) and velocity U(t) of a condition. */
static double offset(const pd_bc *bc, double t)
{
    return bc->kind == PD_BC_VELOCITY ? pd_profile_integral(&bc->profile, t)
                                      : pd_profile_value(&bc->profile, t);
}

static double rate(const pd_bc *bc, double t)
{
    return bc->kind == PD_BC_VELOCITY ? pd_profile_value(&bc->profile, t)
                                      : pd_profile_rate(&bc->profile, t);
}

static pd_status held_init(pd_sim *sim, void **state)
{
    return init_or_free(sim, state, 1);
}

static pd_status held_constrain(pd_sim *sim, void *state, int phase)
{
    const bc_state *st = state;
    const double dt = sim->sc.dt;
    const uint8_t *lost = sim->lost;
    const double *V = sim->p->volume, *rho = sim->p->density;
    /* at KICK1 the step is n; after the drift it is n+1 */
    const int64_t n = phase == PD_PHASE_KICK1 ? sim->step : sim->step - 1;
    const double t0 = (double)n * dt, t1 = (double)(n + 1) * dt;
    double work = 0;
    for (int k = 0; k < st->count; k++) {
        const cond *c = &st->c[k];
        const int a = c->bc->axis;
        double *x = sim->p->x[a], *y = sim->y[a], *v = sim->v[a], *f = sim->f[a];
        double sum = 0;
        switch (phase) {
        case PD_PHASE_SETUP: {
            const double P = offset(c->bc, sim->time), U = rate(c->bc, sim->time);
            for (int64_t m = 0; m < c->n; m++)
                if (c->rows[m] >= 0) {
                    y[c->rows[m]] = x[c->rows[m]] + P;
                    v[c->rows[m]] = U;
                }
            break;
        }
        case PD_PHASE_KICK1: {
            const double u = (offset(c->bc, t1) - offset(c->bc, t0)) / dt;
            for (int64_t m = 0; m < c->n; m++) {
                const int64_t i = c->rows[m];
                if (i < 0)
                    continue;
                c->fprev[m] = f[i];
                if (!(lost && lost[i]))
                    v[i] = u;
            }
            break;
        }
        case PD_PHASE_DRIFT: {
            const double P = offset(c->bc, t1);
            for (int64_t m = 0; m < c->n; m++)
                if (c->rows[m] >= 0 && !(lost && lost[c->rows[m]]))
                    y[c->rows[m]] = x[c->rows[m]] + P;
            break;
        }
        case PD_PHASE_KICK2: {
            const double U0 = rate(c->bc, t0), U1 = rate(c->bc, t1);
            const double dP = offset(c->bc, t1) - offset(c->bc, t0);
            const double dK = 0.5 * (U1 * U1 - U0 * U0);
            if (c->terms)
                memset(c->terms, 0, (size_t)c->n * sizeof(double));
            for (int64_t m = 0; m < c->n; m++) {
                const int64_t i = c->rows[m];
                if (i < 0 || (lost && lost[i]))
                    continue;
                const double t = V[i] * (rho[i] * dK - 0.5 * (c->fprev[m] + f[i]) * dP);
                if (!c->terms)
                    sum += t;
                else if (own_row(sim, i))
                    c->terms[m] = t;
                v[i] = U1;
            }
            if (c->terms) /* a piece: over the ranks */
                sum = member_sum(sim, c);
            work += sum;
            break;
        }
        }
    }
    if (phase == PD_PHASE_KICK2)
        sim->work += work;
    return PD_OK;
}

static int held_declared(const pd_scene *s)
{
    return has_bc(s, 0);
}

static void held_reaction(const pd_sim *sim, void *state, double *const r[3])
{
    const bc_state *st = state;
    const double *V = sim->p->volume, *rho = sim->p->density;
    for (int k = 0; k < st->count; k++) {
        const cond *c = &st->c[k];
        const int a = c->bc->axis;
        const double acc = c->bc->kind == PD_BC_VELOCITY && !sim->sc.relax
                               ? pd_profile_rate(&c->bc->profile, sim->time)
                               : 0.0; /* at rest when relaxed */
        for (int64_t m = 0; m < c->n; m++) {
            const int64_t i = c->rows[m];
            if (i >= 0 && !(sim->lost && sim->lost[i]))
                r[a][i] += V[i] * (rho[i] * acc - sim->f[a][i]);
        }
    }
}

const pd_effect pd_effect_prescribed = {
    .name = "prescribed-motion", .timer = PD_T_INTEGRATE, .init = held_init, .free = bc_free,
    .constrain = held_constrain, .declared = held_declared, .reaction = held_reaction};
