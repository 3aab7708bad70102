/*
 * states.h: helpers the primary-sample state spaces share (space.h): the
 * step scales of the light-triangle coordinates and the plain-number
 * contribution of the mmlt states (mmlt_states.c).
 */
#ifndef LMC_MCMC_STATES_H
#define LMC_MCMC_STATES_H

#include "lmc/kernels/target.h"
#include "render/integrators/integrator.h"
#include "render/integrators/path.h"
#include "render/sampler.h"
#include "render/scene.h"
#include "render/settings.h"

/* The small-step factor for a coordinate that picks an area light's
 * triangle: 1 / (largest triangle count of an area light of s), 1 when no
 * area light has more than one triangle (see states.c). */
double mc_light_u1_scale(const scene *s);

/* Fills OUT_scale[0 .. dim-1] for a camera stream in pt_li's layout
 * (integrator.h; pssmlt and lmc), or with media set pt_li_media's (each
 * bounce led by its flight's PT_DIMS_MEDIA numbers): 1, except
 * mc_light_u1_scale(s) on the first light-position number of every
 * bounce, PT_DIMS_CAMERA + (PT_DIMS_PER_BOUNCE + lead) b + lead + 1, which
 * picks the triangle of next-event estimation's light sample. */
void mc_pt_step_scale(const scene *s, int dim, int media, double *OUT_scale);

/* The contribution of an mmlt state of a length-k family with n strategies
 * (the layout of mcmc.c's header; margin r and area (W + 2r)(H + 2r) of
 * the film grown by the filter radius), read from smp: n_k times the MIS-weighted
 * estimate of its strategy, as the state's image value (not checked for
 * NaN), and its raster position. cam and lp hold BDPT_MAX_VERTICES each;
 * cnt counts the rays. */
rgb mc_mmlt_contribution(const scene *s, const render_settings *rs, int k, int n, double margin,
                         double area, lmc_sampler *smp, bdpt_vertex *cam, bdpt_vertex *lp,
                         render_counters *cnt, double *OUT_rx, double *OUT_ry);

/* Its last part: the value of strategy (s, t) from the walked subpaths
 * cam[0 .. t-1] and lp[0 .. s-1] and, for s = 1, the light sample's
 * numbers uc; *IO_rx, *IO_ry hold the film numbers' raster point and get
 * the splat's for t = 1. */
rgb mc_mmlt_connect(const scene *sc, const bdpt_vertex *cam, int t, const bdpt_vertex *lp, int s,
                    const double *uc, int n, double area, render_counters *cnt, double *IO_rx,
                    double *IO_ry);

/* E[mc_mmlt_contribution | all but the technique coordinate]: the sum of
 * the MIS-weighted contributions of every strategy of length k for the
 * subpaths of smp (read in the same layout; the technique number is drawn
 * and ignored), scaled as mc_mmlt_contribution without its factor n_k.
 * Its mean is b_k, with far less variance than one strategy times n_k. */
double mc_mmlt_expected(const scene *s, const render_settings *rs, int k, double margin,
                        double area, lmc_sampler *smp, bdpt_vertex *cam, bdpt_vertex *lp,
                        render_counters *cnt);

/* A chain's scratch for a space's target (target.h's scratch functions,
 * set by mc_states_use_scratch): the plain evaluations' counters and BDPT
 * subpaths, and for derivatives a path scratch made on first use. */
typedef struct mc_states_scratch {
  render_counters cnt; /* plain evaluations: rays and non-finite contributions */
  bdpt_vertex cam[BDPT_MAX_VERTICES], lp[BDPT_MAX_VERTICES];
  path_scratch *ps;    /* owned: NULL until mc_states_scratch_path needs it unbound */
  path_scratch *bound; /* borrowed: the thread's workspace (scratch_bind), or NULL */
  int64_t rays_d;      /* rays of the evaluations with derivatives */
  mc_counts counts;    /* evaluations with derivatives (and their non-finite contributions) */
} mc_states_scratch;

/* Sets T's scratch_create, _destroy, _rays and _counts to mc_states_scratch's,
 * and its workspace hooks (a workspace is a path_scratch). */
void mc_states_use_scratch(mc_target *T);
/* The path scratch for derivatives: the bound workspace, else the scratch's
 * own, made on first use (NULL: out of memory). */
path_scratch *mc_states_scratch_path(mc_states_scratch *sc);

/* Sets v from a state's contribution c at raster (rx, ry): a non-finite c
 * is dropped (f = 0) and counted in *nan_samples, as is (uncounted) one of
 * luminance <= 0; f and f_large are the luminance. Returns f. */
double mc_states_value(mc_value *v, rgb c, double rx, double ry, int64_t *nan_samples);

/* The Hessian of f over the state's coordinates from a path evaluation's
 * Hessian of the luminance (pe->hlum over its nd = pe->n_diff slots): slot
 * j is coordinate coord[j] (-1: not one of the state's) with chain-rule
 * factor m[j]; entries scale m_a m_b d^2 lum, over the slots kept in slot
 * order, to OUT_hidx (*OUT_hn of them) and OUT_hess (target.h's packing).
 * Returns 1, or 0 when an entry is not finite. */
int mc_states_hessian(const path_eval *pe, int nd, const int *coord, const double *m,
                      double scale, int *OUT_hn, int *OUT_hidx, double *OUT_hess);

/* A sampler in front of a target's own that hands the path evaluators of
 * render/integrators/path.h the film numbers they expect: they read the raster
 * position as u W, the spaces' states as -r + u (W + 2r) over the film
 * grown by the filter radius r, so the first two camera numbers become
 * (-r + u (W + 2r)) / W (and H's). Optionally the first `skip` numbers of
 * the connect stream are drawn by the evaluator but not the state's (a
 * constant is returned). */
typedef struct mc_film_adapter {
  lmc_sampler base;
  lmc_sampler *inner;
  int stream;
  int pos[LMC_STREAM_COUNT];
  int skip;
  double r, W, H;
} mc_film_adapter;

/* Starts a in stream `stream` of inner (the stream the evaluator reads first). */
void mc_film_adapter_init(mc_film_adapter *a, lmc_sampler *inner, int stream, int skip, double r,
                          double W, double H);
/* The chain-rule factor d(evaluator's number) / d(state's number) of
 * number pos of stream k: (W + 2r) / W and (H + 2r) / H for the film's, else 1. */
double mc_film_adapter_factor(const mc_film_adapter *a, int k, int pos);

#endif
