/*
 * scene.c -- a scene from what a user says (pd-run's options, a library
 * user's pd_scene_spec) to what a run uses:
 *   - pd_scene_check, before the body is read: the options each model
 *     takes and needs (its descriptor, lib/models/), the scene's c with
 *     laws and fibres, that the stiffness is given;
 *   - pd_scene_resolve, against the body: the laws' K= to c, Young's
 *     modulus to K with PMB's fixed Poisson ratio, K to c (3-D or plane
 *     stress, lib/models/plate.c), G0 to s00 (seed 004 eq. 27), the
 *     defaults (contact skin, lost margin, the projectile's K), the stable
 *     step (seed 004 eq. 46) and the refusal of a --dt above it;
 *   - pd_scene_text, the resolved scene as scene-file lines (/scene/options),
 *     enough to rerun or restart.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/comm.h"
#include "models/model.h"

/* The default contact skin's bounds, in spacings (pd-run(1)). */
#define PD_CONTACT_SKIN_MIN 0.5
#define PD_CONTACT_SKIN_MAX 1.0

/* The default contact skin (pd-run(1), "Contact"): half the room between
 * the contact's reach (max d_ij = 1.35 (r_i + r_j) over the body) and the
 * gap g, the nearest lattice distance beyond the horizon, which no bond
 * spans: (g - max d_ij) / 2, within [0.5, 1] spacings.  The list is
 * rebuilt when a particle has moved half the skin, and a build searches
 * around the particles that have moved (g - max d_ij - skin) / 2 from
 * their sites (lib/effects/contact.c): with this skin the two distances
 * are equal.  On the seed's lattice (delta = 3 spacings, g = sqrt(10)
 * spacings, r = spacing/2) 0.906 spacings, where the shattered demo
 * rebuilds its list 194 times instead of 348 (half a spacing, the
 * default before) and a build costs about as much.  The skin changes no
 * bit of a run.  Collective on MPI ranks. */
static double contact_skin_default(const pd_particles *p, const pd_bonds *b)
{
    const double dx = p->spacing;
    double rmax = 0;
    for (int64_t i = 0; i < p->n; i++)
        rmax = fmax(rmax, p->radius[i]);
    rmax = pd_comm_max(rmax);
    if (!(dx > 0))
        return PD_CONTACT_SKIN_MIN * dx;
    /* g / dx: the square root of the least sum of `dimension` squares
     * above (delta/dx)^2 (a horizon of 64 spacings or more: delta/dx, the
     * skin then one spacing) */
    const double m = b->horizon / dx;
    double g = m;
    if (m < 64) {
        const int r = (int)ceil(m) + 1, dim = p->dimension == 2 ? 2 : 3;
        double g2 = INFINITY;
        for (int a = 0; a <= r; a++)
            for (int c = 0; c <= r; c++)
                for (int e = 0; e <= (dim == 3 ? r : 0); e++) {
                    const double q = (double)(a * a + c * c + e * e);
                    if (q > m * m && q < g2)
                        g2 = q;
                }
        g = sqrt(g2);
    }
    const double skin = 0.5 * (g * dx - PD_CONTACT_RADIUS_FAC * 2.0 * rmax);
    if (!isfinite(skin) || skin < PD_CONTACT_SKIN_MIN * dx)
        return PD_CONTACT_SKIN_MIN * dx;
    return skin > PD_CONTACT_SKIN_MAX * dx ? PD_CONTACT_SKIN_MAX * dx : skin;
}

/* Was a model's own option given?  (Each option of a descriptor's needs
 * and takes lists is one of these.) */
static int given(const pd_scene_spec *o, const char *opt)
{
    const struct {
        const char *opt;
        int on;
    } said[] = {{"--c", o->has_c},
                {"--bulk-modulus", o->has_k},
                {"--youngs-modulus", o->has_e},
                {"--shear-modulus", o->has_g},
                {"--influence", o->has_influence},
                {"--ellipsoid", o->sc.nellipsoids > 0},
                {"--ves-lambda", o->has_lambda},
                {"--ves-tau", o->has_tau},
                {"--yield-stress", o->has_yield},
                {"--failure-energy", o->has_g0},
                {"--material", o->has_material},
                {"--interface", o->has_interface},
                {"--fibre", o->sc.has_fibre}};
    for (size_t k = 0; k < sizeof said / sizeof said[0]; k++)
        if (strcmp(said[k].opt, opt) == 0)
            return said[k].on;
    return 0;
}

