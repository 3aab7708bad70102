/*
 * dist.h: one render spread over processes (MPI ranks), or one process.
 *
 * lmc built with MPI (CMake found it: LMC_HAVE_MPI) and started by an MPI
 * launcher (mpirun, srun: its environment names the job's size) runs as
 * one rank of dist_size() processes; otherwise, and in a build without
 * MPI, it is rank 0 of 1 and every call below is the one-process case
 * (a no-op or a copy). The integrators share their work out by rank and
 * reduce their films and counters to rank 0, which writes the image.
 *
 * Determinism. Every reduction adds the ranks' values in rank order on
 * rank 0 (never MPI_Reduce, whose order depends on the implementation),
 * so a render is repeatable for a given number of ranks, and with one
 * rank the result is the process's own: bit for bit a run without mpirun.
 *
 * Every function below except dist_rank, dist_size and dist_active is
 * collective: every rank calls it, the same number of times in the same
 * order, with the same sizes.
 */
#ifndef LMC_RENDER_DIST_H
#define LMC_RENDER_DIST_H

#include <stddef.h>
#include <stdint.h>

/* Joins the job when started by an MPI launcher (MPI_Init_thread, one
 * thread calling MPI); once, first thing in main. dist_finalize is
 * registered with atexit. */
void dist_init(int *argc, char ***argv);

int dist_rank(void);
int dist_size(void);
/* More than one rank. */
int dist_active(void);

/* Whether flag is non-zero on any rank. */
int dist_any(int flag);
/* The largest of v over the ranks. */
double dist_max(double v);
/* buf[0 .. n-1] summed over the ranks, in rank order, into rank 0's buf
 * (the other ranks' buf is left as it was). */
void dist_sum_to_root(double *buf, size_t n);
/* The same for 64-bit counts. */
void dist_sum_to_root_i64(int64_t *buf, size_t n);
/* buf[0 .. n-1] summed over the ranks onto every rank (MPI_Allreduce).
 * Its order of additions is MPI's, so use it to gather parts that only
 * one rank fills (the others hold 0 there: x + 0 is x exactly) or for
 * integers, never to add overlapping sums of doubles. */
void dist_allsum(double *buf, size_t n);
void dist_allsum_i64(int64_t *buf, size_t n);
/* The largest of each v[i] over the ranks, onto every rank. */
void dist_max_n(double *v, int n);
/* This rank's block [*OUT_lo, *OUT_hi) of the items [from, to) when they
 * are shared out in contiguous blocks, rank by rank (all of them under
 * one rank). */
void dist_block(int64_t from, int64_t to, int64_t *OUT_lo, int64_t *OUT_hi);
/* rank 0's buf[0 .. n-1] to every rank. */
void dist_broadcast(double *buf, size_t n);
/* Ends the job with `code` (every rank, from any one): for a failure that
 * leaves the other ranks waiting in a collective. */
void dist_abort(int code);

#endif
