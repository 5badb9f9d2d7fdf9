/*
 * comm.c -- the ranks of a run (MPI) and what they ask of each other:
 * or and min, gathers, a broadcast, the halo's send-and-receive, and sums
 * with the bits of one rank's pd_sum_fixed.  Built without PD_MPI (the
 * serial build) there is one rank, and every call is the one-rank answer.
 */
#include <limits.h>
#include <stdlib.h>
#include <string.h>

#ifdef PD_MPI
#include <mpi.h>
#endif

#include "base/comm.h"

#ifdef PD_MPI

static int started; /* 1: pd_comm_init called MPI_Init_thread */

int pd_comm_mpi(void)
{
    return 1;
}

/* Was this process started by an MPI launcher (mpirun, mpiexec, srun)?
 * Each sets its ranks' environment; a program started alone runs as one
 * rank without MPI_Init, whose singleton start (about 0.4 s with Open
 * MPI) would slow every pipe of pd's programs. */
static int launched(void)
{
    static const char *const vars[] = {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK",
                                       "PMI_SIZE", "MPI_LOCALNRANKS", "MV2_COMM_WORLD_SIZE"};
    for (size_t k = 0; k < sizeof vars / sizeof vars[0]; k++)
        if (getenv(vars[k]))
            return 1;
    return 0;
}

pd_status pd_comm_init(int *argc, char ***argv)
{
    int on = 0, level = 0;
    MPI_Initialized(&on);
    if (on || !launched())
        return PD_OK;
    if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &level) != MPI_SUCCESS)
        return pd_fail(PD_ERR_IO, "MPI could not start");
    started = 1;
    if (level < MPI_THREAD_FUNNELED)
        return pd_fail(PD_ERR_IO, "this MPI has no thread support (MPI_THREAD_FUNNELED), "
                                  "which OpenMP threads in a rank need");
    return PD_OK;
}

void pd_comm_finalize(void)
{
    int done = 0;
    MPI_Finalized(&done);
    if (started && !done)
        MPI_Finalize();
    started = 0;
}

void pd_comm_abort(int code)
{
    int on = 0;
    MPI_Initialized(&on);
    if (on && pd_comm_size() > 1)
        MPI_Abort(MPI_COMM_WORLD, code);
}

int pd_comm_rank(void)
{
    int on = 0, r = 0;
    MPI_Initialized(&on);
    if (on)
        MPI_Comm_rank(MPI_COMM_WORLD, &r);
    return r;
}

int pd_comm_size(void)
{
    int on = 0, s = 1;
    MPI_Initialized(&on);
    if (on)
        MPI_Comm_size(MPI_COMM_WORLD, &s);
    return s;
}

int pd_comm_or(int v)
{
    int out = v != 0;
    if (pd_comm_size() > 1)
        MPI_Allreduce(MPI_IN_PLACE, &out, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD);
    return out;
}

unsigned pd_comm_bits(unsigned v)
{
    unsigned out = v;
    if (pd_comm_size() > 1)
        MPI_Allreduce(MPI_IN_PLACE, &out, 1, MPI_UNSIGNED, MPI_BOR, MPI_COMM_WORLD);
    return out;
}

int64_t pd_comm_min(int64_t v)
{
    long long out = v;
    if (pd_comm_size() > 1)
        MPI_Allreduce(MPI_IN_PLACE, &out, 1, MPI_LONG_LONG, MPI_MIN, MPI_COMM_WORLD);
    return out;
}

