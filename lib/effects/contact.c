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

#include "base/comm.h"
#include "effects/effect.h"
#include "models/model.h"
#include "stencil/grid.h"

#ifdef _OPENMP
#include <omp.h>
#endif

/* The cells of a search and the positions in the cells' order (ys[d][e]
 * is y[d][c.index[e]]: a cell's particles are read one after another, not
 * from all over the arrays); with a kernel that takes the contact of the
 * pairs that started within `gap` (the stencil, the bond list's rows), the
 * displacements too (y - x, in the same order): a pair that started at least
 * `gap` apart comes within `reach` only when |u_i - u_j| >= gap - reach,
 * so a candidate displaced less than that from i started within the gap,
 * is the kernel's, and is left out before it is looked up (fragments that
 * move as one). */
typedef struct {
    pd_cells c;
    double *ys[3];
    int prune;      /* 0: no gap to prune by (ub, pass NULL)      */
    float *ub;      /* 6 a point; at the first point of each cell:
                       a box about its displacements (least x, y, z,
                       then greatest, each rounded outwards to a
                       float), so that a cell displaced as i is is
                       passed over whole                         */
    uint32_t *pass; /* at the first point of each cell that holds a
                       mover (cells_passed): bit 9 (dz + 1) +
                       3 (dy + 1) + dx + 1 set when its neighbour at
                       (dx, dy, dz) is outside the grid, empty, or
                       displaced as one with it (judged by the two
                       boxes): its points pass that neighbour over,
                       and with all 27 set do not search; bit 31:
                       it holds a mover                          */
    double prune2;  /* |u_i - u_j|^2 below this: the kernel's pair */
    int64_t ys_room[3], ub_room, pass_room; /* what the arrays hold */
} cell_search;

typedef struct {
    double cutoff;     /* largest d_ij, m                      */
    double skin;       /* m                                    */
    int64_t *offset;   /* n+1                                  */
    int32_t *partner;  /* candidates within cutoff + skin (a piece of a
                          body on MPI ranks: n + k for the k-th of its
                          remote partners, whose positions are yr)    */
    double *d;         /* d_ij per candidate, m                 */
    int64_t cap;
    double *ybuild[3]; /* positions at the last build           */
    int32_t *rows;     /* the particles with candidates, ascending:
                          the force's loop walks only them      */
    int64_t nrows, rows_cap;
    /* kept from build to build (a build allocates nothing once they have
     * room): the cells of the search, and build_movers's scratch */
    cell_search cs;
    uint8_t *mv;       /* n: 1 a mover, 2 one that does not search  */
    int64_t *who;      /* n: the movers, ascending                  */
    int64_t *toff;     /* n+1: their pairs' offsets into tp, td     */
    int64_t *at;       /* n: fill cursors                           */
    int32_t *tp;       /* the movers' pairs: the partners          */
    double *td;        /* and their d_ij, m                         */
    int64_t tp_room, td_room; /* what tp and td hold                */
    int nbuf;          /* threads with a buffer of their own:      */
    int32_t **bp;      /* a thread's pairs found: the partners     */
    double **bd;       /* and their d_ij, m                         */
    int64_t *bp_room, *bd_room, *bn; /* what they hold, and use   */
    /* a piece of a body on MPI ranks (lib/run/piece.c): the partners of
     * its particles that are neither its own nor its ghosts, their
     * positions received at each step, and its own particles that the
     * other ranks' lists hold */
    int remote;        /* 1: some rank has remote partners (all agree) */
    int64_t nremote;   /* their positions and volumes are kept past the
                          piece's n rows of sim->y and of its particles'
                          volumes (room made at each build), so that the
                          list's loops are the whole body's, bit for bit */
    int64_t *send_row; /* local rows sent, by rank                   */
    int64_t *scount, *rcount; /* doubles sent to / received from each rank */
    double *sbuf, *rbuf;
} contact_list;

static void remote_free(contact_list *cl)
{
    free(cl->send_row);
    free(cl->scount);
    free(cl->rcount);
    free(cl->sbuf);
    free(cl->rbuf);
    cl->send_row = cl->scount = cl->rcount = NULL;
    cl->sbuf = cl->rbuf = NULL;
    cl->nremote = 0;
    cl->remote = 0;
}

static void search_free(cell_search *cs);

