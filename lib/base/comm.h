/*
 * comm.h -- internal (lib/base/comm.c): what a run spread over MPI ranks
 * asks of the others.  In the serial build there is one rank and each of
 * these is the one-rank answer; only the master thread of a rank calls
 * them (MPI_THREAD_FUNNELED).
 */
#ifndef PD_COMM_H
#define PD_COMM_H

#include "pd.h"

/* Every rank's `count` doubles at `mine`, in rank order, into `all` on
 * every rank; counts[r] is rank r's count (the same table on every rank). */
void pd_comm_allgather(const double *mine, const int64_t *counts, double *all);
/* Every rank's one count `mine` into all[r], r its rank, on every rank. */
void pd_comm_counts(int64_t mine, int64_t *all);
/* Each rank's send[r] to rank r, which gets it as recv[this rank]. */
void pd_comm_counts_to(const int64_t *send, int64_t *recv);
/* The bitwise or of v over the ranks (collective): several yes-or-no
 * questions in one reduction. */
unsigned pd_comm_bits(unsigned v);
/* The smallest lo[d] and the largest hi[d] over the ranks, in place. */
void pd_comm_box(double lo[3], double hi[3]);
/* Each rank sends send_count[r] doubles to rank r (from `send`, in rank
 * order) and receives recv_count[r] from it (into `recv`, in rank order). */
void pd_comm_alltoall(const double *send, const int64_t *send_count, double *recv,
                      const int64_t *recv_count);
/* The same of int64 values. */
void pd_comm_alltoall_int(const int64_t *send, const int64_t *send_count, int64_t *recv,
                          const int64_t *recv_count);
/* A sum taken in the one rank's order over rows the ranks hold in rank
 * order, as a chain: pd_comm_chain_in gives the sum of the ranks below (0
 * on rank 0), to which this rank adds its own terms in order; then
 * pd_comm_chain_out passes it on and gives every rank the last one's. */
double pd_comm_chain_in(void);
double pd_comm_chain_out(double sum);
/* Element-wise sums of n doubles over the ranks, in place (exact where
 * each element is non-zero on one rank at most). */
void pd_comm_add(double *x, int64_t n);
/* Element-wise sums, and smallest values, of n int64 over the ranks, in
 * place. */
void pd_comm_add_int(int64_t *x, int64_t n);
void pd_comm_min_int(int64_t *x, int64_t n);
/* Rank 0's `bytes` at buf into every rank's. */
void pd_comm_bcast(void *buf, int64_t bytes);
/* Send `ns` doubles to rank `to` and receive `nr` from rank `from` (either
 * may be -1: none), at once. */
void pd_comm_sendrecv(const double *send, int64_t ns, int to, double *recv, int64_t nr,
                      int from);
/* The sums of m arrays over rows spread over the ranks, bit for bit as
 * pd_sum_fixed sums the whole rows on one rank: rank r holds the rows
 * [lo, lo + count) of n (the ranks' ranges consecutive, in rank order),
 * x[c] points at its values of array c.  sums[c] gets the same total on
 * every rank.  A chunk of PD_SUM_CHUNK rows that two ranks share is summed
 * on as a chain: the lower rank's partial sum goes on to the next. */
void pd_comm_sum_fixed(const double *const *x, int m, int64_t lo, int64_t count, int64_t n,
                       double *sums);

#endif
