/*
 * mcmc_dist.c: the MCMC driver over several MPI ranks (render/dist.h).
 *
 * Every rank runs the same render: the same bootstrap values (each rank
 * draws its block of every batch and they are gathered exactly,
 * mcmc_b.c), so the same b, chains and starting states; then each steps
 * only its own chains (mcmc_chain_here: chain i on rank i modulo the
 * ranks, which spreads every family evenly). The rounds stay in step:
 * after each one the ranks agree on the clocks, a stop and an abandoned
 * round (mcmc.c), so every film holds the same rounds. What one rank's
 * chains learnt the others get here: the chains' counters (the large
 * steps' tallies that refine b, the statistics), before a restart, a
 * snapshot and the end. The splats are summed to rank 0 in rank order
 * (repeatable for a rank count). Under one process every function here
 * is a no-op or the plain case.
 *
 * Since every chain's random stream and start are those one process
 * would use, the chains make the same moves over any number of ranks:
 * b and every count are a one-process run's, and the image differs from
 * it only by the order its splats are added in (lmc's stage-1 records
 * are shared in chain order for the same reason, integrator_lmc.c).
 */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/driver/mcmc_internal.h"
#include "render/dist.h"

int mcmc_chain_here(int i) {
  return dist_size() <= 1 || i % dist_size() == dist_rank();
}

/* A chain's counters as doubles (exact below 2^53): per kernel proposed,
 * accepted, accept_sum, f_sum, f_sum2, inverted, refused, elsewhere, rays; then steps, overflow,
 * regrad, screened, screen_passed, eval_failures, sum_evals, sum_rays; then its labels' tallies
 * (c->lab, 3 per label; the width has room for the most labels of any chain). */
#define MCMC_SYNC_KERNEL 9
#define MCMC_SYNC_FIXED (MC_MAX_KERNELS * MCMC_SYNC_KERNEL + 8)

static void mcmc__pack_chain(const mc_chain *c, double *o) {
  for (int q = 0; q < c->n_kernels; q++) {
    const mc_kernel_stats *k = &c->stats[q];
    double *d = o + q * MCMC_SYNC_KERNEL;
    d[0] = (double)k->proposed, d[1] = (double)k->accepted, d[2] = k->accept_sum;
    d[3] = k->f_sum, d[4] = k->f_sum2;
    d[5] = (double)k->inverted, d[6] = (double)k->refused, d[7] = (double)k->elsewhere;
    d[8] = (double)k->rays;
  }
  double *e = o + MC_MAX_KERNELS * MCMC_SYNC_KERNEL;
  e[0] = (double)c->steps, e[1] = (double)c->overflow, e[2] = (double)c->regrad;
  e[3] = (double)c->screened, e[4] = (double)c->screen_passed;
  e[5] = (double)c->eval_failures, e[6] = (double)c->sum_evals, e[7] = (double)c->sum_rays;
  for (int l = 0; c->lab && l < 3 * c->target->n_labels; l++) e[8 + l] = (double)c->lab[l];
}

static void mcmc__unpack_chain(mc_chain *c, const double *o) {
  for (int q = 0; q < c->n_kernels; q++) {
    mc_kernel_stats *k = &c->stats[q];
    const double *d = o + q * MCMC_SYNC_KERNEL;
    k->proposed = (int64_t)d[0], k->accepted = (int64_t)d[1], k->accept_sum = d[2];
    k->f_sum = d[3], k->f_sum2 = d[4];
    k->inverted = (int64_t)d[5], k->refused = (int64_t)d[6], k->elsewhere = (int64_t)d[7];
    k->rays = (int64_t)d[8];
  }
  const double *e = o + MC_MAX_KERNELS * MCMC_SYNC_KERNEL;
  c->steps = (int64_t)e[0], c->overflow = (int64_t)e[1], c->regrad = (int64_t)e[2];
  c->screened = (int64_t)e[3], c->screen_passed = (int64_t)e[4];
  c->eval_failures = (int64_t)e[5], c->sum_evals = (int64_t)e[6], c->sum_rays = (int64_t)e[7];
  for (int l = 0; c->lab && l < 3 * c->target->n_labels; l++) c->lab[l] = (int64_t)e[8 + l];
}

