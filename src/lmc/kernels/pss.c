/*
 * pss.c: the lazy primary sample vector of a chain (pss.h).
 *
 * Lazy coordinates. Each coordinate i keeps its value and mod[i], the
 * iteration it was last brought up to date at. `iter` counts accepted
 * iterations plus the one being proposed (a rejection rolls it back), and
 * `last_large` is the iteration of the last accepted large step. Reading
 * coordinate i at iteration iter when mod[i] < iter:
 *   - a large step is being proposed: a fresh uniform;
 *   - else, if mod[i] < last_large: a fresh uniform (as of last_large),
 *     then iter - last_large small steps;
 *   - else iter - mod[i] small steps.
 * The small steps are those the accepted iterations in between would have
 * applied (only accepted iterations count: a rejected one restores what it
 * touched), and all of them were small steps, since a large or full step
 * brings every coordinate it proposes up to date. When more than
 * PSS_MAX_REPLAY steps are owed the coordinate gets a fresh uniform
 * instead: that is still a symmetric proposal for a coordinate f did not
 * read (its exact stationary law is uniform either way), and it bounds the
 * work of a read.
 *
 * Backup: the first time an iteration changes a coordinate, its old value
 * and mod are saved and its index pushed on a list; a rejection restores
 * exactly those.
 */
#include "lmc/kernels/pss.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif


/* --- the small step ------------------------------------------------------- */

/* A standard normal number (Box-Muller; one of the pair). */
static double chain__normal(rng *r) {
  double u1 = 1.0 - rng_uniform(r), u2 = rng_uniform(r);
  return sqrt(-2.0 * log(u1)) * cos(2.0 * M_PI * u2);
}

/* The Gaussian small step of n owed iterations: x + sqrt(n) sigma N(0, 1)
 * wrapped into [0, 1) (n steps of N(0, sigma^2) add up to one of n sigma^2). */
static double chain__gauss(double x, double sigma, int64_t n, rng *r) {
  double y = x + sigma * sqrt((double)n) * chain__normal(r);
  y -= floor(y);
  return y < 1.0 ? y : 0.0;
}

/* Kelemen's mutation: +-r with r log-uniform in (s1, s2], wrapped. */
/* The step lengths of Kelemen's mutation for xi in [0, 1] on a table of
 * PSS_STEP_TABLE intervals, (s1 / s2)^xi at the nodes and linear between
 * them: the length is a fixed function of xi in both directions, so the
 * step stays symmetric, and a read costs no exp. */

static double chain__kelemen(double x, double s2, const double *table, rng *r) {
  /* One 32-bit draw: the sign from its top bit, xi from the other 31. */
  uint32_t bits = rng_next_u32(r);
  double sign = (bits >> 31) ? -1.0 : 1.0;
  double t = (double)(bits & 0x7fffffffu) * (PSS_STEP_TABLE * 0x1.0p-31);
  int i = (int)t;
  double d = s2 * (table[i] + (t - i) * (table[i + 1] - table[i]));
  /* Wrapped into [0, 1) (|sign d| < 1/2). */
  double y = x + sign * d;
  if (y < 0.0) y += 1.0;
  else if (y >= 1.0) y -= 1.0;
  return y < 1.0 ? y : 0.0;
}

/* --- the lazy vector ------------------------------------------------------ */

void mc_pss_backup(mc_pss *p, int i) {
  p->bak[i] = p->val[i];
  p->mod_bak[i] = p->mod[i];
  p->touched[p->n_touched++] = i;
}

/* Brings coordinate i up to date for the current iteration. */
double mc_pss_get(mc_pss *p, int i) {
  if (p->mod[i] < p->iter) {
    mc_pss_backup(p, i);
    if (p->large) {
      p->val[i] = rng_uniform(p->r);
    } else {
      int64_t from = p->mod[i];
      if (from < p->last_large) {
        p->val[i] = rng_uniform(p->r);
        from = p->last_large;
      }
      int64_t n = p->iter - from;
      double sc = p->scale ? p->scale[i] : 1.0;
      if (n > PSS_MAX_REPLAY) {
        p->val[i] = rng_uniform(p->r);
      } else if (sc > 0.0 && p->s1 == 0.0) {
        if (n > 0) p->val[i] = chain__gauss(p->val[i], sc * p->s2, n, p->r);
      } else if (sc > 0.0) {
        for (int64_t k = 0; k < n; k++)
          p->val[i] = chain__kelemen(p->val[i], sc * p->s2, p->step_table, p->r);
      }
    }
    p->mod[i] = p->iter;
  }
  return p->val[i];
}