static void contact_free(void *state)
{
    contact_list *cl = state;
    if (cl == NULL)
        return;
    search_free(&cl->cs);
    free(cl->mv);
    free(cl->who);
    free(cl->toff);
    free(cl->at);
    free(cl->tp);
    free(cl->td);
    for (int t = 0; t < cl->nbuf; t++) {
        free(cl->bp[t]);
        free(cl->bd[t]);
    }
    free(cl->bp);
    free(cl->bd);
    free(cl->bp_room);
    free(cl->bd_room);
    free(cl->bn);
    free(cl->offset);
    free(cl->partner);
    free(cl->d);
    for (int k = 0; k < 3; k++)
        free(cl->ybuild[k]);
    free(cl->rows);
    remote_free(cl);
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

#define ALL_PASSED 0x7ffffffu /* the 27 bits of cell_search.pass */
#define HOLDS_MOVER 0x80000000u /* its bit 31 */

static void search_free(cell_search *cs)
{
    pd_cells_free(&cs->c);
    for (int d = 0; d < 3; d++)
        free(cs->ys[d]);
    free(cs->ub);
    free(cs->pass);
    memset(cs, 0, sizeof *cs);
}

/* Are the points of the cells whose points start at entries e and f
 * displaced as one (|u_i - u_j|^2 below prune2 for every pair)?  By the
 * farthest corners of their boxes, as cell_comoves judges a point and a
 * box. */
static int boxes_comove(const cell_search *cs, int64_t e, int64_t f)
{
    double t[3];
    for (int d = 0; d < 3; d++) {
        const double a = (double)cs->ub[6 * e + d + 3] - (double)cs->ub[6 * f + d],
                     b = (double)cs->ub[6 * f + d + 3] - (double)cs->ub[6 * e + d];
        t[d] = a > b ? a : b;
    }
    return t[0] * t[0] + t[1] * t[1] + t[2] * t[2] < cs->prune2 * (1.0 - 1e-12);
}

/* The largest float at or below v, and the least at or above. */
static float float_down(double v)
{
    const float f = (float)v;
    return (double)f > v ? nextafterf(f, -INFINITY) : f;
}

static float float_up(double v)
{
    const float f = (float)v;
    return (double)f < v ? nextafterf(f, INFINITY) : f;
}

/* The cells of the particles but the lost (reach: the cell edge); with a
 * gap above the reach, the boxes of the cells' displacements to prune by.
 * Into cs's arrays from the build before, grown where they are short. */
static pd_status search_build(const pd_sim *sim, double reach, double gap, cell_search *cs)
{
    pd_status s = pd_cells_rebuild_except(&cs->c, sim->n, sim->y, reach, sim->lost);
    if (s != PD_OK)
        return s;
    const int64_t m = cs->c.start[cs->c.dim[0] * cs->c.dim[1] * cs->c.dim[2]];
    const int prune = cs->prune = gap > reach;
    const int64_t need = m > 0 ? m : 1;
    int ok = 1;
    for (int d = 0; d < 3; d++)
        ok = ok && pd_grow((void **)&cs->ys[d], &cs->ys_room[d], need, sizeof(double));
    if (!ok || !pd_grow((void **)&cs->ub, &cs->ub_room, 6 * need, sizeof(float)) ||
        !pd_grow((void **)&cs->pass, &cs->pass_room, need, sizeof(uint32_t))) {
        search_free(cs);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the contact search");
    }
    /* (gap - reach)^2 less a margin far above any rounding of |u| */
    cs->prune2 = prune ? (gap - reach) * (gap - reach) * (1.0 - 1e-9) : 0.0;
    double *const *y = sim->y, *const *x = sim->p->x;
#pragma omp parallel for schedule(static)
    for (int64_t e = 0; e < m; e++)
        for (int d = 0; d < 3; d++)
            cs->ys[d][e] = y[d][cs->c.index[e]];
    if (prune) {
        const int64_t *start = cs->c.start, *full = cs->c.full;
        const int32_t *index = cs->c.index;
#pragma omp parallel for schedule(static)
        for (int64_t q = 0; q < cs->c.nfull; q++) {
            const int64_t k = full[q];
            for (int d = 0; d < 3; d++) {
                double lo = INFINITY, hi = -INFINITY;
                for (int64_t e = start[k]; e < start[k + 1]; e++) {
                    const double u = cs->ys[d][e] - x[d][index[e]];
                    lo = u < lo ? u : lo;
                    hi = u > hi ? u : hi;
                }
                cs->ub[6 * start[k] + d] = float_down(lo);
                cs->ub[6 * start[k] + d + 3] = float_up(hi);
            }
        }
    }
    return PD_OK;
}

/* The pass bits of the cells that hold a mover (mv[i] set), after
 * search_build with a gap to prune by; a mover whose 27 cells are all
 * passed over gets mv[i] = 2 (it does not search).  Each pair of such
 * cells is judged once: a cell's own bit and those of the 13 neighbours
 * after it (bits 13 to 26: the cells of higher index), then the 13 before
 * it, read back from theirs where they hold a mover (neighbour b's bit
 * 26 - b; boxes_comove is symmetric). */
static void cells_passed(cell_search *cs, uint8_t *mv)
{
    const int64_t *dim = cs->c.dim, *start = cs->c.start, *full = cs->c.full;
    const int64_t nfull = cs->c.nfull;
    const int32_t *index = cs->c.index;
    uint32_t *pass = cs->pass;
#pragma omp parallel for schedule(static)
    for (int64_t f = 0; f < nfull; f++) {
        const int64_t k = full[f];
        int any = 0;
        for (int64_t e = start[k]; e < start[k + 1]; e++)
            any |= mv[index[e]];
        pass[start[k]] = any ? HOLDS_MOVER : 0;
    }
    for (int half = 0; half < 2; half++)
#pragma omp parallel for schedule(static)
        for (int64_t f = 0; f < nfull; f++) {
            const int64_t k = full[f];
            if (!(__atomic_load_n(&pass[start[k]], __ATOMIC_RELAXED) & HOLDS_MOVER))
                continue;
            const int64_t kc[3] = {k % dim[0], k / dim[0] % dim[1], k / (dim[0] * dim[1])};
            uint32_t bits = 0;
            for (int b = half ? 0 : 13; b < (half ? 13 : 27); b++) {
                const int64_t q[3] = {kc[0] + b % 3 - 1, kc[1] + b / 3 % 3 - 1, kc[2] + b / 9 - 1};
                int out = 0;
                for (int d = 0; d < 3; d++)
                    out |= q[d] < 0 || q[d] >= dim[d];
                const int64_t n = out ? 0 : (q[2] * dim[1] + q[1]) * dim[0] + q[0];
                if (out || start[n + 1] == start[n]) {
                    bits |= 1u << b;
                    continue;
                }
                const uint32_t theirs =
                    half ? __atomic_load_n(&pass[start[n]], __ATOMIC_RELAXED) : 0;
                if (theirs & HOLDS_MOVER ? (theirs >> (26 - b)) & 1u
                                         : (uint32_t)boxes_comove(cs, start[k], start[n]))
                    bits |= 1u << b;
            }
            __atomic_fetch_or(&pass[start[k]], bits, __ATOMIC_RELAXED);
        }
#pragma omp parallel for schedule(static)
    for (int64_t f = 0; f < nfull; f++) {
        const int64_t k = full[f];
        if ((pass[start[k]] & ALL_PASSED) == ALL_PASSED)
            for (int64_t e = start[k]; e < start[k + 1]; e++)
                if (mv[index[e]])
                    mv[index[e]] = 2;
    }
}

/* The cells around particle i, as pd_cells_adjacent_runs gives them: rows
 * of `width` cells from first[q], their points [lo[q], hi[q]) of the
 * cells' index; i's own cell `home`. */
typedef struct {
    int n, width, dx0, around[9];
    int64_t first[9], lo[9], hi[9], home;
} cell_rows;

static void rows_around(const pd_sim *sim, const cell_search *cs, int64_t i, cell_rows *r)
{
    const double yi[3] = {sim->y[0][i], sim->y[1][i], sim->y[2][i]};
    r->n = pd_cells_adjacent_runs(&cs->c, yi, r->first, &r->width, r->around, &r->dx0);
    for (int q = 0; q < r->n; q++) {
        r->lo[q] = cs->c.start[r->first[q]];
        r->hi[q] = cs->c.start[r->first[q] + r->width];
        if (r->around[q] == 4) /* dy = dz = 0: always there (i's own cell) */
            r->home = r->first[q] - r->dx0;
    }
}

/* Is every point of the cell whose points start at entry e displaced as i
 * is (|u_i - u_j|^2 below prune2, i's displacement ui)?  By its box's
 * farthest corner from ui: the box holds every point's displacement, each
 * difference is rounded as candidates() rounds a point's, and no smaller
 * (rounding keeps the order), so the corner's squares are no smaller;
 * their sum is kept 1e-12 below prune2, far above what summing in another
 * order could change (this file's sums may be reassociated), so a cell
 * passed over holds no pair that candidates() would keep. */
static int cell_comoves(const cell_search *cs, int64_t e, const double ui[3])
{
    double t[3];
    for (int d = 0; d < 3; d++) {
        const double a = ui[d] - (double)cs->ub[6 * e + d],
                     b = (double)cs->ub[6 * e + d + 3] - ui[d];
        t[d] = a > b ? a : b;
    }
    return t[0] * t[0] + t[1] * t[1] + t[2] * t[2] < cs->prune2 * (1.0 - 1e-12);
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
    const int prune = cs->prune;
    const double prune2 = cs->prune2;
    double *const *x = sim->p->x;
    const double ui[3] = {yi[0] - x[0][i], yi[1] - x[1][i], yi[2] - x[2][i]};
    /* the rows' runs of cells not displaced as i is (the whole rows
     * without a gap to prune by), in the rows' order */
    const uint32_t pass = prune ? cs->pass[c->start[rows->home]] : 0;
    int64_t lo[18], hi[18];
    int nspan = 0;
    for (int q = 0; q < rows->n; q++) {
        if (!prune) {
            lo[nspan] = rows->lo[q];
            hi[nspan++] = rows->hi[q];
            continue;
        }
        int64_t from = rows->lo[q];
        for (int w = 0; w < rows->width; w++) {
            const int64_t k = rows->first[q] + w, e0 = c->start[k], e1 = c->start[k + 1];
            const int bit = 3 * rows->around[q] + rows->dx0 + w + 1;
            if (e1 > e0 && (((pass >> bit) & 1) || cell_comoves(cs, e0, ui))) {
                if (e0 > from) {
                    lo[nspan] = from;
                    hi[nspan++] = e0;
                }
                from = e1;
            }
        }
        if (rows->hi[q] > from) {
            lo[nspan] = from;
            hi[nspan++] = rows->hi[q];
        }
    }
    int64_t m = 0;
    int64_t near[256]; /* the entries of a stretch of a row within reach */
    for (int q = 0; q < nspan; q++)
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
                if (prune) { /* displaced as i is: the kernel's pair, not looked up */
                    const double vx = ui[0] - (ys0[e] - x[0][j]), vy = ui[1] - (ys1[e] - x[1][j]),
                                 vz = ui[2] - (ys2[e] - x[2][j]);
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
    cell_search *c = &cl->cs;
    pd_status s = search_build(sim, reach, 0.0, c);
    if (s != PD_OK)
        return s;
    const int64_t n = sim->n;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++) {
        cell_rows r;
        rows_around(sim, c, i, &r);
        cl->offset[i + 1] = candidates(sim, c, &r, reach * reach, i, NULL, NULL);
    }
    cl->offset[0] = 0;
    for (int64_t i = 0; i < n; i++)
        cl->offset[i + 1] += cl->offset[i];
    if ((s = list_room(cl, cl->offset[n])) == PD_OK)
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < n; i++) {
            cell_rows r;
            rows_around(sim, c, i, &r);
            candidates(sim, c, &r, reach * reach, i, cl->partner + cl->offset[i],
                       cl->d + cl->offset[i]);
        }
    return s;
}

