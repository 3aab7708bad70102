/*
 * kernel_mix.h: the mix of kernels every primary-sample integrator's
 * chains make (kernel_mix.c), written once for pssmlt, mmlt, lmc and h2mc.
 *
 * The mix of Kelemen et al. 2002 and Hachisuka et al. 2014: the large step
 * (a fresh uniform sample) with probability `large`, Kelemen's small step
 * (offsets log-uniform in (s1, s2], or Gaussian of scale sigma) and, on a
 * family with a strategy coordinate, the technique mutation (that
 * coordinate redrawn, the others small steps) with `technique` of what the
 * large step leaves. An integrator with a proposal of its own (lmc's MALA,
 * h2mc's Gaussian) gives the small step a fixed probability `small`; its
 * proposal takes what is left, and on families of short paths (1 <=
 * length < min_length, where f is smooth and a gradient costs more than it
 * saves) nothing: the chain renormalises the rest. An optional `extra`
 * kernel (lmc's independence proposal) comes last with probability
 * `extra`.
 *
 * The order of the kernels: large, small, own, technique, extra. The large
 * step is kernel 0, as mc_kernels_scale_large and the space's moves
 * (space.h's add_kernels) expect. The numbers come from the caller (the
 * driver's flags, mcmc_settings, through mc_mix_params_from in method.h);
 * this header knows nothing of the driver.
 */
#ifndef LMC_KERNELS_KERNEL_MIX_H
#define LMC_KERNELS_KERNEL_MIX_H

#include "lmc/kernels/chain.h"

/* The numbers of one chain's mix. */
typedef struct mc_mix_params {
  double large;     /* the large step's probability */
  double technique; /* the technique mutation's share of 1 - large */
  int coord;        /* the strategy coordinate the technique mutation redraws; -1: none */
  int gauss;        /* 1: Gaussian small steps of scale sigma; 0: Kelemen's, in (s1, s2] */
  double sigma;     /* the Gaussian small step's standard deviation */
  double s1, s2;    /* Kelemen's small step's offsets (0 < s1 < s2 < 1/2) */
  /* With a proposal of the integrator's own (mc_kernels_metropolis's own): */
  double small;     /* the small step's probability (own takes what is left) */
  double extra;     /* the extra kernel's probability (> 0 to add it) */
  int length;       /* the family's path length (0: all lengths) */
  int min_length;   /* own gets nothing on families with 1 <= length < min_length */
} mc_mix_params;

/* Writes the mix of mp into OUT_k[] and OUT_p[] (room for MC_MAX_KERNELS)
 * and returns the kernels' count. own (may be NULL: Kelemen's and
 * Hachisuka's mix, the small step taking (1 - technique) (1 - large)) is
 * the integrator's proposal, extra (may be NULL) a last kernel; both are
 * copied. Without own, the technique mutation is in the mix whenever
 * coord >= 0; with own, when its probability is positive. */
int mc_kernels_metropolis(const mc_mix_params *mp, const mc_kernel *own, const mc_kernel *extra,
                          mc_kernel *OUT_k, double *OUT_p);

/* --largestep-scale: the large step's probability (kernel 0, when it is
 * the large step) times scale, at most 1, and the others' together scaled
 * by what is left. */
void mc_kernels_scale_large(const mc_kernel *k, double *p, int n, double scale);

#endif
