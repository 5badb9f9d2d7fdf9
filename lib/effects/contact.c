/*
 * contact.c -- short-range contact forces, seed 000 eqs. 13-15.
 *
 * Between any two particles (bonded or not) closer than
 *   d_ij = min(0.9 |x_j - x_i|, 1.35 (r_i + r_j))     (reference positions)
 * a repulsive force density acts on i:
 *   f_i += (c_S / delta) (|y_j - y_i| - d_ij) V_j (y_j - y_i) / |y_j - y_i|
 * with c_S = 15 c.  The force only repels, and only while |y_ij| < d_ij.
 *
 * d_ij never exceeds 1.35 (r_i + r_j) (about 1.35 spacings), far below the
 * horizon, so the pairs live in a list of their own with cutoff
 * max d + skin, built with cell lists and rebuilt only when some particle
 * has moved more than skin/2 since the last build (then no pair can have
 * come within max d unseen).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "effects/effect.h"
#include "models/model.h"
#include "stencil/grid.h"

#ifdef _OPENMP
#include <omp.h>
#endif

typedef struct {
    double cutoff;     /* largest d_ij, m                      */
    double skin;       /* m                                    */
    int64_t *offset;   /* n+1                                  */
    int32_t *partner;  /* candidates within cutoff + skin       */
    double *d;         /* d_ij per candidate, m                 */
    int64_t cap;
    double *ybuild[3]; /* positions at the last build           */
} contact_list;

static void contact_free(void *state)
{
    contact_list *cl = state;
    if (cl == NULL)
        return;
    free(cl->offset);
    free(cl->partner);
    free(cl->d);
    for (int k = 0; k < 3; k++)
        free(cl->ybuild[k]);
    free(cl);
}

