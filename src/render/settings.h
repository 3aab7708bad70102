/*
 * settings.h: how to render. Filled from the scene's <integrator> or <dpt>
 * block first, then overridden by the command line. Each field has a bit in
 * `set` so a later source can tell what an earlier one chose explicitly.
 */
#ifndef LMC_RENDER_SETTINGS_H
#define LMC_RENDER_SETTINGS_H

#include <stdint.h>

enum {
  SET_INTEGRATOR = 1 << 0,
  SET_MAXDEPTH = 1 << 1,
  SET_RRDEPTH = 1 << 2,
  SET_SPP = 1 << 3,
  SET_TIME = 1 << 4,
  SET_LARGESTEP = 1 << 5,
  SET_SIGMA = 1 << 6,
  SET_MINDEPTH = 1 << 7,
  SET_ADAPT = 1 << 8,
  SET_BOOTSTRAP = 1 << 9
};

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
  /* MCMC (src/lmc) */
  double largestep;      /* large-step probability */
  double sigma;          /* Kelemen small-step scale */
  int64_t bootstrap;     /* bootstrap paths */
  char adapt[16];        /* LMC preconditioner adaptation */
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
  s.sigma = 1.0 / 64.0;
  s.bootstrap = 0;
  return s;
}

#endif