/* The movers' search buffers of nt threads, kept from build to build:
 * each thread's used count set to 0.  Returns 0, or -1 out of memory (the
 * buffers as they were). */
static int thread_buffers(contact_list *cl, int nt)
{
    if (nt > cl->nbuf) {
        int32_t **bp = realloc(cl->bp, (size_t)nt * sizeof *bp);
        if (bp)
            cl->bp = bp;
        double **bd = realloc(cl->bd, (size_t)nt * sizeof *bd);
        if (bd)
            cl->bd = bd;
        int64_t *r1 = realloc(cl->bp_room, (size_t)nt * sizeof *r1);
        if (r1)
            cl->bp_room = r1;
        int64_t *r2 = realloc(cl->bd_room, (size_t)nt * sizeof *r2);
        if (r2)
            cl->bd_room = r2;
        int64_t *bn = realloc(cl->bn, (size_t)nt * sizeof *bn);
        if (bn)
            cl->bn = bn;
        if (!bp || !bd || !r1 || !r2 || !bn)
            return -1;
        for (int t = cl->nbuf; t < nt; t++) {
            cl->bp[t] = NULL;
            cl->bd[t] = NULL;
            cl->bp_room[t] = cl->bd_room[t] = 0;
        }
        cl->nbuf = nt;
    }
    memset(cl->bn, 0, (size_t)nt * sizeof *cl->bn);
    return 0;
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
    const size_t rows = (size_t)(n > 0 ? n : 1);
    if (cl->mv == NULL && (cl->mv = malloc(rows)) == NULL) /* kept for the next builds */
        return pd_fail(PD_ERR_NOMEM, "out of memory for the contact search");
    uint8_t *mv = cl->mv;
    int64_t nm = 0;
#pragma omp parallel for schedule(static) reduction(+ : nm)
    for (int64_t i = 0; i < n; i++) {
        const double ux = y[0][i] - x[0][i], uy = y[1][i] - x[1][i], uz = y[2][i] - x[2][i];
        mv[i] = !(ux * ux + uy * uy + uz * uz < umin2) && !(lost && lost[i]);
        nm += mv[i];
    }
    if (nm == 0)
        return PD_OK;
    if (cl->who == NULL) { /* the first build with movers: the rest of the scratch */
        cl->who = malloc(rows * sizeof(int64_t));
        cl->toff = malloc((rows + 1) * sizeof(int64_t));
        cl->at = malloc(rows * sizeof(int64_t));
        if (!cl->who || !cl->toff || !cl->at) {
            free(cl->who);
            free(cl->toff);
            free(cl->at);
            cl->who = cl->toff = cl->at = NULL;
            return pd_fail(PD_ERR_NOMEM, "out of memory for the contact search");
        }
    }
    cell_search *c = &cl->cs;
    int64_t *who = cl->who, *toff = cl->toff;
    pd_status s = search_build(sim, reach, gap, c);
    if (s == PD_OK) {
        if (c->prune)
            cells_passed(c, mv);
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
        int bad = thread_buffers(cl, nt) != 0;
        int32_t **bp = cl->bp;
        double **bd = cl->bd;
        int64_t *bn = cl->bn;
        if (!bad)
#pragma omp parallel num_threads(nt) reduction(| : bad)
        {
#ifdef _OPENMP
            const int64_t T = omp_get_num_threads(), t = omp_get_thread_num();
#else
            const int64_t T = 1, t = 0;
#endif
            for (int64_t k = nm * t / T; k < nm * (t + 1) / T && !bad; k++) {
                const int64_t i = who[k];
                if (mv[i] == 2) { /* its 27 cells displaced as it is */
                    toff[k + 1] = 0;
                    continue;
                }
                /* room for every particle of the mover's 27 cells */
                cell_rows r;
                rows_around(sim, c, i, &r);
                int64_t most = 0;
                for (int q = 0; q < r.n; q++)
                    most += r.hi[q] - r.lo[q];
                if (!pd_grow((void **)&bp[t], &cl->bp_room[t], bn[t] + most, sizeof(int32_t)) ||
                    !pd_grow((void **)&bd[t], &cl->bd_room[t], bn[t] + most, sizeof(double))) {
                    bad = 1;
                    break;
                }
                toff[k + 1] =
                    candidates(sim, c, &r, reach * reach, i, bp[t] + bn[t], bd[t] + bn[t]);
                bn[t] += toff[k + 1];
            }
        }
        if (!bad) {
            for (int64_t k = 0; k < nm; k++)
                toff[k + 1] += toff[k];
            const int64_t need = toff[nm] > 0 ? toff[nm] : 1;
            bad = !pd_grow((void **)&cl->tp, &cl->tp_room, need, sizeof(int32_t)) ||
                  !pd_grow((void **)&cl->td, &cl->td_room, need, sizeof(double));
        }
        int32_t *tp = cl->tp;
        double *td = cl->td;
        for (int64_t t = 0, at = 0; t < nt && !bad; at += bn[t], t++)
            if (bn[t] > 0) {
                memcpy(tp + at, bp[t], (size_t)bn[t] * sizeof(int32_t));
                memcpy(td + at, bd[t], (size_t)bn[t] * sizeof(double));
            }
        if (bad)
            s = pd_fail(PD_ERR_NOMEM, "out of memory for the contact pairs");
    }
    if (s == PD_OK && toff[nm] > 0) {
        /* the counts: a mover's own pairs; a non-mover's from the movers */
        const int32_t *tp = cl->tp;
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
        int64_t *at = cl->at; /* fill cursors */
        const int32_t *tp = cl->tp;
        const double *td = cl->td;
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
    }
    if (s != PD_OK) /* no half-built list */
        memset(cl->offset, 0, (size_t)(n + 1) * sizeof(int64_t));
    return s;
}

