/*
 * mcmc_error.c: each pixel's standard error for the MCMC integrators
 * (--error on).
 *
 * A chain's successive splats are correlated, so the spread of one chain's
 * mutations says little about the image's error; whole chains, though, are
 * independent of one another (each has its own random stream). The chains
 * of every family are dealt into G = MCMC_ERROR_GROUPS groups (chain j of
 * a family into group j mod G; every family has at least MCMC_MIN_CHAINS
 * >= G chains, so every group holds some of each), and each group keeps
 * its own image beside the film's. A group's splats are scaled by its own
 * share of the family (n_g / n_gk for the n_gk of the family's n_g chains
 * it holds), so that each group's image is an estimate of the whole
 * chains' image; the G estimates are independent and alike, and the
 * variance of their mean is their sample variance over G (G - 1 degrees of
 * freedom: the batch-means estimate over groups of chains).
 *
 * To that the normalisation's own error is added: the image is b times
 * the chains' histogram, and b's relative variance (var b / b^2, from the
 * bootstrap and the large steps, mcmc_b.c) times the pixel's square is its
 * share, per family where the families keep their own buffers (with
 * several families and b baked in, the largest family's relative variance
 * stands for all). The direct pass's error (--direct separate: pt's
 * passes) is in the film's esum; film_error_develop_to adds the two.
 *
 * Assumptions (docs/methods.md): the chains are independent given b and
 * the bootstrap's samples. They are not quite: their starting states are
 * drawn from one bootstrap, stratified (systematic resampling), which
 * makes the groups slightly negatively correlated (the estimate errs
 * high), and the bootstrap's finite sample biases every group alike (not
 * seen; it vanishes as the chains run). lmc's --adapt cache builds one
 * gradient cache from every chain in its first stage, a weak link between
 * the groups. With several families per-family buffers normalise each by
 * its own mutations; the groups use the families' shares of a round and b
 * from before the chains for their relative weights (exact but for a short
 * last round and b's refinement, both far below the error).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/driver/mcmc_internal.h"
#include "render/dist.h"

lmc_status mcmc__error_init(mcmc_render *R, lmc_error *err) {
  if (!R->rs->error) return LMC_OK;
  const int G = MCMC_ERROR_GROUPS;
  film *out = R->out;
  size_t n = 3 * (size_t)out->width * (size_t)out->height;
  /* Infinite until the chains have made a round. Without chains (b = 0:
   * the bootstrap met no light on the chains' paths) the chains' part is 0
   * and so is its spread, as for a pixel whose passes all saw nothing. */
  if (dist_rank() == 0) {
    free(out->evar);
    out->evar = malloc(n * sizeof(double));
    if (!out->evar)
      return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "--error: out of memory for a %dx%d film",
                           out->width, out->height);
    for (size_t i = 0; i < n; i++) out->evar[i] = R->n_slots > 0 ? INFINITY : 0.0;
  }
  if (R->n_slots == 0) return LMC_OK;
  R->egroup = calloc((size_t)G * n, sizeof(double));
  if (!R->egroup)
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0,
                         "--error: out of memory for the images of %d chain groups (%.0f MB)", G,
                         (double)G * (double)n * sizeof(double) / 1048576.0);
  for (int g = 0; g < R->n_fam; g++) {
    const mcmc_family *F = &R->fam[g];
    /* The family's weight among the groups' families (see above): b_g
     * and a full round over its share of one (per-family buffers only). */
    double w = R->norm == MCMC_NORM_BUFFERS ? F->bt.b * MCMC_ROUND / F->m_round : 1.0;
    for (int j = 0; j < F->n_chains; j++) {
      mcmc_chain_slot *sl = &R->slots[F->first_chain + j];
      int k = j % G, n_gk = (F->n_chains - k + G - 1) / G;
      sl->group = k;
      sl->gscale = w * (double)F->n_chains / (double)n_gk;
    }
  }
  return LMC_OK;
}

/* b's relative variance, family g's (mcmc_b.c: refined with the large
 * steps unless b was baked in before the chains). */
