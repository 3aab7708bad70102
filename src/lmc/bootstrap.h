/*
 * bootstrap.h: the estimate of b (the normalisation of an MCMC render) from
 * independent samples, for one or several families of chains (pssmlt's one,
 * mmlt's and lmc's one per path length).
 *
 * b_g = E[f_g(u)] over uniform u is estimated by the mean of independent
 * samples of f_g. Two phases (mc_boot_run):
 *   - the pilot, `batch` samples per family, plans the main phase: family
 *     g's share of every later batch, by Neyman allocation in proportion
 *     to sigma_g / sqrt(c_g) (the pilot's per-sample standard deviation
 *     over the square root of its cost per sample, at least an eighth of
 *     an even share), which minimises the standard error of sum_g b_g for
 *     the cost spent; and how many samples the main phase draws: enough
 *     for a standard error of rel_err of the sum by the pilot's figures,
 *     at least one batch, at most what cap_total and the time allow;
 *   - the main phase draws batches of batch * n_fam samples split by those
 *     shares, and b_g is the mean of its samples alone.
 * The number of samples behind each b_g thus depends only on the pilot
 * (and on the clock), never on the samples it averages: b_g is exactly
 * unbiased. Pooling the pilot in, or re-planning after every batch, or
 * stopping once the running standard error is small, is not: with a
 * heavy-tailed f a batch that meets a rare bright sample raises the
 * estimated error, so more samples follow and dilute it, while a run
 * without one stops early, low (tests/test_bootstrap.c measures it).
 * The pilot's samples are kept in f for other uses (mcmc.c picks the
 * chains' starting states from all samples).
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
  int64_t first;   /* b from samples [first, n) */
  int64_t cap;     /* room in f (and fe) */
  double cost;     /* cost of its samples so far (rays; > 0 makes Neyman's c_g) */
  double b, b_var; /* the estimate and the variance of the estimate */
  double s, s2;    /* sum of the estimating samples and of their squares */
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
/* Sets n and recomputes b, b_var, s, s2 from samples [first, n). */
void mc_boot_update(mc_boot *bt, int64_t n);
/* The main phase's plan from the current estimates (the pilot's): shares
 * into OUT_share[n_fam], and returns the samples to draw in all (at least
 * batch * n_fam, at most left). */
int64_t mc_boot_plan(const mc_boot *boot, int n_fam, double rel_err, int64_t batch, int64_t left,
                     double *OUT_share);
/* Both phases (above) over boot[0 .. n_fam-1], which start empty. Returns
 * 0, or 1 when the pilot could not be allocated. A family the main phase
 * could not reach (no memory, a stop) keeps the pilot's estimate. */
int mc_boot_run(mc_boot *boot, int n_fam, const mc_boot_params *p, mc_boot_draw_fn draw, void *ctx);

#endif
