/*
 * halo.c -- what a piece of a body spread over MPI ranks (lib/run/piece.c)
 * does at each step: its ghosts' positions and s0 from their owners, its
 * ghosts kept at rest, and sums over the ranks in the whole body's order.
 */
#include <stdlib.h>
#include <string.h>

#include "base/comm.h"
#include "state/sim.h"

void pd_piece_free(pd_piece *pc)
{
    if (pc == NULL)
        return;
    free(pc->rows);
    free(pc->own_at);
    free(pc->piece_at);
    free(pc->blocks);
    free(pc->buf);
    free(pc->sum3);
    pd_particles_free(pc->p);
    pd_bonds_free(pc->b);
    free(pc->keep);
    free(pc);
}

void pd_piece_ghosts_rest(pd_sim *sim)
{
    const pd_piece *pc = sim->piece;
    for (int d = 0; d < 3; d++) {
        memset(sim->f[d], 0, (size_t)pc->own_lo * sizeof(double));
        memset(sim->v[d], 0, (size_t)pc->own_lo * sizeof(double));
        memset(sim->f[d] + pc->own_hi, 0, (size_t)(sim->n - pc->own_hi) * sizeof(double));
        memset(sim->v[d] + pc->own_hi, 0, (size_t)(sim->n - pc->own_hi) * sizeof(double));
    }
}

/* Rows [lo, lo + rows) of the m arrays a into buf, m doubles a row, or
 * back. */
static void pack(double *const *a, int m, double *buf, int64_t lo, int64_t rows, int in)
{
    for (int64_t r = 0; r < rows; r++)
        for (int c = 0; c < m; c++)
            if (in)
                a[c][lo + r] = buf[m * r + c];
            else
                buf[m * r + c] = a[c][lo + r];
}

void pd_piece_exchange(pd_sim *sim, double *const *a, int m)
{
    const pd_piece *pc = sim->piece;
    const int down = pc->rank - 1, up = pc->rank + 1 < pc->ranks ? pc->rank + 1 : -1;
    const int64_t above = sim->n - pc->own_hi;
    double *send = pc->buf, *recv;
    /* to the rank below its ghosts above, from the rank above ours */
    recv = send + m * pc->send_down;
    pack(a, m, send, pc->own_lo, pc->send_down, 0);
    pd_comm_sendrecv(send, m * pc->send_down, down, recv, m * above, up);
    pack(a, m, recv, pc->own_hi, above, 1);
    /* to the rank above its ghosts below, from the rank below ours */
    recv = send + m * pc->send_up;
    pack(a, m, send, pc->own_hi - pc->send_up, pc->send_up, 0);
    pd_comm_sendrecv(send, m * pc->send_up, up, recv, m * pc->own_lo, down);
    pack(a, m, recv, 0, pc->own_lo, 1);
}

pd_status pd_piece_halo(pd_sim *sim)
{
    double *a[4] = {sim->y[0], sim->y[1], sim->y[2], sim->s0};
    pd_piece_exchange(sim, a, sim->s0 ? 4 : 3);
    return PD_OK;
}

pd_status pd_piece_add_in_order(const pd_sim *sim, const double *v, int64_t n, double *sum)
{
    const int P = sim->piece->ranks;
    int64_t *each = malloc((size_t)P * sizeof(int64_t));
    if (!each)
        return pd_fail(PD_ERR_NOMEM, "out of memory for a sum over the ranks");
    pd_comm_counts(n, each);
    int64_t total = 0;
    for (int r = 0; r < P; r++)
        total += each[r];
    double *all = malloc((size_t)(total > 0 ? total : 1) * sizeof(double));
    const pd_status st = all ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory for a sum over the ranks");
    if (all) {
        pd_comm_allgather(v, each, all);
        for (int64_t k = 0; k < total; k++)
            *sum += all[k];
    }
    free(all);
    free(each);
    return st;
}

