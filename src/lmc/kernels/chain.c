/*
 * chain.c: the built-in kernels and the Metropolis-Hastings step with
 * expected-value splatting, on the lazy primary sample vector of pss.c.
 * See chain.h for the model.
 */
#include "lmc/kernels/chain.h"
#include "lmc/kernels/pss.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* --- kernels ----------------------------------------------------------------- */

mc_kernel mc_kernel_large(void) {
  mc_kernel k = {0};
  k.name = "large";
  k.kind = MC_KERNEL_LARGE;
  return k;
}

mc_kernel mc_kernel_small_gauss(double sigma) {
  mc_kernel k = mc_kernel_small(0.0, sigma);
  k.name = "small";
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
    if (k[i].kind == MC_KERNEL_SMALL && !(k[i].s1 >= 0.0 && k[i].s1 < k[i].s2 && k[i].s2 < 0.5))
      return lmc_error_set(err, LMC_EINVAL, NULL, 0,
                           "mc_chain_create: small step needs 0 < s1 < s2 < 1/2 "
                           "(Gaussian: s1 = 0, 0 < sigma < 1/2)");
    if (k[i].kind == MC_KERNEL_TECHNIQUE && (k[i].coord < 0 || k[i].coord >= target->dim))
      return lmc_error_set(err, LMC_EINVAL, NULL, 0, "mc_chain_create: bad technique coordinate");
    if (k[i].kind == MC_KERNEL_TECHNIQUE && target->n_labels > 0)
      return lmc_error_set(err, LMC_EINVAL, NULL, 0,
                           "mc_chain_create: no technique kernel on a labelled target");
    if (k[i].kind == MC_KERNEL_FULL && (!k[i].propose || !k[i].log_density))
      return lmc_error_set(err, LMC_EINVAL, NULL, 0, "mc_chain_create: full kernel without densities");
    if ((k[i].kind == MC_KERNEL_OWN) != (target->chain_kind != NULL))
      return lmc_error_set(err, LMC_EINVAL, NULL, 0,
                           target->chain_kind
                               ? "these states take their own moves only (kernel %s)"
                               : "kernel %s needs states of its own kind",
                           k[i].name ? k[i].name : "?");
    total += prob[i];
  }
  if (!(total > 0.0))
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "mc_chain_create: probabilities sum to 0");

  mc_chain *c = calloc(1, sizeof *c);
  mc_pss *p = mc_pss_create(target->dim);
  int D = target->dim;
  if (c) c->pss = p;
  if (!c || !p) goto oom;
  c->x.u = calloc((size_t)D, sizeof(double));
  c->y.u = calloc((size_t)D, sizeof(double));
  c->sub = calloc((size_t)D, sizeof(int));
  c->x.grad = calloc((size_t)D, sizeof(double));
  c->y.grad = calloc((size_t)D, sizeof(double));
  if (!c->x.u || !c->y.u || !c->x.grad || !c->y.grad || !c->sub)
    goto oom;
  if (target->eval_hess) {
    size_t hsz = (size_t)MC_HESS_MAX * (MC_HESS_MAX + 1) / 2;
    c->x.hidx = calloc(MC_HESS_MAX, sizeof(int));
    c->y.hidx = calloc(MC_HESS_MAX, sizeof(int));
    c->x.hess = calloc(hsz, sizeof(double));
    c->y.hess = calloc(hsz, sizeof(double));
    if (!c->x.hidx || !c->y.hidx || !c->x.hess || !c->y.hess) goto oom;
  }
  if (target->n_labels > 0) {
    if (!target->eval_label || !target->eval_all) {
      mc_chain_destroy(c);
      return lmc_error_set(err, LMC_EINVAL, NULL, 0,
                           "mc_chain_create: labelled target without eval_label/eval_all");
    }
    c->cy = calloc((size_t)target->n_labels, sizeof *c->cy);
    c->cx = calloc((size_t)target->n_labels, sizeof *c->cx);
    c->drawn = calloc((size_t)D, sizeof *c->drawn);
    c->lab = calloc(3 * (size_t)target->n_labels, sizeof *c->lab);
    if (!c->cy || !c->cx || !c->drawn || !c->lab) goto oom;
  }
  c->x.dim = c->y.dim = D;
  mc_pss_init(p, target, s1, s2, &c->r, &c->overflow);
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
    /* Labelled targets with relabel: the roulette's evaluation of the
     * current state must leave the proposal's work in c->scratch. */
    if (target->n_labels > 0 && target->relabel) {
      c->scratch_alt = target->scratch_create(target);
      if (!c->scratch_alt) goto oom;
    }
  }
  if (target->chain_kind) {
    lmc_status st = target->chain_kind->create(c, err);
    if (st) {
      mc_chain_destroy(c);
      return st;
    }
  }
  *OUT_chain = c;
  return LMC_OK;