static pd_status contact_init(pd_sim *sim, void **state)
{
    contact_list *cl = calloc(1, sizeof *cl);
    if (cl == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the contact list");
    double rmax = 0;
    for (int64_t i = 0; i < sim->n; i++)
        rmax = fmax(rmax, sim->p->radius[i]);
    cl->cutoff = PD_CONTACT_RADIUS_FAC * 2.0 * rmax;
    cl->skin = sim->sc.contact_skin;
    cl->offset = calloc((size_t)sim->n + 1, sizeof(int64_t));
    for (int k = 0; k < 3; k++)
        cl->ybuild[k] = malloc((size_t)sim->n * sizeof(double));
    if (cl->offset == NULL || !cl->ybuild[0] || !cl->ybuild[1] || !cl->ybuild[2]) {
        contact_free(cl);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the contact list");
    }
    *state = cl;
    return PD_OK;
}

/* The cells of a search and the positions in the cells' order (ys[d][e]
 * is y[d][c.index[e]]: a cell's particles are read one after another, not
 * from all over the arrays); with a kernel that takes the contact of the
 * pairs that started within `gap` (the stencil, the bond list's rows), the
 * displacements too (us, in the same order): a pair that started at least
 * `gap` apart comes within `reach` only when |u_i - u_j| >= gap - reach,
 * so a candidate displaced less than that from i started within the gap,
 * is the kernel's, and is left out before it is looked up (fragments that
 * move as one). */
typedef struct {
    pd_cells c;
    double *ys[3];
    double *us[3];  /* NULL: no gap to prune by                  */
    double prune2;  /* |u_i - u_j|^2 below this: the kernel's pair */
} cell_search;

static void search_free(cell_search *cs)
{
    pd_cells_free(&cs->c);
    for (int d = 0; d < 3; d++) {
        free(cs->ys[d]);
        free(cs->us[d]);
    }
}

/* The cells of the particles but the lost (reach: the cell edge); with a
 * gap above the reach, the displacements to prune by. */
static pd_status search_build(const pd_sim *sim, double reach, double gap, cell_search *cs)
{
    memset(cs, 0, sizeof *cs);
    pd_status s = pd_cells_build_except(&cs->c, sim->n, sim->y, reach, sim->lost);
    if (s != PD_OK)
        return s;
    const int64_t m = cs->c.start[cs->c.dim[0] * cs->c.dim[1] * cs->c.dim[2]];
    const int prune = gap > reach;
    for (int d = 0; d < 3; d++)
        if ((cs->ys[d] = malloc((size_t)(m > 0 ? m : 1) * sizeof(double))) == NULL ||
            (prune && (cs->us[d] = malloc((size_t)(m > 0 ? m : 1) * sizeof(double))) == NULL)) {
            search_free(cs);
            return pd_fail(PD_ERR_NOMEM, "out of memory for the contact search");
        }
    /* (gap - reach)^2 less a margin far above any rounding of |u| */
    cs->prune2 = prune ? (gap - reach) * (gap - reach) * (1.0 - 1e-9) : 0.0;
    double *const *y = sim->y, *const *x = sim->p->x;
#pragma omp parallel for schedule(static)
    for (int64_t e = 0; e < m; e++)
        for (int d = 0; d < 3; d++) {
            const int32_t i = cs->c.index[e];
            cs->ys[d][e] = y[d][i];
            if (prune)
                cs->us[d][e] = y[d][i] - x[d][i];
        }
    return PD_OK;
}

/* The points of the cells around particle i, as pd_cells_adjacent_rows
 * gives them: rows [lo[q], hi[q]) of the cells' index. */
typedef struct {
    int n;
    int64_t lo[9], hi[9];
} cell_rows;

static void rows_around(const pd_sim *sim, const cell_search *cs, int64_t i, cell_rows *r)
{
    const double yi[3] = {sim->y[0][i], sim->y[1][i], sim->y[2][i]};
    r->n = pd_cells_adjacent_rows(&cs->c, yi, r->lo, r->hi);
}

/* Candidates of i within cutoff + skin among the points of `rows` (i's
 * rows_around): count (out == NULL) or write. */
static int64_t candidates(const pd_sim *sim, const cell_search *cs, const cell_rows *rows,
                          double reach2, int64_t i, int32_t *out, double *dout)
{
    const pd_cells *c = &cs->c;
    const double *ys0 = cs->ys[0], *ys1 = cs->ys[1], *ys2 = cs->ys[2];
    const pd_particles *p = sim->p;
    double *const *y = sim->y;
    if (sim->lost && sim->lost[i]) /* out of the body for good: no contact */
        return 0;
    /* the stencil pairs' contact is the lattice kernel's (lib/stencil/grid.c),
     * the half bonds' that of the bond list's AVX-512 rows (lib/models/pmb.c) */
    const pd_grid *grid = pd_grid_contact(sim->grid) ? sim->grid : NULL;
    const pd_half_bonds *hb = sim->half.contact ? &sim->half : NULL;
    const double yi[3] = {y[0][i], y[1][i], y[2][i]};
    const int64_t *lo = rows->lo, *hi = rows->hi;
    int64_t m = 0;
    int64_t near[256]; /* the entries of a stretch of a row within reach */
    const double *us0 = cs->us[0], *us1 = cs->us[1], *us2 = cs->us[2], prune2 = cs->prune2;
    double *const *x = sim->p->x;
    const double ui[3] = {yi[0] - x[0][i], yi[1] - x[1][i], yi[2] - x[2][i]};
    for (int q = 0; q < rows->n; q++)
        for (int64_t e0 = lo[q]; e0 < hi[q]; e0 += 256) {
            const int64_t e1 = hi[q] - e0 > 256 ? e0 + 256 : hi[q];
            int nn = 0; /* most are out of reach: kept or not without a branch */
            for (int64_t e = e0; e < e1; e++) {
                const double dx = yi[0] - ys0[e], dy = yi[1] - ys1[e], dz = yi[2] - ys2[e];
                near[nn] = e;
                nn += !(dx * dx + dy * dy + dz * dz > reach2);
            }
            for (int a = 0; a < nn; a++) {
                const int64_t e = near[a];
                const int32_t j = c->index[e];
                if (us0) { /* displaced as i is: the kernel's pair, not looked up */
                    const double vx = ui[0] - us0[e], vy = ui[1] - us1[e], vz = ui[2] - us2[e];
                    if (vx * vx + vy * vy + vz * vz < prune2)
                        continue;
                }
                if (j == i || (grid && pd_grid_pair(grid, i, j)) ||
                    (hb && pd_half_find(hb, j < i ? j : i, j < i ? i : j) >= 0))
                    continue;
                if (out) {
                    double ex = p->x[0][i] - p->x[0][j], ey = p->x[1][i] - p->x[1][j],
                           ez = p->x[2][i] - p->x[2][j];
                    double r0 = sqrt(ex * ex + ey * ey + ez * ez);
                    out[m] = j;
                    dout[m] = fmin(PD_CONTACT_REF_FRAC * r0,
                                   PD_CONTACT_RADIUS_FAC * (p->radius[i] + p->radius[j]));
                }
                m++;
            }
        }
    return m;
}

/* Room for `total` pairs in the list. */
static pd_status list_room(contact_list *cl, int64_t total)
{
    if (total <= cl->cap)
        return PD_OK;
    int64_t cap = total + total / 4 + 16;
    int32_t *np = realloc(cl->partner, (size_t)cap * sizeof(int32_t));
    if (np)
        cl->partner = np;
    double *nd = realloc(cl->d, (size_t)cap * sizeof(double));
    if (nd)
        cl->d = nd;
    if (np == NULL || nd == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for %lld contact pairs", (long long)total);
    cl->cap = cap;
    return PD_OK;
}

/* The list from every particle's own search (each pair found from both
 * ends): without the lattice stencil. */
static pd_status build_all(pd_sim *sim, contact_list *cl, double reach)
{
    cell_search c;
    pd_status s = search_build(sim, reach, 0.0, &c);
    if (s != PD_OK)
        return s;
    const int64_t n = sim->n;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++) {
        cell_rows r;
        rows_around(sim, &c, i, &r);
        cl->offset[i + 1] = candidates(sim, &c, &r, reach * reach, i, NULL, NULL);
    }
    cl->offset[0] = 0;
    for (int64_t i = 0; i < n; i++)
        cl->offset[i + 1] += cl->offset[i];
    if ((s = list_room(cl, cl->offset[n])) == PD_OK)
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < n; i++) {
            cell_rows r;
            rows_around(sim, &c, i, &r);
            candidates(sim, &c, &r, reach * reach, i, cl->partner + cl->offset[i],
                       cl->d + cl->offset[i]);
        }
    search_free(&c);
    return s;
}

