/*
 * profile.c -- functions of time for boundary conditions: a constant,
 * piecewise-linear points (inline or from a table file) and square pulses,
 * each with its exact integral G(t) = int_0^t g and its derivative.
 *
 * Piecewise linear through (t_k, v_k), held at the end values outside:
 *   g(t) = v_k + (t - t_k) (v_{k+1} - v_k) / (t_{k+1} - t_k),  t_k <= t < t_{k+1}
 *   A(t) = int_{t_0}^t g:  A(t_k) = sum of the trapezoids before t_k, and
 *          A(t) = A(t_k) + (t - t_k) (v_k + g(t)) / 2 inside a segment
 *          (exact: g is linear there), A(t) = v_0 (t - t_0) before t_0
 *   G(t) = A(t) - A(0).
 * Pulses V_k for D_k each, from t = 0: g piecewise constant, G piecewise
 * linear through the cumulative sums of V_k D_k.
 */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "pd.h"

void pd_profile_free(pd_profile *g)
{
    if (g == NULL)
        return;
    free(g->t);
    free(g->v);
    free(g->G);
    free(g->d);
    memset(g, 0, sizeof *g);
}

static pd_status alloc(pd_profile *g, int64_t n)
{
    g->n = n;
    g->t = calloc((size_t)n, sizeof(double));
    g->v = calloc((size_t)n, sizeof(double));
    g->G = calloc((size_t)n + 1, sizeof(double));
    g->d = calloc((size_t)n, sizeof(double));
    if (g->t == NULL || g->v == NULL || g->G == NULL || g->d == NULL) {
        pd_profile_free(g);
        return pd_fail(PD_ERR_NOMEM, "out of memory for a profile");
    }
    return PD_OK;
}

/* Comma-separated numbers: how many (0 on a malformed list); *out malloc'ed. */
static int64_t parse_list(const char *s, double **out)
{
    int64_t n = 1;
    for (const char *c = s; *c; c++)
        n += *c == ',';
    double *x = malloc((size_t)n * sizeof(double));
    char *buf = strdup(s);
    if (x == NULL || buf == NULL) {
        free(x);
        free(buf);
        return 0;
    }
    int64_t k = 0;
    char *p = buf;
    /* strtok would skip empty fields: walk the commas by hand */
    for (;;) {
        char *comma = strchr(p, ',');
        if (comma)
            *comma = '\0';
        if (!pd_parse_double(p, &x[k])) {
            k = 0;
            break;
        }
        k++;
        if (comma == NULL)
            break;
        p = comma + 1;
    }
    free(buf);
    if (k != n) {
        free(x);
        return 0;
    }
    *out = x;
    return n;
}

/* The integrals of a points profile at its knots, from t_0. */
static void points_integrals(pd_profile *g)
{
    g->G[0] = 0;
    for (int64_t k = 0; k + 1 < g->n; k++)
        g->G[k + 1] = g->G[k] + 0.5 * (g->t[k + 1] - g->t[k]) * (g->v[k] + g->v[k + 1]);
    g->G[g->n] = 0;
}

/* Check and keep n (time, value) pairs xy[2k], xy[2k+1]. */
static pd_status make_points(pd_profile *g, const double *xy, int64_t n, const char *what)
{
    if (n < 1)
        return pd_fail(PD_ERR_INVALID, "profile '%s': no points", what);
    for (int64_t k = 1; k < n; k++)
        if (!(xy[2 * k] > xy[2 * k - 2]))
            return pd_fail(PD_ERR_INVALID,
                           "profile '%s': times must increase strictly (%.17g after %.17g)", what,
                           xy[2 * k], xy[2 * k - 2]);
    pd_status s = alloc(g, n);
    if (s != PD_OK)
        return s;
    g->kind = PD_PROFILE_POINTS;
    for (int64_t k = 0; k < n; k++) {
        g->t[k] = xy[2 * k];
        g->v[k] = xy[2 * k + 1];
    }
    points_integrals(g);
    return PD_OK;
}

