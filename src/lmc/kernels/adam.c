/*
 * adam.c: Adam moments and the preconditioners built from them (adam.h).
 */
#include "lmc/kernels/adam.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

lmc_status adam_init(adam_stats *a, int cap, lmc_error *err) {
  memset(a, 0, sizeof *a);
  if (cap < 1) return lmc_error_set(err, LMC_EINVAL, NULL, 0, "adam: %d coordinates", cap);
  a->cap = cap;
  /* One block: m1, m2, beta1_t, beta2_t and count (8-byte entries each). */
  size_t n = (size_t)cap;
  double *blk = calloc(5 * n, sizeof(double));
  if (!blk) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "adam: out of memory");
  a->adam_m1 = blk;
  a->adam_m2 = blk + n;
  a->beta1_t = blk + 2 * n;
  a->beta2_t = blk + 3 * n;
  a->count = (int64_t *)(blk + 4 * n);
  for (int i = 0; i < cap; i++) a->beta1_t[i] = a->beta2_t[i] = 1.0;
  return LMC_OK;
}

void adam_free(adam_stats *a) {
  if (!a) return;
  free(a->adam_m1); /* the block */
  memset(a, 0, sizeof *a);
}

void adam_reset(adam_stats *a) {
  memset(a->adam_m1, 0, (size_t)a->cap * sizeof(double));
  memset(a->adam_m2, 0, (size_t)a->cap * sizeof(double));
  memset(a->count, 0, (size_t)a->cap * sizeof(int64_t));
  for (int i = 0; i < a->cap; i++) a->beta1_t[i] = a->beta2_t[i] = 1.0;
  a->t = 0;
}

void adam_update(adam_stats *a, int n, const double *g) {
  if (n > a->cap) n = a->cap;
  for (int i = 0; i < n; i++) {
    a->adam_m1[i] = ADAM_BETA1 * a->adam_m1[i] + (1.0 - ADAM_BETA1) * g[i];
    a->adam_m2[i] = ADAM_BETA2 * a->adam_m2[i] + (1.0 - ADAM_BETA2) * g[i] * g[i];
    a->count[i]++;
    a->beta1_t[i] *= ADAM_BETA1;
    a->beta2_t[i] *= ADAM_BETA2;
  }
  a->t++;
}

void adam_moments(const adam_stats *a, int i, double *OUT_m1, double *OUT_m2) {
  int64_t t = a->count[i];
  if (t == 0) {
    *OUT_m1 = 0.0, *OUT_m2 = 0.0;
    return;
  }
  /* Bias correction: divide by 1 - beta^t (t large: 1), with beta^t kept
   * per coordinate by adam_update (a pow per coordinate and step cost the
   * diminishing schedule several per cent of its time). */
  double c1 = 1.0 - a->beta1_t[i], c2 = 1.0 - a->beta2_t[i];
  *OUT_m1 = a->adam_m1[i] / c1;
  *OUT_m2 = a->adam_m2[i] / c2;
}

void adam_precond(const adam_stats *a, int n, double eps, double lo, double hi, double *OUT_M) {
  for (int i = 0; i < n; i++) {
    if (i >= a->cap || a->count[i] == 0 || a->adam_m2[i] == 0.0) {
      OUT_M[i] = 1.0 < lo ? lo : (1.0 > hi ? hi : 1.0);
      continue;
    }
    double m1, m2;
    adam_moments(a, i, &m1, &m2);
    OUT_M[i] = adam_precond_from_m2(m2, eps, lo, hi);
  }
}

void adam_precond_diminish(const adam_stats *a, int n, double eps, double lo, double hi,
                           double t0, double *OUT_M) {
  adam_precond(a, n, eps, lo, hi, OUT_M);
  double w = a->t > 0 ? t0 / (double)a->t : 1.0;
  if (w > 1.0) w = 1.0;
  for (int i = 0; i < n; i++) OUT_M[i] = (1.0 - w) + w * OUT_M[i];
}
