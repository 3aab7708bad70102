/*
 * mcmc.h: the Markov chain Monte Carlo integrators (every table of registry.c:
 * pssmlt, mmlt, lmc, h2mc) as the command line sees them.
 */
#ifndef LMC_MCMC_MCMC_H
#define LMC_MCMC_MCMC_H

#include "render/film.h"
#include "render/integrators/integrator.h"
#include "render/options.h"
#include "render/scene.h"
#include "render/settings.h"

/* 1 when `name` names an MCMC integrator (mc_method_find, method.h). */
int mcmc_is_integrator(const char *name);

/* The flags besides the renderer's own, for the command line: direct's
 * (render/integrators/integrator.h), then the MCMC integrators': the
 * driver's, each state space's and each integrator's (render/options.h),
 * up to max tables into OUT; returns their count. */
int mcmc_option_tables(const lmc_opt_table **OUT, int max);

/* Sets the flag `name` (without dashes) of any table to value in *rs, as
 * `--name value` on the command line would (lmc_opt_set). Fails with
 * LMC_EINVAL and the message on an unknown flag or a bad value. */
lmc_status mcmc_set(render_settings *rs, const char *name, const char *value, lmc_error *err);

/* The settings of scene s: its own (s->settings), then its passed-on
 * <integrator>/<dpt> parameters through every table (the renderer's and
 * mcmc_option_tables'), into *OUT. Fails on a bad value (file, line). */
lmc_status mcmc_scene_settings(const scene *s, render_settings *OUT, lmc_error *err);

/* 1 when the MCMC integrator rs->integrator renders a scene's
 * participating media with rs's flags (its states among its
 * media_states, method.h, and neither --technique-jump nor
 * --path-mutations: the inverse path sampler has no medium vertices yet);
 * 0 otherwise, and for any other name. */
int mcmc_renders_media(const render_settings *rs);

/* The MCMC integrators' names, up to max into OUT; returns their count. */
int mcmc_integrator_names(const char **OUT, int max);

/* Renders s with the MCMC integrator rs->integrator into `out` (created
 * here), as render_run does for pt and bdpt: bootstrap, chains, splats,
 * the image scaled by b / (mutations per pixel). Stops at rs->spp
 * mutations per pixel, at rs->time_limit, or when render_request_stop()
 * is called; the film then holds a correctly normalised image of all
 * mutations so far. Prints one statistics line per proposal type unless
 * rs->quiet. */
lmc_status mcmc_render_run(const scene *s, const render_settings *rs, film *out,
                           render_stats *st, lmc_error *err);

#endif