oom:
  mc_chain_destroy(c);
  if (!c) mc_pss_destroy(p);
  return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for a chain of %d coordinates",
                       D);
}

void mc_chain_destroy(mc_chain *c) {
  if (!c) return;
  if (c->own && c->target->chain_kind) c->target->chain_kind->destroy(c);
  mc_pss_destroy(c->pss);
  free(c->x.u);
  free(c->y.u);
  free(c->sub);
  free(c->x.grad);
  free(c->y.grad);
  free(c->x.hidx);
  free(c->y.hidx);
  free(c->x.hess);
  free(c->y.hess);
  free(c->cy);
  free(c->cx);
  free(c->drawn);
  free(c->lab);
  if (c->scratch && c->target->scratch_destroy) c->target->scratch_destroy(c->scratch);
  if (c->scratch_alt && c->target->scratch_destroy) c->target->scratch_destroy(c->scratch_alt);
  free(c);
}

/* Evaluates the state the lazy vector holds into st (f = 0 on failure),
 * with its gradient when want_grad >= 1 and its Hessian when 2 (targets
 * with eval_hess). */
static void chain__eval(mc_chain *c, mc_state *st, int want_grad) {
  mc_pss_rewind(c->pss);
  st->grad_ok = 0;
  st->hess_ok = 0;
  st->grad_eval = want_grad;
  const mc_target *T = c->target;
  int rc;
  if (want_grad >= 2 && T->eval_hess)
    rc = T->eval_hess(T, c->scratch, &c->pss->base, st->label, &st->v, st->grad, &st->grad_ok,
                      &st->hn, st->hidx, st->hess, &st->hess_ok);
  else if (T->n_labels > 0)
    rc = T->eval_label(T, c->scratch, &c->pss->base, st->label, &st->v,
                       want_grad ? st->grad : NULL, &st->grad_ok);
  else
    rc = T->eval(T, c->scratch, &c->pss->base, &st->v, want_grad ? st->grad : NULL,
                 &st->grad_ok);
  if (T->n_labels == 0 || !T->relabel) st->v.f_large = st->v.f;
  if (rc != 0 || !(st->v.f >= 0.0) || !isfinite(st->v.f)) {
    if (rc != 0) c->eval_failures++;
    st->v.f = st->v.f_large = 0.0;
    st->grad_ok = 0;
    st->hess_ok = 0;
  }
  if (!st->grad_ok) st->hess_ok = 0;
}

/* The gradient of the current state, evaluated lazily: after
 * pss__materialise every coordinate is up to date, so the evaluation
 * replays x exactly (f is a function of u). The stored f is kept: when a
 * coordinate past a stream's block made the new f differ (pseudo-marginal,
 * chain.h), x gets no gradient. A difference of rounding (a target whose
 * evaluation with the gradient is other code, as the spaces' are, agreeing
 * to 1e-9) is not one. */
static void chain__regrad_state(mc_chain *c, mc_state *st, int order) {
  mc_value v = st->v;
  if (!(v.f > 0.0)) {
    st->grad_ok = st->hess_ok = 0;
    st->grad_eval = order;
    return;
  }
  chain__eval(c, st, order);
  if (!(fabs(st->v.f - v.f) <= 1e-9 * v.f)) st->grad_ok = st->hess_ok = 0;
  st->v = v;
}

static void chain__regrad(mc_chain *c, int order) {
  c->regrad++;
  chain__regrad_state(c, &c->x, order);
}

/* Sums the labels' f (labelled targets), dropping non-finite or negative
 * entries; returns the count kept. */
static int chain__clean(mc_contrib *cb, int n, double *OUT_sum) {
  int m = 0;
  double sum = 0.0;
  for (int j = 0; j < n; j++) {
    double f = cb[j].v.f;
    if (!(f > 0.0) || !isfinite(f)) continue;
    cb[m++] = cb[j];
    sum += f;
  }
  *OUT_sum = isfinite(sum) ? sum : 0.0;
  return isfinite(sum) ? m : 0;
}