static int listed(const char *const *list, const char *opt)
{
    for (int k = 0; list && list[k]; k++)
        if (strcmp(list[k], opt) == 0)
            return 1;
    return 0;
}

/* An option of some model's own that the scene's model m neither needs nor
 * takes: refused, naming the models that take it. */
static pd_status refuse_others(const pd_scene_spec *o, const pd_model *m)
{
    for (int k = 0; pd_model_at(k); k++) {
        const pd_model *other = pd_model_at(k);
        const char *const *lists[2] = {other->needs, other->takes};
        for (int l = 0; l < 2; l++)
            for (int q = 0; lists[l] && lists[l][q]; q++) {
                const char *opt = lists[l][q];
                if (!given(o, opt) || listed(m->needs, opt) || listed(m->takes, opt))
                    continue;
                char owners[128] = "";
                for (int r = 0; pd_model_at(r); r++)
                    if (listed(pd_model_at(r)->needs, opt) || listed(pd_model_at(r)->takes, opt))
                        snprintf(owners + strlen(owners), sizeof owners - strlen(owners),
                                 "%s%s", owners[0] ? "|" : "", pd_model_at(r)->name);
                return pd_fail(PD_ERR_INVALID, "%s is for --model %s, not %s", opt, owners,
                               m->name);
            }
    }
    return PD_OK;
}

/* Some option m needs is not given: refused, naming all it needs. */
static pd_status need_own(const pd_scene_spec *o, const pd_model *m)
{
    char all[256] = "";
    int missing = 0, total = 0;
    for (int q = 0; m->needs && m->needs[q]; q++) {
        missing |= !given(o, m->needs[q]);
        total++;
    }
    for (int q = 0; missing && q < total; q++)
        snprintf(all + strlen(all), sizeof all - strlen(all), "%s%s",
                 q == 0 ? "" : q == total - 1 ? " and " : ", ", m->needs[q]);
    return missing ? pd_fail(PD_ERR_INVALID, "--model %s needs %s", m->name, all) : PD_OK;
}

/* A quasi-static scene (--relax): what it cannot hold. */
static pd_status relax_check(const pd_scene_spec *o, const pd_model *m)
{
    if (o->sc.has_projectile)
        return pd_fail(PD_ERR_INVALID, "--relax is quasi-static: a projectile moves by its "
                       "inertia and has no static state (drive an --indenter instead)");
    if (m->dissipative)
        return pd_fail(PD_ERR_INVALID, "--relax is quasi-static: --model %s keeps a history "
                       "that each step's time advances, which relaxation's iterations would "
                       "advance too (relax pmb or lps)", m->name);
    if (o->sc.damping_set[0] != '\0')
        return pd_fail(PD_ERR_INVALID, "--relax takes --damping C, the relaxation's own "
                       "damping of every particle, without a set");
    if (o->has_time)
        return pd_fail(PD_ERR_INVALID, "--relax takes --steps, the number of load steps, not "
                       "--time");
    if (!o->has_dt)
        return pd_fail(PD_ERR_INVALID, "--relax needs --dt, the time of a load step: load "
                       "step n holds the loads of time n dt");
    return PD_OK;
}

