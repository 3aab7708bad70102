/*
 * mmlt_states.h: the mmlt states (--states mmlt, mmlt_states.c): one
 * family of chains per path length, a state being the strategy (s, t) and
 * its camera, light and connect streams (Hachisuka et al. 2014), with f,
 * its gradient and its Hessian.
 */
#ifndef LMC_MCMC_MMLT_STATES_H
#define LMC_MCMC_MMLT_STATES_H

#include "lmc/kernels/target.h"
#include "render/error.h"
#include "render/scene.h"
#include "render/settings.h"

#define MC_MMLT_UNBOUNDED 24    /* the longest path (segments) when maxdepth is -1 */
#define MC_MMLT_MAX_FAMILIES 64 /* lengths, at most */
/* The small step's default scale on these states (without --sigma): on
 * ring-caustics at 20 s, once the light-position steps were scaled
 * (mc_light_u1_scale), 0.05 gave relative MSE 0.10 against 0.17 - 0.28 for
 * 1/64, 0.03, 0.1 and 0.2, one run each. */
#define MC_MMLT_SIGMA 0.05

/* One length's target and what it reads. */
typedef struct mc_mmlt_states {
  const scene *s;      /* borrowed */
  render_settings rs;  /* mindepth -1: the family's length is what counts */
  int length;          /* k, segments */
  int n_strategies;    /* n_k: 1 for k = 1, else k + 1 */
  double margin;       /* filter radius r */
  double area;         /* (W + 2r)(H + 2r) */
  double *step_scale;  /* owned: the target's step_scale */
  int media;           /* through the scene's media (rs.no_media unset): each subpath
                          vertex's numbers led by its flight's; no gradients there yet */
  int per_vertex;      /* numbers per subpath vertex: BDPT_DIMS_PER_VERTEX (+ BDPT_DIMS_MEDIA) */
} mc_mmlt_states;

/* Sets up *OUT_target for paths of `length` segments over ctx (both owned
 * by the caller; ctx must outlive the target and be freed with
 * mc_mmlt_states_free). */
lmc_status mc_mmlt_states_init(mc_target *OUT_target, mc_mmlt_states *ctx, const scene *s,
                               const render_settings *rs, int length, lmc_error *err);
void mc_mmlt_states_free(mc_mmlt_states *ctx);

#endif
