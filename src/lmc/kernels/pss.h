/*
 * pss.h: a chain's lazy primary sample vector (Kelemen, Szirmay-Kalos,
 * Antal and Csonka 2002, "A simple and robust mutation strategy for the
 * Metropolis light transport algorithm"), internal to the chain (chain.c);
 * pss.c has the model. The target reads coordinates through `base`.
 */
#ifndef LMC_MCMC_PSS_H
#define LMC_MCMC_PSS_H

#include <stdint.h>

#include "lmc/kernels/chain.h"

#define PSS_MAX_REPLAY 64 /* 16 made mmlt worse on ring-caustics: 0.0141 against 0.0108 at 60 s */
#define PSS_STEP_TABLE 256 /* Kelemen's step lengths, tabulated (chain__kelemen) */

struct mc_pss {
  lmc_sampler base; /* reads coordinates (the target draws from it) */
  int dim;
  int stream_off[LMC_STREAM_COUNT], stream_dim[LMC_STREAM_COUNT];
  int stream, pos[LMC_STREAM_COUNT];
  double *val, *bak;
  int64_t *mod, *mod_bak;
  int *touched, n_touched;
  int64_t iter, last_large;
  int large;        /* the proposal being evaluated is a large step */
  double s1, s2;    /* the chain's small step (owed steps are replayed with it) */
  double step_table[PSS_STEP_TABLE + 1]; /* Kelemen: (s1 / s2)^(i / PSS_STEP_TABLE) */
  const double *scale; /* per-coordinate factor on s1, s2 (target.h; NULL: 1) */
  rng *r;
  int64_t *overflow;
};

/* A vector of dim coordinates (NULL: out of memory); destroy accepts NULL. */
mc_pss *mc_pss_create(int dim);
void mc_pss_destroy(mc_pss *p);
/* Its layout (the target's streams), its small step (s1, s2, the
 * target's step scales), the chain's generator and overflow counter. */
void mc_pss_init(mc_pss *p, const mc_target *target, double s1, double s2, rng *r,
                 int64_t *overflow);

/* Coordinate i brought up to date / set (backed up first). */
double mc_pss_get(mc_pss *p, int i);
void mc_pss_set(mc_pss *p, int i, double v);
/* Reading restarts at every stream's first coordinate. */
void mc_pss_rewind(mc_pss *p);
/* An iteration begins (large: a large step is proposed); it is accepted
 * or rejected (every coordinate it touched restored). */
void mc_pss_begin(mc_pss *p, int large);
void mc_pss_accept(mc_pss *p);
void mc_pss_reject(mc_pss *p);
/* Every coordinate brought up to date, into OUT_u (dim). */
void mc_pss_materialise(mc_pss *p, double *OUT_u);

#endif
