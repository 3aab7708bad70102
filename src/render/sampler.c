/*
 * sampler.c: the independent sampler.
 */
#include "render/sampler.h"

#include <stddef.h>

static double indep_next(lmc_sampler *self) {
  lmc_indep_sampler *s = (lmc_indep_sampler *)self;
  return rng_uniform(&s->r);
}

static void indep_use_stream(lmc_sampler *self, int stream) {
  (void)self;
  (void)stream;
}

rng *sampler_indep_rng(lmc_sampler *s) {
  return s->next == indep_next ? &((lmc_indep_sampler *)s)->r : NULL;
}

void indep_sampler_init(lmc_indep_sampler *s, uint64_t seed, uint64_t seq) {
  s->base.next = indep_next;
  s->base.use_stream = indep_use_stream;
  rng_seed(&s->r, rng_hash64(seed), rng_hash64(seq ^ 0x5851f42d4c957f2dull));
}