/* ---------------------------------------------------------------------
 * A piece of a body on MPI ranks (lib/run/piece.c).  Its own particles get
 * the whole body's lists, pair for pair and in the same order, so that
 * their forces keep the one rank's bits.  The whole body's list is
 * build_movers's (or build_all's: every particle a mover), each row in
 * ascending partner (list_order), as the piece's pairs are sorted here by
 * their partners' rows of the whole body.  The ranks lay the same grid
 * (the bounding box over all ranks, pd_cells_geometry), every rank learns
 * every mover, and each finds the pairs of its own particles among the
 * movers and its own and ghost particles; a pair of another rank's mover
 * with a particle of this rank's that the other rank's piece does not hold
 * is sent to it.  A partner that is neither a particle of the piece nor a
 * ghost is remote: its owner sends its position at every step.  The rows
 * exchanged are the two ends of the pairs, which every rank sees alike (a
 * pair is in the lists of both its ends).
 */

typedef struct {
    int64_t row;    /* the piece's own particle whose pair it is     */
    int64_t j;      /* the partner's row of the whole body          */
    double d;       /* d_ij, m                                       */
    double v;       /* the partner's volume, m^3                     */
} pair_rec;

static int cmp_pair(const void *a, const void *b)
{
    const pair_rec *x = a, *y = b;
    if (x->row != y->row)
        return x->row < y->row ? -1 : 1;
    return (x->j > y->j) - (x->j < y->j);
}

