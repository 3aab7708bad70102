/*
 * bootstrap.c: the two-phase estimate of b (bootstrap.h).
 */
#include "lmc/driver/bootstrap.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>

#include "render/dist.h"

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
  const double *fe = bt->has_fe ? bt->fe : bt->f;
  double s = 0.0, s2 = 0.0, ps = 0.0, ps2 = 0.0;
  int64_t m = 0, pm = 0, j0 = 0;
  if (bt->upd_n > 0 && bt->upd_n <= n && bt->upd_first == bt->first &&
      bt->upd_split == bt->split) {
    j0 = bt->upd_n;
    s = bt->upd_s, s2 = bt->upd_s2, m = bt->upd_m;
    ps = bt->upd_ps, ps2 = bt->upd_ps2, pm = bt->upd_pm;
  }
  for (int64_t j = j0; j < n; j++) {
    int est = j >= bt->first && (!bt->split || (j - bt->first) % 2 == 1);
    if (est) {
      s += fe[j], s2 += fe[j] * fe[j], m++;
    } else {
      ps += fe[j], ps2 += fe[j] * fe[j], pm++;
    }
  }
  bt->upd_n = n, bt->upd_first = bt->first, bt->upd_split = bt->split;
  bt->upd_s = s, bt->upd_s2 = s2, bt->upd_m = m;
  bt->upd_ps = ps, bt->upd_ps2 = ps2, bt->upd_pm = pm;
  double mean = m > 0 ? s / (double)m : 0.0;
  double var = m > 1 ? fmax(0.0, (s2 - (double)m * mean * mean) / (double)(m - 1)) : 0.0;
  double pmean = pm > 0 ? ps / (double)pm : 0.0;
  double pvar = pm > 1 ? fmax(0.0, (ps2 - (double)pm * pmean * pmean) / (double)(pm - 1)) : 0.0;
  bt->n = n;
  bt->n_est = m;
  bt->b = mean;
  bt->b_var = m > 0 ? var / (double)m : 0.0;
  bt->s = s;
  bt->s2 = s2;
  bt->n_plan = pm;
  bt->plan_b = pmean;
  bt->plan_var = pvar;
}

void mc_boot_shares(const mc_boot *boot, int n_fam, double *OUT_share) {
  double wsum = 0.0, ssum = 0.0;
  for (int g = 0; g < n_fam; g++) {
    const mc_boot *B = &boot[g];
    double n = (double)B->n;
    double cost = n > 0.0 ? fmax(1.0, B->cost / n) : 1.0;
    double v = isfinite(B->plan_var) ? B->plan_var : 0.0;
    OUT_share[g] = sqrt(v / cost); /* the weight, for now */
    wsum += OUT_share[g];
  }
  for (int g = 0; g < n_fam; g++) {
    double share = wsum > 0.0 ? OUT_share[g] / wsum : 1.0 / n_fam;
    OUT_share[g] = fmax(share, 1.0 / (8.0 * n_fam));
    ssum += OUT_share[g];
  }
  for (int g = 0; g < n_fam; g++) OUT_share[g] /= ssum;
}

double mc_boot_rel_err(const mc_boot *boot, int n_fam, const int64_t *n_est) {
  double var = 0.0, b = 0.0;
  for (int g = 0; g < n_fam; g++) {
    double v = isfinite(boot[g].plan_var) ? boot[g].plan_var : 0.0;
    if (v > 0.0) var += n_est[g] > 0 ? v / (double)n_est[g] : INFINITY;
    b += boot[g].plan_b;
  }
  if (var == 0.0) return 0.0;
  return b > 0.0 ? sqrt(var) / b : INFINITY;
}

/* Draws up to to[g] for every family and updates the figures. */
static void boot__draw(mc_boot *boot, int n_fam, int64_t *to, mc_boot_draw_fn draw, void *ctx) {
  draw(ctx, boot, n_fam, to);
  for (int g = 0; g < n_fam; g++) mc_boot_update(&boot[g], to[g] > boot[g].n ? to[g] : boot[g].n);
}

int mc_boot_run(mc_boot *boot, int n_fam, const mc_boot_params *p, mc_boot_draw_fn draw,
                void *ctx) {
  const double t0 = omp_get_wtime();
  int64_t *to = malloc((size_t)n_fam * sizeof(int64_t));
  int64_t *n_est = malloc((size_t)n_fam * sizeof(int64_t));
  double *share = malloc((size_t)n_fam * sizeof(double));
  int status = 0;
  if (!to || !n_est || !share) {
    status = 1;
    goto done;
  }

  /* The pilot (or all of a fixed size): every sample estimates for now. */
  const int64_t pilot = p->fixed > 0 ? p->fixed : p->batch;
  for (int g = 0; g < n_fam; g++) {
    boot[g].n = boot[g].first = boot[g].upd_n = 0;
    boot[g].split = 0;
    if (!mc_boot_reserve(&boot[g], pilot)) {
      status = 1;
      goto done;
    }
    to[g] = pilot;
  }
  boot__draw(boot, n_fam, to, draw, ctx);
  if (p->fixed > 0 || dist_any(p->stop && p->stop())) goto done;

  /* The main phase: the pilot becomes planning only. */
  const int timed = isfinite(p->seconds);
  for (int g = 0; g < n_fam; g++) {
    boot[g].first = boot[g].n;
    boot[g].split = !timed;
    mc_boot_update(&boot[g], boot[g].n);
  }
  mc_boot_shares(boot, n_fam, share);
  int64_t drawn = pilot * n_fam;
  while (drawn < p->cap_total) {
    /* This batch's samples per family: its share, twice when split (the
     * planning sample first, then the estimating one). */
    const int per = timed ? 1 : 2;
    int64_t total = p->batch * n_fam, added = 0;
    if (total * per > p->cap_total - drawn) total = (p->cap_total - drawn) / per;
    if (total <= 0) break;
    for (int g = 0; g < n_fam; g++) {
      int64_t add = (int64_t)((double)total * share[g]);
      to[g] = boot[g].n + per * (add > 0 ? add : 1);
      if (!mc_boot_reserve(&boot[g], to[g])) to[g] = boot[g].n;
      added += to[g] - boot[g].n;
    }
    if (added == 0) break;
    boot__draw(boot, n_fam, to, draw, ctx);
    drawn += added;
    /* (Over several ranks the first to reach the time or a stop decides.) */
    if (dist_any((timed && omp_get_wtime() - t0 > p->seconds) || (p->stop && p->stop()))) break;
    if (!timed) {
      for (int g = 0; g < n_fam; g++) n_est[g] = boot[g].n_est;
      if (mc_boot_rel_err(boot, n_fam, n_est) < p->rel_err) break;
      mc_boot_shares(boot, n_fam, share);
    }
  }
  /* A family the main phase did not reach keeps the pilot's estimate. */
  for (int g = 0; g < n_fam; g++)
    if (boot[g].n_est == 0) {
      boot[g].first = 0;
      boot[g].split = 0;
      mc_boot_update(&boot[g], boot[g].n);
    }
done:
  free(to), free(n_est), free(share);
  return status;
}