pd_status pd_scene_check(pd_scene_spec *o)
{
    const pd_model *m = pd_model_of(o->sc.model);
    if (m == NULL)
        return pd_fail(PD_ERR_INVALID, "unknown model %d", (int)o->sc.model);
    pd_status s = refuse_others(o, m);
    if (s == PD_OK)
        s = need_own(o, m);
    if (s != PD_OK)
        return s;
    if (o->sc.relax && (s = relax_check(o, m)) != PD_OK)
        return s;
    if (o->sc.nno_failure > 0 && !o->sc.has_failure)
        return pd_fail(PD_ERR_INVALID, "--no-failure %s keeps bonds from breaking: it needs "
                       "--failure or --failure-energy", o->sc.no_failure[0]);
    if (o->sc.fields & ~m->fields) /* frame fields the model cannot write */
        return pd_fail(PD_ERR_INVALID, "--fields %s: --model %s does not write it",
                       (o->sc.fields & ~m->fields & PD_FIELD_ENERGY) ? "energy" : "stress",
                       m->name);
    if (o->nlaws > 0 || o->sc.has_fibre) {
        int s00 = o->sc.fibre_s00[0] > 0;
        for (int k = 0; k < o->nlaws; k++)
            s00 |= o->laws[k].s00 > 0;
        if (s00 && !o->sc.has_failure)
            return pd_fail(PD_ERR_INVALID, "a critical stretch of --material, --interface or "
                           "--fibre needs --failure or --failure-energy (the scene's s00 and "
                           "alpha)");
        /* the scene's c: the fibres' matrix, else the stiffest material
         * (contact, and the materials without a law) */
        if (!o->has_c && !o->has_k && !o->has_e && o->sc.has_fibre)
            o->sc.c = o->sc.fibre_c[1], o->has_c = 1;
        for (int k = 0; k < o->nlaws && !o->has_c && !o->has_k && !o->has_e; k++)
            if (o->laws[k].a == o->laws[k].b && o->law_k[k] == 0)
                o->sc.c = fmax(o->sc.c, o->laws[k].c);
        if (o->sc.c > 0)
            o->has_c = 1;
        for (int k = 0; k < o->nlaws && !o->has_c && !o->has_k && !o->has_e; k++)
            if (o->laws[k].a == o->laws[k].b)
                o->sc.bulk_modulus = fmax(o->sc.bulk_modulus, o->law_k[k]);
        if (!o->has_c && o->sc.bulk_modulus > 0)
            o->has_k = 1;
    }
    if (!o->has_c && !o->has_k && !o->has_e)
        return pd_fail(PD_ERR_INVALID,
                       "give the stiffness: --c or --bulk-modulus (or --youngs-modulus)");
    return PD_OK;
}

/* --time T: the fewest steps of at most the time step that reach T, and
 * the time step T / steps, so that the last step ends at T. */
static pd_status steps_to_end(pd_scene_spec *o)
{
    pd_scene *sc = &o->sc;
    const double n = ceil(o->end_time / sc->dt);
    if (!(n <= 1e15))
        return pd_fail(PD_ERR_INVALID, "--time %g s takes more than 1e15 steps of %g s",
                       o->end_time, sc->dt);
    int64_t steps = (int64_t)n;
    if (steps > 1 && o->end_time / (double)(steps - 1) <= sc->dt)
        steps--; /* T / dt is a whole number but for its rounding */
    sc->steps = steps;
    sc->dt = o->end_time / (double)steps;
    return PD_OK;
}