/* A table file: `time value` lines, `#` comments, blank lines. */
static pd_status read_table(const char *path, pd_profile *g)
{
    FILE *fp = fopen(path, "r");
    if (fp == NULL)
        return pd_fail(PD_ERR_IO, "cannot read the profile table '%s': %s", path, strerror(errno));
    double *xy = NULL;
    int64_t n = 0, cap = 0, line = 0;
    char *text = NULL;
    size_t len = 0;
    pd_status s = PD_OK;
    while (s == PD_OK && getline(&text, &len, fp) != -1) {
        line++;
        char *hash = strchr(text, '#');
        if (hash)
            *hash = '\0';
        char *w[3] = {NULL, NULL, NULL}, *save = NULL;
        int nw = 0;
        for (char *tok = strtok_r(text, " \t\r\n", &save); tok && nw < 3;
             tok = strtok_r(NULL, " \t\r\n", &save))
            w[nw++] = tok;
        if (nw == 0)
            continue;
        double tv[2];
        if (nw != 2 || !pd_parse_double(w[0], &tv[0]) || !pd_parse_double(w[1], &tv[1])) {
            s = pd_fail(PD_ERR_INVALID, "profile table '%s' line %lld: expected 'time value'", path,
                        (long long)line);
            break;
        }
        if (n == cap) {
            cap = cap ? 2 * cap : 64;
            double *m = realloc(xy, (size_t)cap * 2 * sizeof(double));
            if (m == NULL) {
                s = pd_fail(PD_ERR_NOMEM, "out of memory reading '%s'", path);
                break;
            }
            xy = m;
        }
        xy[2 * n] = tv[0];
        xy[2 * n + 1] = tv[1];
        n++;
    }
    if (s == PD_OK && ferror(fp))
        s = pd_fail(PD_ERR_IO, "cannot read the profile table '%s'", path);
    free(text);
    fclose(fp);
    if (s == PD_OK)
        s = make_points(g, xy, n, path);
    free(xy);
    return s;
}

pd_status pd_profile_parse(const char *spec, pd_profile *g)
{
    memset(g, 0, sizeof *g);
    double c;
    if (pd_parse_double(spec, &c)) {
        pd_status s = alloc(g, 1);
        if (s == PD_OK) {
            g->kind = PD_PROFILE_CONSTANT;
            g->v[0] = c;
        }
        return s;
    }
    if (strncmp(spec, "table:", 6) == 0) {
        if (spec[6] == '\0')
            return pd_fail(PD_ERR_INVALID, "profile '%s': table: needs a FILE", spec);
        return read_table(spec + 6, g);
    }
    int points = strncmp(spec, "points:", 7) == 0, pulses = strncmp(spec, "pulses:", 7) == 0;
    if (!points && !pulses)
        return pd_fail(PD_ERR_INVALID,
                       "profile '%s': expected a number, points:T0,V0,..., table:FILE or "
                       "pulses:V1,D1,...",
                       spec);
    double *x = NULL;
    int64_t m = parse_list(spec + 7, &x);
    if (m == 0 || m % 2 != 0) {
        free(x);
        return pd_fail(PD_ERR_INVALID, "profile '%s': expected pairs of numbers after '%.7s'",
                       spec, spec);
    }
    pd_status s = PD_OK;
    if (points)
        s = make_points(g, x, m / 2, spec);
    else {
        for (int64_t k = 0; k < m / 2 && s == PD_OK; k++)
            if (!(x[2 * k + 1] > 0))
                s = pd_fail(PD_ERR_INVALID, "profile '%s': pulse durations must be positive",
                            spec);
        if (s == PD_OK)
            s = alloc(g, m / 2);
        if (s == PD_OK) {
            g->kind = PD_PROFILE_PULSES;
            double t = 0;
            for (int64_t k = 0; k < g->n; k++) {
                g->t[k] = t;
                g->v[k] = x[2 * k];
                g->d[k] = x[2 * k + 1];
                g->G[k + 1] = g->G[k] + x[2 * k] * x[2 * k + 1];
                t += x[2 * k + 1];
            }
            g->end = t;
            for (int64_t k = 0; k < g->n && s == PD_OK; k++)
                if (!isfinite(g->G[k + 1]))
                    s = pd_fail(PD_ERR_INVALID, "profile '%s': not finite", spec);
        }
    }
    free(x);
    if (s != PD_OK)
        pd_profile_free(g);
    return s;
}