static int cmp_i64(const void *a, const void *b)
{
    const int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

static int cmp_i64_pair(const void *a, const void *b)
{
    const int64_t *x = a, *y = b;
    return x[0] != y[0] ? (x[0] > y[0]) - (x[0] < y[0]) : (x[1] > y[1]) - (x[1] < y[1]);
}

/* The rank that owns row g of the whole body. */
static int owner_of(const pd_piece *pc, int64_t g)
{
    int lo = 0, hi = pc->ranks - 1;
    while (lo < hi) {
        const int mid = (lo + hi + 1) / 2;
        if (pc->own_at[mid] <= g)
            lo = mid;
        else
            hi = mid - 1;
    }
    return lo;
}

static int in_piece(const pd_piece *pc, int r, int64_t g)
{
    return g >= pc->piece_at[2 * r] && g < pc->piece_at[2 * r + 1];
}

/* A point of the search: a particle of the piece, or a mover of any rank. */
typedef struct {
    int64_t g;     /* row of the whole body                    */
    int64_t local; /* row of the piece, or -1                  */
    double x[3], r, v;
    int mover;
} search_point;

/* Does the pair of a (at ya, xa, ra, its cell ka) and point q pass
 * candidates()'s tests (within reach, in the adjacent cells of the whole
 * body's grid, not pruned, not a kernel pair)?  Its d_ij into *d. */
static int pair_test(const pd_sim *sim, const pd_cells *G, const double ya[3], const double xa[3],
                     double ra, const int64_t ka[3], int64_t la, const double yq[3],
                     const search_point *q, double reach2, double prune2, int prune, double *d)
{
    const double dx = ya[0] - yq[0], dy = ya[1] - yq[1], dz = ya[2] - yq[2];
    if (dx * dx + dy * dy + dz * dz > reach2)
        return 0;
    int64_t kq[3];
    pd_cells_locate(G, yq, kq);
    for (int a = 0; a < 3; a++)
        if (kq[a] < ka[a] - 1 || kq[a] > ka[a] + 1)
            return 0;
    if (prune) {
        const double vx = (ya[0] - xa[0]) - (yq[0] - q->x[0]), vy = (ya[1] - xa[1]) - (yq[1] - q->x[1]),
                     vz = (ya[2] - xa[2]) - (yq[2] - q->x[2]);
        if (vx * vx + vy * vy + vz * vz < prune2)
            return 0;
    }
    if (la >= 0 && q->local >= 0) { /* both in the piece: the kernel's pair? */
        const int64_t i = la, j = q->local;
        if (pd_grid_contact(sim->grid) && pd_grid_pair(sim->grid, i, j))
            return 0;
        if (sim->half.contact && pd_half_find(&sim->half, j < i ? j : i, j < i ? i : j) >= 0)
            return 0;
    }
    const double ex = xa[0] - q->x[0], ey = xa[1] - q->x[1], ez = xa[2] - q->x[2];
    const double r0 = sqrt(ex * ex + ey * ey + ez * ez);
    *d = fmin(PD_CONTACT_REF_FRAC * r0, PD_CONTACT_RADIUS_FAC * (ra + q->r));
    return 1;
}

/* The search of a piece's pairs: what it reads, and what it finds. */
enum { PAIR_OW = 7 }; /* a pair sent: the mover, our particle, its position, d, its volume */
typedef struct {
    const pd_sim *sim;
    const pd_cells *G;       /* the whole body's grid                    */
    const search_point *pt;  /* the points and their positions           */
    const uint8_t *mv;       /* the piece's movers                       */
    const double *py[3];
    double reach2, prune2;
    int prune;
    pair_rec *rec;           /* the own particles' pairs                 */
    int64_t nrec, caprec;
    double *out;             /* to the movers' owners                    */
    int64_t *dest, nout, capout, capdest;
} pair_search;

/* The pair of own particle i (not lost) and point k, when it passes
 * candidates()'s tests: into i's list; a pair of another rank's mover
 * with a non-mover that rank's piece lacks goes to that rank too. */
static pd_status add_pair(pair_search *ps, int64_t i, int64_t k)
{
    const pd_sim *sim = ps->sim;
    const pd_piece *pc = sim->piece;
    const search_point *s = &ps->pt[k];
    const int mover = ps->mv[i];
    const double yi[3] = {sim->y[0][i], sim->y[1][i], sim->y[2][i]};
    const double xi[3] = {sim->p->x[0][i], sim->p->x[1][i], sim->p->x[2][i]};
    const double yq[3] = {ps->py[0][k], ps->py[1][k], ps->py[2][k]};
    int64_t ki[3];
    double d;
    if (!mover && !s->mover)
        return PD_OK;
    pd_cells_locate(ps->G, yi, ki);
    if (!pair_test(sim, ps->G, yi, xi, sim->p->radius[i], ki, i, yq, s, ps->reach2, ps->prune2,
                   ps->prune, &d))
        return PD_OK;
    if (!pd_grow((void **)&ps->rec, &ps->caprec, ps->nrec + 1, sizeof *ps->rec))
        return pd_fail(PD_ERR_NOMEM, "out of memory for the contact pairs");
    pair_rec *r = &ps->rec[ps->nrec++];
    r->row = i;
    r->j = s->g;
    r->d = d;
    r->v = s->v;
    const int t = mover ? pc->rank : owner_of(pc, s->g);
    if (t == pc->rank || in_piece(pc, t, pc->first + i))
        return PD_OK;
    if (!pd_grow((void **)&ps->out, &ps->capout, PAIR_OW * (ps->nout + 1), sizeof(double)) ||
        !pd_grow((void **)&ps->dest, &ps->capdest, ps->nout + 1, sizeof(int64_t)))
        return pd_fail(PD_ERR_NOMEM, "out of memory for the contact pairs");
    double *o = ps->out + PAIR_OW * ps->nout;
    o[0] = (double)s->g;
    o[1] = (double)(pc->first + i);
    o[2] = yi[0], o[3] = yi[1], o[4] = yi[2], o[5] = d;
    o[6] = sim->p->volume[i];
    ps->dest[ps->nout++] = t;
    return PD_OK;
}

static pd_status build_piece(pd_sim *sim, contact_list *cl, double reach)
{
    const pd_piece *pc = sim->piece;
    const int P = pc->ranks, me = pc->rank;
    const int64_t n = sim->n, first = pc->first;
    double *const *y = sim->y, *const *x = sim->p->x;
    const uint8_t *lost = sim->lost;
    /* the whole body's grid */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int64_t i = pc->own_lo; i < pc->own_hi; i++)
        for (int d = 0; d < 3; d++)
            if (isfinite(y[d][i]) && !(lost && lost[i])) {
                lo[d] = y[d][i] < lo[d] ? y[d][i] : lo[d];
                hi[d] = y[d][i] > hi[d] ? y[d][i] : hi[d];
            }
    pd_comm_box(lo, hi);
    pd_cells G;
    pd_cells_geometry(&G, lo, hi, pc->n_whole, reach);
    /* the movers (build_movers's; build_all's: everyone), of every rank */
    const int kernel = pd_grid_contact(sim->grid) || sim->half.contact;
    const double gap = sim->grid ? pd_grid_gap(sim->grid) : sim->half.gap;
    const double umin = kernel ? 0.5 * (gap - reach) : 0.0;
    const double umin2 = umin > 0 ? umin * umin : 0.0;
    const int prune = kernel && gap > reach;
    const double prune2 = prune ? (gap - reach) * (gap - reach) * (1.0 - 1e-9) : 0.0;
    uint8_t *mv = malloc((size_t)(n > 0 ? n : 1));
    int64_t *counts = malloc((size_t)P * 3 * sizeof(int64_t)), *c2 = counts + P, *c3 = counts + 2 * P;
    if (mv == NULL || counts == NULL) {
        free(mv);
        free(counts);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the contact search");
    }
    int64_t nmine = 0;
    for (int64_t i = 0; i < n; i++) {
        const double ux = y[0][i] - x[0][i], uy = y[1][i] - x[1][i], uz = y[2][i] - x[2][i];
        mv[i] = !(ux * ux + uy * uy + uz * uz < umin2) && !(lost && lost[i]);
        nmine += mv[i] && i >= pc->own_lo && i < pc->own_hi;
    }
    enum { MW = 9 }; /* a mover: row, y, x, radius, volume */
    double *mine = malloc((size_t)(nmine > 0 ? nmine : 1) * MW * sizeof(double));
    pd_status st = mine ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory for the movers");
    int64_t m = 0;
    double *M = NULL;
    if (st == PD_OK) {
        for (int64_t i = pc->own_lo, k = 0; i < pc->own_hi; i++)
            if (mv[i]) {
                double *q = mine + MW * k++;
                q[0] = (double)(first + i);
                for (int d = 0; d < 3; d++) {
                    q[1 + d] = y[d][i];
                    q[4 + d] = x[d][i];
                }
                q[7] = sim->p->radius[i];
                q[8] = sim->p->volume[i];
            }
        pd_comm_counts(nmine * MW, counts);
        for (int r = 0; r < P; r++)
            m += counts[r] / MW;
        if ((M = malloc((size_t)(m > 0 ? m : 1) * MW * sizeof(double))) == NULL)
            st = pd_fail(PD_ERR_NOMEM, "out of memory for the movers");
        else
            pd_comm_allgather(mine, counts, M);
    }
    free(mine);
    /* the points: the piece's particles that are neither movers nor lost,
     * and every mover */
    const int64_t np = n + m;
    search_point *pt = st == PD_OK ? malloc((size_t)(np > 0 ? np : 1) * sizeof *pt) : NULL;
    double *py[3] = {NULL, NULL, NULL};
    uint8_t *skip = st == PD_OK ? malloc((size_t)(np > 0 ? np : 1)) : NULL;
    for (int d = 0; d < 3 && st == PD_OK; d++)
        py[d] = malloc((size_t)(np > 0 ? np : 1) * sizeof(double));
    if (st == PD_OK && (!pt || !skip || !py[0] || !py[1] || !py[2]))
        st = pd_fail(PD_ERR_NOMEM, "out of memory for the contact search");
    pd_cells C;
    memset(&C, 0, sizeof C);
    if (st == PD_OK) {
        for (int64_t i = 0; i < n; i++) {
            pt[i] = (search_point){.g = first + i, .local = i, .r = sim->p->radius[i],
                                   .v = sim->p->volume[i], .mover = 0};
            for (int d = 0; d < 3; d++) {
                pt[i].x[d] = x[d][i];
                py[d][i] = y[d][i];
            }
            skip[i] = mv[i] || (lost && lost[i]);
        }
        for (int64_t k = 0; k < m; k++) {
            const double *q = M + MW * k;
            const int64_t g = (int64_t)q[0];
            search_point *s = &pt[n + k];
            *s = (search_point){.g = g, .local = g >= first && g < first + n ? g - first : -1,
                                .r = q[7], .v = q[8], .mover = 1};
            for (int d = 0; d < 3; d++) {
                s->x[d] = q[4 + d];
                py[d][n + k] = q[1 + d];
            }
            skip[n + k] = 0;
        }
        st = pd_cells_build_except(&C, np, py, reach, skip);
    }
    /* the pairs of the own particles, and those sent to the movers' owners:
     * an own mover's from its own search, a non-mover's from the searches
     * of the movers (only movers search, as in build_movers) */
    pair_search ps = {.sim = sim, .G = &G, .pt = pt, .mv = mv, .py = {py[0], py[1], py[2]},
                      .reach2 = reach * reach, .prune2 = prune2, .prune = prune};
    for (int64_t i = pc->own_lo; i < pc->own_hi && st == PD_OK; i++) {
        if (!mv[i]) /* (a lost particle is no mover) */
            continue;
        int64_t rl[9], rh[9];
        const double yi[3] = {y[0][i], y[1][i], y[2][i]};
        const int nr = pd_cells_adjacent_rows(&C, yi, rl, rh);
        for (int q = 0; q < nr && st == PD_OK; q++)
            for (int64_t e = rl[q]; e < rh[q] && st == PD_OK; e++)
                if (pt[C.index[e]].g != first + i)
                    st = add_pair(&ps, i, C.index[e]);
    }
    for (int64_t k = n; k < np && st == PD_OK; k++) { /* every mover: own non-movers near it */
        int64_t rl[9], rh[9];
        const double yk[3] = {py[0][k], py[1][k], py[2][k]};
        const int nr = pd_cells_adjacent_rows(&C, yk, rl, rh);
        for (int q = 0; q < nr && st == PD_OK; q++)
            for (int64_t e = rl[q]; e < rh[q] && st == PD_OK; e++) {
                const int64_t i = C.index[e]; /* a point of the piece (movers are past n) */
                if (i < n && i >= pc->own_lo && i < pc->own_hi)
                    st = add_pair(&ps, i, k);
            }
    }
    pair_rec *rec = ps.rec;
    double *out = ps.out;
    int64_t nrec = ps.nrec, caprec = ps.caprec, nout = ps.nout, *dest = ps.dest;
    enum { OW = PAIR_OW };
    pd_cells_free(&C);
    /* the pairs sent (in rank order: a counting sort by destination) */
    st = pd_comm_or(st != PD_OK) && st == PD_OK ? pd_fail(PD_ERR_IO, "a rank failed in the contact search") : st;
    double *sorted = NULL, *got = NULL;
    if (st == PD_OK) {
        for (int r = 0; r < P; r++)
            counts[r] = 0;
        for (int64_t e = 0; e < nout; e++)
            counts[dest[e]] += OW;
        int64_t *at = c3; /* cursors */
        for (int64_t r = 0, sum = 0; r < P; sum += counts[r], r++)
            at[r] = sum;
        sorted = malloc((size_t)(OW * nout > 0 ? OW * nout : 1) * sizeof(double));
        if (sorted)
            for (int64_t e = 0; e < nout; e++) {
                memcpy(sorted + at[dest[e]], out + OW * e, OW * sizeof(double));
                at[dest[e]] += OW;
            }
        /* how many each rank sends here */
        int64_t ngot = 0;
        pd_comm_counts_to(counts, c2);
        for (int r = 0; r < P; r++)
            ngot += c2[r];
        if (sorted)
            got = malloc((size_t)(ngot > 0 ? ngot : 1) * sizeof(double));
        if (got)
            pd_comm_alltoall(sorted, counts, got, c2);
        else
            st = pd_fail(PD_ERR_NOMEM, "out of memory for the contact pairs");
        for (int64_t e = 0; st == PD_OK && e < ngot / OW; e++) { /* a remote non-mover's pair */
            const double *o = got + OW * e;
            if (!pd_grow((void **)&rec, &caprec, nrec + 1, sizeof *rec)) {
                st = pd_fail(PD_ERR_NOMEM, "out of memory for the contact pairs");
                break;
            }
            pair_rec *r = &rec[nrec++];
            r->row = (int64_t)o[0] - first;
            r->j = (int64_t)o[1];
            r->d = o[5];
            r->v = o[6];
        }
    }
    free(sorted);
    free(got);
    free(out);
    free(dest);
    free(M);
    free(pt);
    free(skip);
    for (int d = 0; d < 3; d++)
        free(py[d]);
    free(mv);
    /* the lists, and the remote partners */
    remote_free(cl);
    int64_t *remote = NULL, *send = NULL, nsend = 0, capsend = 0;
    if (st == PD_OK) {
        if (nrec > 0) /* (qsort of nothing: no array at all) */
            qsort(rec, (size_t)nrec, sizeof *rec, cmp_pair);
        remote = malloc((size_t)(nrec > 0 ? nrec : 1) * sizeof(int64_t));
        if (remote == NULL)
            st = pd_fail(PD_ERR_NOMEM, "out of memory for the contact pairs");
    }
    int64_t nr = 0;
    for (int64_t e = 0; st == PD_OK && e < nrec; e++) {
        const int64_t g = rec[e].j;
        if (!(g >= first && g < first + n))
            remote[nr++] = g;
        const int t = owner_of(pc, g);
        if (t != me && !in_piece(pc, t, first + rec[e].row)) { /* it needs ours */
            if (!pd_grow((void **)&send, &capsend, 2 * (nsend + 1), sizeof(int64_t))) {
                st = pd_fail(PD_ERR_NOMEM, "out of memory for the contact pairs");
                break;
            }
            send[2 * nsend] = t;
            send[2 * nsend + 1] = rec[e].row;
            nsend++;
        }
    }
    if (st == PD_OK) {
        qsort(remote, (size_t)nr, sizeof(int64_t), cmp_i64);
        int64_t u = 0;
        for (int64_t e = 0; e < nr; e++)
            if (u == 0 || remote[e] != remote[u - 1])
                remote[u++] = remote[e];
        nr = u;
        if (nsend > 0) /* by rank, then row */
            qsort(send, (size_t)nsend, 2 * sizeof(int64_t), cmp_i64_pair);
        int64_t v = 0;
        for (int64_t e = 0; e < nsend; e++)
            if (v == 0 || send[2 * e] != send[2 * v - 2] || send[2 * e + 1] != send[2 * v - 1]) {
                send[2 * v] = send[2 * e];
                send[2 * v + 1] = send[2 * e + 1];
                v++;
            }
        nsend = v;
        cl->nremote = nr;
        cl->scount = calloc((size_t)P, sizeof(int64_t));
        cl->rcount = calloc((size_t)P, sizeof(int64_t));
        cl->send_row = malloc((size_t)(nsend > 0 ? nsend : 1) * sizeof(int64_t));
        cl->sbuf = malloc((size_t)(3 * nsend > 0 ? 3 * nsend : 1) * sizeof(double));
        cl->rbuf = malloc((size_t)(3 * nr > 0 ? 3 * nr : 1) * sizeof(double));
        int room = 1; /* the remote partners past the piece's own rows */
        for (int d = 0; d < 3; d++) {
            double *ny = realloc(sim->y[d], (size_t)(n + nr > 0 ? n + nr : 1) * sizeof(double));
            room &= ny != NULL;
            if (ny)
                sim->y[d] = ny;
        }
        double *nv = realloc(pc->p->volume, (size_t)(n + nr > 0 ? n + nr : 1) * sizeof(double));
        if (nv)
            pc->p->volume = nv;
        if (!cl->scount || !cl->rcount || !cl->send_row || !cl->sbuf || !cl->rbuf || !room || !nv)
            st = pd_fail(PD_ERR_NOMEM, "out of memory for the contact pairs");
        for (int64_t e = 0; st == PD_OK && e < nsend; e++) {
            cl->send_row[e] = send[2 * e + 1];
            cl->scount[send[2 * e]] += 3;
        }
        for (int64_t e = 0; st == PD_OK && e < nr; e++)
            cl->rcount[owner_of(pc, remote[e])] += 3;
    }
    /* the lists of the piece's rows: its own particles' (the ghosts' empty) */
    memset(cl->offset, 0, (size_t)(n + 1) * sizeof(int64_t));
    if (st == PD_OK)
        st = list_room(cl, nrec);
    if (st == PD_OK) {
        for (int64_t e = 0; e < nrec; e++)
            cl->offset[rec[e].row + 1]++;
        for (int64_t i = 0; i < n; i++)
            cl->offset[i + 1] += cl->offset[i];
        for (int64_t e = 0; e < nrec; e++) {
            const int64_t g = rec[e].j;
            int64_t at = g - first;
            if (!(g >= first && g < first + n)) { /* its slot among the remote */
                int64_t a = 0, b = nr;
                while (a < b) {
                    const int64_t mid = (a + b) / 2;
                    if (remote[mid] < g)
                        a = mid + 1;
                    else
                        b = mid;
                }
                at = n + a;
                pc->p->volume[at] = rec[e].v;
            }
            cl->partner[e] = (int32_t)at;
            cl->d[e] = rec[e].d;
        }
        /* the rows each rank sends here are those it counted (both ends of
         * a pair see it alike): checked, for a list built wrong is silent */
        int64_t *rd = malloc((size_t)P * sizeof(int64_t));
        if (rd) {
            pd_comm_counts_to(cl->scount, rd);
            for (int r = 0; r < P && st == PD_OK; r++)
                if (rd[r] != cl->rcount[r])
                    st = pd_fail(PD_ERR_INVALID, "the contact pairs of ranks %d and %d disagree", r, me);
        } else
            st = pd_fail(PD_ERR_NOMEM, "out of memory for the contact pairs");
        free(rd);
    }
    if (st != PD_OK)
        memset(cl->offset, 0, (size_t)(n + 1) * sizeof(int64_t));
    cl->remote = pd_comm_or(st == PD_OK && (nr > 0 || nsend > 0));
    sim->contact_remote = nr > sim->contact_remote ? nr : sim->contact_remote;
    free(rec);
    free(remote);
    free(send);
    free(counts);
    return st;
}

