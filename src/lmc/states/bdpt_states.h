/*
 * bdpt_states.h: the bdpt states (--states bdpt) as a labelled mc_target
 * (target.h), for pssmlt, lmc and h2mc.
 *
 * A state is the numbers of one BDPT sample in bdpt_li's layout
 * (integrator.h: the film position and the camera subpath, the light
 * subpath, one connect triple per camera vertex) and a label, one strategy
 * (s, t) of a path length in [kmin, kmax]. One family of chains covers
 * every length. The target of label (s, t) is the strategy's MIS-weighted
 * contribution (A L for t >= 2, A = (W + 2r)(H + 2r) the film grown by
 * the filter radius r; the light-tracing splat for t = 1), so the labels'
 * sum F(u) is the whole BDPT sample and b = E[F] is BDPT's estimate of the
 * image's sum, with BDPT's variance: no per-length normalisation.
 *
 * Kernels (chain.h). Small steps and LMC's steps keep the label, move the
 * numbers of its two subpaths (and for s = 1 its light sample) and
 * evaluate that strategy alone, at the cost of its own rays. The large
 * step draws a whole BDPT sample, splats every strategy of it and moves
 * to one chosen in proportion to its contribution, with the exact ratio
 * F(u') / F(u). This is the state space of the LMC paper's implementation
 * (Luan et al. 2020, on Li et al.'s dpt), whose large step uses an
 * inexact ratio in place of F(u); here F(u) of a state moved by small
 * steps is computed by a Russian roulette when needed (chain.h).
 *
 * Absolute directions (rough_min < 1). A label's own coordinates read the
 * direction of every rough scattering vertex of its subpaths (a BSDF with
 * no delta lobe and roughness above rough_min, bsdf_is_rough) as world
 * spherical coordinates (integrator.h, bdpt_param), so that a small step
 * of the camera's numbers leaves the later directions in place instead of
 * swinging them round with the shading frame: paths through a glass box
 * to the sun, a door gap or a caustic stay valid under small moves of
 * their first vertices. The large step samples BSDF-relative numbers;
 * relabel rewrites the chosen strategy's rough directions into spherical
 * coordinates (their lobe numbers, unused there, fresh), and the state's
 * density in its coordinates is f times the product of pdf J over those
 * vertices (BSDF density times the sphere map's solid angle per unit
 * square). The LMC paper's implementation does the same above roughness
 * 0.05 (its roughnessThreshold), with the discrete numbers perturbed too.
 *
 * Gradients (lmc): eval_label with a gradient runs path_eval_bdpt_abs
 * (render/integrators/path.h) on the same numbers, the plain evaluation otherwise
 * (the same value to about 1e-9, and faster).
 *
 * Media: on a scene with participating media (unless rs.no_media) the
 * subpaths and the connections run through them as bdpt_li's do, each
 * vertex's numbers led by its free flight's two (a surface or a
 * scattering point in a medium); no gradients there yet (eval_label with
 * a gradient fails, no eval_hess), so only the kernels without them
 * (pssmlt's) run on such a target.
 */
#ifndef LMC_MCMC_BDPT_STATES_H
#define LMC_MCMC_BDPT_STATES_H

#include <stdint.h>

#include "lmc/kernels/target.h"
#include "render/error.h"
#include "render/integrators/integrator.h"
#include "render/scene.h"
#include "render/settings.h"

#define MC_BDPT_UNBOUNDED (BDPT_MAX_VERTICES - 2) /* the longest path (segments) when maxdepth is
                                                    -1: subpaths of BDPT_MAX_VERTICES vertices */

typedef struct mc_strategy {
  int s, t;
} mc_strategy;

typedef struct mc_bdpt_states {
  const scene *s;      /* borrowed */
  render_settings rs;  /* mindepth -1, maxdepth kmax: the labels decide */
  double margin, area; /* filter radius r, (W + 2r)(H + 2r) */
  double rough_min;    /* absolute directions above this roughness (>= 1: none) */
  int kmin, kmax;
  int n_labels;
  mc_strategy *strat;  /* owned: label -> (s, t) */
  short *label_of;     /* owned: label of (s, t) at s (kmax + 2) + t, -1 for none */
  double *step_scale;  /* owned: the target's step_scale (light-position numbers) */
  int media;           /* through the scene's media (it has some, rs.no_media unset): each
                          vertex's numbers then begin with its flight's BDPT_DIMS_MEDIA */
  int per_vertex;      /* numbers per subpath vertex: BDPT_DIMS_PER_VERTEX (+ BDPT_DIMS_MEDIA) */
  int dir_at;          /* where a vertex's direction pair begins among them (1, or 3) */
} mc_bdpt_states;

/* Sets up *OUT_target over ctx (both owned by the caller; ctx must outlive
 * the target and be freed with mc_bdpt_states_free) for the lengths kmin ..
 * kmax of scene s, with rs's depths and roulette; directions at vertices
 * rougher than rough_min are absolute (>= 1: none; --roughness-threshold). */
lmc_status mc_bdpt_states_init(mc_target *OUT_target, mc_bdpt_states *ctx, const scene *s,
                               const render_settings *rs, double rough_min, int kmin, int kmax,
                               lmc_error *err);
void mc_bdpt_states_free(mc_bdpt_states *ctx);

/* Path length (segments) of a label. */
int mc_bdpt_states_length(const mc_bdpt_states *ctx, int label);

/* The value of label (s, t) (eval_label's f, value, raster point and
 * f_large) from its walked subpaths cam[0 .. t-1] and lp[0 .. s-1], made
 * from its numbers with the label's parametrization (bdpt_param {t - 1,
 * rough_min} and {s - 1, rough_min}; the camera walk through (rx, ry), or
 * (0, 0) for t = 1), and for s = 1 the connect triple uc (else zeros). */
void mc_bdpt_states_value(const mc_bdpt_states *ctx, const bdpt_vertex *cam, int t,
                          const bdpt_vertex *lp, int s, const double *uc, double rx, double ry,
                          mc_value *OUT_value, render_counters *cnt);


#endif