/* Sets coordinate i for the current iteration (full kernels). */
void mc_pss_set(mc_pss *p, int i, double v) {
  if (p->mod[i] < p->iter) mc_pss_backup(p, i);
  p->val[i] = v;
  p->mod[i] = p->iter;
}

static double pss__next(lmc_sampler *self) {
  mc_pss *p = (mc_pss *)self;
  int k = p->stream;
  if (p->pos[k] >= p->stream_dim[k]) {
    /* Past the block: a fresh number (pseudo-marginal, see chain.h). */
    (*p->overflow)++;
    return rng_uniform(p->r);
  }
  return mc_pss_get(p, p->stream_off[k] + p->pos[k]++);
}

static void pss__skip(lmc_sampler *self, int n) {
  mc_pss *p = (mc_pss *)self;
  p->pos[p->stream] += n;
}

static void pss__use_stream(lmc_sampler *self, int stream) {
  mc_pss *p = (mc_pss *)self;
  if (stream >= 0 && stream < LMC_STREAM_COUNT) p->stream = stream;
}

void mc_pss_rewind(mc_pss *p) {
  p->stream = 0;
  for (int k = 0; k < LMC_STREAM_COUNT; k++) p->pos[k] = 0;
}

/* Starts proposing iteration iter + 1. */
void mc_pss_begin(mc_pss *p, int large) {
  p->iter++;
  p->large = large;
  p->n_touched = 0;
  mc_pss_rewind(p);
}

void mc_pss_accept(mc_pss *p) {
  if (p->large) p->last_large = p->iter;
  p->n_touched = 0;
}

void mc_pss_reject(mc_pss *p) {
  for (int k = 0; k < p->n_touched; k++) {
    int i = p->touched[k];
    p->val[i] = p->bak[i];
    p->mod[i] = p->mod_bak[i];
  }
  p->n_touched = 0;
  p->iter--;
}

/* Brings every coordinate up to date (before a full kernel) and copies them. */
void mc_pss_materialise(mc_pss *p, double *OUT_u) {
  p->large = 0;
  for (int i = 0; i < p->dim; i++) OUT_u[i] = mc_pss_get(p, i);
}

mc_pss *mc_pss_create(int dim) {
  if (dim < 0) return NULL;
  /* One block: the struct, then val, bak, mod, mod_bak (8-byte entries)
   * and touched. */
  size_t n = (size_t)dim;
  mc_pss *p = calloc(1, sizeof *p + 4 * n * sizeof(double) + n * sizeof(int));
  if (!p) return NULL;
  double *blk = (double *)(p + 1);
  p->val = blk;
  p->bak = blk + n;
  p->mod = (int64_t *)(blk + 2 * n);
  p->mod_bak = (int64_t *)(blk + 3 * n);
  p->touched = (int *)(blk + 4 * n);
  p->dim = dim;
  return p;
}

void mc_pss_destroy(mc_pss *p) { free(p); }

void mc_pss_init(mc_pss *p, const mc_target *target, double s1, double s2, rng *r,
                 int64_t *overflow) {
  for (int s = 0, off = 0; s < LMC_STREAM_COUNT; s++) {
    p->stream_off[s] = off;
    p->stream_dim[s] = target->stream_dim[s];
    off += target->stream_dim[s];
  }
  p->base.next = pss__next;
  p->base.use_stream = pss__use_stream;
  p->base.skip_n = pss__skip;
  p->r = r;
  p->s1 = s1;
  p->s2 = s2;
  for (int i = 0; i <= PSS_STEP_TABLE; i++)
    p->step_table[i] = s1 > 0.0 ? exp(-log(s2 / s1) * i / PSS_STEP_TABLE) : 0.0;
  p->scale = target->step_scale;
  p->overflow = overflow;
}
