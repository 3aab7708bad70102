/*
 * bootstrap.h: the estimate of b (the normalisation of an MCMC render) from
 * independent samples, for one or several families of chains (pssmlt's one,
 * mmlt's and lmc's one per path length).
 *
 * b_g = E[f_g(u)] over uniform u is estimated by the mean of independent
 * samples of f_g, so that how many samples stand behind each b_g never
 * depends on the samples it averages: then b_g is exactly unbiased.
 * Pooling every sample and stopping once the running standard error is
 * small (the rule this module replaced) is not: with a heavy-tailed f a
 * batch that meets a rare bright sample raises the estimated error, so
 * more samples follow and dilute it, while a run without one stops
 * early, low (tests/test_bootstrap.c measures it: 0.23 of the truth on a
 * toy whose mean comes from one sample in 256).
 *
 * mc_boot_run. A pilot of `batch` samples per family comes first. Then
 * the main phase, in batches of batch * n_fam samples shared among the
 * families by Neyman allocation: family g in proportion to sigma_g /
 * sqrt(c_g) (per-sample standard deviation over the square root of the
 * cost per sample, at least an eighth of an even share), which minimises
 * the standard error of sum_g b_g for the cost spent. Its two modes:
 *   - until a time (`seconds` finite): the shares are the pilot's, and
 *     batches are drawn until the time or cap_total is reached. b_g is
 *     the mean of the main phase's samples, whose number depends only on
 *     the pilot and the clock.
 *   - until an error (no time limit): every batch draws each family's
 *     share twice, once for a planning stream and once for an estimating
 *     stream (alternate samples of the main phase). The pilot and the
 *     planning stream re-plan the shares after every batch and decide
 *     when to stop: once the estimating stream's standard error, by the
 *     planning stream's figures, is below rel_err of sum_g b_g (or at
 *     cap_total). b_g is the mean of the estimating stream alone, whose
 *     length depends only on the planning samples. The price is twice the
 *     samples for the same error; the gain is an error near rel_err even
 *     when the pilot alone would underestimate a heavy tail.
 * The pilot's and the planning stream's samples stay in f for other uses
 * (mcmc.c picks the chains' starting states from all samples).
 *
 * With `fixed` > 0 every family draws exactly that many samples, all of
 * them in b_g (a fixed size, unbiased too).
 */
#ifndef LMC_MCMC_BOOTSTRAP_H
#define LMC_MCMC_BOOTSTRAP_H

#include <stdint.h>

/* One family's samples and its estimate. */
typedef struct mc_boot {
  double *f;       /* sample values (owned; grown by mc_boot_reserve) */
  double *fe;      /* values that estimate b instead of f (owned; NULL: f does) */
  int has_fe;      /* fe is kept */
  int64_t n;       /* samples drawn */
  int64_t first;   /* where the estimating samples begin (the pilot's size) */
  int split;       /* 1: of samples first.., only every second (first + 1, + 3, ...) estimates */
  int64_t cap;     /* room in f (and fe) */
  double cost;     /* cost of its samples so far (rays; > 0 makes Neyman's c_g) */
  int64_t n_est;   /* estimating samples */
  double b, b_var; /* their mean and the variance of that mean */
  double s, s2;    /* their sum and sum of squares */
  double plan_b,
      plan_var; /* the other samples (pilot, planning stream): mean, per-sample variance */
  int64_t n_plan;
  /* mc_boot_update's own running sums over samples [0, upd_n) (both
   * streams), valid while first and split are those they were summed
   * under */
  int64_t upd_n, upd_first, upd_m, upd_pm;
  int upd_split;
  double upd_s, upd_s2, upd_ps, upd_ps2;
} mc_boot;

/* Fills samples [boot[g].n, to[g]) of every family g (f, and fe when
 * has_fe) and adds their cost to boot[g].cost; must not change n. */
typedef void (*mc_boot_draw_fn)(void *ctx, mc_boot *boot, int n_fam, const int64_t *to);

typedef struct mc_boot_params {
  int64_t fixed;     /* > 0: exactly this many samples per family, all estimating */
  int64_t batch;     /* the pilot's samples per family; main batches hold batch *
                        n_fam */
  int64_t cap_total; /* most samples in all, pilot included */
  double rel_err;    /* the main phase's target standard error, relative to sum_g
                        b_g */
  double seconds;    /* no new main batch after this long (INFINITY: no limit) */
  int (*stop)(void); /* NULL, or 1 to stop drawing (Ctrl-C) */
} mc_boot_params;

/* Room for n samples (grown by doubling); 0 when out of memory. */
int mc_boot_reserve(mc_boot *bt, int64_t n);
/* Frees the arrays. */
void mc_boot_free(mc_boot *bt);
/* Sets n and recomputes both streams' figures from samples [0, n): from
 * the last call's sums when first and split are unchanged and n did not
 * shrink (the same additions in the same order, so the same figures). */
void mc_boot_update(mc_boot *bt, int64_t n);
/* Neyman's shares from the planning figures (plan_var, cost, n) into
 * OUT_share[n_fam] (summing to 1). */
void mc_boot_shares(const mc_boot *boot, int n_fam, double *OUT_share);
/* The standard error of sum_g b_g that n_est[g] estimating samples give,
 * by the planning figures, relative to sum_g plan_b (INFINITY when that
 * is 0 and some variance is not). */
double mc_boot_rel_err(const mc_boot *boot, int n_fam, const int64_t *n_est);
/* The pilot and the main phase (above) over boot[0 .. n_fam-1], which
 * start empty. Over several MPI ranks (render/dist.h) it is collective:
 * draw must leave every rank holding every value, and the time and stop
 * are agreed (the first rank to see them decides), so every rank makes
 * the same decisions and ends with the same b. Returns 0, or 1 when the
 * pilot could not be allocated. A family the main phase could not reach
 * (no memory, a stop) keeps the pilot's estimate. */
int mc_boot_run(mc_boot *boot, int n_fam, const mc_boot_params *p, mc_boot_draw_fn draw, void *ctx);

#endif
