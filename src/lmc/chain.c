/*
 * chain.c: the lazy primary sample vector (Kelemen et al. 2002, "A simple
 * and robust mutation strategy for the Metropolis light transport
 * algorithm"), the built-in kernels and the Metropolis-Hastings step with
 * expected-value splatting. See chain.h for the model.
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
#include "lmc/chain.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PSS_MAX_REPLAY 64

struct mc_pss {
  lmc_sampler base; /* reads coordinates (the target draws from it) */
  int dim;
  int stream_off[LMC_STREAM_COUNT], stream_dim[LMC_STREAM_COUNT];
  int stream, pos[LMC_STREAM_COUNT];
  double *val, *bak;
  int64_t *mod, *mod_bak;
  int *touched, n_touched;
  int64_t iter, last_large;
  int large;        /* the proposal being evaluated is a large step */
  double s1, s2;    /* the chain's small step (owed steps are replayed with it) */
  const double *scale; /* per-coordinate factor on s1, s2 (target.h; NULL: 1) */
  rng *r;
  int64_t *overflow;
};

/* --- the small step ------------------------------------------------------- */

/* Kelemen's mutation: +-r with r log-uniform in (s1, s2], wrapped. */
static double chain__kelemen(double x, double s1, double s2, rng *r) {
  double xi = rng_uniform(r), sign = rng_uniform(r) < 0.5 ? -1.0 : 1.0;
  double d = s2 * exp(-log(s2 / s1) * xi);
  double y = x + sign * d;
  y -= floor(y);
  return y < 1.0 ? y : 0.0;
}

/* --- the lazy vector ------------------------------------------------------ */

static void pss__backup(mc_pss *p, int i) {
  p->bak[i] = p->val[i];
  p->mod_bak[i] = p->mod[i];
  p->touched[p->n_touched++] = i;
}

/* Brings coordinate i up to date for the current iteration. */
static double pss__get(mc_pss *p, int i) {
  if (p->mod[i] < p->iter) {
    pss__backup(p, i);
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
      } else if (sc > 0.0) {
        for (int64_t k = 0; k < n; k++)
          p->val[i] = chain__kelemen(p->val[i], sc * p->s1, sc * p->s2, p->r);
      }
    }
    p->mod[i] = p->iter;
  }
  return p->val[i];
}

/* Sets coordinate i for the current iteration (full kernels). */
static void pss__set(mc_pss *p, int i, double v) {
  if (p->mod[i] < p->iter) pss__backup(p, i);
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
  return pss__get(p, p->stream_off[k] + p->pos[k]++);
}

static void pss__use_stream(lmc_sampler *self, int stream) {
  mc_pss *p = (mc_pss *)self;
  if (stream >= 0 && stream < LMC_STREAM_COUNT) p->stream = stream;
}

static void pss__rewind(mc_pss *p) {
  p->stream = 0;
  for (int k = 0; k < LMC_STREAM_COUNT; k++) p->pos[k] = 0;
}

/* Starts proposing iteration iter + 1. */
static void pss__begin(mc_pss *p, int large) {
  p->iter++;
  p->large = large;
  p->n_touched = 0;
  pss__rewind(p);
}

static void pss__accept(mc_pss *p) {
  if (p->large) p->last_large = p->iter;
  p->n_touched = 0;
}

static void pss__reject(mc_pss *p) {
  for (int k = 0; k < p->n_touched; k++) {
    int i = p->touched[k];
    p->val[i] = p->bak[i];
    p->mod[i] = p->mod_bak[i];
  }
  p->n_touched = 0;
  p->iter--;
}

/* Brings every coordinate up to date (before a full kernel) and copies them. */
static void pss__materialise(mc_pss *p, double *OUT_u) {
  p->large = 0;
  for (int i = 0; i < p->dim; i++) OUT_u[i] = pss__get(p, i);
}

/* --- kernels ----------------------------------------------------------------- */

mc_kernel mc_kernel_large(void) {
  mc_kernel k = {0};
  k.name = "large";
  k.kind = MC_KERNEL_LARGE;
  return k;
}

mc_kernel mc_kernel_small(double s1, double s2) {
  mc_kernel k = {0};
  k.name = "small";
  k.kind = MC_KERNEL_SMALL;
  k.s1 = s1;
  k.s2 = s2;
  return k;
}

