/*
 * kernel_mix.c: the kernel mixes that several integrators share
 * (method.h): Kelemen's and Hachisuka's default mix, and the
 * --largestep-scale rescaling of a mix's probabilities.
 */
#include <math.h>

#include "lmc/driver/method.h"

int mc_kernels_metropolis(const mcmc_settings *ms, const mc_space_family *F, mc_kernel *OUT_k,
                          double *OUT_p) {
  double large = ms->largestep;
  OUT_k[0] = mc_kernel_large();
  OUT_p[0] = large;
  OUT_k[1] = ms->small_gauss ? mc_kernel_small_gauss(ms->sigma)
                             : mc_kernel_small(1.0 / 1024.0, ms->sigma);
  OUT_p[1] = 1.0 - large;
  if (F->technique < 0) return 2;
  /* The technique mutation: the strategy redrawn, the rest small steps. */
  OUT_k[2] = mc_kernel_technique(F->technique);
  OUT_p[1] = (1.0 - ms->technique_prob) * (1.0 - large);
  OUT_p[2] = ms->technique_prob * (1.0 - large);
  return 3;
}

void mc_kernels_scale_large(const mc_kernel *k, double *p, int n, double scale) {
  if (n < 1 || k[0].kind != MC_KERNEL_LARGE || !(p[0] < 1.0)) return;
  double pl = fmin(1.0, p[0] * scale), rest = (1.0 - pl) / (1.0 - p[0]);
  p[0] = pl;
  for (int q = 1; q < n; q++) p[q] *= rest;
}
