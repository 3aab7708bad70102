/*
 * lmc_kernel.c: the LMC (preconditioned MALA) kernel and the cache's
 * independence kernel for chain.h (see lmc_kernel.h for the model).
 */
#include "lmc/kernels/lmc_kernel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/kernels/mala.h"

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

const lmc_settings lmc_settings_defaults = {
    .adapt = LMC_ADAPT_CACHE,
    .step = 1e-5,
    .step_range = 1.0,
    .adam_eps = 1e-8,
    .precond_lo = 1e-3,
    .precond_hi = 1e3,
    .grad_bound = 1e3,
    .cache_fraction = 0.1,
    .iso_prob = 0.4,
};

lmc_settings lmc_settings_default(void) { return lmc_settings_defaults; }

lmc_kernel_params lmc_kernel_params_from_settings(const lmc_settings *ls, double sigma) {
  lmc_kernel_params p = lmc_kernel_params_default();
  p.adapt = (lmc_adapt)ls->adapt;
  p.step = ls->step;
  p.step_range = ls->step_range;
  p.eps = ls->adam_eps;
  p.lo = ls->precond_lo;
  p.hi = ls->precond_hi;
  p.grad_bound = ls->grad_bound;
  /* Kelemen's offsets as mmlt and pssmlt draw them: in (1/1024, sigma]. */
  if (sigma > p.s1 && sigma < 0.5) p.s2 = sigma;
  p.cache.eps = p.eps, p.cache.lo = p.lo, p.cache.hi = p.hi;
  p.delayed = ls->delayed;
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
  k->M_chain = calloc(n, sizeof(double));
  k->g = malloc(n * sizeof(double));
  k->M = calloc(n, sizeof(double));
  k->m1 = malloc(n * sizeof(double));
  k->m2 = malloc(n * sizeof(double));
  k->cidx = malloc(n * sizeof(int));
  k->cu = malloc(n * sizeof(double));
  k->last_label = -1;
  for (int j = 0; j < 2; j++) {
    k->memo_u[j] = malloc(n * sizeof(double));
    k->memo_M[j] = malloc(n * sizeof(double));
    k->memo_key[j] = -1;
  }
  if (!k->M_chain || !k->g || !k->M || !k->m1 || !k->m2 || !k->cidx || !k->cu || !k->memo_u[0] ||
      !k->memo_u[1] || !k->memo_M[0] || !k->memo_M[1]) {
    lmc_mala_free(k);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "lmc: out of memory");
  }
  adam_precond(&k->adam, dim, p->eps, p->lo, p->hi, k->M_chain);
  return LMC_OK;
}

void lmc_mala_free(lmc_mala *k) {
  if (!k) return;
  adam_free(&k->adam);
  free(k->M_chain), free(k->g), free(k->M), free(k->m1), free(k->m2), free(k->cidx), free(k->cu);
  for (int j = 0; j < 2; j++) free(k->memo_u[j]), free(k->memo_M[j]);
  memset(k, 0, sizeof *k);
}