/* A label of cb[0..n-1] chosen in proportion to f with the uniform u. */
static int chain__pick(const mc_contrib *cb, int n, double sum, double u) {
  double target = u * sum, acc = 0.0;
  for (int j = 0; j < n - 1; j++) {
    acc += cb[j].v.f;
    if (target < acc) return j;
  }
  return n - 1;
}

/* Makes label cb's state current (labelled targets): the numbers u of
 * the large step are rewritten into the label's coordinates (relabel),
 * the value scaled by the Jacobian. */
static void chain__take(mc_chain *c, const mc_contrib *cb, double *u) {
  const mc_target *T = c->target;
  c->x.label = cb->label;
  c->x.v = cb->v;
  c->x.v.f_large = cb->v.f;
  c->x.grad_ok = c->x.grad_eval = 0;
  if (!T->relabel) return;
  double jac = T->relabel(T, c->scratch, cb->label, u, &c->r);
  if (!(jac >= 0.0) || !isfinite(jac)) jac = 0.0;
  c->x.v.f *= jac;
  c->x.v.value = rgb_scale(c->x.v.value, jac);
  if (!(c->x.v.f > 0.0) || !isfinite(c->x.v.f)) {
    /* Not for a consistent target; a state of f = 0 accepts any
     * proposal (chain.c's ratio), so the chain leaves it at once. */
    c->x.v.f = 0.0;
    c->x.v.value = rgb_zero();
  }
}

double mc_chain_start(mc_chain *c, uint64_t seed, uint64_t seq, uint64_t chain_seq) {
  mc_pss *p = c->pss;
  const mc_target *T = c->target;
  for (int i = 0; i < p->dim; i++) p->mod[i] = 0;
  p->iter = 0;
  p->last_large = 0;
  rng_seed(&c->r, seed, seq);
  mc_pss_begin(p, 1);
  if (T->n_labels > 0) {
    /* Every label of the starting numbers; the state takes one in
     * proportion to its f (drawn from the chain's own stream). */
    mc_pss_rewind(p);
    int n = T->eval_all(T, c->scratch, &p->base, -1, c->cy);
    n = chain__clean(c->cy, n < 0 ? 0 : n, &c->sum_x);
    mc_pss_accept(p);
    rng_seed(&c->r, seed, chain_seq);
    double u = rng_uniform(&c->r);
    memset(&c->x.v, 0, sizeof c->x.v);
    c->x.label = 0;
    c->x.grad_ok = c->x.grad_eval = 0;
    if (n > 0) {
      int j = chain__pick(c->cy, n, c->sum_x, u);
      chain__take(c, &c->cy[j], p->val);
    } else {
      c->sum_x = 0.0;
    }
    c->steps = 0;
    c->x.from_large = 1;
    return c->x.v.f;
  }
  chain__eval(c, &c->x, 0);
  mc_pss_accept(p);
  rng_seed(&c->r, seed, chain_seq);
  c->steps = 0;
  c->x.from_large = 1;
  if (T->chain_kind) return T->chain_kind->start(c);
  return c->x.v.f;
}

lmc_status mc_chain_set_kernels(mc_chain *c, const mc_kernel *k, const double *prob, int n,
                                lmc_error *err) {
  if (n < 1 || n > MC_MAX_KERNELS)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "mc_chain_set_kernels: %d kernels", n);
  for (int i = 0; i < n; i++) {
    if (k[i].kind == MC_KERNEL_SMALL && (k[i].s1 != c->pss->s1 || k[i].s2 != c->pss->s2))
      return lmc_error_set(err, LMC_EINVAL, NULL, 0,
                           "mc_chain_set_kernels: the small step must stay the chain's");
    if (k[i].kind == MC_KERNEL_FULL && (!k[i].propose || !k[i].log_density))
      return lmc_error_set(err, LMC_EINVAL, NULL, 0, "mc_chain_set_kernels: full kernel without densities");
    if ((k[i].kind == MC_KERNEL_OWN) != (c->target->chain_kind != NULL))
      return lmc_error_set(err, LMC_EINVAL, NULL, 0, "mc_chain_set_kernels: kernel %s of another kind of state",
                           k[i].name ? k[i].name : "?");
  }
  c->with_grad = 0;
  for (int i = 0; i < n; i++) {
    /* A kernel that changes starts its statistics afresh. */
    int same = i < c->n_kernels && c->kernels[i].kind == k[i].kind &&
               c->kernels[i].propose == k[i].propose && c->kernels[i].self == k[i].self &&
               (k[i].kind != MC_KERNEL_OWN || c->kernels[i].coord == k[i].coord);
    if (!same) memset(&c->stats[i], 0, sizeof c->stats[i]);
    c->kernels[i] = k[i];
    if (k[i].needs_grad) c->with_grad = 1;
  }
  c->n_kernels = n;
  mc_chain_set_probs(c, prob);
  return LMC_OK;
}