static double mcmc__b_relvar(const mcmc_render *R, int g) {
  const mcmc_family *F = &R->fam[g];
  double b = R->norm == MCMC_NORM_BOOT ? F->bt.b : F->b_ref;
  double v = R->norm == MCMC_NORM_BOOT ? F->bt.b_var : F->b_ref_var;
  return b > 0.0 ? v / (b * b) : 0.0;
}

/* Each pixel's variance into out->evar (rank 0) from buffers that hold
 * every rank's sums. */
static void mcmc__error_pixels(mcmc_render *R) {
  film *out = R->out;
  const int G = MCMC_ERROR_GROUPS;
  size_t n = 3 * (size_t)out->width * (size_t)out->height;
  double c = (R->norm == MCMC_NORM_SCALE ? R->fam[0].b_ref : 1.0) / (double)R->done_per_chain;
  double relvar_max = 0.0;
  for (int g = 0; g < R->n_fam; g++)
    if (R->fam[g].n_chains > 0) relvar_max = fmax(relvar_max, mcmc__b_relvar(R, g));
  /* (between rounds, when the chains' threads are idle) */
#pragma omp parallel for num_threads(R->nthreads) schedule(static)
  for (size_t i = 0; i < n; i++) {
    double s = 0.0, s2 = 0.0;
    for (int k = 0; k < G; k++) {
      double x = c * R->egroup[(size_t)k * n + i];
      s += x;
      s2 += x * x;
    }
    double mean = s / G, var = (s2 - G * mean * mean) / (G - 1.0);
    var = var > 0.0 ? var / G : 0.0;
    if (R->norm == MCMC_NORM_BUFFERS) {
      for (int g = 0; g < R->n_fam; g++) {
        const mcmc_family *F = &R->fam[g];
        if (!F->splat || F->done <= 0) continue;
        double x = F->b_ref * F->splat[i] / (double)F->done;
        var += mcmc__b_relvar(R, g) * x * x;
      }
    } else {
      double x = out->splat[i] * out->splat_scale;
      var += relvar_max * x * x;
    }
    out->evar[i] = var;
  }
}

/* Buffer q of those the variance reads (q = 0: the groups' images; q = 1
 * + g: family g's splats, for b's part, when the families keep their
 * own), its length in *OUT_len; NULL for a family without one. */
static double *mcmc__ebuf(mcmc_render *R, int q, size_t *OUT_len) {
  size_t n = 3 * (size_t)R->out->width * (size_t)R->out->height;
  *OUT_len = q == 0 ? (size_t)MCMC_ERROR_GROUPS * n : n;
  if (q == 0) return R->egroup;
  return R->norm == MCMC_NORM_BUFFERS ? R->fam[q - 1].splat : NULL;
}

/* Over several ranks those buffers are summed to rank 0 in copies of its
 * own, kept for the chains that go on after a snapshot. */
void mcmc__error_develop(mcmc_render *R) {
  if (!R->egroup) return;
  int here = dist_rank() == 0 && R->done_per_chain > 0 && R->out->evar;
  if (!dist_active()) {
    if (here) mcmc__error_pixels(R);
    return;
  }
  size_t total = 0, len;
  for (int q = 0; q <= R->n_fam; q++)
    if (mcmc__ebuf(R, q, &len)) total += len;
  double *keep = malloc(total * sizeof *keep);
  if (!keep) dist_abort(1); /* (collective: the others would wait) */
  double *at = keep;
  for (int q = 0; q <= R->n_fam; q++) {
    double *b = mcmc__ebuf(R, q, &len);
    if (!b) continue;
    memcpy(at, b, len * sizeof *keep);
    dist_sum_to_root(b, len);
    at += len;
  }
  if (here) mcmc__error_pixels(R);
  at = keep;
  for (int q = 0; q <= R->n_fam; q++) {
    double *b = mcmc__ebuf(R, q, &len);
    if (!b) continue;
    memcpy(b, at, len * sizeof *keep);
    at += len;
  }
  free(keep);
}