void lmc_mala_set_record(lmc_mala *k, gcache *record) { k->record = record; }
void lmc_mala_set_target(lmc_mala *k, const mc_target *target) { k->target = target; }

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
  int labelled = k->target && k->target->label_coords;
  if (labelled) key = x->label + 1; /* the keyed cache's key (lmc_mala_set_target) */
  size_t bytes = (size_t)x->dim * sizeof(double);
  for (int j = 0; j < 2; j++)
    if (k->memo_key[j] == key && !memcmp(k->memo_u[j], x->u, bytes)) return k->memo_M[j];
  int slot = k->memo_next;
  k->memo_next ^= 1;
  double *M = k->memo_M[slot];
  double one = 1.0 < k->p.lo ? k->p.lo : (1.0 > k->p.hi ? k->p.hi : 1.0);
  int found = 0;
  if (labelled) {
    /* The label's entries, looked up at its coordinates and scattered
     * back; every other coordinate gets 1. */
    int n = k->target->label_coords(k->target, x->label, k->cidx);
    for (int i = 0; i < x->dim; i++) M[i] = one;
    if (n > 0 && key <= gcache_max_dim(k->cache) && gcache_len(k->cache, key) == n) {
      for (int i = 0; i < n; i++) k->cu[i] = x->u[k->cidx[i]];
      found = gcache_precond(k->cache, key, k->cu, &k->p.cache, k->m1);
      for (int i = 0; i < n; i++) M[k->cidx[i]] = k->m1[i];
    }
    if (k->p.norm != LMC_NORM_OFF) {
      for (int i = 0; i < n; i++) k->m1[i] = M[k->cidx[i]];
      lmc__normalise(k->p.norm, k->m1, n);
      for (int i = 0; i < n; i++) M[k->cidx[i]] = k->m1[i];
    }
  } else {
    int kk = key <= gcache_max_dim(k->cache) ? key : 0;
    found = kk ? gcache_precond(k->cache, kk, x->u, &k->p.cache, M) : 0;
    for (int i = kk; i < x->dim; i++) M[i] = one;
    lmc__normalise(k->p.norm, M, key);
  }
  k->st.lookups++;
  if (found) k->st.lookup_hits++;
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
    /* Labelled targets count by label + 1 (the integrator maps labels to
     * path lengths), others by key. */
    int stat = k->own_key == 0 ? 0 : k->target && k->target->label_coords ? x->label + 1 : k->own_key;
    int t = k->own_key == 0, b = stat < LMC_STAT_KEYS ? stat : LMC_STAT_KEYS - 1;
    k->st.key_proposed[t][b]++;
    k->st.key_accepted[t][b] += accepted != 0;
  }
  k->st.steps++;
  k->st.streak = accepted ? 0 : k->st.streak + 1;
  if (k->st.streak > k->st.max_streak) k->st.max_streak = k->st.streak;
  int adapting = k->p.adapt == LMC_ADAPT_ADAM || k->p.adapt == LMC_ADAPT_DIMINISH ||
                 (k->p.adapt == LMC_ADAPT_CACHE && !k->stage2);
  if (!adapting) return;
  /* Labelled targets: the moments follow one label's coordinates, from
   * the last large step on (as the paper's implementation restarts them). */
  int labelled = k->target && k->target->label_coords;
  if (labelled && accepted && (x->label != k->last_label || x->from_large)) {
    adam_reset(&k->adam);
    k->last_label = x->label;
    k->M_chain_stale = 1;
  }
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
  if (labelled) {
    /* Under the key label + 1, at the label's coordinates. */
    int n = k->target->label_coords(k->target, x->label, k->cidx);
    for (int i = 0; i < n; i++) {
      k->cu[i] = x->u[k->cidx[i]];
      adam_moments(&k->adam, k->cidx[i], &k->m1[i], &k->m2[i]);
    }
    if (n > 0 && gcache_add(k->record, x->label + 1, k->cu, k->m1, k->m2, x->v.f))
      k->st.recorded++;
    else
      k->st.record_full++;
    return;
  }
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

/* ---- The cached walk ---------------------------------------------------- */

lmc_cwalk_params lmc_cwalk_params_default(void) {
  lmc_cwalk_params p;
  p.step = 0.005;
  p.prior = 0.005;
  p.drift_max = 5.0;
  p.k = 5;
  p.radius = 0.01;
  p.eps = 1e-3;
  p.lo = 0.01;
  p.hi = 100.0;
  return p;
}

lmc_cwalk_params lmc_cwalk_params_from_settings(const lmc_settings *ls) {
  lmc_cwalk_params p = lmc_cwalk_params_default();
  if (ls->cache_step > 0.0) p.step = ls->cache_step;
  if (ls->cache_prior > 0.0) p.prior = ls->cache_prior;
  if (ls->cache_radius > 0.0) p.radius = ls->cache_radius;
  if (ls->cache_k > 0) p.k = ls->cache_k < GCACHE_MAX_K ? ls->cache_k : GCACHE_MAX_K;
  if (ls->cache_no_drift) p.drift_max = 0.0;
  return p;
}