double pd_comm_max(double v)
{
    double out = v;
    if (pd_comm_size() > 1)
        MPI_Allreduce(MPI_IN_PLACE, &out, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    return out;
}

int64_t pd_comm_total(int64_t v)
{
    int64_t out = v;
    if (pd_comm_size() > 1)
        MPI_Allreduce(MPI_IN_PLACE, &out, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
    return out;
}

int64_t pd_comm_below(int64_t v)
{
    int64_t out = 0;
    if (pd_comm_size() > 1)
        MPI_Exscan(&v, &out, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
    return pd_comm_rank() == 0 ? 0 : out; /* rank 0's is undefined */
}

/* Counts and displacements as MPI's ints (the callers' counts are far
 * below INT_MAX: a rank's rows of one array, or a chunk count). */
static void int_counts(const int64_t *counts, int P, int *c, int *at)
{
    int64_t sum = 0;
    for (int r = 0; r < P; r++) {
        c[r] = (int)counts[r];
        at[r] = (int)sum;
        sum += counts[r];
    }
}

void pd_comm_allgather(const double *mine, const int64_t *counts, double *all)
{
    const int P = pd_comm_size(), me = pd_comm_rank();
    if (P == 1) {
        memmove(all, mine, (size_t)counts[0] * sizeof(double));
        return;
    }
    int *c = malloc((size_t)P * 2 * sizeof(int));
    if (c == NULL)
        MPI_Abort(MPI_COMM_WORLD, 1); /* a few ints: nothing else could go on */
    int_counts(counts, P, c, c + P);
    MPI_Allgatherv(mine, c[me], MPI_DOUBLE, all, c, c + P, MPI_DOUBLE, MPI_COMM_WORLD);
    free(c);
}

void pd_comm_counts(int64_t mine, int64_t *all)
{
    if (pd_comm_size() == 1) {
        all[0] = mine;
        return;
    }
    MPI_Allgather(&mine, 1, MPI_INT64_T, all, 1, MPI_INT64_T, MPI_COMM_WORLD);
}

void pd_comm_counts_to(const int64_t *send, int64_t *recv)
{
    if (pd_comm_size() == 1) {
        recv[0] = send[0];
        return;
    }
    MPI_Alltoall(send, 1, MPI_INT64_T, recv, 1, MPI_INT64_T, MPI_COMM_WORLD);
}

void pd_comm_bcast(void *buf, int64_t bytes)
{
    if (pd_comm_size() > 1)
        MPI_Bcast(buf, (int)bytes, MPI_BYTE, 0, MPI_COMM_WORLD);
}

pd_status pd_comm_error_from(int from, pd_status s)
{
    if (pd_comm_size() == 1)
        return s;
    struct {
        int code;
        char text[1024];
    } e;
    memset(&e, 0, sizeof e);
    if (pd_comm_rank() == from) {
        e.code = (int)s;
        strncpy(e.text, pd_errmsg(), sizeof e.text - 1);
    }
    MPI_Bcast(&e, (int)sizeof e, MPI_BYTE, from, MPI_COMM_WORLD);
    return pd_fail((pd_status)e.code, "%s", e.text);
}

void pd_comm_barrier(void)
{
    if (pd_comm_size() > 1)
        MPI_Barrier(MPI_COMM_WORLD);
}

double pd_comm_chain_in(void)
{
    const int me = pd_comm_rank();
    double s = 0;
    if (me > 0)
        MPI_Recv(&s, 1, MPI_DOUBLE, me - 1, 11, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    return s;
}

double pd_comm_chain_out(double sum)
{
    const int me = pd_comm_rank(), P = pd_comm_size();
    if (me + 1 < P)
        MPI_Send(&sum, 1, MPI_DOUBLE, me + 1, 11, MPI_COMM_WORLD);
    if (P > 1)
        MPI_Bcast(&sum, 1, MPI_DOUBLE, P - 1, MPI_COMM_WORLD);
    return sum;
}

void pd_comm_add(double *x, int64_t n)
{
    if (pd_comm_size() > 1)
        MPI_Allreduce(MPI_IN_PLACE, x, (int)n, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
}

void pd_comm_add_int(int64_t *x, int64_t n)
{
    if (pd_comm_size() > 1)
        MPI_Allreduce(MPI_IN_PLACE, x, (int)n, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
}

void pd_comm_min_int(int64_t *x, int64_t n)
{
    if (pd_comm_size() > 1)
        MPI_Allreduce(MPI_IN_PLACE, x, (int)n, MPI_INT64_T, MPI_MIN, MPI_COMM_WORLD);
}

void pd_comm_box(double lo[3], double hi[3])
{
    if (pd_comm_size() == 1)
        return;
    MPI_Allreduce(MPI_IN_PLACE, lo, 3, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
    MPI_Allreduce(MPI_IN_PLACE, hi, 3, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
}

/* pd_comm_alltoall of values of type t, `size` bytes each. */
static void alltoall(const void *send, const int64_t *send_count, void *recv,
                     const int64_t *recv_count, MPI_Datatype t, size_t size)
{
    const int P = pd_comm_size();
    if (P == 1) {
        memmove(recv, send, (size_t)send_count[0] * size);
        return;
    }
    int *c = malloc((size_t)P * 4 * sizeof(int));
    if (c == NULL)
        MPI_Abort(MPI_COMM_WORLD, 1);
    int_counts(send_count, P, c, c + P);
    int_counts(recv_count, P, c + 2 * P, c + 3 * P);
    MPI_Alltoallv(send, c, c + P, t, recv, c + 2 * P, c + 3 * P, t, MPI_COMM_WORLD);
    free(c);
}

void pd_comm_alltoall(const double *send, const int64_t *send_count, double *recv,
                      const int64_t *recv_count)
{
    alltoall(send, send_count, recv, recv_count, MPI_DOUBLE, sizeof(double));
}

void pd_comm_alltoall_int(const int64_t *send, const int64_t *send_count, int64_t *recv,
                          const int64_t *recv_count)
{
    alltoall(send, send_count, recv, recv_count, MPI_INT64_T, sizeof(int64_t));
}

void pd_comm_sendrecv(const double *send, int64_t ns, int to, double *recv, int64_t nr,
                      int from)
{
    MPI_Sendrecv(send, (int)ns, MPI_DOUBLE, to < 0 ? MPI_PROC_NULL : to, 7, recv, (int)nr,
                 MPI_DOUBLE, from < 0 ? MPI_PROC_NULL : from, 7, MPI_COMM_WORLD,
                 MPI_STATUS_IGNORE);
}

#else /* one rank */

int pd_comm_mpi(void)
{
    return 0;
}

pd_status pd_comm_init(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    return PD_OK;
}

void pd_comm_finalize(void)
{
}

void pd_comm_abort(int code)
{
    (void)code;
}

int pd_comm_rank(void)
{
    return 0;
}

int pd_comm_size(void)
{
    return 1;
}

int pd_comm_or(int v)
{
    return v != 0;
}

unsigned pd_comm_bits(unsigned v)
{
    return v;
}

int64_t pd_comm_min(int64_t v)
{
    return v;
}

double pd_comm_max(double v)
{
    return v;
}

int64_t pd_comm_total(int64_t v)
{
    return v;
}

int64_t pd_comm_below(int64_t v)
{
    (void)v;
    return 0;
}

void pd_comm_allgather(const double *mine, const int64_t *counts, double *all)
{
    memmove(all, mine, (size_t)counts[0] * sizeof(double));
}

void pd_comm_counts(int64_t mine, int64_t *all)
{
    all[0] = mine;
}

void pd_comm_counts_to(const int64_t *send, int64_t *recv)
{
    recv[0] = send[0];
}

void pd_comm_bcast(void *buf, int64_t bytes)
{
    (void)buf;
    (void)bytes;
}

void pd_comm_box(double lo[3], double hi[3])
{
    (void)lo;
    (void)hi;
}

pd_status pd_comm_error_from(int from, pd_status s)
{
    (void)from;
    return s;
}

void pd_comm_barrier(void)
{
}

double pd_comm_chain_in(void)
{
    return 0;
}

double pd_comm_chain_out(double sum)
{
    return sum;
}

void pd_comm_add(double *x, int64_t n)
{
    (void)x;
    (void)n;
}

void pd_comm_add_int(int64_t *x, int64_t n)
{
    (void)x;
    (void)n;
}

void pd_comm_min_int(int64_t *x, int64_t n)
{
    (void)x;
    (void)n;
}

void pd_comm_alltoall(const double *send, const int64_t *send_count, double *recv,
                      const int64_t *recv_count)
{
    (void)recv_count;
    memmove(recv, send, (size_t)send_count[0] * sizeof(double));
}

void pd_comm_alltoall_int(const int64_t *send, const int64_t *send_count, int64_t *recv,
                          const int64_t *recv_count)
{
    (void)recv_count;
    memmove(recv, send, (size_t)send_count[0] * sizeof(int64_t));
}

void pd_comm_sendrecv(const double *send, int64_t ns, int to, double *recv, int64_t nr,
                      int from)
{
    (void)send, (void)ns, (void)to, (void)recv, (void)nr, (void)from;
}

#endif

static int echo; /* 1: the last failure was another rank's */

pd_status pd_comm_agree(pd_status s)
{
    if (pd_comm_size() > 1 && pd_comm_or(s != PD_OK) && s == PD_OK) {
        echo = 1;
        return pd_fail(PD_ERR_IO, "another MPI rank failed");
    }
    return s;
}

int pd_comm_echo(void)
{
    const int e = echo;
    echo = 0;
    return e;
}

#define SUM_MAX 8 /* arrays summed at once */

void pd_comm_sum_fixed(const double *const *x, int m, int64_t lo, int64_t count, int64_t n,
                       double *sums)
{
    const int P = pd_comm_size(), me = pd_comm_rank();
    if (P == 1) {
        for (int c = 0; c < m; c++)
            sums[c] = pd_sum_fixed(x[c], n);
        return;
    }
#ifdef PD_MPI
    const int64_t C = PD_SUM_CHUNK, hi = lo + count;
    double carry[SUM_MAX] = {0};
    /* a chunk begun below: its partial sum comes from the rank below */
    if (lo % C != 0 && lo > 0)
        MPI_Recv(carry, m, MPI_DOUBLE, me - 1, 9, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    /* the chunks this rank finishes (it holds their last row) */
    const int64_t c0 = lo / C, c1 = count > 0 ? (hi - 1) / C : c0 - 1;
    double *done = malloc((size_t)((c1 - c0 + 1) > 0 ? c1 - c0 + 1 : 1) * m * sizeof(double));
    int64_t *counts = malloc((size_t)P * sizeof(int64_t));
    if (done == NULL || counts == NULL)
        MPI_Abort(MPI_COMM_WORLD, 1);
    int64_t nd = 0;
    for (int64_t ch = c0; ch <= c1; ch++) {
        const int64_t a = ch * C > lo ? ch * C : lo, end = (ch + 1) * C < n ? (ch + 1) * C : n;
        const int64_t b = end < hi ? end : hi;
        for (int c = 0; c < m; c++) {
            double s = ch == c0 ? carry[c] : 0.0;
            for (int64_t i = a; i < b; i++)
                s += x[c][i - lo];
            carry[c] = s;
        }
        if (end <= hi) {
            memcpy(done + nd * m, carry, (size_t)m * sizeof(double));
            nd++;
            memset(carry, 0, sizeof carry);
        }
    }
    /* a chunk left unfinished: its partial sum goes on to the rank above
     * (with nothing of this rank's in it, the one from below goes on) */
    if (hi % C != 0 && hi < n && (count > 0 || lo % C != 0))
        MPI_Send(carry, m, MPI_DOUBLE, me + 1, 9, MPI_COMM_WORLD);
    long long mine = nd * m, *all = malloc((size_t)P * sizeof(long long));
    if (all == NULL)
        MPI_Abort(MPI_COMM_WORLD, 1);
    MPI_Allgather(&mine, 1, MPI_LONG_LONG, all, 1, MPI_LONG_LONG, MPI_COMM_WORLD);
    int64_t total = 0;
    for (int r = 0; r < P; r++)
        total += counts[r] = all[r];
    free(all);
    double *part = malloc((size_t)(total > 0 ? total : 1) * sizeof(double));
    if (part == NULL)
        MPI_Abort(MPI_COMM_WORLD, 1);
    pd_comm_allgather(done, counts, part);
    for (int c = 0; c < m; c++) {
        double s = 0;
        for (int64_t k = 0; k < total / m; k++)
            s += part[k * m + c];
        sums[c] = s;
    }
    free(part);
    free(done);
    free(counts);
#else
    (void)lo, (void)count, (void)me;
#endif
}
