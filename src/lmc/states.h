/*
 * states.h: helpers the primary-sample state spaces share (space.h): the
 * step scales of the light-triangle coordinates and the plain-number
 * contribution of the mmlt states (mmlt_states.c).
 */
#ifndef LMC_MCMC_STATES_H
#define LMC_MCMC_STATES_H

#include "render/integrator.h"
#include "render/sampler.h"
#include "render/scene.h"
#include "render/settings.h"

/* The small-step factor for a coordinate that picks an area light's
 * triangle: 1 / (largest triangle count of an area light of s), 1 when no
 * area light has more than one triangle (see states.c). */
double mc_light_u1_scale(const scene *s);

/* Fills OUT_scale[0 .. dim-1] for a camera stream in pt_li's layout
 * (integrator.h; pssmlt and lmc): 1, except mc_light_u1_scale(s) on the
 * first light-position number of every bounce, PT_DIMS_CAMERA +
 * PT_DIMS_PER_BOUNCE b + 1, which picks the triangle of next-event
 * estimation's light sample. */
void mc_pt_step_scale(const scene *s, int dim, double *OUT_scale);

/* The contribution of an mmlt state of a length-k family with n strategies
 * (the layout of mcmc.c's header; margin r and area (W + 2r)(H + 2r) of
 * the film grown by the filter radius), read from smp: n_k times the MIS-weighted
 * estimate of its strategy, as the state's image value (not checked for
 * NaN), and its raster position. cam and lp hold BDPT_MAX_VERTICES each;
 * cnt counts the rays. */
rgb mc_mmlt_contribution(const scene *s, const render_settings *rs, int k, int n, double margin,
                         double area, lmc_sampler *smp, bdpt_vertex *cam, bdpt_vertex *lp,
                         render_counters *cnt, double *OUT_rx, double *OUT_ry);

/* E[mc_mmlt_contribution | all but the technique coordinate]: the sum of
 * the MIS-weighted contributions of every strategy of length k for the
 * subpaths of smp (read in the same layout; the technique number is drawn
 * and ignored), scaled as mc_mmlt_contribution without its factor n_k.
 * Its mean is b_k, with far less variance than one strategy times n_k. */
double mc_mmlt_expected(const scene *s, const render_settings *rs, int k, double margin,
                        double area, lmc_sampler *smp, bdpt_vertex *cam, bdpt_vertex *lp,
                        render_counters *cnt);

#endif