lmc_status lmc_cwalk_init(lmc_cwalk *k, const mc_target *target, const gcache *cache,
                          const lmc_cwalk_params *p, lmc_error *err) {
  memset(k, 0, sizeof *k);
  if (!target->label_coords || !cache)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "lmc: the cached walk needs a labelled target and a cache");
  k->p = *p;
  k->target = target;
  k->cache = cache;
  k->scale = target->step_scale;
  k->dim = target->dim;
  size_t n = (size_t)target->dim;
  k->idx = malloc(n * sizeof(int));
  k->v = malloc(n * sizeof(double));
  k->mean = malloc(n * sizeof(double));
  k->sd = malloc(n * sizeof(double));
  int ok = k->idx && k->v && k->mean && k->sd;
  for (int j = 0; j < 2; j++) {
    k->memo_v[j] = malloc(n * sizeof(double));
    k->memo_mean[j] = malloc(n * sizeof(double));
    k->memo_sd[j] = malloc(n * sizeof(double));
    k->memo_label[j] = -1;
    ok = ok && k->memo_v[j] && k->memo_mean[j] && k->memo_sd[j];
  }
  if (!ok) {
    lmc_cwalk_free(k);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "lmc: out of memory");
  }
  return LMC_OK;
}

void lmc_cwalk_free(lmc_cwalk *k) {
  if (!k) return;
  free(k->idx), free(k->v), free(k->mean), free(k->sd);
  for (int j = 0; j < 2; j++) free(k->memo_v[j]), free(k->memo_mean[j]), free(k->memo_sd[j]);
  memset(k, 0, sizeof *k);
}

/* The Gaussian at state x (see lmc_kernel.h) into k->mean, k->sd over the
 * label's coordinates k->idx (k->v: x there); returns their count. */
static int lmc__cwalk_gauss(lmc_cwalk *k, const mc_state *x) {
  int n = k->target->label_coords(k->target, x->label, k->idx);
  for (int i = 0; i < n; i++) k->v[i] = x->u[k->idx[i]];
  /* The same state as one of the last two: the same Gaussian. */
  for (int j = 0; j < 2; j++)
    if (k->memo_label[j] == x->label && k->memo_n[j] == n &&
        !memcmp(k->memo_v[j], k->v, (size_t)n * sizeof(double))) {
      memcpy(k->mean, k->memo_mean[j], (size_t)n * sizeof(double));
      memcpy(k->sd, k->memo_sd[j], (size_t)n * sizeof(double));
      return n;
    }
  const lmc_cwalk_params *p = &k->p;
  int key = x->label + 1, found = 0;
  int64_t nb[GCACHE_MAX_K];
  double d2[GCACHE_MAX_K];
  k->st.lookups++;
  if (n > 0 && key <= gcache_max_dim(k->cache) && gcache_len(k->cache, key) == n &&
      gcache_size_dim(k->cache, key) > 0) {
    found = gcache_knn_within(k->cache, key, k->v, p->k, p->radius * p->radius * (double)n, nb, d2);
  }
  if (found == 0) {
    for (int i = 0; i < n; i++) k->mean[i] = 0.0, k->sd[i] = p->prior;
  } else {
    k->st.hits++;
    double w[GCACHE_MAX_K], wsum = 0.0;
    for (int j = 0; j < found; j++) w[j] = 1.0 / (d2[j] * d2[j] + 1e-6), wsum += w[j];
    double inv_prior2 = 1.0 / (p->prior * p->prior), s2 = p->step * p->step;
    for (int i = 0; i < n; i++) {
      double m1 = 0.0, m2 = 0.0;
      for (int j = 0; j < found; j++) {
        m1 += w[j] * gcache_entry_m1(k->cache, key, nb[j])[i];
        m2 += w[j] * gcache_entry_m2(k->cache, key, nb[j])[i];
      }
      m1 /= wsum, m2 /= wsum;
      double M = adam_precond_from_m2(m2, p->eps, p->lo, p->hi);
      double cov = 1.0 / (1.0 / (s2 * (M + 1.0)) + inv_prior2);
      double dr = m1 < -p->drift_max ? -p->drift_max : m1 > p->drift_max ? p->drift_max : m1;
      k->mean[i] = dr * cov / 2.0;
      k->sd[i] = sqrt(cov);
    }
  }
  /* In the state's coordinates (the step scale c of the rescaled ones). */
  if (k->scale)
    for (int i = 0; i < n; i++) k->mean[i] *= k->scale[k->idx[i]], k->sd[i] *= k->scale[k->idx[i]];
  int j = k->memo_next;
  k->memo_next ^= 1;
  k->memo_label[j] = x->label;
  k->memo_n[j] = n;
  memcpy(k->memo_v[j], k->v, (size_t)n * sizeof(double));
  memcpy(k->memo_mean[j], k->mean, (size_t)n * sizeof(double));
  memcpy(k->memo_sd[j], k->sd, (size_t)n * sizeof(double));
  return n;
}