/* The list with the lattice stencil, which takes the contact of every
 * pair that started within the horizon: the list holds only pairs that
 * started at least `gap` apart (the shortest lattice distance the stencil
 * lacks; with the bond list's AVX-512 rows, which take the half bonds'
 * pairs, the shortest distance of a pair that is not one), and such a
 * pair comes within `reach` only when |u_i| + |u_j| >= gap - reach, so
 * one of its ends (a "mover") has moved at least (gap - reach)/2 from its
 * site.  Only the movers search the cells; a pair of a
 * mover i and another particle j goes into j's list too when j is not a
 * mover (in ascending i: the same order at any thread count).  No mover,
 * no pair: not even the cells are built.  The pairs are those of
 * build_all; only a non-mover's list is in another order.  Lost particles
 * are out of contact. */
static pd_status build_movers(pd_sim *sim, contact_list *cl, double reach)
{
    const double gap = sim->grid ? pd_grid_gap(sim->grid) : sim->half.gap;
    const double umin = 0.5 * (gap - reach);
    const double umin2 = umin > 0 ? umin * umin : 0.0; /* 0: every particle */
    double *const *y = sim->y, *const *x = sim->p->x;
    const uint8_t *lost = sim->lost;
    const int64_t n = sim->n;
    memset(cl->offset, 0, (size_t)(n + 1) * sizeof(int64_t));
    uint8_t *mv = malloc((size_t)(n > 0 ? n : 1));
    if (mv == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the contact search");
    int64_t nm = 0;
#pragma omp parallel for schedule(static) reduction(+ : nm)
    for (int64_t i = 0; i < n; i++) {
        const double ux = y[0][i] - x[0][i], uy = y[1][i] - x[1][i], uz = y[2][i] - x[2][i];
        mv[i] = !(ux * ux + uy * uy + uz * uz < umin2) && !(lost && lost[i]);
        nm += mv[i];
    }
    if (nm == 0) {
        free(mv);
        return PD_OK;
    }
    cell_search c;
    memset(&c, 0, sizeof c);
    int64_t *who = malloc((size_t)nm * sizeof(int64_t)), *toff = malloc((size_t)(nm + 1) * sizeof(int64_t));
    int32_t *tp = NULL;
    double *td = NULL;
    pd_status s = who && toff ? search_build(sim, reach, gap, &c)
                              : pd_fail(PD_ERR_NOMEM, "out of memory for the contact search");
    if (s == PD_OK) {
        for (int64_t i = 0, k = 0; i < n; i++)
            if (mv[i])
                who[k++] = i;
        /* the movers' own searches, into a scratch list: each thread takes
         * a contiguous share of the movers, in order, into its own buffer,
         * and the buffers are joined in thread order (one search per
         * mover; the same list at any thread count) */
        toff[0] = 0;
        int nt = 1;
#ifdef _OPENMP
        nt = omp_get_max_threads();
#endif
        int32_t **bp = calloc((size_t)nt, sizeof *bp);
        double **bd = calloc((size_t)nt, sizeof *bd);
        int64_t *bn = calloc((size_t)nt, sizeof *bn);
        int bad = !bp || !bd || !bn;
        if (!bad)
#pragma omp parallel num_threads(nt) reduction(| : bad)
        {
#ifdef _OPENMP
            const int64_t T = omp_get_num_threads(), t = omp_get_thread_num();
#else
            const int64_t T = 1, t = 0;
#endif
            int64_t cap = 0;
            for (int64_t k = nm * t / T; k < nm * (t + 1) / T && !bad; k++) {
                /* room for every particle of the mover's 27 cells */
                const int64_t i = who[k];
                cell_rows r;
                rows_around(sim, &c, i, &r);
                int64_t most = 0;
                for (int q = 0; q < r.n; q++)
                    most += r.hi[q] - r.lo[q];
                if (bn[t] + most > cap) {
                    cap = 2 * (bn[t] + most) + 1024;
                    int32_t *np = realloc(bp[t], (size_t)cap * sizeof(int32_t));
                    if (np)
                        bp[t] = np;
                    double *nd = realloc(bd[t], (size_t)cap * sizeof(double));
                    if (nd)
                        bd[t] = nd;
                    bad |= !np || !nd;
                    if (bad)
                        break;
                }
                toff[k + 1] =
                    candidates(sim, &c, &r, reach * reach, i, bp[t] + bn[t], bd[t] + bn[t]);
                bn[t] += toff[k + 1];
            }
        }
        if (!bad) {
            for (int64_t k = 0; k < nm; k++)
                toff[k + 1] += toff[k];
            tp = malloc((size_t)(toff[nm] > 0 ? toff[nm] : 1) * sizeof(int32_t));
            td = malloc((size_t)(toff[nm] > 0 ? toff[nm] : 1) * sizeof(double));
            bad = tp == NULL || td == NULL;
        }
        for (int64_t t = 0, at = 0; t < nt && !bad; at += bn[t], t++)
            if (bn[t] > 0) {
                memcpy(tp + at, bp[t], (size_t)bn[t] * sizeof(int32_t));
                memcpy(td + at, bd[t], (size_t)bn[t] * sizeof(double));
            }
        for (int t = 0; bp && bd && t < nt; t++) {
            free(bp[t]);
            free(bd[t]);
        }
        free(bp);
        free(bd);
        free(bn);
        if (bad)
            s = pd_fail(PD_ERR_NOMEM, "out of memory for the contact pairs");
    }
    if (s == PD_OK && toff[nm] > 0) {
        /* the counts: a mover's own pairs; a non-mover's from the movers */
        for (int64_t k = 0; k < nm; k++) {
            cl->offset[who[k] + 1] += toff[k + 1] - toff[k];
            for (int64_t e = toff[k]; e < toff[k + 1]; e++)
                cl->offset[tp[e] + 1] += !mv[tp[e]];
        }
        for (int64_t i = 0; i < n; i++)
            cl->offset[i + 1] += cl->offset[i];
        s = list_room(cl, cl->offset[n]);
    }
    if (s == PD_OK && toff[nm] > 0) {
        int64_t *at = malloc((size_t)n * sizeof(int64_t)); /* fill cursors */
        if (at == NULL)
            s = pd_fail(PD_ERR_NOMEM, "out of memory for the contact search");
        else {
            memcpy(at, cl->offset, (size_t)n * sizeof(int64_t));
            for (int64_t k = 0; k < nm; k++) {
                const int64_t i = who[k], m = toff[k + 1] - toff[k];
                memcpy(cl->partner + at[i], tp + toff[k], (size_t)m * sizeof(int32_t));
                memcpy(cl->d + at[i], td + toff[k], (size_t)m * sizeof(double));
                at[i] += m;
                for (int64_t e = toff[k]; e < toff[k + 1]; e++)
                    if (!mv[tp[e]]) {
                        cl->partner[at[tp[e]]] = (int32_t)i;
                        cl->d[at[tp[e]]++] = td[e];
                    }
            }
            free(at);
        }
    }
    if (s != PD_OK) /* no half-built list */
        memset(cl->offset, 0, (size_t)(n + 1) * sizeof(int64_t));
    search_free(&c);
    free(mv);
    free(who);
    free(toff);
    free(tp);
    free(td);
    return s;
}

static pd_status contact_build(pd_sim *sim, contact_list *cl)
{
    double t0 = pd_wtime();
    const double reach = cl->cutoff + cl->skin;
    pd_status s = pd_grid_contact(sim->grid) || sim->half.contact ? build_movers(sim, cl, reach)
                                                                  : build_all(sim, cl, reach);
    if (s != PD_OK)
        return s;
    const int64_t n = sim->n;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            cl->ybuild[k][i] = sim->y[k][i];
    sim->contact_builds++;
    sim->timers[PD_T_NEIGHBOR] += pd_wtime() - t0;
    return PD_OK;
}

/* Has any particle moved more than skin/2 since the last build? */
static int needs_rebuild(const pd_sim *sim, const contact_list *cl)
{
    if (sim->contact_builds == 0)
        return 1;
    double lim2 = 0.25 * cl->skin * cl->skin;
    int moved = 0;
#pragma omp parallel for schedule(static) reduction(| : moved)
    for (int64_t i = 0; i < sim->n; i++) {
        double dx = sim->y[0][i] - cl->ybuild[0][i], dy = sim->y[1][i] - cl->ybuild[1][i],
               dz = sim->y[2][i] - cl->ybuild[2][i];
        double d2 = dx * dx + dy * dy + dz * dz;
        moved |= !(d2 <= lim2);
    }
    return moved;
}

static pd_status contact_force(pd_sim *sim, void *state)
{
    contact_list *cl = state;
    if (needs_rebuild(sim, cl)) {
        double t0 = pd_wtime();
        pd_status s = contact_build(sim, cl);
        if (s != PD_OK)
            return s;
        /* booked as neighbour lists by contact_build, not as contact */
        sim->timers[PD_T_CONTACT] -= pd_wtime() - t0;
    }
    if (cl->offset[sim->n] == 0) /* no pair (the stencil has them all) */
        return PD_OK;
    const double k = PD_CONTACT_SCALE * sim->sc.c / sim->b->horizon;
    const double *V = sim->p->volume;
    double *const *y = sim->y;
    double *restrict fx = sim->f[0], *restrict fy = sim->f[1], *restrict fz = sim->f[2];
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        const double yi0 = y[0][i], yi1 = y[1][i], yi2 = y[2][i];
        double ax = 0, ay = 0, az = 0;
        for (int64_t q = cl->offset[i]; q < cl->offset[i + 1]; q++) {
            const int32_t j = cl->partner[q];
            const double dx = y[0][j] - yi0, dy = y[1][j] - yi1, dz = y[2][j] - yi2;
            const double r2 = dx * dx + dy * dy + dz * dz;
            const double d = cl->d[q];
            if (r2 >= d * d)
                continue;
            const double r = sqrt(r2);
            if (r < d && r > 0.0) {
                const double fk = k * V[j] * (r - d) / r;
                ax += fk * dx;
                ay += fk * dy;
                az += fk * dz;
            }
        }
        fx[i] += ax;
        fy[i] += ay;
        fz[i] += az;
    }
    return PD_OK;
}

