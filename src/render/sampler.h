/*
 * sampler.h: where an integrator takes its random numbers from.
 *
 * Every sampling routine in lmc takes its uniform numbers as arguments; the
 * integrators draw them from an lmc_sampler. The independent sampler draws
 * from a PCG32 stream; the MCMC integrators (src/lmc) supply a primary
 * sample space vector instead, so the same path code serves both.
 *
 * Streams: a path takes its numbers from up to three streams, so that a
 * primary sample vector has a stable layout when a subpath changes length
 * (as in Kelemen et al. 2002 and multiplexed MLT):
 *   LMC_STREAM_CAMERA   film position, then the camera subpath's bounces;
 *   LMC_STREAM_LIGHT    the light subpath (emitter choice, position, direction, bounces);
 *   LMC_STREAM_CONNECT  next-event estimation and connection choices.
 * The documented per-stream layout is in path.h (LMC_DIMS_*).
 */
#ifndef LMC_RENDER_SAMPLER_H
#define LMC_RENDER_SAMPLER_H

#include "render/rng.h"

enum {
  LMC_STREAM_CAMERA = 0,
  LMC_STREAM_LIGHT = 1,
  LMC_STREAM_CONNECT = 2,
  LMC_STREAM_COUNT = 3
};

typedef struct lmc_sampler lmc_sampler;
struct lmc_sampler {
  /* Next uniform number in [0, 1) of the current stream. */
  double (*next)(lmc_sampler *self);
  /* Switches to `stream`, resuming where that stream stopped. */
  void (*use_stream)(lmc_sampler *self, int stream);
};

static inline double sampler_next(lmc_sampler *s) { return s->next(s); }
static inline void sampler_use_stream(lmc_sampler *s, int stream) { s->use_stream(s, stream); }

/* The independent sampler: one PCG32 stream for everything. */
typedef struct lmc_indep_sampler {
  lmc_sampler base;
  rng r;
} lmc_indep_sampler;

void indep_sampler_init(lmc_indep_sampler *s, uint64_t seed, uint64_t seq);
/* The stream of s when s is an independent sampler, else NULL. A hot loop
 * may then draw rng_uniform from it directly: the same numbers as
 * sampler_next, without the indirect call. */
rng *sampler_indep_rng(lmc_sampler *s);

#endif
