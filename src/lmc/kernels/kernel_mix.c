/*
 * kernel_mix.c: the mix of kernels that pssmlt, mmlt, lmc and h2mc share
 * (kernel_mix.h): Kelemen's and Hachisuka's large, small and technique
 * steps, with an integrator's own proposal in what they leave; and the
 * --largestep-scale rescaling of a mix's probabilities.
 */
#include "lmc/kernels/kernel_mix.h"

#include <math.h>

int mc_kernels_metropolis(const mc_mix_params *mp, const mc_kernel *own, const mc_kernel *extra,
                          mc_kernel *OUT_k, double *OUT_p) {
  double large = mp->large;
  int n = 0;
  /* The large step, then the small step: Gaussian, or Kelemen's. */
  OUT_k[n] = mc_kernel_large(), OUT_p[n++] = large;
  OUT_k[n] = mp->gauss ? mc_kernel_small_gauss(mp->sigma) : mc_kernel_small(mp->s1, mp->s2);
  if (!own) {
    /* Kelemen's and Hachisuka's mix: the small step takes the rest, less
     * the technique mutation's share of it. */
    if (mp->coord < 0) {
      OUT_p[n++] = 1.0 - large;
      return n;
    }
    OUT_p[n++] = (1.0 - mp->technique) * (1.0 - large);
    OUT_k[n] = mc_kernel_technique(mp->coord);
    OUT_k[n].s1 = mp->s1, OUT_k[n].s2 = mp->s2;
    OUT_p[n++] = mp->technique * (1.0 - large);
    return n;
  }
  /* An integrator's own proposal: the small step a fixed share, the
   * technique mutation its share of the rest, the extra kernel its own. */
  double small = mp->small, xp = extra ? mp->extra : 0.0;
  double tech = mp->coord >= 0 ? mp->technique * (1.0 - large) : 0.0;
  OUT_p[n++] = small;
  /* Short paths: the own proposal's slot gets nothing (up to rounding),
   * the chain renormalises the mix. */
  if (mp->length >= 1 && mp->length < mp->min_length) small = 1.0 - large - xp - tech;
  OUT_k[n] = *own;
  OUT_p[n++] = fmax(0.0, 1.0 - large - small - xp - tech);
  if (tech > 0.0) {
    OUT_k[n] = mc_kernel_technique(mp->coord);
    OUT_k[n].s1 = mp->s1, OUT_k[n].s2 = mp->s2;
    OUT_p[n++] = tech;
  }
  if (xp > 0.0) OUT_k[n] = *extra, OUT_p[n++] = xp;
  return n;
}

void mc_kernels_scale_large(const mc_kernel *k, double *p, int n, double scale) {
  if (n < 1 || k[0].kind != MC_KERNEL_LARGE || !(p[0] < 1.0)) return;
  double pl = fmin(1.0, p[0] * scale), rest = (1.0 - pl) / (1.0 - p[0]);
  p[0] = pl;
  for (int q = 1; q < n; q++) p[q] *= rest;
}