void mc_chain_set_probs(mc_chain *c, const double *prob) {
  double total = 0.0, acc = 0.0;
  for (int i = 0; i < c->n_kernels; i++) total += prob[i] > 0.0 ? prob[i] : 0.0;
  if (!(total > 0.0)) return;
  for (int i = 0; i < c->n_kernels; i++) {
    acc += (prob[i] > 0.0 ? prob[i] : 0.0) / total;
    c->cdf[i] = acc;
  }
  c->cdf[c->n_kernels - 1] = 1.0;
}

void mc_chain_bind(mc_chain *c, void *ws) {
  const mc_target *T = c->target;
  if (!T->scratch_bind) return;
  if (c->scratch) T->scratch_bind(c->scratch, ws);
  if (c->scratch_alt) T->scratch_bind(c->scratch_alt, ws);
}

int64_t mc_chain_rays(const mc_chain *c) {
  const mc_target *T = c->target;
  int64_t own = T->chain_kind ? T->chain_kind->rays(c) : 0;
  if (!T->scratch_rays) return own;
  return own + (c->scratch ? T->scratch_rays(c->scratch) : 0) +
         (c->scratch_alt ? T->scratch_rays(c->scratch_alt) : 0);
}

int mc_chain_pick(mc_chain *c) {
  double uk = rng_uniform(&c->r);
  int ki = 0;
  while (ki < c->n_kernels - 1 && uk >= c->cdf[ki]) ki++;
  return ki;
}

int mc_chain_max_splats(const mc_chain *c) {
  return c->target->n_labels > 0 ? c->target->n_labels + 1 : 2;
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
  smp.base.skip_n = NULL;
  rng_seed(&smp.r, seed, seq);
  mc_value v;
  memset(&v, 0, sizeof v);
  int ok = 0;
  if (t->n_labels > 0) {
    /* F(u), the sum over the labels (target.h). */
    mc_contrib local[64];
    mc_contrib *cb = t->n_labels <= 64 ? local : malloc((size_t)t->n_labels * sizeof *cb);
    double sum = 0.0;
    if (cb) {
      int n = t->eval_all(t, scratch, &smp.base, -1, cb);
      chain__clean(cb, n < 0 ? 0 : n, &sum);
      if (cb != local) free(cb);
    }
    v.f = sum;
    if (OUT_value) *OUT_value = v;
    return sum;
  }
  if (t->eval(t, scratch, &smp.base, &v, NULL, &ok) != 0 || !(v.f >= 0.0) || !isfinite(v.f))
    v.f = 0.0;
  if (OUT_value) *OUT_value = v;
  return v.f;
}

/* The recording sampler of the labelled large step: fresh uniforms from
 * the chain's stream, each kept in y.u at its coordinate (numbers past a
 * stream's block are fresh and not kept, as pss__next's). */
typedef struct chain__rec {
  lmc_sampler base;
  mc_chain *c;
  int stream, pos[LMC_STREAM_COUNT];
} chain__rec;

static double chain__rec_next(lmc_sampler *self) {
  chain__rec *r = (chain__rec *)self;
  mc_chain *c = r->c;
  mc_pss *p = c->pss;
  double u = rng_uniform(&c->r);
  int k = r->stream;
  if (r->pos[k] >= p->stream_dim[k]) {
    c->overflow++;
    return u;
  }
  int i = p->stream_off[k] + r->pos[k]++;
  c->y.u[i] = u;
  c->drawn[c->n_drawn++] = i;
  return u;
}

static void chain__rec_stream(lmc_sampler *self, int stream) {
  chain__rec *r = (chain__rec *)self;
  if (stream >= 0 && stream < LMC_STREAM_COUNT) r->stream = stream;
}

/* F of the current state: every label evaluated at its coordinates, the
 * state's own label counted with its stored f (so that F >= f exactly). */
