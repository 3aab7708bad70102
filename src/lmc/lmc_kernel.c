/*
 * lmc_kernel.c: the LMC (preconditioned MALA) kernel and the cache's
 * independence kernel for chain.h (see lmc_kernel.h for the model).
 */
#include "lmc/lmc_kernel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/mala.h"

lmc_kernel_params lmc_kernel_params_default(void) {
  lmc_kernel_params p;
  memset(&p, 0, sizeof p);
  p.adapt = LMC_ADAPT_CACHE;
  p.step = 1e-5;
  p.step_range = 1.0;
  p.eps = 1e-8;
  p.lo = 1e-3;
  p.hi = 1e3;
  p.grad_bound = 1e3;
  p.s1 = 1.0 / 1024.0;
  p.s2 = 1.0 / 64.0;
  p.diminish_t0 = 100.0;
  p.cache.k = 8;
  p.cache.radius = 0.1;
  p.cache.eps = p.eps, p.cache.lo = p.lo, p.cache.hi = p.hi;
  p.record_stride = 4;
  p.norm = LMC_NORM_OFF; /* measured: no normalisation helped on ring-caustics (README) */
  return p;
}

lmc_kernel_params lmc_kernel_params_from_settings(const render_settings *rs) {
  lmc_kernel_params p = lmc_kernel_params_default();
  p.adapt = rs->adapt;
  p.step = rs->lmc_step;
  p.step_range = rs->step_range;
  p.eps = rs->adam_eps;
  p.lo = rs->precond_lo;
  p.hi = rs->precond_hi;
  p.grad_bound = rs->grad_bound;
  /* Kelemen's offsets as mmlt and pssmlt draw them: in (1/1024, sigma]. */
  if (rs->sigma > p.s1 && rs->sigma < 0.5) p.s2 = rs->sigma;
  p.cache.eps = p.eps, p.cache.lo = p.lo, p.cache.hi = p.hi;
  p.delayed = rs->delayed;
  return p;
}

lmc_status lmc_mala_init(lmc_mala *k, int dim, const lmc_kernel_params *p, lmc_error *err) {
  memset(k, 0, sizeof *k);
  if (dim < 1) return lmc_error_set(err, LMC_EINVAL, NULL, 0, "lmc: %d coordinates", dim);
  k->p = *p;
  k->dim = dim;
  k->cur_step = p->step;
  lmc_status st = adam_init(&k->adam, dim, err);
  if (st != LMC_OK) return st;
  size_t n = (size_t)dim;
  k->M_chain = malloc(n * sizeof(double));
  k->g = malloc(n * sizeof(double));
  k->M = malloc(n * sizeof(double));
  k->m1 = malloc(n * sizeof(double));
  k->m2 = malloc(n * sizeof(double));
  for (int j = 0; j < 2; j++) {
    k->memo_u[j] = malloc(n * sizeof(double));
    k->memo_M[j] = malloc(n * sizeof(double));
    k->memo_key[j] = -1;
  }
  if (!k->M_chain || !k->g || !k->M || !k->m1 || !k->m2 || !k->memo_u[0] || !k->memo_u[1] ||
      !k->memo_M[0] || !k->memo_M[1]) {
    lmc_mala_free(k);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "lmc: out of memory");
  }
  adam_precond(&k->adam, dim, p->eps, p->lo, p->hi, k->M_chain);
  return LMC_OK;
}

void lmc_mala_free(lmc_mala *k) {
  if (!k) return;
  adam_free(&k->adam);
  free(k->M_chain), free(k->g), free(k->M), free(k->m1), free(k->m2);
  for (int j = 0; j < 2; j++) free(k->memo_u[j]), free(k->memo_M[j]);
  memset(k, 0, sizeof *k);
}

void lmc_mala_set_record(lmc_mala *k, gcache *record) { k->record = record; }

void lmc_mala_begin_stage2(lmc_mala *k, const gcache *cache) {
  k->cache = cache;
  k->stage2 = 1;
  k->record = NULL;
  k->memo_key[0] = k->memo_key[1] = -1;
}

int lmc_state_key(const mc_state *x) {
  if (!x->grad_ok || !(x->v.f > 0.0)) return 0;
  for (int i = x->dim - 1; i >= 0; i--)
    if (x->grad[i] != 0.0 && isfinite(x->grad[i])) return i + 1;
  return 0;
}

/* g = c grad f / f (the gradient in the rescaled coordinates, lmc_kernel.h)
 * truncated into k->g; returns the cache key k(x) (0: the state has no
 * usable gradient and takes the Kelemen fallback). */
static int lmc__gradient(lmc_mala *k, const mc_state *x) {
  int key = lmc_state_key(x);
  if (key == 0) return 0;
  double inv = 1.0 / x->v.f;
  const double *c = k->p.scale;
  for (int i = 0; i < x->dim; i++) k->g[i] = x->grad[i] * inv * (c ? c[i] : 1.0);
  mala_truncate(x->dim, k->g, k->p.grad_bound);
  return key;
}