/* The list at the last build, for a restart: its positions. */
static void contact_save(const pd_sim *sim, void *state, pd_restart *r)
{
    const contact_list *cl = state;
    r->contact_builds = sim->contact_builds;
    for (int d = 0; d < 3; d++)
        r->contact_position[d] = sim->contact_builds > 0 ? cl->ybuild[d] : NULL;
}

/* The list as it was built: from the positions of the last build. */
static pd_status contact_restore(pd_sim *sim, void *state, const pd_restart *r)
{
    if (r->contact_builds <= 0)
        return PD_OK;
    if (r->contact_position[0] == NULL)
        return pd_fail(PD_ERR_FORMAT, "the restart data have no contact list positions");
    contact_list *cl = state;
    double *y[3] = {sim->y[0], sim->y[1], sim->y[2]};
    for (int d = 0; d < 3; d++)
        sim->y[d] = r->contact_position[d];
    pd_status s = contact_build(sim, cl);
    for (int d = 0; d < 3; d++)
        sim->y[d] = y[d];
    sim->contact_builds = r->contact_builds;
    return s;
}

static int contact_declared(const pd_scene *s)
{
    return s->has_contact;
}

/* The contact energy, half of each pair to each end (the list holds both
 * i-j and j-i): e_i += sum_j 1/4 (c_S/delta) (d - r)^2 V_i V_j. */