static double chain__sum_current(mc_chain *c) {
  const mc_target *T = c->target;
  mc_pss *p = c->pss;
  /* The lazy vector brings each coordinate up to date as eval_all reads
   * it (the coordinates it does not read stay owed, as after any step). */
  p->large = 0;
  mc_pss_rewind(p);
  c->sum_evals++;
  int64_t r0 = mc_chain_rays(c);
  int n = T->eval_all(T, c->scratch_alt ? c->scratch_alt : c->scratch, &p->base, c->x.label, c->cx);
  c->sum_rays += mc_chain_rays(c) - r0;
  double sum = c->x.v.f_large;
  for (int j = 0; j < n; j++) {
    double f = c->cx[j].v.f;
    if (c->cx[j].label != c->x.label && f > 0.0 && isfinite(f)) sum += f;
  }
  return isfinite(sum) ? sum : c->x.v.f_large;
}

/* The large step of a labelled target (chain.h). */
static void chain__large_labelled(mc_chain *c, int ki, mc_splat_fn splat, void *ctx) {
  const mc_target *T = c->target;
  mc_pss *p = c->pss;

  /* Propose a fresh u' and evaluate every label there. */
  chain__rec rec = {{chain__rec_next, chain__rec_stream, NULL}, c, 0, {0}};
  c->n_drawn = 0;
  int n = T->eval_all(T, c->scratch, &rec.base, -1, c->cy);
  double sum_y;
  n = chain__clean(c->cy, n < 0 ? 0 : n, &sum_y);
  c->n_cy = n;
  mc_kernel_stats *ks = &c->stats[ki];
  ks->proposed++;
  ks->f_sum += sum_y;
  ks->f_sum2 += sum_y * sum_y;

  /* a = min(1, F(u') / F(u)), with F(u) from the roulette when unknown. */
  double a_hat = 0.0, a = 0.0;
  double fx = c->x.v.f_large;
  if (!(sum_y > 0.0)) {
    a_hat = a = 0.0;
  } else if (!(fx > 0.0)) {
    a_hat = a = 1.0;
  } else if (c->sum_x > 0.0) {
    a_hat = a = fmin(1.0, sum_y / c->sum_x);
  } else {
    double pr = fmin(1.0, sum_y / fx);
    if (rng_uniform(&c->r) < pr) {
      c->sum_x = chain__sum_current(c);
      a = fmin(1.0, sum_y / c->sum_x);
      a_hat = fmin(1.0, a / pr);
    }
  }

  /* Expected-value splatting: the proposal over all its labels. */
  if (splat) {
    if (a_hat > 0.0)
      for (int j = 0; j < n; j++) splat(ctx, &c->cy[j].v, a_hat / sum_y);
    if (a_hat < 1.0 && c->x.v.f > 0.0) splat(ctx, &c->x.v, (1.0 - a_hat) / c->x.v.f);
  }

  /* Accept with probability a (a_hat is a / p after a roulette that
   * evaluated, 0 after one that did not). */
  ks->accept_sum += a_hat;
  int accepted = a_hat > 0.0 && (a_hat >= 1.0 || rng_uniform(&c->r) < a_hat);
  if (accepted) {
    int j = chain__pick(c->cy, n, sum_y, rng_uniform(&c->r));
    ks->accepted++;
    chain__take(c, &c->cy[j], c->y.u);
    c->x.from_large = 1;
    mc_pss_begin(p, 1);
    for (int q = 0; q < c->n_drawn; q++) mc_pss_set(p, c->drawn[q], c->y.u[c->drawn[q]]);
    mc_pss_accept(p);
    c->sum_x = sum_y;
  }
  c->steps++;
  for (int i = 0; i < c->n_kernels; i++)
    if (c->kernels[i].on_step) c->kernels[i].on_step(c->kernels[i].self, &c->x, accepted);
}

/* The end of a step whose full kernel proposed outside [0,1)^dim (its
 * propose returned -INFINITY): acceptance 0, the current state splatted
 * with weight 1, as mc_chain_step does for a proposal with f(y) = 0. */
static void chain__reject_outside(mc_chain *c, int ki, mc_splat_fn splat, void *ctx) {
  if (splat && c->x.v.f > 0.0) splat(ctx, &c->x.v, 1.0 / c->x.v.f);
  c->stats[ki].proposed++;
  mc_pss_reject(c->pss);
  c->steps++;
  for (int i = 0; i < c->n_kernels; i++)
    if (c->kernels[i].on_step) c->kernels[i].on_step(c->kernels[i].self, &c->x, 0);
}

