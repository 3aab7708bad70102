/*
 * arr_sampler.h: a sampler (render/sampler.h) that replays one array of
 * numbers, 0.5 past its end, streams ignored; for the tests that walk
 * given numbers (test_bdpt_invert, test_invert_jacobian).
 */
#ifndef LMC_TESTS_ARR_SAMPLER_H
#define LMC_TESTS_ARR_SAMPLER_H

#include "render/sampler.h"

typedef struct arr_smp {
  lmc_sampler base;
  const double *u;
  int n, pos;
} arr_smp;

static inline double arr_next(lmc_sampler *self) {
  arr_smp *a = (arr_smp *)self;
  return a->pos < a->n ? a->u[a->pos++] : 0.5;
}

static inline void arr_stream(lmc_sampler *self, int stream) { (void)self, (void)stream; }

/* The sampler over u[0 .. n - 1]. */
static inline arr_smp arr_at(const double *u, int n) {
  arr_smp a = {{arr_next, arr_stream, NULL}, u, n, 0};
  return a;
}

#endif
