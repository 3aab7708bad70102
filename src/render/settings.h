/*
 * settings.h: how to render. Filled from the scene's <integrator> or <dpt>
 * block first, then overridden by the command line. Each field has a bit in
 * `set` so a later source can tell what an earlier one chose explicitly.
 */
#ifndef LMC_RENDER_SETTINGS_H
#define LMC_RENDER_SETTINGS_H

#include <stdint.h>

struct film; /* render/film.h */

enum {
  SET_INTEGRATOR = 1 << 0,
  SET_MAXDEPTH = 1 << 1,
  SET_RRDEPTH = 1 << 2,
  SET_SPP = 1 << 3,
  SET_TIME = 1 << 4,
  SET_MINDEPTH = 1 << 5,
  SET_SAMPLER = 1 << 6
};

/* Room for a network address "HOST:PORT" (options.h's LMC_OPT_ADDRESS). */
#define LMC_ADDRESS_MAX 264

/* A plugin's own setting as checked text (render/options.h). */
#define LMC_MAX_PARAMS 48
typedef struct lmc_param {
  char name[32];
  char value[96];
} lmc_param;

typedef struct render_settings {
  unsigned set;          /* SET_* bits of the fields chosen explicitly */
  char integrator[32];   /* pt, bdpt, pssmlt, mmlt, lmc, h2mc */
  int maxdepth;          /* Mitsuba's maxDepth: longest path in segments; -1 unbounded */
  int mindepth;          /* shortest path in segments that is counted (-1: all) */
  int rrdepth;           /* Russian roulette from this many segments on */
  int64_t spp;           /* samples (or mutations) per pixel */
  double time_limit;     /* seconds; 0 = none (spp decides) */
  int threads;           /* 0 = all cores */
  uint64_t seed;
  int sampler;           /* pt and bdpt: LMC_SAMPLER_INDEPENDENT or _SOBOL (render/sampler.h) */
  double snapshot;       /* seconds between intermediate images (0: none) */
  char display_server[LMC_ADDRESS_MAX]; /* --display-server HOST[:PORT] of a tev viewer ("": none) */
  double display_interval;              /* seconds between the images sent to it */
  int error;             /* --error on: each pixel's standard error in the EXR */
  /* Called by the render drivers every `snapshot` seconds with the film
   * normalised as if the render stopped then (borrowed for the call) and
   * the seconds since the render began. cli/render.c hooks the files of
   * --snapshot and the images of --display-server here, each at its own
   * interval: it sets `snapshot` to the shorter of the two for the
   * drivers. NULL: none. */
  void (*snapshot_fn)(void *ctx, const struct film *f, double seconds);
  void *snapshot_ctx;
  /* The settings of the MCMC driver, the state spaces and the integrators,
   * as checked text (their tables, render/options.h). */
  lmc_param params[LMC_MAX_PARAMS];
  int n_params;
  int quiet;             /* no progress bar */
  int strict;            /* --strict: what would render wrong stops the render (LMC_ESTRICT) */
  int no_media;          /* pt renders the scene's media as empty space (the MCMC driver's
                            direct pass, beside chains that do not render media) */
} render_settings;

static inline render_settings render_settings_default(void) {
  render_settings s = {0};
  s.integrator[0] = 'p';
  s.integrator[1] = 't';
  s.maxdepth = -1;
  s.mindepth = -1;
  s.rrdepth = 5;
  s.spp = 16;
  s.seed = 1;
  s.display_interval = 1.0;
  return s;
}

#endif