/* The remote partners' positions, from their owners (every step). */
static void remote_positions(pd_sim *sim, contact_list *cl)
{
    if (!cl->remote)
        return;
    const double t0 = pd_wtime();
    int64_t k = 0;
    for (int r = 0; r < sim->piece->ranks; r++)
        for (int64_t e = 0; e < cl->scount[r] / 3; e++, k++)
            for (int d = 0; d < 3; d++)
                cl->sbuf[3 * k + d] = sim->y[d][cl->send_row[k]];
    pd_comm_alltoall(cl->sbuf, cl->scount, cl->rbuf, cl->rcount);
    for (int64_t e = 0; e < cl->nremote; e++)
        for (int d = 0; d < 3; d++)
            sim->y[d][sim->n + e] = cl->rbuf[3 * e + d];
    sim->timers[PD_T_RANKS] += pd_wtime() - t0;
}

/* Each row of the list in ascending partner, its d_ij beside it.  The
 * searches leave a row in the order of the cells around it (whose edge is
 * the reach, cutoff + skin), and the force and energy loops sum a row in
 * the list's order: in ascending partner the sums are the same whatever
 * the skin and whenever the list was built, so the skin changes no bit of
 * a run (pd-run(1), Contact).  A row holds a few pairs: insertion sort. */