mc_kernel mc_kernel_technique(int coord) {
  mc_kernel k = {0};
  k.name = "technique";
  k.kind = MC_KERNEL_TECHNIQUE;
  k.coord = coord;
  return k;
}

/* --- the chain ------------------------------------------------------------------ */

lmc_status mc_chain_create(mc_chain **OUT_chain, const mc_target *target, const mc_kernel *k,
                           const double *prob, int n, lmc_error *err) {
  *OUT_chain = NULL;
  if (n < 1 || n > MC_MAX_KERNELS || target->dim < 1)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "mc_chain_create: %d kernels, dim %d", n,
                         target->dim);
  double total = 0.0, s1 = 1.0 / 1024.0, s2 = 1.0 / 64.0;
  int n_small = 0;
  for (int i = 0; i < n; i++) {
    if (k[i].kind == MC_KERNEL_SMALL) {
      if (n_small++ && (k[i].s1 != s1 || k[i].s2 != s2))
        return lmc_error_set(err, LMC_EINVAL, NULL, 0,
                             "mc_chain_create: small steps of one chain must share s1, s2");
      s1 = k[i].s1;
      s2 = k[i].s2;
    }
    if (!(prob[i] >= 0.0))
      return lmc_error_set(err, LMC_EINVAL, NULL, 0, "mc_chain_create: bad probability");
    if (k[i].kind == MC_KERNEL_SMALL && !(k[i].s1 > 0.0 && k[i].s1 < k[i].s2 && k[i].s2 < 0.5))
      return lmc_error_set(err, LMC_EINVAL, NULL, 0,
                           "mc_chain_create: small step needs 0 < s1 < s2 < 1/2");
    if (k[i].kind == MC_KERNEL_TECHNIQUE && (k[i].coord < 0 || k[i].coord >= target->dim))
      return lmc_error_set(err, LMC_EINVAL, NULL, 0, "mc_chain_create: bad technique coordinate");
    if (k[i].kind == MC_KERNEL_FULL && (!k[i].propose || !k[i].log_density))
      return lmc_error_set(err, LMC_EINVAL, NULL, 0, "mc_chain_create: full kernel without densities");
    total += prob[i];
  }
  if (!(total > 0.0))
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "mc_chain_create: probabilities sum to 0");

  mc_chain *c = calloc(1, sizeof *c);
  mc_pss *p = calloc(1, sizeof *p);
  int D = target->dim;
  if (c) c->pss = p;
  if (!c || !p) goto oom;
  p->val = calloc((size_t)D, sizeof(double));
  p->bak = calloc((size_t)D, sizeof(double));
  p->mod = calloc((size_t)D, sizeof(int64_t));
  p->mod_bak = calloc((size_t)D, sizeof(int64_t));
  p->touched = calloc((size_t)D, sizeof(int));
  c->x.u = calloc((size_t)D, sizeof(double));
  c->y.u = calloc((size_t)D, sizeof(double));
  c->x.grad = calloc((size_t)D, sizeof(double));
  c->y.grad = calloc((size_t)D, sizeof(double));
  if (!p->val || !p->bak || !p->mod || !p->mod_bak || !p->touched || !c->x.u || !c->y.u ||
      !c->x.grad || !c->y.grad)
    goto oom;
  c->x.dim = c->y.dim = D;
  p->dim = D;
  for (int s = 0, off = 0; s < LMC_STREAM_COUNT; s++) {
    p->stream_off[s] = off;
    p->stream_dim[s] = target->stream_dim[s];
    off += target->stream_dim[s];
  }
  p->base.next = pss__next;
  p->base.use_stream = pss__use_stream;
  p->r = &c->r;
  p->s1 = s1;
  p->s2 = s2;
  p->scale = target->step_scale;
  p->overflow = &c->overflow;
  c->target = target;
  c->n_kernels = n;
  double acc = 0.0;
  for (int i = 0; i < n; i++) {
    c->kernels[i] = k[i];
    if (k[i].needs_grad) c->with_grad = 1;
    acc += prob[i] / total;
    c->cdf[i] = acc;
  }
  c->cdf[n - 1] = 1.0;
  if (target->scratch_create) {
    c->scratch = target->scratch_create(target);
    if (!c->scratch) goto oom;
  }
  *OUT_chain = c;
  return LMC_OK;