/* Normalises M over its first n coordinates (see lmc_kernel.h) in place. */
static void lmc__normalise(int norm, double *M, int n) {
  if (norm == LMC_NORM_OFF || n < 1) return;
  double c = 0.0;
  if (norm == LMC_NORM_MEAN) {
    for (int i = 0; i < n; i++) c += M[i];
    c /= (double)n;
  } else if (norm == LMC_NORM_GEOMEAN) {
    for (int i = 0; i < n; i++) c += log(M[i]);
    c = exp(c / (double)n);
  } else {
    for (int i = 0; i < n; i++) c = M[i] > c ? M[i] : c;
  }
  if (!(c > 0.0) || !isfinite(c)) return;
  double inv = 1.0 / c;
  for (int i = 0; i < n; i++) M[i] *= inv;
}

/* The chain's Adam M (ADAM, DIMINISH) at a state of key
 * `key`: normalised over the key coordinates, and for DIMINISH mixed with
 * I after normalising. */
static const double *lmc__precond_chain(lmc_mala *k, const mc_state *x, int key) {
  /* Adam's moments change only in on_step, between steps: rebuilding M
   * here, when a proposal needs it, gives the M of the last update. */
  if (k->M_chain_stale) {
    adam_precond(&k->adam, k->dim, k->p.eps, k->p.lo, k->p.hi, k->M_chain);
    k->M_chain_stale = 0;
  }
  if (k->p.norm == LMC_NORM_OFF && k->p.adapt != LMC_ADAPT_DIMINISH) return k->M_chain;
  memcpy(k->M, k->M_chain, (size_t)x->dim * sizeof(double));
  lmc__normalise(k->p.norm, k->M, key);
  if (k->p.adapt == LMC_ADAPT_DIMINISH) {
    double w = k->adam.t > 0 ? k->p.diminish_t0 / (double)k->adam.t : 1.0;
    if (w > 1.0) w = 1.0;
    for (int i = 0; i < x->dim; i++) k->M[i] = (1.0 - w) + w * k->M[i];
  }
  return k->M;
}

/* The preconditioner at state x with key `key` (> 0); NULL means I. */
static const double *lmc__precond(lmc_mala *k, const mc_state *x, int key) {
  if (k->p.adapt == LMC_ADAPT_NONE) return NULL;
  /* CACHE stage 1 runs with M = I (Adam's moments are recorded, not used),
   * so that its image is unbiased and kept. */
  if (k->p.adapt == LMC_ADAPT_CACHE && !k->stage2) return NULL;
  if (k->p.adapt != LMC_ADAPT_CACHE) return lmc__precond_chain(k, x, key);
  /* Stage 2: a pure function of x (its first `key` coordinates); the same
   * state as one of the last two lookups gives the same M. */
  size_t bytes = (size_t)x->dim * sizeof(double);
  for (int j = 0; j < 2; j++)
    if (k->memo_key[j] == key && !memcmp(k->memo_u[j], x->u, bytes)) return k->memo_M[j];
  int slot = k->memo_next;
  k->memo_next ^= 1;
  double *M = k->memo_M[slot];
  int kk = key <= gcache_max_dim(k->cache) ? key : 0;
  int found = kk ? gcache_precond(k->cache, kk, x->u, &k->p.cache, M) : 0;
  k->st.lookups++;
  if (found) k->st.lookup_hits++;
  double one = 1.0 < k->p.lo ? k->p.lo : (1.0 > k->p.hi ? k->p.hi : 1.0);
  for (int i = kk; i < x->dim; i++) M[i] = one;
  lmc__normalise(k->p.norm, M, key);
  memcpy(k->memo_u[slot], x->u, bytes);
  k->memo_key[slot] = key;
  return M;
}

static double lmc__propose(void *self, rng *r, const mc_state *x, double *OUT_y) {
  lmc_mala *k = self;
  k->own_step = 1;
  int key = lmc__gradient(k, x);
  k->own_key = key;
  if (key == 0) {
    /* Fallback: Kelemen's small step, with its exact density. */
    k->st.fallback++;
    mala_kelemen_sample_c(x->dim, x->u, k->p.s1, k->p.s2, k->p.scale, r, OUT_y);
    return mala_kelemen_log_density_c(x->dim, x->u, k->p.s1, k->p.s2, k->p.scale, OUT_y);
  }
  k->st.mala++;
  const double *M = lmc__precond(k, x, key);
  /* This step's s: log-uniform over [s / R, s R], drawn independently of
   * the state (lmc_kernel.h). */
  k->cur_step = k->p.step;
  if (k->p.step_range > 1.0) k->cur_step *= exp(log(k->p.step_range) * (2.0 * rng_uniform(r) - 1.0));
  mala_sample_c(x->dim, x->u, k->g, M, k->p.scale, k->cur_step, r, OUT_y);
  return mala_log_density_c(x->dim, x->u, k->g, M, k->p.scale, k->cur_step, OUT_y);
}

