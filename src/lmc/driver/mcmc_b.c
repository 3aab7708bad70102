/*
 * mcmc_b.c: the MCMC driver's normalisation: the bootstrap's samples (or
 * the state space's own estimator) give b before the chains, the chains'
 * large steps refine it, and the film gets the chains' splats times b
 * (mcmc.c's header: Normalisation, Refining b, Bootstrap).
 */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/driver/mcmc_internal.h"
#include "render/dist.h"

uint64_t mcmc__boot_seq(int g, int64_t j) {
  return rng_hash64(((uint64_t)(g + 1) << 44) ^ (uint64_t)j);
}
uint64_t mcmc__chain_seq(int g, int i) {
  return rng_hash64(((uint64_t)(g + 1) << 44) ^ (1ull << 43) ^ (uint64_t)i);
}

/* mc_boot_draw_fn over the families: draws bootstrap samples
 * [bt.n, to[g]) of every family g in parallel (each sample from its own
 * stream, so the values do not depend on threads); the cost is rays. Over
 * several ranks each draws its block of every batch and the blocks are
 * gathered exactly (dist_allsum over zeros elsewhere), so every rank holds
 * every value, the same as one process would, and the cost is summed. */
static void mcmc__bootstrap_draw(void *ctx, mc_boot *boot, int n_fam, const int64_t *to) {
  mcmc_render *R = ctx;
  for (int g = 0; g < n_fam; g++) {
    const mc_target *T = &R->fam[g].sf->target;
    mc_boot *B = &boot[g];
    int64_t from = B->n, lo, hi, cost = 0;
    dist_block(from, to[g], &lo, &hi);
    for (int64_t j = from; j < to[g]; j++) {
      if (j >= lo && j < hi) continue;
      B->f[j] = 0.0;
      if (B->has_fe) B->fe[j] = 0.0;
    }
    const uint64_t seed = R->crs.seed;
#pragma omp parallel num_threads(R->nthreads)
    {
      void *sc = T->scratch_create(T);
      int tid = omp_get_thread_num();
#pragma omp for schedule(dynamic, 256)
      for (int64_t j = lo; j < hi; j++) {
        B->f[j] = sc ? mc_eval_independent(T, sc, seed, mcmc__boot_seq(g, j), NULL) : 0.0;
        if (B->has_fe) {
          /* An independent sample for b (the one above picks starting states). */
          lmc_indep_sampler smp;
          indep_sampler_init(&smp, seed, mcmc__boot_seq(g, j) ^ MCMC_EXPECT_SEQ);
          double v = sc ? T->eval_expect(T, sc, &smp.base) : 0.0;
          B->fe[j] = v >= 0.0 && isfinite(v) ? v : 0.0;
        }
      }
      if (sc) {
        int64_t rays = T->scratch_rays(sc);
#pragma omp atomic
        R->cnt[tid].rays += rays;
#pragma omp atomic
        cost += rays;
      }
      T->scratch_destroy(sc);
    }
    if (dist_active()) {
      dist_allsum(B->f + from, (size_t)(to[g] - from));
      if (B->has_fe) dist_allsum(B->fe + from, (size_t)(to[g] - from));
      dist_allsum_i64(&cost, 1);
    }
    B->cost += (double)cost;
  }
}

/* Mean and variance of the mean of n samples with sums s, s2. */
static void mcmc__mean_var(double s, double s2, double n, double *OUT_mean, double *OUT_var) {
  double mean = n > 0.0 ? s / n : 0.0;
  double var = n > 1.0 ? fmax(0.0, (s2 - n * mean * mean) / (n - 1.0)) : 0.0;
  *OUT_mean = mean;
  *OUT_var = n > 0.0 ? var / n : 0.0;
}

/* b_ref of every family with chains: the bootstrap's samples pooled with
 * its chains' large-step tallies (on spaces with pool_large), added in
 * chain order (deterministic). Both are unbiased samples of b_g, so the
 * pooled mean is unbiased. A space with its own estimator of b keeps it
 * alone: there a large step is one strategy's value, whose tail is far
 * heavier (on ring-caustics-glass one large step of length 10 took that
 * length's b from 46 to 3657, and the render's relative MSE from 0.04 to
 * 4.2; on the torus pooling lowered b in each of four runs looked at:
 * unbiased, but a typical run darker). (An inverse-variance weighting of
 * the two means was tried and dropped: with heavy tails a low estimate
 * comes with a low estimated variance, and on ring-caustics it pulled the
 * long lengths' b far down.) Returns the sum of b_ref over the families
 * and its variance in OUT_var. */
