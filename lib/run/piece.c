/*
 * piece.c -- a run spread over MPI ranks: each rank steps a piece of the
 * body (pd.h, pd_sim_piece), the same bits as one rank.
 *
 *   - Blocks.  A body's bond kernel cuts it into blocks of rows (the
 *     stencil's slabs of outer planes, lib/stencil/grid.c; the bond list's
 *     runs of rows, lib/bonds/half.c): a block's bonds write only to the
 *     block and the next, even blocks run before odd ones, and every sum
 *     is taken in an order the blocks fix.  The ranks own whole blocks, in
 *     order, about as many rows each, at least one block each.
 *   - Ghosts.  A piece is its own blocks, the block above them (whose
 *     particles are partners of its last block's bonds) and the one below.
 *     Its phases are the whole body's (a block's parity is its whole-body
 *     index's).  It walks again the bonds of the block below its own that
 *     reach its own particles (the stencil's with a partner of its own,
 *     the bond list's from the block's first row with one) rather than
 *     receiving the forces they put on them: each of its own particles then gets
 *     every bond's force, in the whole body's order, and so the same
 *     bits.  Both walks of a bond see the same positions and s0 and break
 *     it alike.  The ghosts' own forces lack bonds, and their bonds with
 *     each other are not walked (their states here are stale; only its
 *     own rows' are read or written); the ghosts are set to rest after
 *     the forces, and their positions and s0 come from their owners
 *     before the next ones.
 *   - Sums over the body (energies, the indenter's force, the energy of
 *     broken bonds and of lost particles) are taken in the whole body's
 *     order: pd_comm_sum_fixed, pd_sim_add_released, in rank order.
 *   - Files.  Every rank writes its own rows of each frame and restart
 *     slot into the one run file, at once (parallel HDF5, lib/io), with
 *     the sums over the body every rank holds; the series and status
 *     lines take their figures over the ranks in the same order
 *     (pd_sim_part, pd_sim_broken, pd_sim_lost, pd_sim_damage_stats).
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/comm.h"
#include "effects/effect.h"
#include "models/model.h"
#include "stencil/grid.h"

/* Rows [g0, g0 + n) of p into rows [0, n) of q (q may be p). */
static void move_rows(pd_particles *q, const pd_particles *p, int64_t g0, int64_t n)
{
    for (int d = 0; d < 3; d++)
        memmove(q->x[d], p->x[d] + g0, (size_t)n * sizeof(double));
    memmove(q->volume, p->volume + g0, (size_t)n * sizeof(double));
    memmove(q->density, p->density + g0, (size_t)n * sizeof(double));
    memmove(q->radius, p->radius + g0, (size_t)n * sizeof(double));
    memmove(q->material, p->material + g0, (size_t)n * sizeof(int32_t));
    memmove(q->id, p->id + g0, (size_t)n * sizeof(int64_t));
}

/* The whole body's rows [g0, g1) as particles of their own. */
static pd_particles *slice_particles(const pd_particles *p, int64_t g0, int64_t g1)
{
    const int64_t n = g1 - g0;
    pd_particles *q = pd_particles_new(n);
    if (q == NULL)
        return NULL;
    move_rows(q, p, g0, n);
    q->spacing = p->spacing;
    q->dimension = p->dimension;
    q->thickness = p->thickness;
    return q;
}

/* The bonds of rows [g0, g1) between rows of the range, as lists in the
 * whole body's family order, with the states `intact` gives them.  The
 * families of rows whose partners are all in the range are whole. */
