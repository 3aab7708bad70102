/*
 * dist.c: dist.h over MPI (LMC_HAVE_MPI), or the one-process case.
 *
 * The job is joined only when an MPI launcher started the process: its
 * environment names the job's size (OpenMPI's OMPI_COMM_WORLD_SIZE, PMIx's
 * PMIX_RANK, MPICH's and Slurm's PMI_SIZE). A plain `lmc render` therefore
 * never initialises MPI (a singleton MPI_Init costs time and may print
 * warnings in containers), and a build without MPI ignores the launcher.
 *
 * Sums to rank 0: each other rank sends its buffer in chunks (MPI counts
 * are ints); rank 0 receives rank 1's, adds it, then rank 2's, and so on.
 */
#define _POSIX_C_SOURCE 200809L
#include "render/dist.h"

#include <stdlib.h>
#include <string.h>

#ifdef LMC_HAVE_MPI
#include <mpi.h>
#endif

static int dist__rank = 0, dist__size = 1;
#ifdef LMC_HAVE_MPI
static int dist__joined = 0;
#endif

/* Elements per message: below INT_MAX and a buffer of a few hundred MB. */
#define DIST_CHUNK ((size_t)1 << 25)

#ifdef LMC_HAVE_MPI
static void dist__finalize(void) {
  int done = 0;
  MPI_Finalized(&done);
  if (!done) MPI_Finalize();
}
#endif

void dist_init(int *argc, char ***argv) {
#ifdef LMC_HAVE_MPI
  if (!getenv("OMPI_COMM_WORLD_SIZE") && !getenv("PMIX_RANK") && !getenv("PMI_SIZE")) return;
  int provided = 0;
  if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) return;
  dist__joined = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &dist__rank);
  MPI_Comm_size(MPI_COMM_WORLD, &dist__size);
  atexit(dist__finalize);
#else
  (void)argc, (void)argv;
#endif
}

int dist_rank(void) { return dist__rank; }
int dist_size(void) { return dist__size; }
int dist_active(void) { return dist__size > 1; }

int dist_any(int flag) {
#ifdef LMC_HAVE_MPI
  if (dist__size > 1) {
    int in = flag != 0, out = 0;
    MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    return out;
  }
#endif
  return flag != 0;
}

double dist_max(double v) {
#ifdef LMC_HAVE_MPI
  if (dist__size > 1) {
    double out = v;
    MPI_Allreduce(&v, &out, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    return out;
  }
#endif
  return v;
}

#ifdef LMC_HAVE_MPI
/* The rank-ordered sum of dist_sum_to_root for either element type:
 * add(dst, src, n) adds n elements. */
static void dist__sum_to_root(void *buf, size_t n, size_t elem, MPI_Datatype type,
                              void (*add)(void *, const void *, size_t)) {
  if (dist__size <= 1 || n == 0) return;
  size_t chunk = n < DIST_CHUNK ? n : DIST_CHUNK;
  if (dist__rank != 0) {
    for (size_t at = 0; at < n; at += chunk) {
      size_t m = n - at < chunk ? n - at : chunk;
      MPI_Send((char *)buf + at * elem, (int)m, type, 0, 0, MPI_COMM_WORLD);
    }
    return;
  }
  void *tmp = malloc(chunk * elem);
  if (!tmp) dist_abort(1);
  for (int r = 1; r < dist__size; r++)
    for (size_t at = 0; at < n; at += chunk) {
      size_t m = n - at < chunk ? n - at : chunk;
      MPI_Recv(tmp, (int)m, type, r, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      add((char *)buf + at * elem, tmp, m);
    }
  free(tmp);
}

static void dist__add_double(void *dst, const void *src, size_t n) {
  double *d = dst;
  const double *s = src;
  for (size_t i = 0; i < n; i++) d[i] += s[i];
}

static void dist__add_i64(void *dst, const void *src, size_t n) {
  int64_t *d = dst;
  const int64_t *s = src;
  for (size_t i = 0; i < n; i++) d[i] += s[i];
}
#endif

void dist_sum_to_root(double *buf, size_t n) {
#ifdef LMC_HAVE_MPI
  dist__sum_to_root(buf, n, sizeof *buf, MPI_DOUBLE, dist__add_double);
#else
  (void)buf, (void)n;
#endif
}

void dist_sum_to_root_i64(int64_t *buf, size_t n) {
#ifdef LMC_HAVE_MPI
  dist__sum_to_root(buf, n, sizeof *buf, MPI_INT64_T, dist__add_i64);
#else
  (void)buf, (void)n;
#endif
}

#ifdef LMC_HAVE_MPI
static void dist__allsum(void *buf, size_t n, size_t elem, MPI_Datatype type) {
  if (dist__size <= 1) return;
  for (size_t at = 0; at < n; at += DIST_CHUNK) {
    size_t m = n - at < DIST_CHUNK ? n - at : DIST_CHUNK;
    MPI_Allreduce(MPI_IN_PLACE, (char *)buf + at * elem, (int)m, type, MPI_SUM, MPI_COMM_WORLD);
  }
}
#endif

void dist_allsum(double *buf, size_t n) {
#ifdef LMC_HAVE_MPI
  dist__allsum(buf, n, sizeof *buf, MPI_DOUBLE);
#else
  (void)buf, (void)n;
#endif
}

void dist_allsum_i64(int64_t *buf, size_t n) {
#ifdef LMC_HAVE_MPI
  dist__allsum(buf, n, sizeof *buf, MPI_INT64_T);
#else
  (void)buf, (void)n;
#endif
}

void dist_max_n(double *v, int n) {
#ifdef LMC_HAVE_MPI
  if (dist__size > 1 && n > 0) MPI_Allreduce(MPI_IN_PLACE, v, n, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
#else
  (void)v, (void)n;
#endif
}

void dist_block(int64_t from, int64_t to, int64_t *OUT_lo, int64_t *OUT_hi) {
  int64_t n = to > from ? to - from : 0;
  *OUT_lo = from + n * dist__rank / dist__size;
  *OUT_hi = from + n * (dist__rank + 1) / dist__size;
}

void dist_broadcast(double *buf, size_t n) {
#ifdef LMC_HAVE_MPI
  if (dist__size <= 1) return;
  for (size_t at = 0; at < n; at += DIST_CHUNK) {
    size_t m = n - at < DIST_CHUNK ? n - at : DIST_CHUNK;
    MPI_Bcast(buf + at, (int)m, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  }
#else
  (void)buf, (void)n;
#endif
}

void dist_abort(int code) {
#ifdef LMC_HAVE_MPI
  if (dist__joined) MPI_Abort(MPI_COMM_WORLD, code);
#endif
  exit(code);
}