void mcmc__sync_chains(mcmc_render *R) {
  if (!dist_active() || R->n_slots <= 0) return;
  unsigned labels = 0;
  for (int i = 0; i < R->n_slots; i++) {
    int nl = R->slots[i].chain->target->n_labels;
    if (nl > 0 && (unsigned)nl > labels) labels = (unsigned)nl;
  }
  size_t width = MCMC_SYNC_FIXED + 3 * (size_t)labels;
  size_t n = (size_t)R->n_slots * width;
  double *buf = calloc(n, sizeof *buf);
  if (!buf) dist_abort(1); /* (collective: the others would wait) */
  for (int i = 0; i < R->n_slots; i++)
    if (mcmc_chain_here(i)) mcmc__pack_chain(R->slots[i].chain, buf + (size_t)i * width);
  dist_allsum(buf, n);
  for (int i = 0; i < R->n_slots; i++)
    if (!mcmc_chain_here(i)) mcmc__unpack_chain(R->slots[i].chain, buf + (size_t)i * width);
  free(buf);
}

void mcmc__snapshot(mcmc_render *R, double seconds) {
  const render_settings *rs = R->rs;
  double t0 = omp_get_wtime();
  R->n_snapshots++;
  mcmc__sync_chains(R);
  mcmc__publish(R, R->done_per_chain, 1);
  if (!dist_active()) {
    mcmc__error_develop(R);
    R->snapshot_seconds += omp_get_wtime() - t0;
    rs->snapshot_fn(rs->snapshot_ctx, R->out, seconds);
    return;
  }
  /* Rank 0's film gets every rank's splats for the snapshot, then its own back. */
  size_t n = 3 * (size_t)R->out->width * (size_t)R->out->height;
  double *keep = malloc(n * sizeof *keep);
  if (!keep) dist_abort(1);
  memcpy(keep, R->out->splat, n * sizeof *keep);
  dist_sum_to_root(R->out->splat, n);
  mcmc__error_develop(R);
  R->snapshot_seconds += omp_get_wtime() - t0;
  if (dist_rank() == 0) rs->snapshot_fn(rs->snapshot_ctx, R->out, seconds);
  memcpy(R->out->splat, keep, n * sizeof *keep);
  free(keep);
}

void mc_share_counters(void *first, int n, size_t stride, size_t size) {
  if (!dist_active() || n <= 0) return;
  size_t w = size / sizeof(int64_t);
  int64_t *buf = malloc((size_t)n * w * sizeof *buf);
  if (!buf) dist_abort(1); /* (collective: the others would wait) */
  char *p = first;
  for (int i = 0; i < n; i++) memcpy(buf + (size_t)i * w, p + (size_t)i * stride, size);
  dist_allsum_i64(buf, (size_t)n * w);
  for (int i = 0; i < n; i++) memcpy(p + (size_t)i * stride, buf + (size_t)i * w, size);
  free(buf);
}

/* The scene targets' counters of this rank's chains added to *c, and
 * their mutations to *mutations (may be NULL). */
void mcmc__counts_here(const mcmc_render *R, mc_counts *c, int64_t *mutations) {
  for (int i = 0; R->slots && i < R->n_slots; i++) {
    const mc_chain *ch = R->slots[i].chain;
    if (!ch || !mcmc_chain_here(i)) continue;
    const mcmc_family *F = &R->fam[R->slots[i].family];
    mc_space_counts(F->sf, ch->scratch, c);
    mc_space_counts(F->sf, ch->scratch_alt, c);
    if (mutations) *mutations += F->done;
  }
}

/* The scene targets' counters of every chain summed over the ranks, and
 * the integrator's own statistics shared (method.h), on every rank. */
void mcmc__share_stats(mcmc_render *R, mc_counts *OUT) {
  mc_counts c = {0};
  mcmc__counts_here(R, &c, NULL);
  if (dist_active()) {
    int64_t v[3] = {c.grad_evals, c.hess_evals, c.nan_samples};
    dist_allsum_i64(v, 3);
    c.grad_evals = v[0], c.hess_evals = v[1], c.nan_samples = v[2];
    if (R->M->share_stats) R->M->share_stats(R->mrun);
    if (R->moves) R->sp.moves->share_stats(R->moves);
  }
  *OUT = c;
}
