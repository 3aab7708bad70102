/*
 * bootstrap.c: the two-phase estimate of b (bootstrap.h).
 */
#include "lmc/bootstrap.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>

int mc_boot_reserve(mc_boot *bt, int64_t n) {
  if (n <= bt->cap) return 1;
  int64_t c = bt->cap > 0 ? bt->cap : n;
  while (c < n) c *= 2;
  double *f = realloc(bt->f, (size_t)c * sizeof(double));
  if (!f) return 0;
  bt->f = f;
  if (bt->has_fe) {
    double *fe = realloc(bt->fe, (size_t)c * sizeof(double));
    if (!fe) return 0;
    bt->fe = fe;
  }
  bt->cap = c;
  return 1;
}

void mc_boot_free(mc_boot *bt) {
  free(bt->f);
  free(bt->fe);
  bt->f = bt->fe = NULL;
  bt->cap = 0;
}

void mc_boot_update(mc_boot *bt, int64_t n) {
  const double *f = bt->has_fe ? bt->fe : bt->f;
  double s = 0.0, s2 = 0.0;
  for (int64_t j = bt->first; j < n; j++) s += f[j], s2 += f[j] * f[j];
  int64_t m = n - bt->first;
  double mean = m > 0 ? s / (double)m : 0.0;
  double var = m > 1 ? fmax(0.0, (s2 - (double)m * mean * mean) / (double)(m - 1)) : 0.0;
  bt->n = n;
  bt->b = mean;
  bt->b_var = m > 0 ? var / (double)m : 0.0;
  bt->s = s;
  bt->s2 = s2;
}

int64_t mc_boot_plan(const mc_boot *boot, int n_fam, double rel_err, int64_t batch, int64_t left,
                     double *OUT_share) {
  double wsum = 0.0, b = 0.0, ssum = 0.0, need = 0.0;
  for (int g = 0; g < n_fam; g++) {
    const mc_boot *B = &boot[g];
    double n = (double)(B->n - B->first);
    double sd2 = n > 0.0 && isfinite(B->b_var) ? B->b_var * n : 0.0;
    double cost = n > 0.0 ? fmax(1.0, B->cost / n) : 1.0;
    OUT_share[g] = sqrt(sd2 / cost); /* the weight, for now */
    wsum += OUT_share[g];
    b += B->b;
  }
  for (int g = 0; g < n_fam; g++) {
    double share = wsum > 0.0 ? OUT_share[g] / wsum : 1.0 / n_fam;
    OUT_share[g] = fmax(share, 1.0 / (8.0 * n_fam));
    ssum += OUT_share[g];
  }
  for (int g = 0; g < n_fam; g++) {
    const mc_boot *B = &boot[g];
    double n = (double)(B->n - B->first);
    double sd2 = n > 0.0 && isfinite(B->b_var) ? B->b_var * n : 0.0;
    OUT_share[g] /= ssum;
    need += sd2 / OUT_share[g]; /* Var(sum_g b_g) = sum_g sd_g^2 / (N share_g) */
  }
  double N = b > 0.0 && rel_err > 0.0 ? need / (rel_err * b * rel_err * b) : 0.0;
  int64_t n = N < (double)left ? (int64_t)ceil(N) : left;
  if (n < batch * n_fam) n = batch * n_fam;
  return n < left ? n : left;
}

/* Draws up to to[g] for every family and updates the estimates. */
static void boot__draw(mc_boot *boot, int n_fam, int64_t *to, mc_boot_draw_fn draw, void *ctx) {
  draw(ctx, boot, n_fam, to);
  for (int g = 0; g < n_fam; g++) mc_boot_update(&boot[g], to[g] > boot[g].n ? to[g] : boot[g].n);
}

int mc_boot_run(mc_boot *boot, int n_fam, const mc_boot_params *p, mc_boot_draw_fn draw,
                void *ctx) {
  const double t0 = omp_get_wtime();
  int64_t *to = malloc((size_t)n_fam * sizeof(int64_t));
  double *share = malloc((size_t)n_fam * sizeof(double));
  if (!to || !share) {
    free(to), free(share);
    return 1;
  }
  const int64_t pilot = p->fixed > 0 ? p->fixed : p->batch;
  for (int g = 0; g < n_fam; g++) {
    boot[g].n = boot[g].first = 0;
    if (!mc_boot_reserve(&boot[g], pilot)) {
      free(to), free(share);
      return 1;
    }
    to[g] = pilot;
  }
  boot__draw(boot, n_fam, to, draw, ctx);
  if (p->fixed > 0 || (p->stop && p->stop())) {
    free(to), free(share);
    return 0;
  }

  int64_t left =
      mc_boot_plan(boot, n_fam, p->rel_err, p->batch, p->cap_total - pilot * n_fam, share);
  for (int g = 0; g < n_fam; g++) boot[g].first = boot[g].n;
  while (left > 0) {
    int64_t total = p->batch * n_fam, added = 0;
    if (total > left) total = left;
    for (int g = 0; g < n_fam; g++) {
      int64_t add = (int64_t)((double)total * share[g]);
      to[g] = boot[g].n + (add > 0 ? add : 1);
      if (!mc_boot_reserve(&boot[g], to[g])) to[g] = boot[g].n;
      added += to[g] - boot[g].n;
    }
    if (added == 0) break;
    boot__draw(boot, n_fam, to, draw, ctx);
    left -= added;
    if (omp_get_wtime() - t0 > p->seconds) break;
    if (p->stop && p->stop()) break;
  }
  for (int g = 0; g < n_fam; g++)
    if (boot[g].n == boot[g].first) {
      boot[g].first = 0;
      mc_boot_update(&boot[g], boot[g].n);
    }
  free(to), free(share);
  return 0;
}