double mcmc__refine_b(mcmc_render *R, double *OUT_var) {
  double b = 0.0, v = 0.0;
  for (int g = 0; g < R->n_fam; g++) {
    mcmc_family *F = &R->fam[g];
    double s = 0.0, s2 = 0.0;
    int64_t nl = 0;
    for (int i = 0; i < F->n_chains && R->sp.pool_large; i++) {
      const mc_chain *c = R->slots[F->first_chain + i].chain;
      for (int q = 0; q < c->n_kernels; q++) {
        if (c->kernels[q].kind != MC_KERNEL_LARGE) continue;
        s += c->stats[q].f_sum;
        s2 += c->stats[q].f_sum2;
        nl += c->stats[q].proposed;
      }
    }
    mcmc__mean_var(F->bt.s + s, F->bt.s2 + s2, (double)(F->bt.n_est + nl), &F->b_ref,
                   &F->b_ref_var);
    F->n_large = nl;
    b += F->b_ref;
    v += F->b_ref_var;
  }
  *OUT_var = v;
  return b;
}

/* Puts the chains' image (done mutations per chain) into the film with the
 * refined b: one family through splat_scale; per-family buffers, when
 * compose is set, by summing b_g times each buffer into the film's splats. */
void mcmc__publish(mcmc_render *R, int64_t done, int compose) {
  film *out = R->out;
  if (done <= 0) return;
  double v;
  if (R->norm != MCMC_NORM_BOOT) mcmc__refine_b(R, &v);
  if (R->norm != MCMC_NORM_BUFFERS) {
    out->splat_scale = (R->norm == MCMC_NORM_SCALE ? R->fam[0].b_ref : 1.0) / (double)done;
    return;
  }
  /* Per-family buffers: each normalised by its own chains' mutations. */
  out->splat_scale = 1.0;
  if (!compose) return;
  int64_t n = 3 * (int64_t)out->width * out->height;
  memset(out->splat, 0, (size_t)n * sizeof(double));
  for (int g = 0; g < R->n_fam; g++) {
    const mcmc_family *F = &R->fam[g];
    if (!F->splat || F->done <= 0) continue;
    double b = F->b_ref / (double)F->done;
    for (int64_t i = 0; i < n; i++) out->splat[i] += b * F->splat[i];
  }
}

/* Bootstrap (bootstrap.h): the pilot (or all of --bootstrap N), then the
 * main phase planned from it, in at most a tenth of the time left (after
 * --direct separate's pt pass), at most MCMC_BOOT_CAP samples in all; a
 * space with its own estimator of b gets a pilot per family for the
 * starting states alone, then estimates b in the rest of that time. */
lmc_status mcmc__bootstrap(mcmc_render *R, lmc_error *err) {
  const render_settings *rs = R->rs;
  const double t_boot = omp_get_wtime();
  progress_phase(&R->bar, "bootstrap", R->timed ? (t_boot - R->t0) / rs->time_limit : 0.0);
  mc_boot_params bp = {
      .fixed = R->sp.estimate_b ? MCMC_BOOT_BATCH : R->ms.bootstrap > 0 ? R->ms.bootstrap : 0,
      .batch = MCMC_BOOT_BATCH,
      .cap_total = MCMC_BOOT_CAP,
      .rel_err = R->ms.bootstrap_error,
      .seconds = R->timed ? 0.1 * (rs->time_limit - (t_boot - R->t0)) : INFINITY,
      .stop = render_stop_signal,
  };
  mc_boot *boot = malloc((size_t)(R->n_fam > 0 ? R->n_fam : 1) * sizeof(mc_boot));
  int failed = !boot;
  if (boot) {
    for (int g = 0; g < R->n_fam; g++) boot[g] = R->fam[g].bt, boot[g].has_fe = 0;
    failed = mc_boot_run(boot, R->n_fam, &bp, mcmc__bootstrap_draw, R);
    if (!failed && R->sp.estimate_b) {
      double left = R->timed ? bp.seconds - (omp_get_wtime() - t_boot) : INFINITY;
      mc_space_b_request rq = {R->ms.bootstrap > 0 ? R->ms.bootstrap : 0,
                               R->timed ? fmax(left, 0.0) : INFINITY, R->ms.bootstrap_error,
                               MCMC_BOOT_CAP, rs->seed, R->nthreads};
      R->shared_paths = R->sp.estimate_b(&R->sp, boot, &rq, R->cnt);
      failed = R->shared_paths < 0;
    }
    for (int g = 0; g < R->n_fam; g++) R->fam[g].bt = boot[g];
    free(boot);
  }
  if (failed) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the bootstrap");
  R->b_total = R->b_var = 0.0;
  for (int g = 0; g < R->n_fam; g++) {
    mcmc_family *F = &R->fam[g];
    F->b_ref = F->bt.b;
    F->b_ref_var = F->bt.b_var;
    F->n_large = 0;
    R->b_total += F->bt.b, R->b_var += F->bt.b_var;
  }
  render_stats *st = R->st;
  st->mcmc_b_boot = st->mcmc_b = R->b_total;
  st->mcmc_boot_paths = R->shared_paths;
  for (int g = 0; g < R->n_fam; g++) st->mcmc_boot_paths += R->fam[g].bt.n;
  st->mcmc_b_boot_se = st->mcmc_b_se = sqrt(R->b_var);
  return LMC_OK;
}