/* log q(to | from) of the Gaussian now in k (for `from`'s n coordinates).
 * A coordinate whose nearest image alone is exact to double precision (the
 * test of mala_log_wrapped_normal) adds -d^2 / (2 sd^2) - log sd - log
 * sqrt(2 pi), with the logs of those sd taken once, as the log of their
 * product; the others take the full function. */
static double lmc__cwalk_log_q(const lmc_cwalk *k, int n, const double *to_u) {
  double l = 0.0, prod = 1.0;
  int n_fast = 0;
  for (int i = 0; i < n; i++) {
    double sd = k->sd[i];
    if (!(sd > 0.0)) continue; /* a coordinate the step scale keeps fixed */
    double mu = k->v[i] + k->mean[i];
    double d0 = mala_torus_diff(to_u[k->idx[i]], mu);
    double inv = 0.5 / (sd * sd);
    if (mala_nearest_image_exact(d0, inv) && sd > 1e-100) {
      l -= d0 * d0 * inv;
      prod *= sd; /* stays a normal number: >= 1e-150 * 1e-100 */
      n_fast++;
      if (prod < 1e-150) l += log(prod), prod = 1.0;
    } else {
      l += mala_log_wrapped_normal(to_u[k->idx[i]], mu, sd);
    }
  }
  return l - log(prod) - n_fast * MALA_LOG_SQRT_TWO_PI;
}

static double lmc__cwalk_propose(void *self, rng *r, const mc_state *x, double *OUT_y) {
  lmc_cwalk *k = self;
  k->own = 1;
  k->st.proposed++;
  int n = lmc__cwalk_gauss(k, x); /* (the chain takes only the label's coordinates) */
  /* Normal numbers in Box-Muller pairs, one per moving coordinate. */
  double z[2];
  int nz = 0;
  for (int i = 0; i < n; i++) {
    if (!(k->sd[i] > 0.0)) continue;
    if (nz == 0) mala_std_normal_pair(r, &z[0], &z[1]), nz = 2;
    OUT_y[k->idx[i]] = mala_wrap(k->v[i] + k->mean[i] + k->sd[i] * z[--nz]);
  }
  return lmc__cwalk_log_q(k, n, OUT_y);
}

static double lmc__cwalk_log_density(void *self, const mc_state *from, const double *to_u) {
  lmc_cwalk *k = self;
  int n = lmc__cwalk_gauss(k, from);
  return lmc__cwalk_log_q(k, n, to_u);
}

static void lmc__cwalk_on_step(void *self, const mc_state *x, int accepted) {
  lmc_cwalk *k = self;
  (void)x;
  if (k->own && accepted) k->st.accepted++;
  k->own = 0;
}

static int lmc__cwalk_coords(void *self, const mc_state *x, int *OUT_idx) {
  lmc_cwalk *k = self;
  return k->target->label_coords(k->target, x->label, OUT_idx);
}

mc_kernel lmc_cwalk_kernel(lmc_cwalk *k) {
  mc_kernel kn;
  memset(&kn, 0, sizeof kn);
  kn.name = "cache-walk";
  kn.kind = MC_KERNEL_FULL;
  kn.needs_grad = 0;
  kn.self = k;
  kn.propose = lmc__cwalk_propose;
  kn.log_density = lmc__cwalk_log_density;
  kn.on_step = lmc__cwalk_on_step;
  kn.coords = lmc__cwalk_coords;
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