oom:
  mc_chain_destroy(c);
  if (!c) free(p);
  return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for a chain of %d coordinates",
                       D);
}

void mc_chain_destroy(mc_chain *c) {
  if (!c) return;
  if (c->pss) {
    free(c->pss->val);
    free(c->pss->bak);
    free(c->pss->mod);
    free(c->pss->mod_bak);
    free(c->pss->touched);
    free(c->pss);
  }
  free(c->x.u);
  free(c->y.u);
  free(c->x.grad);
  free(c->y.grad);
  if (c->scratch && c->target->scratch_destroy) c->target->scratch_destroy(c->scratch);
  free(c);
}

/* Evaluates the state the lazy vector holds into st (f = 0 on failure),
 * with its gradient when want_grad. */
static void chain__eval(mc_chain *c, mc_state *st, int want_grad) {
  pss__rewind(c->pss);
  st->grad_ok = 0;
  st->grad_eval = want_grad != 0;
  int rc = c->target->eval(c->target, c->scratch, &c->pss->base, &st->v,
                           want_grad ? st->grad : NULL, &st->grad_ok);
  if (rc != 0 || !(st->v.f >= 0.0) || !isfinite(st->v.f)) {
    if (rc != 0) c->eval_failures++;
    st->v.f = 0.0;
    st->grad_ok = 0;
  }
}

/* The gradient of the current state, evaluated lazily: after
 * pss__materialise every coordinate is up to date, so the evaluation
 * replays x exactly (f is a function of u). The stored f is kept: when a
 * coordinate past a stream's block made the new f differ (pseudo-marginal,
 * chain.h), x gets no gradient. A difference of rounding (a target whose
 * evaluation with the gradient is other code, lmc_bdpt_target.c, agreeing
 * to 1e-9) is not one. */
static void chain__regrad_state(mc_chain *c, mc_state *st) {
  mc_value v = st->v;
  if (!(v.f > 0.0)) {
    st->grad_ok = 0;
    st->grad_eval = 1;
    return;
  }
  chain__eval(c, st, 1);
  if (!(fabs(st->v.f - v.f) <= 1e-9 * v.f)) st->grad_ok = 0;
  st->v = v;
}

static void chain__regrad(mc_chain *c) {
  c->regrad++;
  chain__regrad_state(c, &c->x);
}

double mc_chain_start(mc_chain *c, uint64_t seed, uint64_t seq, uint64_t chain_seq) {
  mc_pss *p = c->pss;
  for (int i = 0; i < p->dim; i++) p->mod[i] = 0;
  p->iter = 0;
  p->last_large = 0;
  rng_seed(&c->r, seed, seq);
  pss__begin(p, 1);
  chain__eval(c, &c->x, 0);
  pss__accept(p);
  rng_seed(&c->r, seed, chain_seq);
  c->steps = 0;
  return c->x.v.f;
}

/* The independent sampler of mc_eval_independent: one uniform per read, in
 * reading order, as a large step of the lazy vector draws them. */
typedef struct chain__indep {
  lmc_sampler base;
  rng r;
} chain__indep;

static double chain__indep_next(lmc_sampler *self) { return rng_uniform(&((chain__indep *)self)->r); }
static void chain__indep_stream(lmc_sampler *self, int stream) { (void)self, (void)stream; }

double mc_eval_independent(const mc_target *t, void *scratch, uint64_t seed, uint64_t seq,
                           mc_value *OUT_value) {
  chain__indep smp;
  smp.base.next = chain__indep_next;
  smp.base.use_stream = chain__indep_stream;
  rng_seed(&smp.r, seed, seq);
  mc_value v;
  memset(&v, 0, sizeof v);
  int ok = 0;
  if (t->eval(t, scratch, &smp.base, &v, NULL, &ok) != 0 || !(v.f >= 0.0) || !isfinite(v.f))
    v.f = 0.0;
  if (OUT_value) *OUT_value = v;
  return v.f;
}