pd_status pd_scene_resolve(pd_scene_spec *o, const pd_particles *p, const pd_bonds *b,
                           const char *body)
{
    pd_scene *sc = &o->sc;
    pd_status s = pd_scene_check(o); /* (again, for a caller that did not) */
    if (s != PD_OK)
        return s;
    const pd_model *m = pd_model_of(sc->model);
    for (int k = 0; k < o->nlaws; k++) /* --material/--interface K=: c for the dimension */
        if (o->law_k[k] > 0)
            o->laws[k].c = pd_pmb_c_for(p, o->law_k[k], b->horizon);
    sc->nlaws = o->nlaws;
    sc->laws = o->laws;
    s = pd_scene_has_laws(sc) ? pd_bond_laws_check(p, sc) : PD_OK;
    if (s != PD_OK)
        return s;
    if (o->has_e) /* PMB's fixed Poisson ratio: K from E by dimension */
        sc->bulk_modulus = pd_pmb_bulk_from_youngs(sc->youngs_modulus, p->dimension);
    if (o->has_k || o->has_e)
        sc->c = pd_pmb_c_for(p, sc->bulk_modulus, b->horizon);
    if (!o->has_k && !o->has_e)
        sc->bulk_modulus = sc->youngs_modulus = 0; /* a scene's K or E that --c overrode */
    if (m->state_based && p->dimension == 2)
        return pd_fail(PD_ERR_INVALID, "--model %s is for 3-D bodies; '%s' is a 2-D plate (run "
                       "it with pmb)", m->name, body);
    if (o->has_g0)
        sc->s00 = pd_pmb_s0_for(p, o->g0, sc->c, b->horizon);
    if (sc->has_contact && !(sc->contact_skin > 0))
        sc->contact_skin = contact_skin_default(p, b);
    if (!(sc->lost_margin > 0))
        sc->lost_margin = pd_lost_margin_default(p);
    if (sc->balance_limit == 0)
        sc->balance_limit = PD_BALANCE_LIMIT;
    /* the smallest over the particles and the largest stiffness: on MPI
     * ranks each may hold its own rows' families alone (pd_read_bonds_run),
     * the ranks' together (a min or max in any order is exact) */
    sc->dt_stable = pd_stable_dt(p, b, sc);
    if (pd_comm_size() > 1)
        sc->dt_stable = pd_comm_or(isnan(sc->dt_stable)) ? NAN : -pd_comm_max(-sc->dt_stable);
    if (sc->has_projectile && !o->has_proj_k)
        sc->proj_k = pd_comm_max(pd_projectile_default_k(p, b, sc));
    if (sc->relax) { /* dt is the load steps' time; the iterations take the stable step */
        if (!isfinite(sc->dt_stable))
            return pd_fail(PD_ERR_INVALID, "no bonds, so nothing to relax");
        sc->relax_dt = sc->safety * sc->dt_stable;
        if (!(sc->relax_tolerance > 0))
            sc->relax_tolerance = PD_RELAX_TOLERANCE;
        if (sc->relax_iterations <= 0)
            sc->relax_iterations = PD_RELAX_ITERATIONS;
    } else if (!o->has_dt) {
        if (!isfinite(sc->dt_stable))
            return pd_fail(PD_ERR_INVALID, "no bonds, so no stable time step; give --dt");
        sc->dt = sc->safety * sc->dt_stable;
    } else if (sc->dt > sc->dt_stable && !o->force_dt)
        return pd_fail(PD_ERR_INVALID, "--dt %g s exceeds the stable time step %g s (seed 004 eq. "
                       "46); use --force-dt to run anyway", sc->dt, sc->dt_stable);
    return o->has_time && !sc->relax ? steps_to_end(o) : PD_OK;
}

/* ------------------------------------------------------------ frames */

int pd_frame_at(const pd_scene *sc, int64_t n)
{
    return (sc->every > 0 && n % sc->every == 0) || n == sc->steps;
}

/* The multiples of `every` (none when 0) and the last step of a run of
 * `total` steps, from step `first` + 1 (0 when `fresh`); how many. */
static int64_t sampled_steps(int64_t every, int64_t total, int64_t first, int fresh,
                             int64_t *steps)
{
    const int64_t from = fresh ? 0 : first + 1; /* the steps this run takes */
    int64_t m = 0, last = -1;
    if (every > 0)
        for (int64_t n = (from + every - 1) / every * every; n <= total; n += every) {
            if (steps)
                steps[m] = n;
            m++;
            last = n;
        }
    if (total >= from && last != total) {
        if (steps)
            steps[m] = total;
        m++;
    }
    return m;
}

int64_t pd_frame_steps(const pd_scene *sc, int64_t first, int fresh, int64_t *steps)
{
    return sampled_steps(sc->every, sc->steps, first, fresh, steps);
}

int pd_series_at(const pd_scene *sc, int64_t n)
{
    return sc->series > 0 && (n % sc->series == 0 || n == sc->steps);
}

int64_t pd_series_steps(const pd_scene *sc, int64_t first, int fresh, int64_t *steps)
{
    return sc->series > 0 ? sampled_steps(sc->series, sc->steps, first, fresh, steps) : 0;
}

/* ------------------------------------------------------------ before step 1 */