static void contact_energy(const pd_sim *sim, void *state, double *e)
{
    const contact_list *cl = state;
    pd_grid_contact_energy(sim, e);
    pd_half_contact_energy(sim, e);
    if (sim->contact_builds == 0)
        return;
    const double k = PD_CONTACT_SCALE * sim->sc.c / sim->b->horizon;
    const double *V = sim->p->volume;
    double *const *y = sim->y;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        double sum = 0;
        for (int64_t q = cl->offset[i]; q < cl->offset[i + 1]; q++) {
            const int32_t j = cl->partner[q];
            const double dx = y[0][j] - y[0][i], dy = y[1][j] - y[1][i], dz = y[2][j] - y[2][i];
            const double r = sqrt(dx * dx + dy * dy + dz * dz), d = cl->d[q];
            if (r < d)
                sum += 0.25 * k * (d - r) * (d - r) * V[j];
        }
        e[i] += sum * V[i];
    }
}

const pd_effect pd_effect_contact = {
    .name = "contact", .timer = PD_T_CONTACT, .init = contact_init, .force = contact_force,
    .free = contact_free, .energy = contact_energy, .kind = PD_ENERGY_CONTACT,
    .declared = contact_declared, .save = contact_save, .restore = contact_restore};

int64_t pd_sim_contact_builds(const pd_sim *sim)
{
    return sim->contact_builds;
}