static void list_order(contact_list *cl, int64_t n)
{
#pragma omp parallel for schedule(dynamic, 1024)
    for (int64_t i = 0; i < n; i++)
        for (int64_t q = cl->offset[i] + 1; q < cl->offset[i + 1]; q++) {
            const int32_t j = cl->partner[q];
            const double d = cl->d[q];
            int64_t a = q;
            for (; a > cl->offset[i] && cl->partner[a - 1] > j; a--) {
                cl->partner[a] = cl->partner[a - 1];
                cl->d[a] = cl->d[a - 1];
            }
            cl->partner[a] = j;
            cl->d[a] = d;
        }
}

static pd_status contact_build(pd_sim *sim, contact_list *cl)
{
    double t0 = pd_wtime();
    const double reach = cl->cutoff + cl->skin;
    pd_status s = sim->piece                                        ? build_piece(sim, cl, reach)
                  : pd_grid_contact(sim->grid) || sim->half.contact ? build_movers(sim, cl, reach)
                                                                    : build_all(sim, cl, reach);
    const int64_t n = sim->n;
    if (s == PD_OK && !sim->piece) /* a piece's rows are sorted so (build_piece) */
        list_order(cl, n);
    int64_t nrows = 0;
    for (int64_t i = 0; s == PD_OK && i < n; i++)
        nrows += cl->offset[i + 1] > cl->offset[i];
    if (s == PD_OK && nrows > cl->rows_cap) {
        int32_t *r = realloc(cl->rows, (size_t)nrows * sizeof(int32_t));
        if (r == NULL)
            s = pd_fail(PD_ERR_NOMEM, "out of memory for the contact list");
        else {
            cl->rows = r;
            cl->rows_cap = nrows;
        }
    }
    if (s != PD_OK) { /* no half-built list */
        memset(cl->offset, 0, (size_t)(n + 1) * sizeof(int64_t));
        cl->nrows = 0;
        return s;
    }
    cl->nrows = 0;
    for (int64_t i = 0; i < n; i++)
        if (cl->offset[i + 1] > cl->offset[i])
            cl->rows[cl->nrows++] = (int32_t)i;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            cl->ybuild[k][i] = sim->y[k][i];
    sim->contact_builds++;
    sim->timers[PD_T_NEIGHBOR] += pd_wtime() - t0;
    return PD_OK;
}