static int chain__step(mc_chain *c, mc_splat_fn splat, void *ctx) {
  if (c->target->chain_kind) return c->target->chain_kind->step(c, splat, ctx);
  mc_pss *p = c->pss;
  int ki = mc_chain_pick(c);
  mc_kernel *k = &c->kernels[ki];
  if (k->kind == MC_KERNEL_LARGE && c->target->n_labels > 0) {
    chain__large_labelled(c, ki, splat, ctx);
    return ki;
  }
  c->y.label = c->x.label;

  /* Propose y and evaluate it; log_ratio = log q(x|y) - log q(y|x). With
   * delayed acceptance, screen = the log of a1(y, x) / a1(x, y) (chain.h),
   * or -INFINITY when the first test rejected y. */
  double log_ratio = 0.0, screen = 0.0;
  int full = k->kind == MC_KERNEL_FULL;
  if (full) {
    /* A kernel on a subset of the coordinates reads and writes those
     * alone; the others take the lazy vector's small step (chain.h). */
    int n_sub = k->coords ? k->coords(k->self, &c->x, c->sub) : -1;
    if (n_sub >= 0) {
      p->large = 0;
      for (int q = 0; q < n_sub; q++) c->x.u[c->sub[q]] = mc_pss_get(p, c->sub[q]);
    } else {
      mc_pss_materialise(p, c->x.u);
    }
    if (c->x.grad_eval < k->needs_grad) chain__regrad(c, k->needs_grad);
    mc_pss_begin(p, 0);
    double log_fwd = k->propose(k->self, &c->r, &c->x, c->y.u);
    if (log_fwd == -INFINITY) {
      /* y lies outside [0,1)^dim, where the target is zero: rejected as
       * such a proposal would be, with nothing evaluated. */
      chain__reject_outside(c, ki, splat, ctx);
      return ki;
    }
    if (k->label && c->target->n_labels > 0) c->y.label = k->label(k->self);
    if (n_sub >= 0) {
      for (int q = 0; q < n_sub; q++) mc_pss_set(p, c->sub[q], c->y.u[c->sub[q]]);
    } else {
      for (int i = 0; i < p->dim; i++) mc_pss_set(p, i, c->y.u[i]);
    }
    int delayed = k->log_screen && c->x.v.f > 0.0;
    /* The proposal with what the kernel needs at a state (gradient, or
     * Hessian: the reverse density is built from it); none before a first
     * test of delayed acceptance. A kernel that evaluated y gives its value. */
    if (k->value && !k->needs_grad && !k->log_screen && k->value(k->self, &c->y.v)) {
      c->y.grad_ok = c->y.hess_ok = c->y.grad_eval = 0;
      if (!(c->y.v.f >= 0.0) || !isfinite(c->y.v.f)) c->y.v.f = c->y.v.f_large = 0.0;
    } else {
      chain__eval(c, &c->y, delayed ? 0 : k->needs_grad);
    }
    if (delayed && c->y.v.f > 0.0) {
      c->screened++;
      double s1 = k->log_screen(k->self, &c->x, c->y.u, c->y.v.f);
      double la1 = s1 < 0.0 ? s1 : 0.0;
      if (!(rng_uniform(&c->r) < exp(la1))) {
        screen = -INFINITY;
      } else {
        c->screen_passed++;
        if (k->needs_grad) chain__regrad_state(c, &c->y, k->needs_grad);
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
    mc_pss_begin(p, 0);
    mc_pss_set(p, k->coord, rng_uniform(&c->r));
    chain__eval(c, &c->y, k->needs_grad);
  } else {
    mc_pss_begin(p, k->kind == MC_KERNEL_LARGE);
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
    mc_pss_accept(p);
    mc_state t = c->x;
    c->x = c->y;
    c->y = t;
    c->x.from_large = k->kind == MC_KERNEL_LARGE;
    c->sum_x = 0.0; /* labelled targets: F of the new state is not known */
  } else {
    mc_pss_reject(p);
  }
  c->steps++;
  for (int i = 0; i < c->n_kernels; i++)
    if (c->kernels[i].on_step) c->kernels[i].on_step(c->kernels[i].self, &c->x, accepted);
  return ki;
}

int mc_chain_step(mc_chain *c, mc_splat_fn splat, void *ctx) {
  int64_t r0 = mc_chain_rays(c);
  int label = c->x.label;
  int ki = chain__step(c, splat, ctx);
  int64_t rays = mc_chain_rays(c) - r0;
  c->stats[ki].rays += rays;
  if (c->lab && label >= 0 && label < c->target->n_labels) {
    int64_t *l = c->lab + 3 * (size_t)label;
    l[0]++;
    if (c->kernels[ki].kind != MC_KERNEL_LARGE) l[1]++, l[2] += rays;
  }
  return ki;
}
