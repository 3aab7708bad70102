/*
 * rng.h: PCG32 (O'Neill 2014), a small, fast generator with independent
 * streams. Every pixel sample, chain and thread owns its stream, derived
 * from (seed, index) with rng_hash64, so images do not depend on the
 * thread schedule.
 */
#ifndef LMC_RENDER_RNG_H
#define LMC_RENDER_RNG_H

#include <stdint.h>

typedef struct rng {
  uint64_t state;
  uint64_t inc;
} rng;

/* SplitMix64 finaliser: a good 64-bit mixing function. */
static inline uint64_t rng_hash64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

static inline uint32_t rng_next_u32(rng *r) {
  uint64_t old = r->state;
  r->state = old * 6364136223846793005ull + r->inc;
  uint32_t xorshifted = (uint32_t)(((old >> 18u) ^ old) >> 27u);
  uint32_t rot = (uint32_t)(old >> 59u);
  return (xorshifted >> rot) | (xorshifted << ((-rot) & 31u));
}

/* Seeds stream `seq` of the generator with `seed`. */
static inline void rng_seed(rng *r, uint64_t seed, uint64_t seq) {
  r->state = 0u;
  r->inc = (seq << 1u) | 1u;
  rng_next_u32(r);
  r->state += seed;
  rng_next_u32(r);
}

/* Uniform double in [0, 1) with 53 random bits. */
static inline double rng_uniform(rng *r) {
  uint64_t hi = rng_next_u32(r), lo = rng_next_u32(r);
  return (double)(((hi << 32) | lo) >> 11) * 0x1.0p-53;
}

/* Uniform integer in [0, n) (n > 0), without modulo bias. */
static inline uint32_t rng_uniform_u32(rng *r, uint32_t n) {
  uint32_t threshold = (uint32_t)(-n) % n;
  for (;;) {
    uint32_t x = rng_next_u32(r);
    if (x >= threshold) return x % n;
  }
}

#endif