static pd_status slice_bonds(const pd_particles *p, const pd_bonds *b, const uint64_t *intact,
                             int64_t g0, int64_t g1, pd_bonds **out)
{
    const int64_t n = g1 - g0;
    int64_t count = 0;
    for (int64_t i = g0; i < g1; i++) {
        pd_bond_iter it;
        for (pd_family_start_partners(b, p, i, &it); pd_family_next(&it);)
            count += it.j >= g0 && it.j < g1;
    }
    pd_bonds *q = pd_bonds_alloc(n, count);
    if (q == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the bonds of a piece of the body");
    q->horizon = b->horizon;
    int64_t k = 0;
    for (int64_t i = g0; i < g1; i++) {
        pd_bond_iter it;
        for (pd_family_start(b, p, i, &it); pd_family_next(&it);) {
            if (it.j < g0 || it.j >= g1)
                continue;
            q->neighbor[k] = (int32_t)(it.j - g0);
            q->length[k] = it.length;
            q->vfactor[k] = it.vfactor;
            if (pd_bond_intact(intact, it.q))
                q->intact[k >> 6] |= UINT64_C(1) << (k & 63);
            k++;
        }
        q->offset[i - g0 + 1] = k;
    }
    *out = q;
    return PD_OK;
}

/* The window p, b of a body (pd_read_body_ranks) cut in place to its rows
 * [g0, g1), as slice_particles and slice_bonds would copy them (the
 * pre-crack bits kept too), with the states `intact` gives its bonds
 * (intact may be b->intact): a piece that takes the window over holds no
 * second copy of its bonds.  *keep gets a bit for each of b's bonds, set
 * when kept. */
static pd_status cut_window(pd_particles *p, pd_bonds *b, const uint64_t *intact, int64_t g0,
                            int64_t g1, uint64_t **keep)
{
    const int64_t m = g1 - g0;
    *keep = calloc((size_t)pd_bits_words(b->count) + 1, sizeof(uint64_t));
    if (*keep == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for a piece of the body");
    move_rows(p, p, g0, m);
    p->n = p->total = p->own_hi = m;
    p->first = p->own_lo = 0;
    p->window = 0;
    /* bond k' <= k goes where bond k was: each bit read before it is written */
    int64_t k = 0, lo = b->offset[g0];
    for (int64_t i = g0; i < g1; i++) {
        const int64_t hi = b->offset[i + 1];
        for (int64_t q = lo; q < hi; q++) {
            const int64_t j = b->neighbor[q];
            if (j < g0 || j >= g1)
                continue;
            (*keep)[q >> 6] |= UINT64_C(1) << (q & 63);
            b->neighbor[k] = (int32_t)(j - g0);
            b->length[k] = b->length[q];
            b->vfactor[k] = b->vfactor[q];
            const uint64_t bit = UINT64_C(1) << (k & 63);
            b->intact[k >> 6] = pd_bond_intact(intact, q) ? b->intact[k >> 6] | bit
                                                          : b->intact[k >> 6] & ~bit;
            if (b->precrack)
                b->precrack[k >> 6] = pd_bond_intact(b->precrack, q)
                                          ? b->precrack[k >> 6] | bit
                                          : b->precrack[k >> 6] & ~bit;
            k++;
        }
        b->offset[i - g0 + 1] = k;
        lo = hi;
    }
    b->offset[0] = 0;
    const int64_t words = pd_bits_words(k) + 1;
    for (int64_t w = pd_bits_words(k); w < words; w++) /* past the last bond: clear */
        b->intact[w] = b->precrack ? (b->precrack[w] = 0) : 0;
    if (k & 63) {
        const uint64_t mask = (UINT64_C(1) << (k & 63)) - 1;
        b->intact[(k - 1) >> 6] &= mask;
        if (b->precrack)
            b->precrack[(k - 1) >> 6] &= mask;
    }
    b->n = m;
    b->count = k;
    /* the arrays shrunk to the piece (a failed shrink keeps them) */
    const size_t c = (size_t)(k > 0 ? k : 1);
    void *q;
    if ((q = realloc(b->neighbor, c * sizeof(int32_t))))
        b->neighbor = q;
    if ((q = realloc(b->length, c * sizeof(double))))
        b->length = q;
    if ((q = realloc(b->vfactor, c * sizeof(double))))
        b->vfactor = q;
    if ((q = realloc(b->intact, (size_t)words * sizeof(uint64_t))))
        b->intact = q;
    if (b->precrack && (q = realloc(b->precrack, (size_t)words * sizeof(uint64_t))))
        b->precrack = q;
    if ((q = realloc(b->offset, (size_t)(m + 1) * sizeof(int64_t))))
        b->offset = q;
    return PD_OK;
}

/* A lattice body's piece keeps its families compact, as the whole body
 * does (no per-bond arrays; pd_bonds_compact on the piece's particles q,
 * rows [g0, g0 + q->n) of p): each family the stencil's partners within
 * the piece, which must be the whole family's in its order, with the
 * states `intact` gives them (and b's pre-crack bits).  *out
 * NULL when they are not (the piece's lattice walked in another order):
 * the caller then takes the lists. */
static pd_status slice_compact(const pd_particles *p, const pd_bonds *b, const uint64_t *intact,
                               const pd_particles *q, int64_t g0, pd_bonds **out)
{
    *out = NULL;
    pd_bonds *c = NULL;
    pd_status s = pd_bonds_compact(q, b->stencil, b->horizon, &c);
    if (s != PD_OK || pd_bonds_has_lists(c)) {
        pd_bonds_free(c);
        return s == PD_ERR_NOMEM ? s : PD_OK;
    }
    memset(c->intact, 0, (size_t)pd_bits_words(c->count) * sizeof(uint64_t));
    if (b->precrack &&
        (c->precrack = calloc((size_t)pd_bits_words(c->count) + 1, sizeof(uint64_t))) == NULL) {
        pd_bonds_free(c);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the pre-crack of a piece");
    }
    int same = 1;
    for (int64_t i = 0; i < q->n && same; i++) {
        pd_bond_iter it, jt;
        pd_family_start_partners(c, q, i, &jt);
        for (pd_family_start_partners(b, p, g0 + i, &it); pd_family_next(&it) && same;) {
            if (it.j < g0 || it.j >= g0 + q->n)
                continue;
            same = pd_family_next(&jt) && jt.j == it.j - g0;
            if (same && pd_bond_intact(intact, it.q))
                c->intact[jt.q >> 6] |= UINT64_C(1) << (jt.q & 63);
            if (same && c->precrack && pd_bond_intact(b->precrack, it.q))
                c->precrack[jt.q >> 6] |= UINT64_C(1) << (jt.q & 63);
        }
        same = same && !pd_family_next(&jt);
    }
    if (same)
        *out = c;
    else
        pd_bonds_free(c);
    return PD_OK;
}

/* The first block of rank r's piece: the block below its own (rank 0:
 * block 0). */
static int64_t piece_first_block(const int64_t *K, int r)
{
    return r == 0 ? 0 : K[r] - 1;
}

/* The share of a block whose bonds a rank above the first walks again,
 * below its own: of the stencil's, those of the block below with a
 * partner of its own (a plane p of a block of T reaches the next with the
 * offsets whose outer component is at least T - p: mean |d_outer| / T of
 * the bonds, 0.38 at delta = 3 h); of the bond list's, the block below
 * from its first row with such a partner on (about the rows a bond spans,
 * one block). */
#define PIECE_DUP_GRID 0.4
#define PIECE_DUP_LIST 1.0

/* The P ranks' blocks of a body of n rows in nb blocks (block k's first
 * row start[k], start[nb] = n): rank r owns blocks [K[r], K[r + 1]), one
 * at least each, about as many rows walked each, a rank above the first
 * walking dup_blocks of a block below its own again (dup rows): rank 0
 * owns W rows, the others W - dup, W = (n + (P - 1) dup) / P. */
static pd_status cut_ranks(int64_t n, int64_t nb, const int64_t *start, int P, double dup_blocks,
                           int64_t *K)
{
    if (nb < (int64_t)P)
        return pd_fail(PD_ERR_INVALID,
                       "the body is cut into %lld block%s and each of the %d MPI ranks needs one: "
                       "run it on at most %lld rank%s",
                       (long long)nb, nb == 1 ? "" : "s", P, (long long)nb, nb == 1 ? "" : "s");
    K[0] = 0;
    K[P] = nb;
    const double dup = dup_blocks * (double)n / (double)(nb > 0 ? nb : 1);
    const double W = ((double)n + (P - 1) * dup) / P;
    for (int r = 1; r < P; r++) {
        int64_t k = K[r - 1] + 1;
        while (k < nb - (P - r) && (double)start[k] < r * W - (r - 1) * dup)
            k++;
        K[r] = k;
    }
    return PD_OK;
}

int pd_piece_reads_rows(const pd_particles *p, const pd_scene *sc)
{
    const pd_model *model = pd_model_of(sc->model);
    return pd_comm_size() > 1 && model && !pd_grid_possible(p, sc, model->stencil(sc));
}

/* This rank's rows of a body of n rows in nb blocks (block k's first row
 * start[k], start[nb] = n), cut as cut_ranks cuts it: rows[0..1] its
 * piece's, rows[2..3] its own, rows[4..5] the piece and a block more on
 * each side; dup_blocks as cut_ranks takes it. */
static pd_status piece_rows_at(int64_t n, int64_t nb, const int64_t *start, double dup_blocks,
                               int64_t rows[6])
{
    const int P = pd_comm_size(), me = pd_comm_rank();
    int64_t *K = malloc((size_t)(P + 1) * sizeof(int64_t));
    pd_status s = K ? cut_ranks(n, nb, start, P, dup_blocks, K)
                    : pd_fail(PD_ERR_NOMEM, "out of memory for the pieces");
    if (s == PD_OK) {
        const int64_t L = piece_first_block(K, me), U = K[me + 1] + 1 < nb ? K[me + 1] + 1 : nb;
        rows[0] = start[L];
        rows[1] = start[U];
        rows[2] = start[K[me]];
        rows[3] = start[K[me + 1]];
        rows[4] = start[L > 0 ? L - 1 : 0];
        rows[5] = start[U + 1 < nb ? U + 1 : nb];
    }
    free(K);
    return s;
}

pd_status pd_piece_rows(int64_t n, int64_t span, int64_t *g0, int64_t *g1, int64_t *o0,
                        int64_t *o1)
{
    int64_t nb = 0, rows[6];
    const int64_t block = pd_half_block_of(n, span, &nb);
    int64_t *start = malloc((size_t)(nb + 1) * sizeof(int64_t));
    pd_status s = start ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory for the pieces");
    for (int64_t k = 0; s == PD_OK && k <= nb; k++)
        start[k] = k * block < n ? k * block : n;
    if (s == PD_OK)
        s = piece_rows_at(n, nb, start, PIECE_DUP_LIST, rows);
    if (s == PD_OK) {
        *g0 = rows[0];
        *g1 = rows[1];
        *o0 = rows[2];
        *o1 = rows[3];
    }
    free(start);
    return s;
}

int pd_piece_lattice_rows(const pd_particles *share, const pd_stencil *st, int64_t rows[6])
{
    int32_t *lc[3];
    for (int a = 0; a < 3; a++)
        lc[a] = malloc((size_t)(share->n > 0 ? share->n : 1) * sizeof(int32_t));
    int axis[3], ok = pd_comm_min(lc[0] && lc[1] && lc[2]) == 1;
    if (ok) /* the whole body's lattice, over the ranks' shares (collective) */
        ok = pd_comm_min(pd_lattice_coords(share, axis, lc)) == 1;
    /* blocks of outer planes as thick as the table reaches along them */
    int thick = 1;
    for (int k = 0; ok && k < st->nk; k++)
        thick = abs(st->d[k][axis[2]]) > thick ? abs(st->d[k][axis[2]]) : thick;
    int64_t lo = INT32_MAX, hi = INT32_MAX, nb = 0;
    for (int64_t i = 0; ok && i < share->n; i++) {
        lo = lc[2][i] < lo ? lc[2][i] : lo;
        hi = -lc[2][i] < hi ? -lc[2][i] : hi;
    }
    if (ok) {
        lo = pd_comm_min(lo);
        hi = -pd_comm_min(hi);
        nb = (hi - lo + thick) / thick;
    }
    int64_t *start = ok ? malloc(((size_t)nb + 1) * sizeof(int64_t)) : NULL;
    if (ok)
        ok = pd_comm_min(start != NULL) == 1;
    if (ok) { /* each block's first row, were the rows in lattice order */
        pd_lattice_block_starts(lc[2], 0, share->n, lo, thick, nb, start);
        ok = pd_comm_min(piece_rows_at(pd_body_count(share), nb, start, PIECE_DUP_GRID, rows) ==
                         PD_OK) == 1;
    }
    free(start);
    for (int a = 0; a < 3; a++)
        free(lc[a]);
    return ok;
}

int pd_piece_lattice_fits(const pd_particles *p, const pd_bonds *b, const pd_scene *sc)
{
    const pd_model *model = pd_model_of(sc->model);
    pd_grid *plan = NULL;
    int ok = model && pd_grid_plan_window(p, b, sc, model->stencil(sc), &plan) == PD_OK && plan;
    ok = pd_comm_min(ok) == 1; /* pd_grid_plan_window: NULL on every rank, or none */
    const int64_t nb = ok ? pd_grid_blocks(plan, NULL, NULL, NULL) : 0;
    int64_t *start = malloc((size_t)(nb + 1) * sizeof(int64_t)), rows[6];
    ok = pd_comm_min(ok && start) == 1;
    if (ok) { /* the plan cuts the body as p was cut */
        pd_grid_blocks(plan, start, NULL, NULL);
        ok = piece_rows_at(pd_body_count(p), nb, start, PIECE_DUP_GRID, rows) == PD_OK &&
             rows[2] == p->first + p->own_lo && rows[3] == p->first + p->own_hi &&
             rows[4] == p->first && rows[5] == p->first + p->n;
        ok = pd_comm_min(ok) == 1;
    }
    free(start);
    pd_grid_free(plan);
    return ok;
}

/* The piece's bond history (VES, EPS) from the whole body's hw, w values
 * for each directed bond of b in its families' order: NULL out of memory,
 * or (*bad) when a piece's family is not the whole one's less the partners
 * beyond the piece, in order. */
static double *slice_history(const pd_particles *p, const pd_bonds *b, const double *hw, int w,
                             const pd_piece *pc, int *bad)
{
    const pd_bonds *q = pc->b;
    const int64_t g = pc->first - p->first; /* the piece's first row in p */
    double *h = malloc((size_t)(q->count > 0 ? q->count : 1) * (size_t)w * sizeof(double));
    *bad = 0;
    for (int64_t i = 0; h && i < pc->p->n && !*bad; i++) {
        pd_bond_iter it, jt;
        pd_family_start_partners(b, p, g + i, &it);
        for (pd_family_start_partners(q, pc->p, i, &jt); pd_family_next(&jt) && !*bad;) {
            int found = 0;
            while (!found && pd_family_next(&it))
                found = it.j == jt.j + g;
            if (found)
                memcpy(h + jt.q * w, hw + it.q * w, (size_t)w * sizeof(double));
            *bad = !found;
        }
    }
    return h;
}

/* The bond history of a piece cut from a window (cut_window) from the
 * window's, hw (w values a bond): its kept bonds', in order.  NULL: out of
 * memory. */
static double *kept_history(const pd_piece *pc, const double *hw, int w)
{
    double *h = malloc((size_t)(pc->b->count > 0 ? pc->b->count : 1) * (size_t)w * sizeof(double));
    for (int64_t q = 0, k = 0; h && q < pc->keep_count; q++)
        if (pd_bond_intact(pc->keep, q)) /* a set bit: kept */
            memcpy(h + (k++) * w, hw + q * w, (size_t)w * sizeof(double));
    return h;
}

/* The piece goes on from the restart data r of the body p (of its rows,
 * and its bonds' history), at `step`, with velocities v; its bond states
 * are its bonds' (sliced from the restart's).  Collective (the contact
 * list's build). */
static pd_status piece_restore(const pd_particles *p, const pd_bonds *b, pd_sim *sim,
                               int64_t step, const pd_restart *r, int64_t r_first,
                               double *const v[3])
{
    const pd_piece *pc = sim->piece;
    const int64_t g = pc->first - r_first; /* the piece's first row in r, v */
    pd_restart mine = *r;
    double *vel[3];
    for (int d = 0; d < 3; d++) {
        mine.position[d] = r->position[d] + g;
        mine.force[d] = r->force[d] + g;
        mine.contact_position[d] = r->contact_position[d] ? r->contact_position[d] + g : NULL;
        vel[d] = v[d] + g;
    }
    mine.s0 = r->s0 ? r->s0 + g : NULL;
    mine.lost = r->lost ? r->lost + g : NULL;
    mine.bond_history = NULL;
    mine.history_bonds = 0;
    int bad = 0;
    /* the bonds read (a window taken over: kept, or none of a lattice's) */
    const int64_t count = pc->keep ? pc->keep_count : b ? b->count : 0;
    const int history = r->bond_history != NULL && (pc->keep || b) && r->history_bonds == count;
    if (history) {
        mine.bond_history = pc->keep ? kept_history(pc, r->bond_history, r->history_width)
                                     : slice_history(p, b, r->bond_history, r->history_width,
                                                     pc, &bad);
        mine.history_bonds = pc->b->count;
    }
    pd_status s = PD_OK;
    if (r->bond_history && !history)
        s = pd_fail(PD_ERR_FORMAT, "the restart data have a bond history of %lld directed "
                                   "bonds, the body %lld",
                    (long long)r->history_bonds, (long long)count);
    else if (history && mine.bond_history == NULL)
        s = pd_fail(PD_ERR_NOMEM, "out of memory for the bond history of a piece");
    else if (bad)
        s = pd_fail(PD_ERR_INVALID, "a piece's families are not the whole body's");
    s = pd_comm_agree(s); /* the contact list's build below is collective */
    if (s == PD_OK)
        s = pd_sim_restore(sim, step, &mine, vel, pc->b->intact);
    free(mine.bond_history);
    return s;
}

/* The AVX-512 rows' contact gap of the body p, b over this rank's own rows
 * [lo, hi) of p and the other ranks' (pd_half_gap_rows; collective), after
 * st, this rank's state. */
static pd_status window_gap(const pd_particles *p, const pd_bonds *b, int64_t lo, int64_t hi,
                            pd_status st, double *gap)
{
    pd_half_bonds h;
    memset(&h, 0, sizeof h);
    st = pd_comm_agree(st == PD_OK ? pd_half_build(b, &h) : st);
    if (st == PD_OK)
        st = pd_half_gap_rows(&h, b, p, lo, hi, 1, gap);
    pd_half_free(&h);
    return st;
}

/* This rank's piece of the body p, b (bond states `intact`) under the
 * scene sc, at rest at step 0, with the whole body's figures.  p may be a
 * window of the body (pd_read_body_ranks): then it holds the piece's rows,
 * b their bonds, and the body is walked as a bond list. */
static pd_status piece_cut(const pd_particles *p, const pd_bonds *b, pd_particles **tp,
                           pd_bonds **tb, const pd_scene *sc, const uint64_t *intact,
                           pd_sim **out)
{
    *out = NULL;
    const int P = pd_comm_size(), me = pd_comm_rank();
    const pd_model *model = pd_model_of(sc->model);
    if (model == NULL)
        return pd_fail(PD_ERR_INVALID, "unknown model %d", (int)sc->model);
    /* how the whole body's kernel cuts it, as pd_sim_new would (the
     * lattice stencil's blocks, else the bond list's), without its run:
     * the first row of each block, and the end */
    pd_grid *plan = NULL;
    const int compact = !pd_bonds_has_lists(b) && b->stencil; /* a window: of a lattice */
    pd_status st = !p->window ? pd_grid_plan(p, b, sc, model->stencil(sc), &plan)
                   : compact  ? pd_grid_plan_window(p, b, sc, model->stencil(sc), &plan)
                              : PD_OK;
    if (st == PD_OK && p->window && compact && plan == NULL) /* pd_read_body_ranks found it */
        st = pd_fail(PD_ERR_INVALID, "the windows of a lattice body find no stencil");
    if (st != PD_OK)
        return st;
    const int grid = plan != NULL;
    int64_t nb = 0, block = 0;
    if (grid)
        nb = pd_grid_blocks(plan, NULL, NULL, NULL);
    else /* b may hold the families of this rank's rows alone (pd_read_bonds_rows):
            the largest span over the ranks (collective) */
        block = pd_half_block_of(pd_body_count(p), -pd_comm_min(-pd_half_span(b)), &nb);
    if (grid && nb == 0) {
        pd_grid_free(plan);
        return pd_fail(PD_ERR_INVALID, "on MPI ranks the particles must be in lattice order, as "
                                       "pd-bonds writes them");
    }
    pd_piece *pc = calloc(1, sizeof *pc);
    int64_t *start = malloc((size_t)(nb + 1) * sizeof(int64_t));
    int64_t *K = malloc((size_t)(P + 1) * sizeof(int64_t));
    if (pc) {
        pc->rows = malloc((size_t)P * sizeof(int64_t));
        pc->blocks = malloc((size_t)P * sizeof(int64_t));
        pc->own_at = malloc((size_t)(P + 1) * sizeof(int64_t));
        pc->piece_at = malloc((size_t)P * 2 * sizeof(int64_t));
    }
    if (!pc || !start || !K || !pc->rows || !pc->blocks || !pc->own_at || !pc->piece_at) {
        free(start);
        free(K);
        pd_piece_free(pc);
        pd_grid_free(plan);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the pieces of the body");
    }
    const int64_t n = pd_body_count(p), w0 = p->first; /* p's rows: [w0, w0 + p->n) */
    /* the whole body's figures, before a window taken over is cut: the box
     * outside which a particle is lost, and the contact cap of the AVX-512
     * rows (collective for a window) */
    double box_lo[3], box_hi[3];
    pd_lost_box(p, sc->lost_margin, box_lo, box_hi);
    const double cap = pd_half_contact_cap(p);
    double gap = 0;
    if (grid) {
        int thick;
        pd_grid_blocks(plan, start, pc->axis, &thick);
        pc->table = plan;
        double hi[3];
        pd_body_bounds(p, pc->origin, hi); /* a window: over the ranks (collective) */
    } else {
        pc->half_block = block;
        for (int64_t k = 0; k <= nb; k++)
            start[k] = k * pc->half_block < n ? k * pc->half_block : n;
    }
    st = cut_ranks(n, nb, start, P, grid ? PIECE_DUP_GRID : PIECE_DUP_LIST, K);
    if (st == PD_OK) {
        for (int r = 0; r < P; r++) {
            pc->rows[r] = start[K[r + 1]] - start[K[r]];
            pc->blocks[r] = K[r + 1] - K[r];
            pc->own_at[r] = start[K[r]];
            pc->piece_at[2 * r] = start[piece_first_block(K, r)];
            pc->piece_at[2 * r + 1] = start[K[r + 1] + 1 < nb ? K[r + 1] + 1 : nb];
        }
        pc->own_at[P] = n;
        const int64_t L = piece_first_block(K, me), U = K[me + 1] + 1 < nb ? K[me + 1] + 1 : nb;
        pc->rank = me;
        pc->ranks = P;
        pc->n_whole = n;
        pc->grid = grid;
        pc->first = start[L];
        pc->blk0 = L;
        pc->own_lo = start[K[me]] - start[L];
        pc->own_hi = start[K[me + 1]] - start[L];
        pc->own_blk_lo = K[me] - L;
        pc->own_blk_hi = K[me + 1] - L;
        pc->send_down = me > 0 ? start[K[me] + 1] - start[K[me]] : 0;
        pc->send_up = me < P - 1 ? start[K[me + 1]] - start[piece_first_block(K, me + 1)] : 0;
        const int64_t g1 = start[U], rows = g1 - pc->first;
        const int64_t halo = rows - (pc->own_hi - pc->own_lo) + pc->send_down + pc->send_up;
        pc->buf = malloc((size_t)(halo > 0 ? halo : 1) * 4 * sizeof(double));
        pc->sum3 = malloc((size_t)(rows > 0 ? rows : 1) * 3 * sizeof(double));
        if (pc->first < w0 || g1 > w0 + p->n ||
            (p->window && (w0 + p->own_lo != start[K[me]] || w0 + p->own_hi != start[K[me + 1]])))
            st = pd_fail(PD_ERR_INVALID, "a piece of the body is not cut as it was read");
        else if (!pc->buf || !pc->sum3)
            st = pd_fail(PD_ERR_NOMEM, "out of memory for a piece of the body");
        /* the AVX-512 rows' contact gap over the ranks' own rows, before a
         * window taken over is cut (collective) */
        if (tp && sc->has_contact)
            st = window_gap(p, b, pc->first + pc->own_lo - w0, pc->first + pc->own_hi - w0, st,
                            &gap);
        const int cut = tp && pd_bonds_has_lists(b); /* a window of lists: cut in place */
        if (st == PD_OK && cut) { /* the window becomes the piece */
            pc->keep_count = b->count; /* the window's bonds, before the cut */
            st = cut_window(*tp, *tb, intact, pc->first - w0, g1 - w0, &pc->keep);
            if (st == PD_OK) {
                pc->p = *tp;
                pc->b = *tb;
                *tp = NULL;
                *tb = NULL;
            }
        } else if (st == PD_OK && (pc->p = slice_particles(p, pc->first - w0, g1 - w0)) == NULL)
            st = pd_fail(PD_ERR_NOMEM, "out of memory for a piece of the body");
        /* the stencil walks a lattice body's compact families: the piece's
         * stay compact too; else its lists */
        if (st == PD_OK && grid && !pd_bonds_has_lists(b) && b->stencil)
            st = slice_compact(p, b, intact, pc->p, pc->first - w0, &pc->b);
        if (st == PD_OK && pc->b == NULL)
            st = slice_bonds(p, b, intact, pc->first - w0, g1 - w0, &pc->b);
        if (st == PD_OK && tp && !cut) { /* a lattice's window, sliced: it goes before the
                                            piece's run is built */
            pd_particles_free(*tp);
            pd_bonds_free(*tb);
            *tp = NULL;
            *tb = NULL;
            p = NULL;
            b = NULL;
        }
    }
    free(start);
    free(K);
    pd_sim *sim = NULL; /* its sets: their members in the piece */
    if (st == PD_OK)
        st = pd_sim_new_cut(pc->p, pc->b, sc, pc, &sim);
    if (st == PD_OK && grid && pd_grid_blocks(sim->grid, NULL, NULL, NULL) < pc->own_blk_hi)
        st = pd_fail(PD_ERR_INVALID, "a piece of the body is not cut as the whole body is");
    pc->table = NULL; /* the piece's stencil has its lengths and volumes */
    pd_grid_free(plan);
    st = pd_comm_agree(st); /* the whole body's figures below are collective */
    if (st != PD_OK) {
        pd_sim_free(sim);
        pd_piece_free(pc);
        return st;
    }
    sim->piece_owned = 1;
    /* its blocks' energies of broken bonds, kept for some steps */
    const int64_t own = pc->blocks[pc->rank] > 0 ? pc->blocks[pc->rank] : 1;
    if ((sim->rel_held = malloc((size_t)(PD_RELEASED_STEPS * own) * sizeof(double))) == NULL)
        st = pd_fail(PD_ERR_NOMEM, "out of memory for a piece of the body");
    /* the whole body's figures: the box outside which a particle is lost,
     * and the AVX-512 rows' contact gap and cap */
    memcpy(sim->box_lo, box_lo, sizeof box_lo);
    memcpy(sim->box_hi, box_hi, sizeof box_hi);
    if (sim->half.contact) { /* over the ranks' own rows (collective) */
        int64_t lo, hi;
        pd_sim_owned(sim, &lo, &hi);
        if (tp) /* found before the window was cut */
            sim->half.gap = gap;
        else
            st = window_gap(p, b, lo - w0, hi - w0, st, &sim->half.gap);
        sim->half.contact_cap = cap;
    }
    if (st != PD_OK) {
        pd_sim_free(sim);
        return st;
    }
    *out = sim;
    return PD_OK;
}

pd_status pd_sim_piece_new(const pd_particles *p, const pd_bonds *b, const pd_scene *sc,
                           const uint64_t *intact, pd_sim **out)
{
    pd_sim *sim = NULL;
    pd_status s = pd_comm_agree(piece_cut(p, b, NULL, NULL, sc, intact ? intact : b->intact, &sim));
    if (s != PD_OK)
        return s;
    pd_piece_ghosts_rest(sim);
    *out = sim;
    return PD_OK;
}

pd_status pd_sim_piece_take(pd_particles **p, pd_bonds **b, const pd_scene *sc,
                            const uint64_t *intact, pd_sim **out)
{
    pd_sim *sim = NULL;
    if (!(*p)->window)
        return pd_comm_agree(pd_fail(PD_ERR_INVALID, "a piece takes over a window of the body"));
    pd_status s = pd_comm_agree(piece_cut(*p, *b, p, b, sc, intact ? intact : (*b)->intact, &sim));
    if (s != PD_OK)
        return s;
    pd_piece_ghosts_rest(sim);
    *out = sim;
    return PD_OK;
}

void pd_sim_piece_rows(const pd_sim *sim, int64_t *g0, int64_t *g1)
{
    const pd_piece *pc = sim->piece;
    *g0 = pc ? pc->first : 0;
    *g1 = pc ? pc->first + pc->p->n : sim->n;
}

pd_status pd_sim_piece_restore(pd_sim *sim, const pd_particles *p, const pd_bonds *b,
                               int64_t step, const pd_restart *r, int64_t r_first,
                               double *const v[3])
{
    pd_status s = piece_restore(p, b, sim, step, r, r_first, v);
    if (s == PD_OK)
        pd_piece_ghosts_rest(sim);
    return s;
}

int64_t pd_sim_halo_bytes(const pd_sim *sim)
{
    const pd_piece *pc = sim->piece;
    return pc ? (pc->send_down + pc->send_up) * (sim->s0 ? 4 : 3) * (int64_t)sizeof(double) : 0;
}

void pd_sim_owned(const pd_sim *sim, int64_t *lo, int64_t *hi)
{
    const pd_piece *pc = sim->piece;
    *lo = pc ? pc->first + pc->own_lo : 0;
    *hi = pc ? pc->first + pc->own_hi : sim->n;
}

void pd_sim_part(const pd_sim *sim, pd_part *part)
{
    const pd_piece *pc = sim->piece;
    const int64_t *off = sim->b->offset;
    if (pc == NULL) {
        *part = (pd_part){0, 0, sim->n, sim->n, 0, 0, sim->b->count, sim->b->count};
        return;
    }
    part->lo = pc->own_lo;
    part->first = pc->first + pc->own_lo;
    part->rows = pc->own_hi - pc->own_lo;
    part->n = pc->n_whole;
    part->klo = off[pc->own_lo];
    part->bonds = off[pc->own_hi] - off[pc->own_lo];
    /* the ranks' own bonds follow one another in rank order */
    part->bond0 = pd_comm_below(part->bonds);
    part->nbonds = pd_comm_total(part->bonds);
}