static double lmc__log_density(void *self, const mc_state *from, const double *to_u) {
  lmc_mala *k = self;
  int key = lmc__gradient(k, from);
  if (key == 0)
    return mala_kelemen_log_density_c(from->dim, from->u, k->p.s1, k->p.s2, k->p.scale, to_u);
  const double *M = lmc__precond(k, from, key);
  return mala_log_density_c(from->dim, from->u, k->g, M, k->p.scale, k->cur_step, to_u);
}

/* Delayed acceptance's screen from `from` to to_u (lmc_kernel.h). */
static double lmc__log_screen(void *self, const mc_state *from, const double *to_u, double f_to) {
  lmc_mala *k = self;
  double s = log(f_to) - log(from->v.f);
  if (lmc__gradient(k, from) == 0) return s;
  const double *c = k->p.scale;
  for (int i = 0; i < from->dim; i++)
    if (k->g[i] != 0.0) s += mala_torus_diff(from->u[i], to_u[i]) / (c ? c[i] : 1.0) * k->g[i];
  return s;
}

static void lmc__on_step(void *self, const mc_state *x, int accepted) {
  lmc_mala *k = self;
  int own = k->own_step;
  k->own_step = 0;
  /* Statistics: per key of the state proposed from, and stalls. */
  if (own) {
    int t = k->own_key == 0, b = k->own_key < LMC_STAT_KEYS ? k->own_key : LMC_STAT_KEYS - 1;
    k->st.key_proposed[t][b]++;
    k->st.key_accepted[t][b] += accepted != 0;
  }
  k->st.steps++;
  k->st.streak = accepted ? 0 : k->st.streak + 1;
  if (k->st.streak > k->st.max_streak) k->st.max_streak = k->st.streak;
  int adapting = k->p.adapt == LMC_ADAPT_ADAM || k->p.adapt == LMC_ADAPT_DIMINISH ||
                 (k->p.adapt == LMC_ADAPT_CACHE && !k->stage2);
  if (!adapting) return;
  /* Update Adam with the current state's gradient of log f. */
  int key = lmc__gradient(k, x);
  if (key == 0) return;
  adam_update(&k->adam, x->dim, k->g);
  /* CACHE stage 1 only records the moments (its M is I); the others
   * rebuild M when they next propose (most steps are not theirs). */
  if (k->p.adapt != LMC_ADAPT_CACHE) k->M_chain_stale = 1;
  /* Stage 1 of CACHE: record every record_stride-th state of our own steps
   * (x->u is valid only after a full kernel's step). */
  if (!own || !k->record || k->p.record_stride <= 0) return;
  if (++k->own_steps % k->p.record_stride) return;
  for (int i = 0; i < key; i++) adam_moments(&k->adam, i, &k->m1[i], &k->m2[i]);
  if (gcache_add(k->record, key, x->u, k->m1, k->m2, x->v.f))
    k->st.recorded++;
  else
    k->st.record_full++;
}

mc_kernel lmc_mala_kernel(lmc_mala *k) {
  mc_kernel kn;
  memset(&kn, 0, sizeof kn);
  kn.name = "mala";
  kn.kind = MC_KERNEL_FULL;
  kn.needs_grad = 1;
  kn.s1 = k->p.s1, kn.s2 = k->p.s2;
  kn.self = k;
  kn.propose = lmc__propose;
  kn.log_density = lmc__log_density;
  if (k->p.delayed) kn.log_screen = lmc__log_screen;
  kn.on_step = lmc__on_step;
  return kn;
}

/* ---- The independence kernel ------------------------------------------ */

static double lmc__indep_propose(void *self, rng *r, const mc_state *x, double *OUT_y) {
  lmc_indep *k = self;
  if (!k->cache || gcache_anchor_count(k->cache) == 0) {
    mala_kelemen_sample(x->dim, x->u, k->s1, k->s2, r, OUT_y);
    return mala_kelemen_log_density(x->dim, x->u, k->s1, k->s2, OUT_y);
  }
  gcache_indep_sample(k->cache, x->dim, k->sigma, r, OUT_y);
  return gcache_indep_log_density(k->cache, x->dim, k->sigma, OUT_y);
}

static double lmc__indep_log_density(void *self, const mc_state *from, const double *to_u) {
  lmc_indep *k = self;
  if (!k->cache || gcache_anchor_count(k->cache) == 0)
    return mala_kelemen_log_density(from->dim, from->u, k->s1, k->s2, to_u);
  return gcache_indep_log_density(k->cache, from->dim, k->sigma, to_u);
}

mc_kernel lmc_indep_kernel(lmc_indep *k) {
  mc_kernel kn;
  memset(&kn, 0, sizeof kn);
  kn.name = "cache-indep";
  kn.kind = MC_KERNEL_FULL;
  kn.needs_grad = 0;
  kn.s1 = k->s1, kn.s2 = k->s2;
  kn.self = k;
  kn.propose = lmc__indep_propose;
  kn.log_density = lmc__indep_log_density;
  return kn;
}