static void warn(pd_scene_report *rep, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void warn(pd_scene_report *rep, const char *fmt, ...)
{
    if (rep->nwarnings == PD_SCENE_WARNINGS)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(rep->warning[rep->nwarnings++], sizeof rep->warning[0], fmt, ap);
    va_end(ap);
}

/* A sphere of centre c and radius R moving at v against the particles at
 * t = 0: the deepest particle inside it (*deep, -1: none deeper than tol)
 * and its depth R - |x - c|, m; and the first time a particle is touched,
 * |x - (c + v t)| = R, s (INFINITY: never; 0: at once). */
static double sphere_meets(const pd_particles *p, const double c[3], double R, const double v[3],
                           double tol, int64_t *deep, double *depth)
{
    double first = INFINITY;
    const double vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    *deep = -1;
    *depth = tol;
    for (int64_t i = 0; i < p->n; i++) {
        const double d[3] = {p->x[0][i] - c[0], p->x[1][i] - c[1], p->x[2][i] - c[2]};
        const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        const double in = R - sqrt(dd);
        if (in > *depth) {
            *deep = i;
            *depth = in;
        }
        if (in >= 0) { /* touched at once */
            first = 0;
            continue;
        }
        /* |d - v t|^2 = R^2: t^2 vv - 2 t (d.v) + dd - R^2 = 0, the smaller
         * root when the sphere comes toward the particle */
        const double dv = d[0] * v[0] + d[1] * v[1] + d[2] * v[2];
        const double disc = dv * dv - vv * (dd - R * R);
        if (vv > 0 && dv > 0 && disc >= 0)
            first = fmin(first, (dv - sqrt(disc)) / vv);
    }
    return first;
}

/* An overlap at t = 0 is an error; else the time of the first contact. */
static pd_status sphere_check(const pd_scene_spec *o, const pd_particles *p, const char *what,
                              const double c[3], double R, const double v[3],
                              pd_scene_report *rep)
{
    int64_t deep;
    double depth;
    double t = sphere_meets(p, c, R, v, PD_OVERLAP_TOL * p->spacing, &deep, &depth);
    int64_t id = deep >= 0 ? p->id[deep] : 0;
    if (p->window) { /* over the ranks: the first of the deepest, the first touch */
        t = -pd_body_max(p, -t);
        const double most = pd_body_max(p, depth);
        const int64_t g = deep >= 0 && depth == most ? p->first + deep : INT64_MAX;
        const int64_t at = pd_comm_min(g);
        id = pd_comm_min(at != INT64_MAX && g == at ? id : INT64_MAX);
        deep = at == INT64_MAX ? -1 : at;
        depth = most;
    }
    if (deep >= 0 && !o->sc.allow_overlap)
        return pd_fail(PD_ERR_INVALID,
                       "the %s overlaps the body at t = 0: particle %lld (id %lld) is %.3g m "
                       "inside it (radius %g m); start it outside, or give --allow-overlap",
                       what, (long long)deep, (long long)id, depth, R);
    rep->contact_time = isnan(rep->contact_time) ? t : fmin(rep->contact_time, t);
    const double end = (double)o->sc.steps * o->sc.dt;
    if (isinf(t))
        warn(rep, "the %s never touches the body (it moves away from it or past it): check "
                  "the velocity of --%s", what, what);
    else if (t > end)
        warn(rep, "the %s first touches the body at t = %.3g s, after the run ends (%.3g s, "
                  "%lld steps): more --steps?", what, t, end, (long long)o->sc.steps);
    return PD_OK;
}

/* A modulus of no solid: its unit was likely wrong. */
static void modulus_check(pd_scene_report *rep, const char *name, double v)
{
    if (v > 0 && v < PD_PLAUSIBLE_MODULUS_MIN)
        warn(rep, "%s %g Pa is far below any solid's; GPa or MPa meant? (%g GPa is %g Pa)",
             name, v, v, v * 1e9);
    else if (v > PD_PLAUSIBLE_MODULUS_MAX)
        warn(rep, "%s %g Pa is above any solid's (diamond: about 1.1e12 Pa)", name, v);
}

pd_status pd_scene_inspect(const pd_scene_spec *o, const pd_particles *p, const pd_bonds *b,
                           pd_scene_report *rep)
{
    const pd_scene *sc = &o->sc;
    memset(rep, 0, sizeof *rep);
    rep->contact_time = NAN;
    pd_status s = PD_OK;
    if (sc->has_projectile)
        s = sphere_check(o, p, "projectile", sc->proj_center, sc->proj_radius,
                         sc->proj_velocity, rep);
    if (s == PD_OK && sc->has_indenter)
        s = sphere_check(o, p, "indenter", sc->ind_center, sc->ind_radius,
                         sc->ind_velocity, rep);
    if (s != PD_OK)
        return s;
    double rho_lo = INFINITY, rho_hi = 0;
    for (int64_t i = 0; i < p->n; i++) {
        rho_lo = fmin(rho_lo, p->density[i]);
        rho_hi = fmax(rho_hi, p->density[i]);
    }
    rho_lo = -pd_body_max(p, -rho_lo); /* a window: over the ranks */
    rho_hi = pd_body_max(p, rho_hi);
    if (pd_body_count(p) > 0 && rho_lo < PD_PLAUSIBLE_DENSITY_MIN)
        warn(rep, "density %g kg/m^3 is far below any solid's; g/cm^3 meant? (%g g/cm^3 is "
                  "%g kg/m^3)", rho_lo, rho_lo, rho_lo * 1000);
    if (pd_body_count(p) > 0 && rho_hi > PD_PLAUSIBLE_DENSITY_MAX)
        warn(rep, "density %g kg/m^3 is above any solid's (osmium: 22590 kg/m^3)", rho_hi);
    if (o->has_k)
        modulus_check(rep, "bulk modulus", sc->bulk_modulus);
    if (o->has_e)
        modulus_check(rep, "Young's modulus", sc->youngs_modulus);
    if (o->has_g)
        modulus_check(rep, "shear modulus", sc->shear_modulus);
    if (sc->has_failure && sc->s00 > PD_PLAUSIBLE_S00_MAX)
        warn(rep, "critical stretch s00 %g: bonds stretch %.0f%% before they break; a "
                  "percentage meant as a fraction?", sc->s00, 100 * sc->s00);
    const double m = b->horizon / p->spacing;
    if (p->spacing > 0 && (m < PD_PLAUSIBLE_M_MIN || m > PD_PLAUSIBLE_M_MAX))
        warn(rep, "the horizon is %.3g spacings (%g m over %g m): peridynamic models are "
                  "calibrated for 2 to 6 (3 is usual)", m, b->horizon, p->spacing);
    if (!sc->has_projectile && !sc->has_indenter && sc->nbc == 0)
        warn(rep, "nothing loads the body (no projectile, indenter, boundary condition or "
                  "body force): it stays at rest");
    rep->frames = pd_frame_steps(sc, 0, 1, NULL);
    return PD_OK;
}

/* The resolved scene in scene-file form, enough to rerun. */
char *pd_scene_text(const pd_scene *s)
{
    size_t cap = 2048 + 160 * (size_t)s->nellipsoids;
    char **prof = calloc((size_t)(s->nbc > 0 ? s->nbc : 1), sizeof *prof);
    if (prof == NULL)
        return NULL;
    for (int k = 0; k < s->nbc; k++) { /* a table in resolved form */
        if ((prof[k] = pd_profile_text(&s->bc[k].profile)) == NULL) {
            for (int m = 0; m < k; m++)
                free(prof[m]);
            free(prof);
            return NULL;
        }
        cap += strlen(prof[k]) + 2 * PD_SET_NAME_MAX;
    }
    cap += (size_t)s->nlaws * 160 + 256 + (size_t)s->nno_failure * (PD_SET_NAME_MAX + 16);
    char *t = malloc(cap), *p = t;
    if (t == NULL) {
        for (int k = 0; k < s->nbc; k++)
            free(prof[k]);
        free(prof);
        return NULL;
    }
    const pd_model *m = pd_model_of(s->model);
    if (m->state_based)
        p += sprintf(p, "model %s\nbulk-modulus %.17g\nshear-modulus %.17g\ninfluence %s\n",
                     m->name, s->bulk_modulus, s->shear_modulus, pd_influence_name(s->influence));
    else
        p += sprintf(p, "model %s\nc %.17g\n", m->name, s->c);
    for (int k = 0; k < s->nellipsoids; k++)
        p += sprintf(p, "ellipsoid %.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", s->ellipsoid[k].u[0],
                     s->ellipsoid[k].u[1], s->ellipsoid[k].u[2], s->ellipsoid[k].a,
                     s->ellipsoid[k].b, s->ellipsoid[k].roll);
    for (const pd_model_param *q = m->params; q && q->option; q++)
        p += sprintf(p, "%s %.17g\n", q->option, *(const double *)((const char *)s + q->offset));
    if (s->has_failure)
        p += sprintf(p, "failure %.17g,%.17g\n", s->s00, s->alpha);
    if (s->has_contact)
        p += sprintf(p, "contact\ncontact-skin %.17g\n", s->contact_skin);
    if (s->has_indenter)
        p += sprintf(p, "indenter sphere,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n",
                     s->ind_center[0], s->ind_center[1], s->ind_center[2], s->ind_radius, s->ind_k,
                     s->ind_velocity[0], s->ind_velocity[1], s->ind_velocity[2]);
    if (s->has_projectile)
        p += sprintf(p,
                     "projectile sphere,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n",
                     s->proj_center[0], s->proj_center[1], s->proj_center[2], s->proj_radius,
                     s->proj_mass, s->proj_velocity[0], s->proj_velocity[1], s->proj_velocity[2],
                     s->proj_k);
    for (int k = 0; k < s->nlaws; k++) { /* K= resolved to c */
        const pd_bond_law *l = &s->laws[k];
        if (l->a == l->b)
            p += sprintf(p, "material %d,c=%.17g", (int)l->a, l->c);
        else
            p += sprintf(p, "interface %d,%d,c=%.17g", (int)l->a, (int)l->b, l->c);
        p += l->s00 > 0 ? sprintf(p, ",s00=%.17g\n", l->s00) : sprintf(p, "\n");
    }
    if (s->has_fibre) {
        p += sprintf(p, "fibre %.17g,%.17g,%.17g,%.17g,%.17g", s->fibre_g[0], s->fibre_g[1],
                     s->fibre_g[2], s->fibre_c[0], s->fibre_c[1]);
        p += s->fibre_s00[0] > 0
                 ? sprintf(p, ",%.17g,%.17g\n", s->fibre_s00[0], s->fibre_s00[1])
                 : sprintf(p, "\n");
    }
    p += sprintf(p, "dt %.17g\nsteps %lld\nevery %lld\n", s->dt, (long long)s->steps,
                 (long long)s->every);
    if (s->fields)
        p += sprintf(p, "fields %s%s%s\n", s->fields & PD_FIELD_ENERGY ? "energy" : "",
                     s->fields == (PD_FIELD_ENERGY | PD_FIELD_STRESS) ? "," : "",
                     s->fields & PD_FIELD_STRESS ? "stress" : "");
    if (s->damping > 0)
        p += sprintf(p, "damping %.17g%s%s\n", s->damping, s->damping_set[0] ? "," : "",
                     s->damping_set);
    for (int k = 0; k < s->nno_failure; k++)
        p += sprintf(p, "no-failure %s\n", s->no_failure[k]);
    p += sprintf(p, "lost-margin %.17g\n", s->lost_margin);
    if (s->balance_limit < 0) /* the default is not written: a rerun takes the default */
        p += sprintf(p, "balance-limit off\n");
    else if (s->balance_limit != PD_BALANCE_LIMIT)
        p += sprintf(p, "balance-limit %.17g\n", s->balance_limit);
    if (s->relax)
        p += sprintf(p, "relax\nrelax-tolerance %.17g\nrelax-iterations %lld\n",
                     s->relax_tolerance, (long long)s->relax_iterations);
    else if (s->dt > s->dt_stable)
        p += sprintf(p, "force-dt\n");
    if (s->bond_list)
        p += sprintf(p, "bond-list\n");
    if (s->allow_overlap)
        p += sprintf(p, "allow-overlap\n");
    for (int k = 0; k < s->nbc; k++) {
        p += sprintf(p, "%s %s,%c,%s\n", pd_bc_option(s->bc[k].kind), s->bc[k].set,
                     'x' + s->bc[k].axis, prof[k]);
        free(prof[k]);
    }
    free(prof);
    return t;
}

