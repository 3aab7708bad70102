/*
 * sampler.c: the independent and the Sobol samplers (sampler.h).
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
  s->base.skip_n = NULL;
  rng_seed(&s->r, rng_hash64(seed), rng_hash64(seq ^ 0x5851f42d4c957f2dull));
}

/* --- the Sobol sampler ---------------------------------------------------------- */

const sampler_layout sampler_layout_pt = {
    .stream = {[LMC_STREAM_CAMERA] = {{2}, 1, {1, 2, 1, 2, 1}, 5},
               [LMC_STREAM_LIGHT] = {{0}, 0, {2}, 1},
               [LMC_STREAM_CONNECT] = {{0}, 0, {2}, 1}}};

const sampler_layout sampler_layout_pt_media = {
    .stream = {[LMC_STREAM_CAMERA] = {{2}, 1, {2, 1, 2, 1, 2, 1}, 6},
               [LMC_STREAM_LIGHT] = {{0}, 0, {2}, 1},
               [LMC_STREAM_CONNECT] = {{0}, 0, {2}, 1}}};

const sampler_layout sampler_layout_bdpt = {
    .stream = {[LMC_STREAM_CAMERA] = {{2}, 1, {1, 2, 1}, 3},
               [LMC_STREAM_LIGHT] = {{1, 2, 2}, 3, {1, 2, 1}, 3},
               [LMC_STREAM_CONNECT] = {{0}, 0, {1, 2}, 2}}};

const sampler_layout sampler_layout_bdpt_media = {
    .stream = {[LMC_STREAM_CAMERA] = {{2}, 1, {2, 1, 2, 1}, 4},
               [LMC_STREAM_LIGHT] = {{1, 2, 2}, 3, {2, 1, 2, 1}, 4},
               [LMC_STREAM_CONNECT] = {{0}, 0, {1, 2}, 2}}};

static uint32_t sampler__reverse(uint32_t x) {
  x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
  x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
  x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
  x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
  return (x >> 16) | (x << 16);
}

uint32_t sampler_owen_scramble(uint32_t x, uint32_t key) {
  /* On the reversed bits, adding the key and x ^= x * c with even c change
   * each bit by a function of the bits below it only (Laine and Karras
   * 2011; constants from Burley 2020); reversed back, the bits before it. */
  x = sampler__reverse(x);
  x += key;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return sampler__reverse(x);
}

void sampler_sobol_2d(uint32_t j, uint32_t *OUT_x, uint32_t *OUT_y) {
  /* The second Sobol dimension (primitive polynomial x + 1): direction
   * numbers v_1 = 1/2, v_k = v_(k-1) xor v_(k-1) / 2. */
  uint32_t y = 0, v = 0x80000000u;
  for (uint32_t b = j; b; b >>= 1) {
    if (b & 1u) y ^= v;
    v ^= v >> 1;
  }
  *OUT_x = sampler__reverse(j);
  *OUT_y = y;
}

/* The size of group g of a stream. */
static int sampler__group_size(const sampler_layout *l, int stream, uint32_t g) {
  if (g < (uint32_t)l->stream[stream].n_head) return l->stream[stream].head[g];
  g -= (uint32_t)l->stream[stream].n_head;
  return l->stream[stream].cycle[g % (uint32_t)l->stream[stream].n_cycle];
}

/* A 32-bit fraction and 21 random bits below it, as a double in [0, 1). */
static double sampler__unit(uint32_t x, uint64_t low) {
  return (double)(((uint64_t)x << 21) | (low & 0x1fffffu)) * 0x1.0p-53;
}

static double sobol_next(lmc_sampler *self) {
  lmc_sobol_sampler *s = (lmc_sobol_sampler *)self;
  int k = s->stream;
  if (s->st[k].next == s->st[k].size) {
    /* Start the stream's next group: its keys, the shuffled index, the point. */
    uint32_t g = s->st[k].group++;
    int n = sampler__group_size(s->layout, k, g);
    uint64_t gkey = rng_hash64(s->key ^ rng_hash64(((uint64_t)k << 32) | g));
    uint64_t scr = rng_hash64(gkey + 1);
    uint64_t low = rng_hash64(gkey ^ ((uint64_t)s->index * 0x9e3779b97f4a7c15ull + 2));
    uint32_t j = sampler_owen_scramble(s->index, (uint32_t)gkey), x, y;
    sampler_sobol_2d(j, &x, &y);
    s->st[k].value[0] = sampler__unit(sampler_owen_scramble(x, (uint32_t)scr), low);
    if (n == 2)
      s->st[k].value[1] = sampler__unit(sampler_owen_scramble(y, (uint32_t)(scr >> 32)), low >> 32);
    s->st[k].size = n;
    s->st[k].next = 0;
  }
  return s->st[k].value[s->st[k].next++];
}

static void sobol_use_stream(lmc_sampler *self, int stream) {
  ((lmc_sobol_sampler *)self)->stream = stream;
}

void sobol_sampler_init(lmc_sobol_sampler *s, uint64_t seed, uint64_t pixel, uint32_t index,
                        const sampler_layout *layout) {
  s->base.next = sobol_next;
  s->base.use_stream = sobol_use_stream;
  s->base.skip_n = NULL;
  s->layout = layout;
  s->key = rng_hash64(rng_hash64(seed ^ 0x2545f4914f6cdd1dull) ^ pixel);
  s->index = index;
  s->stream = LMC_STREAM_CAMERA;
  for (int k = 0; k < LMC_STREAM_COUNT; k++) {
    s->st[k].group = 0;
    s->st[k].size = 0;
    s->st[k].next = 0;
  }
}