int mc_chain_step(mc_chain *c, mc_splat_fn splat, void *ctx) {
  mc_pss *p = c->pss;

  /* Pick a kernel. */
  double uk = rng_uniform(&c->r);
  int ki = 0;
  while (ki < c->n_kernels - 1 && uk >= c->cdf[ki]) ki++;
  mc_kernel *k = &c->kernels[ki];

  /* Propose y and evaluate it; log_ratio = log q(x|y) - log q(y|x). With
   * delayed acceptance, screen = the log of a1(y, x) / a1(x, y) (chain.h),
   * or -INFINITY when the first test rejected y. */
  double log_ratio = 0.0, screen = 0.0;
  int full = k->kind == MC_KERNEL_FULL;
  if (full) {
    pss__materialise(p, c->x.u);
    if (k->needs_grad && !c->x.grad_eval) chain__regrad(c);
    pss__begin(p, 0);
    double log_fwd = k->propose(k->self, &c->r, &c->x, c->y.u);
    for (int i = 0; i < p->dim; i++) pss__set(p, i, c->y.u[i]);
    int delayed = k->log_screen && c->x.v.f > 0.0;
    chain__eval(c, &c->y, k->needs_grad && !delayed);
    if (delayed && c->y.v.f > 0.0) {
      c->screened++;
      double s1 = k->log_screen(k->self, &c->x, c->y.u, c->y.v.f);
      double la1 = s1 < 0.0 ? s1 : 0.0;
      if (!(rng_uniform(&c->r) < exp(la1))) {
        screen = -INFINITY;
      } else {
        c->screen_passed++;
        if (k->needs_grad) chain__regrad_state(c, &c->y);
        double s2 = k->log_screen(k->self, &c->y, c->x.u, c->x.v.f);
        screen = (s2 < 0.0 ? s2 : 0.0) - la1;
      }
    }
    if (c->y.v.f > 0.0 && screen > -INFINITY)
      log_ratio = k->log_density(k->self, &c->y, c->x.u) - log_fwd;
  } else if (k->kind == MC_KERNEL_TECHNIQUE) {
    /* A small step of every other coordinate (the lazy vector owes every
     * accepted non-large iteration a small step) with the technique
     * coordinate redrawn: a product of symmetric proposals. */
    pss__begin(p, 0);
    pss__set(p, k->coord, rng_uniform(&c->r));
    chain__eval(c, &c->y, k->needs_grad);
  } else {
    pss__begin(p, k->kind == MC_KERNEL_LARGE);
    chain__eval(c, &c->y, k->needs_grad);
  }

  /* Metropolis-Hastings: a = min(1, f(y) q(x|y) / (f(x) q(y|x))); with
   * delayed acceptance, the second test's a2 (0 after a failed first test,
   * an unbiased estimate of the acceptance probability for the splats). */
  double a;
  if (!(c->y.v.f > 0.0) || screen == -INFINITY) a = 0.0;
  else if (!(c->x.v.f > 0.0)) a = 1.0;
  else {
    double lr = log(c->y.v.f) - log(c->x.v.f) + log_ratio + screen;
    a = lr >= 0.0 ? 1.0 : exp(lr);
    if (!(a >= 0.0)) a = 0.0;
  }

  /* Expected-value splatting of the proposal and the current state. */
  if (splat) {
    if (a > 0.0) splat(ctx, &c->y.v, a / c->y.v.f);
    if (a < 1.0 && c->x.v.f > 0.0) splat(ctx, &c->x.v, (1.0 - a) / c->x.v.f);
  }

  /* Accept or reject. */
  int accepted = rng_uniform(&c->r) < a;
  mc_kernel_stats *ks = &c->stats[ki];
  ks->proposed++;
  ks->accept_sum += a;
  ks->f_sum += c->y.v.f;
  ks->f_sum2 += c->y.v.f * c->y.v.f;
  if (accepted) {
    ks->accepted++;
    pss__accept(p);
    mc_state t = c->x;
    c->x = c->y;
    c->y = t;
  } else {
    pss__reject(p);
  }
  c->steps++;
  for (int i = 0; i < c->n_kernels; i++)
    if (c->kernels[i].on_step) c->kernels[i].on_step(c->kernels[i].self, &c->x, accepted);
  return ki;
}
