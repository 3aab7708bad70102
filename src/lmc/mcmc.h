/*
 * mcmc.h: the Markov chain Monte Carlo integrators (pssmlt, mmlt, lmc) as
 * the command line sees them.
 */
#ifndef LMC_MCMC_MCMC_H
#define LMC_MCMC_MCMC_H

#include "render/film.h"
#include "render/integrator.h"
#include "render/scene.h"
#include "render/settings.h"

/* 1 when `name` is one of the MCMC integrators: pssmlt, mmlt, lmc. */
int mcmc_is_integrator(const char *name);

/* The small-step factor for a coordinate that picks an area light's
 * triangle: 1 / (largest triangle count of an area light of s), 1 when no
 * area light has more than one triangle (see mcmc.c). */
double mcmc_light_u1_scale(const scene *s);

/* Fills OUT_scale[0 .. dim-1] for a camera stream in pt_li's layout
 * (integrator.h; pssmlt and lmc): 1, except mcmc_light_u1_scale(s) on the
 * first light-position number of every bounce, PT_DIMS_CAMERA +
 * PT_DIMS_PER_BOUNCE b + 1, which picks the triangle of next-event
 * estimation's light sample. */
void mcmc_pt_step_scale(const scene *s, int dim, double *OUT_scale);

/* Renders s with the MCMC integrator rs->integrator into `out` (created
 * here), as render_run does for pt and bdpt: bootstrap, chains, splats,
 * the image scaled by b / (mutations per pixel). Stops at rs->spp
 * mutations per pixel, at rs->time_limit, or when render_request_stop()
 * is called; the film then holds a correctly normalised image of all
 * mutations so far. Prints one statistics line per proposal type unless
 * rs->quiet. */
/* The contribution of an mmlt state of a length-k family with n strategies
 * (mcmc.c's layout; margin r and area (W + 2r)(H + 2r) of the film grown
 * by the filter radius), read from smp: n_k times the MIS-weighted
 * estimate of its strategy, as the state's image value (not checked for
 * NaN), and its raster position. cam and lp hold BDPT_MAX_VERTICES each;
 * cnt counts the rays. */
rgb mcmc_mmlt_contribution(const scene *s, const render_settings *rs, int k, int n, double margin,
                           double area, lmc_sampler *smp, bdpt_vertex *cam, bdpt_vertex *lp,
                           render_counters *cnt, double *OUT_rx, double *OUT_ry);

/* E[mcmc_mmlt_contribution | all but the technique coordinate]: the sum of
 * the MIS-weighted contributions of every strategy of length k for the
 * subpaths of smp (read in the same layout; the technique number is drawn
 * and ignored), scaled as mcmc_mmlt_contribution without its factor n_k.
 * Its mean is b_k, with far less variance than one strategy times n_k. */
double mcmc_mmlt_expected(const scene *s, const render_settings *rs, int k, double margin,
                          double area, lmc_sampler *smp, bdpt_vertex *cam, bdpt_vertex *lp,
                          render_counters *cnt);

lmc_status mcmc_render_run(const scene *s, const render_settings *rs, film *out,
                           render_stats *st, lmc_error *err);

#endif
