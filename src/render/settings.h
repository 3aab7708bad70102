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
  SET_LARGESTEP = 1 << 5,
  SET_SIGMA = 1 << 6,
  SET_MINDEPTH = 1 << 7,
  SET_BOOTSTRAP = 1 << 9,
  SET_DIRECT = 1 << 10,
  SET_SAMPLER = 1 << 11,
  SET_SMALL_STEP = 1 << 12,
  SET_LARGESTEP_SCALE = 1 << 13,
  SET_STATES = 1 << 14,
  SET_ROUGH = 1 << 15,
  SET_CHAINS = 1 << 16
};

/* The state space of the MCMC integrators' chains (--states; src/lmc/driver/space.h). */
typedef enum mcmc_states {
  MCMC_STATES_DEFAULT = 0, /* the integrator's own: pssmlt pt, mmlt per-length families */
  MCMC_STATES_PT,          /* the unidirectional path tracer's primary samples (pssmlt) */
  MCMC_STATES_MMLT,        /* one family of chains per path length (Hachisuka et al. 2014) */
  MCMC_STATES_BDPT         /* one family over every length; a state is a BDPT sample's numbers
                              and one of its strategies (mcmc.c) */
} mcmc_states;

/* A plugin's own setting as checked text (render/options.h). */
#define LMC_MAX_PARAMS 48
typedef struct lmc_param {
  char name[32];
  char value[96];
} lmc_param;

typedef struct render_settings {
  unsigned set;          /* SET_* bits of the fields chosen explicitly */
  char integrator[32];   /* pt, bdpt, pssmlt, mmlt, lmc */
  int maxdepth;          /* Mitsuba's maxDepth: longest path in segments; -1 unbounded */
  int mindepth;          /* shortest path in segments that is counted (-1: all) */
  int rrdepth;           /* Russian roulette from this many segments on */
  int64_t spp;           /* samples (or mutations) per pixel */
  double time_limit;     /* seconds; 0 = none (spp decides) */
  int threads;           /* 0 = all cores */
  uint64_t seed;
  int sampler;           /* pt and bdpt: LMC_SAMPLER_INDEPENDENT or _SOBOL (render/sampler.h) */
  /* MCMC (src/lmc) */
  double largestep;      /* large-step probability */
  double technique_prob; /* the technique mutation's share of the other steps (per-length states) */
  double sigma;          /* Kelemen small-step scale (the Gaussian's standard deviation) */
  int small_gauss;       /* --small-step gauss: Gaussian small steps instead of Kelemen's */
  double largestep_scale; /* the large-step probability times this after the first tenth of
                             the chains' budget (the LMC paper's largestepscale; 1: none) */
  int64_t bootstrap;     /* bootstrap paths */
  double bootstrap_error; /* without --bootstrap: draw until b's relative standard error is below this */
  int direct_separate;   /* --direct separate (default): pt renders direct light, MCMC the rest */
  int64_t direct_spp;    /* samples per pixel of that pt pass under --spp (0: spp); Mitsuba's directSamples */
  int mcmc_even;         /* --allocate even: every chain the same mutations (default: in proportion to b_k) */
  int mcmc_states;       /* --states: mcmc_states */
  int chains;            /* --chains: Markov chains (0: mcmc.c's default) */
  double rough_min;      /* bdpt states: absolute directions at vertices rougher than this
                            (--roughness-threshold; >= 1: none) */
  double snapshot;       /* seconds between intermediate images (0: none) */
  /* Called by the render drivers every `snapshot` seconds with the film
   * normalised as if the render stopped then (borrowed for the call) and
   * the seconds since the render began; cli/render.c writes it. NULL: none. */
  void (*snapshot_fn)(void *ctx, const struct film *f, double seconds);
  void *snapshot_ctx;
  /* The plugins' own settings (an integrator's table, render/options.h). */
  lmc_param params[LMC_MAX_PARAMS];
  int n_params;
  int mala;              /* the <dpt> block asked for MALA */
  int h2mc;              /* the <dpt> block asked for H2MC */
  int quiet;             /* no progress bar */
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
  s.largestep = 0.3;
  s.technique_prob = 0.1;
  s.sigma = 1.0 / 64.0;
  s.largestep_scale = 1.0;
  s.rough_min = 0.3;
  s.bootstrap = 0;
  s.bootstrap_error = 0.01;
  s.direct_separate = 1; /* as Mitsuba's pssmlt and the LMC paper's code; see README */
  return s;
}

#endif