/* Has any of this rank's own particles moved more than skin/2 since the
 * last build (or is there none yet)?  (pd_effect.moved) */
static int own_moved(const pd_sim *sim, void *state)
{
    const contact_list *cl = state;
    if (sim->contact_builds == 0)
        return 1;
    double lim2 = 0.25 * cl->skin * cl->skin;
    int moved = 0;
    const int64_t lo = sim->piece ? sim->piece->own_lo : 0, hi = sim->piece ? sim->piece->own_hi : sim->n;
#pragma omp parallel for schedule(static) reduction(| : moved)
    for (int64_t i = lo; i < hi; i++) {
        double dx = sim->y[0][i] - cl->ybuild[0][i], dy = sim->y[1][i] - cl->ybuild[1][i],
               dz = sim->y[2][i] - cl->ybuild[2][i];
        double d2 = dx * dx + dy * dy + dz * dz;
        moved |= !(d2 <= lim2);
    }
    return moved;
}

/* Has any particle moved more than skin/2 since the last build?  A piece:
 * its own, then those of every rank (asked with the step's lost particles
 * when the step asked: sim->moved). */
static int needs_rebuild(const pd_sim *sim, contact_list *cl)
{
    if (sim->moved)
        return sim->moved - 1;
    if (sim->contact_builds == 0)
        return 1;
    int moved = own_moved(sim, cl);
    if (sim->piece) {
        const double t0 = pd_wtime();
        moved = pd_comm_or(moved);
        ((pd_sim *)sim)->timers[PD_T_RANKS] += pd_wtime() - t0; /* a clock */
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
    if (sim->piece) /* the remote partners where they are now */
        remote_positions(sim, cl);
    if (cl->offset[sim->n] == 0) /* no pair (the stencil has them all) */
        return PD_OK;
    const double k = PD_CONTACT_SCALE * sim->sc.c / sim->b->horizon;
    const double *V = sim->p->volume;
    double *const *y = sim->y;
    double *restrict fx = sim->f[0], *restrict fy = sim->f[1], *restrict fz = sim->f[2];
#pragma omp parallel for schedule(static)
    for (int64_t w = 0; w < cl->nrows; w++) { /* the particles with candidates */
        const int64_t i = cl->rows[w];
        const double yi0 = y[0][i], yi1 = y[1][i], yi2 = y[2][i];
        double ax = 0, ay = 0, az = 0;
        int acts = 0;
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
                acts = 1;
            }
        }
        if (acts) { /* a row with no pair in reach adds nothing, not +0 (list_order) */
            fx[i] += ax;
            fy[i] += ay;
            fz[i] += az;
        }
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
    /* the build's positions in the run's own arrays (a piece's build may
     * make room in them), the run's back after it */
    const size_t bytes = (size_t)sim->n * sizeof(double);
    double *now = malloc(3 * (bytes > 0 ? bytes : 1));
    if (now == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the contact list");
    for (int d = 0; d < 3; d++) {
        memcpy(now + d * sim->n, sim->y[d], bytes);
        memcpy(sim->y[d], r->contact_position[d], bytes);
    }
    pd_status s = contact_build(sim, cl);
    for (int d = 0; d < 3; d++)
        memcpy(sim->y[d], now + d * sim->n, bytes);
    free(now);
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
    for (int64_t w = 0; w < cl->nrows; w++) { /* the particles with candidates */
        const int64_t i = cl->rows[w];
        double sum = 0;
        int acts = 0;
        for (int64_t q = cl->offset[i]; q < cl->offset[i + 1]; q++) {
            const int32_t j = cl->partner[q];
            const double dx = y[0][j] - y[0][i], dy = y[1][j] - y[1][i], dz = y[2][j] - y[2][i];
            const double r = sqrt(dx * dx + dy * dy + dz * dz), d = cl->d[q];
            if (r < d) {
                sum += 0.25 * k * (d - r) * (d - r) * V[j];
                acts = 1;
            }
        }
        if (acts)
            e[i] += sum * V[i];
    }
}

const pd_effect pd_effect_contact = {
    .name = "contact", .timer = PD_T_CONTACT, .init = contact_init, .force = contact_force,
    .free = contact_free, .energy = contact_energy, .kind = PD_ENERGY_CONTACT,
    .declared = contact_declared, .save = contact_save, .restore = contact_restore,
    .moved = own_moved};

int64_t pd_sim_contact_builds(const pd_sim *sim)
{
    return sim->contact_builds;
}

int64_t pd_sim_contact_remote(const pd_sim *sim)
{
    return sim->contact_remote;
}
