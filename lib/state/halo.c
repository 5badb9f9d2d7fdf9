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

/* Rows [lo, lo + rows) of y (and s0) into buf, m doubles a row, or back. */
static void pack(pd_sim *sim, double *buf, int64_t lo, int64_t rows, int m, int in)
{
    for (int64_t r = 0; r < rows; r++) {
        double *q = buf + m * r;
        for (int d = 0; d < 3; d++)
            if (in)
                sim->y[d][lo + r] = q[d];
            else
                q[d] = sim->y[d][lo + r];
        if (m == 4) {
            if (in)
                sim->s0[lo + r] = q[3];
            else
                q[3] = sim->s0[lo + r];
        }
    }
}

pd_status pd_piece_halo(pd_sim *sim)
{
    const pd_piece *pc = sim->piece;
    const int m = sim->s0 ? 4 : 3, down = pc->rank - 1, up = pc->rank + 1 < pc->ranks ? pc->rank + 1 : -1;
    const int64_t above = sim->n - pc->own_hi;
    double *send = pc->buf, *recv;
    /* to the rank below its ghosts above, from the rank above ours */
    recv = send + m * pc->send_down;
    pack(sim, send, pc->own_lo, pc->send_down, m, 0);
    pd_comm_sendrecv(send, m * pc->send_down, down, recv, m * above, up);
    pack(sim, recv, pc->own_hi, above, m, 1);
    /* to the rank above its ghosts below, from the rank below ours */
    recv = send + m * pc->send_up;
    pack(sim, send, pc->own_hi - pc->send_up, pc->send_up, m, 0);
    pd_comm_sendrecv(send, m * pc->send_up, up, recv, m * pc->own_lo, down);
    pack(sim, recv, 0, pc->own_lo, m, 1);
    return PD_OK;
}

pd_status pd_piece_add_in_order(const pd_sim *sim, const double *v, int64_t n, double *sum)
{
    const pd_piece *pc = sim->piece;
    const int P = pc->ranks;
    double *counts = malloc((size_t)P * sizeof(double));
    int64_t *ones = calloc((size_t)P, sizeof(int64_t)), *each = malloc((size_t)P * sizeof(int64_t));
    if (!counts || !ones || !each) {
        free(counts);
        free(ones);
        free(each);
        return pd_fail(PD_ERR_NOMEM, "out of memory for a sum over the ranks");
    }
    const double mine = (double)n;
    int64_t total = 0;
    for (int r = 0; r < P; r++)
        ones[r] = 1;
    pd_comm_allgather(&mine, ones, counts);
    for (int r = 0; r < P; r++)
        total += each[r] = (int64_t)counts[r];
    double *all = malloc((size_t)(total > 0 ? total : 1) * sizeof(double));
    if (all) {
        pd_comm_allgather(v, each, all);
        for (int64_t k = 0; k < total; k++)
            *sum += all[k];
    }
    free(all);
    free(counts);
    free(ones);
    free(each);
    return all ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory for a sum over the ranks");
}

