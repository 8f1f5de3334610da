/* sweep_mpi — how catchup-sweep's jobs travel between ranks: a worker
 * (rank 1..K-1) computes the batches rank 0 sends, two batches ahead so
 * that it never waits for the manager, and sends each answer back while it
 * computes the next; rank 0 feeds every worker and takes the answers as
 * they come, polling with MPI_Iprobe and short sleeps so that it does not
 * take a core from the workers (the bookkeeping, MPI aside, is
 * sweep_manager.c's); with one rank, rank 0 computes alone. A stop (a
 * signal, or the results file failing) ends the dispatch with every answer
 * that arrived written. The test hooks that make jobs fail or check that
 * done ones are not redone are read here too. */
#ifndef CUP_SWEEP_MPI_H
#define CUP_SWEEP_MPI_H

#include "sweep_manager.h"

/* Bytes of a batch's answer, unless one job needs more: it arrives in ~10
 * rounds of fragments (see manager_mpi). */
#define MAX_MESSAGE (1u << 20)

/* This process's rank and the number of ranks (MPI_COMM_WORLD), once. */
void mpi_ranks(int rank, int nranks);

/* Rank 0's status to every rank, waited for without spinning: the others
 * wait while rank 0 reads the scenes or creates the results file, and must
 * not take the cores it works on. */
void bcast_status(int *st);

/* Test hooks (environment): CATCHUP_SWEEP_INJECT_FAIL=3,7,11 makes those
 * tasks fail half-way through; CATCHUP_SWEEP_DONE_LIST=FILE lists task ids
 * that must not be computed again (a rank asked to compute one aborts the
 * whole job). hooks_read aborts the job when the list cannot be read. */
typedef struct { long *id; long len; } idset;
typedef struct {
  idset inject, done_before;
  const char *done_file;
} hooks_t;
void hooks_read(hooks_t *h);
void hooks_free(hooks_t *h);

/* A worker's life: batches until rank 0 says stop (or a signal), then its
 * CPU time to rank 0 and goodbye. Returns 0. */
int worker(const sw_sweep *s, const hooks_t *hooks, double time_limit);
/* Rank 0: every job of m's queue computed (by the workers, or alone) and
 * taken into the file; -1 when a worker did not answer the stop within the
 * grace time (the job must then be aborted), else 0. */
int dispatch(manager_t *m, const hooks_t *hooks, double time_limit);

#endif
