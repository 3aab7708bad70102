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
  /* Optional (NULL: draw and drop): moves past the next n numbers of the
   * current stream without reading them (a primary sample vector need not
   * bring them up to date). */
  void (*skip_n)(lmc_sampler *self, int n);
};

static inline double sampler_next(lmc_sampler *s) { return s->next(s); }
/* Moves past the next n numbers of the current stream. */
static inline void sampler_skip(lmc_sampler *s, int n) {
  if (s->skip_n) {
    s->skip_n(s, n);
  } else {
    for (int i = 0; i < n; i++) (void)s->next(s);
  }
}
static inline void sampler_use_stream(lmc_sampler *s, int stream) { s->use_stream(s, stream); }

/* Which sampler the image integrators (pt, bdpt) use (--sampler). */
typedef enum lmc_sampler_kind {
  LMC_SAMPLER_INDEPENDENT = 0, /* PCG32 numbers, independent across samples */
  LMC_SAMPLER_SOBOL            /* Owen-scrambled Sobol, padded per dimension group */
} lmc_sampler_kind;

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

/*
 * The Sobol sampler: the numbers of a pixel's samples 0, 1, 2, ... are
 * stratified against each other, so that smooth integrands converge faster
 * than with independent numbers (randomised quasi-Monte Carlo).
 *
 * Each stream is cut into groups of one or two dimensions, in the order the
 * integrator draws them (a `sampler_layout`: the film position, a BSDF
 * direction and a point on a light are pairs; a lobe or light choice and the
 * Russian roulette number stand alone). A group of a pixel takes point
 * number j of the 2D Sobol (0,2)-sequence (a lone dimension: its first
 * coordinate, the van der Corput sequence), where j is the sample number
 * shuffled by a nested scramble keyed on (seed, pixel, stream, group); each
 * coordinate is then Owen-scrambled (hash-based nested uniform scrambling,
 * Burley 2020) with its own key. The shuffle decorrelates the groups (as in
 * Mitsuba's ldsampler and pbrt-v4's PaddedSobolSampler); the scramble makes
 * every number uniform on [0, 1) on its own, so estimates stay unbiased,
 * while the first 2^k samples of a pixel form a (0,k,2)-net in every pair
 * and are stratified into 2^k intervals in every lone dimension. Below the
 * 2^-32 grid of the sequence, 21 further bits are random.
 */
enum { SAMPLER_LAYOUT_MAX = 8 };

typedef struct sampler_layout {
  /* Per stream: the sizes (1 or 2) of its first `n_head` groups, then of
   * groups repeating `cycle` (n_cycle >= 1). */
  struct {
    unsigned char head[SAMPLER_LAYOUT_MAX];
    int n_head;
    unsigned char cycle[SAMPLER_LAYOUT_MAX];
    int n_cycle;
  } stream[LMC_STREAM_COUNT];
} sampler_layout;

/* pt_li's layout (integrator.h): film pair, then per bounce light choice,
 * light point, lobe, direction, roulette. */
extern const sampler_layout sampler_layout_pt;
/* pt_li_media's: the same with the free flight's pair (channel, distance)
 * first in every bounce. */
extern const sampler_layout sampler_layout_pt_media;
/* bdpt_li's layout (integrator.h): camera stream film pair, then per vertex
 * lobe, direction, roulette; light stream light choice, position,
 * direction, then per vertex as the camera's; connect stream light choice
 * and point, per camera vertex. */
extern const sampler_layout sampler_layout_bdpt;
/* bdpt_li's through media: the free flight's pair (channel, distance)
 * first in every vertex of both subpaths. */
extern const sampler_layout sampler_layout_bdpt_media;

typedef struct lmc_sobol_sampler {
  lmc_sampler base;
  const sampler_layout *layout; /* borrowed */
  uint64_t key;                 /* from (seed, pixel) */
  uint32_t index;               /* the sample number within the pixel */
  int stream;
  struct {
    uint32_t group;   /* groups started so far */
    int size, next;   /* the current group's size; which of its numbers is next */
    double value[2];  /* the current group */
  } st[LMC_STREAM_COUNT];
} lmc_sobol_sampler;

/* Sample `index` of pixel `pixel`; `layout` is borrowed. */
void sobol_sampler_init(lmc_sobol_sampler *s, uint64_t seed, uint64_t pixel, uint32_t index,
                        const sampler_layout *layout);

/* Hash-based nested uniform scrambling of x read as the binary fraction
 * 0.b31 b30 ... b0: each bit is flipped by a function of the key and the
 * bits before it. A bijection; for a uniformly random key the result is
 * uniform. Exposed for the tests. */
uint32_t sampler_owen_scramble(uint32_t x, uint32_t key);
/* Point j of the 2D Sobol (0,2)-sequence, both coordinates as 32-bit
 * fractions (x is the van der Corput radical inverse of j). */
void sampler_sobol_2d(uint32_t j, uint32_t *OUT_x, uint32_t *OUT_y);

#endif