/* The segment or pulse of t: the largest k with t_k <= t (-1 before t_0). */
static int64_t locate(const pd_profile *g, double t)
{
    int64_t lo = -1, hi = g->n; /* t_lo <= t < t_hi */
    while (hi - lo > 1) {
        int64_t mid = lo + (hi - lo) / 2;
        if (g->t[mid] <= t)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

double pd_profile_value(const pd_profile *g, double t)
{
    if (g->kind == PD_PROFILE_CONSTANT)
        return g->v[0];
    int64_t k = locate(g, t);
    if (g->kind == PD_PROFILE_PULSES)
        return k < 0 || t >= g->end ? 0.0 : g->v[k];
    if (k < 0)
        return g->v[0];
    if (k == g->n - 1)
        return g->v[k];
    return g->v[k] + (t - g->t[k]) * (g->v[k + 1] - g->v[k]) / (g->t[k + 1] - g->t[k]);
}

/* A(t) = int_{t_0}^t g of a points profile. */
static double points_antiderivative(const pd_profile *g, double t)
{
    int64_t k = locate(g, t);
    if (k < 0)
        return g->v[0] * (t - g->t[0]);
    return g->G[k] + 0.5 * (t - g->t[k]) * (g->v[k] + pd_profile_value(g, t));
}

double pd_profile_integral(const pd_profile *g, double t)
{
    switch (g->kind) {
    case PD_PROFILE_CONSTANT:
        return g->v[0] * t;
    case PD_PROFILE_POINTS:
        return points_antiderivative(g, t) - points_antiderivative(g, 0.0);
    case PD_PROFILE_PULSES: {
        if (t <= 0)
            return 0.0;
        if (t >= g->end)
            return g->G[g->n];
        int64_t k = locate(g, t);
        return g->G[k] + g->v[k] * (t - g->t[k]);
    }
    }
    return NAN;
}

double pd_profile_rate(const pd_profile *g, double t)
{
    if (g->kind != PD_PROFILE_POINTS)
        return 0.0; /* constant, or piecewise constant (0 at the jumps) */
    int64_t k = locate(g, t);
    if (k < 0 || k == g->n - 1)
        return 0.0;
    return (g->v[k + 1] - g->v[k]) / (g->t[k + 1] - g->t[k]);
}

/* The shortest %g form of x that reads back to x exactly (at most 17
 * digits), so that a log shows 5e-06 and 20, not 5.0000000000000004e-06
 * or 2e+01. */
static int shortest(char *buf, size_t len, double x)
{
    char best[32] = "";
    for (int prec = 17; prec >= 1; prec--) {
        char try[32];
        snprintf(try, sizeof try, "%.*g", prec, x);
        if (strtod(try, NULL) == x && (best[0] == '\0' || strlen(try) <= strlen(best)))
            memcpy(best, try, sizeof best);
    }
    return snprintf(buf, len, "%s", best);
}

char *pd_profile_text(const pd_profile *g)
{
    size_t cap = 64 + (size_t)g->n * 2 * 26;
    char *s = malloc(cap), *p = s;
    if (s == NULL)
        return NULL;
    if (g->kind == PD_PROFILE_CONSTANT) {
        shortest(s, cap, g->v[0]);
        return s;
    }
    p += sprintf(p, "%s", g->kind == PD_PROFILE_POINTS ? "points:" : "pulses:");
    for (int64_t k = 0; k < g->n; k++) {
        /* pulses: the durations as given, so that a reread sums the
         * same start times */
        double a = g->kind == PD_PROFILE_POINTS ? g->t[k] : g->v[k];
        double b = g->kind == PD_PROFILE_POINTS ? g->v[k] : g->d[k];
        p += sprintf(p, "%s", k ? "," : "");
        p += shortest(p, 26, a);
        *p++ = ',';
        p += shortest(p, 26, b);
    }
    return s;
}
