/*
 * path_states.c: space `path`, the states of path-space Metropolis light
 * transport (Veach and Guibas 1997; Veach 1997, chapter 11): whole light
 * paths (lmc/path/pathspace.h), moved by the path mutations of lmc/path in
 * a chain of their own (chain.h's mc_chain_kind), on the same driver as
 * every other MCMC integrator.
 *
 * One family over every length k in [kmin, kmax]. Its target draws the
 * bootstrap's samples: from two numbers of the sampler, a length k
 * (path__length_pmf: half uniform over [kmin, kmax], half geometric) and a
 * whole path of that length (mut_bidir_sample_whole: camera and light
 * walks split at random, joined by a connection), whose value is f / q
 * with q = mut_bidir_whole_pdf times the length's probability, the density
 * of the sample in the path measure. So
 * b = E[lum(f) / q] is the integral of lum(f) over this path space, the
 * chains' normalisation, and the driver's resampling of the bootstrap
 * samples in proportion to lum(f) / q starts the chains at paths
 * distributed about as f.
 *
 * The chain. Its state x is a path, its target lum(f(x)). Its kernels are
 * the moves of mc_path_move with the integrator's weights w_j. A step
 * selects a move among those that apply to x (the bidirectional mutation
 * always; a perturbation, the lens subpath mutation or the manifold
 * perturbation to the paths of its form, mut_perturb.h, mut_lenssub.h,
 * mut_manifold.h) with
 * probability P_j(x) = w_j / (sum of the applicable w), the move proposes
 * y with its own ratio f(y) T_j(y -> x) / (f(x) T_j(x -> y))
 * (mut_bidir_propose, mut_perturb_propose), and the selection enters too:
 * r = P_j(y) / P_j(x) times that (a proposal to which move j does not
 * apply back has r = 0). y is accepted with probability a = min(1, r).
 * Splats as chain.c's
 * (expected values, Veach 1997, sec. 11.5): y with weight a / f(y), x with
 * 1 - a, each as f(path) at the path's raster point; a move that makes no
 * proposal (mut_bidir.h's statuses) leaves x, splatted with weight 1.
 */
#include "lmc/states/path_states.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/driver/space.h"
#include "lmc/kernels/chain.h"
#include "lmc/path/mut_bidir.h"
#include "lmc/path/mut_lenssub.h"
#include "lmc/path/mut_manifold.h"
#include "lmc/path/mut_perturb.h"
#include "lmc/path/mut_pss.h"
#include "lmc/states/states.h"
#include "render/error.h"
#include "render/options.h"

typedef struct path__space {
  mc_space_family fam;
  ps_context ctx;
  mut_bidir mb;
  mut_perturb mp;
  mut_lenssub ml;
  mut_manifold mm;
  mut_manifold mh; /* HSLT */
  mut_pss mq;
  mc_chain_kind kind;
} path__space;

/* A target scratch: the path its last evaluation drew. */
typedef struct path__scratch {
  ps_path p;
  int64_t rays;
} path__scratch;

/* A chain's state: the current path and room for a proposal. */
typedef struct path__chain {
  ps_path buf[2];
  int cur;      /* buf[cur] is the current path */
  int64_t rays; /* traced by the chain's moves */
  bdpt_vertex *pss_v; /* the primary-sample step's scratch (MUT_PSS_SCRATCH), made on first use */
} path__chain;

static void *path__scratch_create(const mc_target *t) {
  (void)t;
  return calloc(1, sizeof(path__scratch));
}

static void path__scratch_destroy(void *s) { free(s); }

static int64_t path__scratch_rays(const void *s) { return ((const path__scratch *)s)->rays; }

/* A path's contribution as the driver splats it. */
static mc_value path__value(const ps_path *p) {
  mc_value v;
  memset(&v, 0, sizeof v);
  v.f = p->lum;
  v.value = p->f;
  v.rx = p->rx, v.ry = p->ry;
  return v;
}

/* The bootstrap's length k in [kmin, kmax]: half uniform, half
 * geometric from kmin (ratio 1/2), so that short paths, which carry most
 * light in most scenes, are not drowned by an unbounded depth's many long
 * lengths, and every length keeps a share. */
static double path__length_pmf(const path__space *P, int k) {
  int n = P->ctx.kmax - P->ctx.kmin + 1, j = k - P->ctx.kmin;
  if (j < 0 || j >= n) return 0.0;
  /* ratio 1/2, normalised over the n lengths: 2^-j / (2 (1 - 2^-n)) */
  return 0.5 / n + 0.5 * ldexp(1.0, -j - 1) / (1.0 - ldexp(1.0, -n));
}

static int path__draw_length(const path__space *P, double u) {
  double acc = 0.0;
  for (int k = P->ctx.kmin; k < P->ctx.kmax; k++) {
    acc += path__length_pmf(P, k);
    if (u < acc) return k;
  }
  return P->ctx.kmax;
}

/* The bootstrap's sample from two numbers of smp (see the opening comment). */
static int path__eval(const mc_target *t, void *scratch, lmc_sampler *smp, mc_value *OUT_value,
                      double *OUT_grad, int *OUT_grad_ok) {
  (void)OUT_grad;
  const path__space *P = t->ctx;
  path__scratch *sc = scratch;
  memset(OUT_value, 0, sizeof *OUT_value);
  if (OUT_grad_ok) *OUT_grad_ok = 0;
  sampler_use_stream(smp, LMC_STREAM_CAMERA);
  double u0 = sampler_next(smp), u1 = sampler_next(smp);
  rng r;
  rng_seed(&r, (uint64_t)(u0 * 9007199254740992.0), (uint64_t)(u1 * 9007199254740992.0));
  int k = path__draw_length(P, rng_uniform(&r));
  sc->p.k = 0, sc->p.lum = 0.0, sc->p.rays = 0;
  mut_bidir_status st = mut_bidir_sample_whole(&P->mb, &r, k, &sc->p);
  sc->rays += sc->p.rays;
  if (st != MUT_BIDIR_OK || !(sc->p.lum > 0.0)) {
    sc->p.lum = 0.0;
    return 0;
  }
  double q = mut_bidir_whole_pdf(&P->mb, &sc->p, 0) * path__length_pmf(P, k);
  if (!(q > 0.0) || !isfinite(sc->p.lum / q)) {
    sc->p.lum = 0.0;
    return 0;
  }
  *OUT_value = path__value(&sc->p);
  OUT_value->f /= q;
  OUT_value->value = rgb_scale(OUT_value->value, 1.0 / q);
  return 0;
}

/* ---- The chain ----------------------------------------------------------------- */

static lmc_status path__chain_create(mc_chain *c, lmc_error *err) {
  path__chain *pc = calloc(1, sizeof *pc);
  if (!pc) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for a path chain");
  c->own = pc;
  return LMC_OK;
}

static void path__chain_destroy(mc_chain *c) {
  path__chain *pc = c->own;
  if (pc) free(pc->pss_v);
  free(c->own);
  c->own = NULL;
}

static double path__chain_start(mc_chain *c) {
  path__chain *pc = c->own;
  const path__scratch *sc = c->scratch;
  pc->cur = 0;
  pc->buf[0] = sc->p;
  if (!(c->x.v.f > 0.0)) pc->buf[0].lum = 0.0, pc->buf[0].f = rgb_zero();
  return pc->buf[0].lum;
}

/* Whether move `move` applies to x. */
static int path__applies(const path__space *P, int move, const ps_path *x) {
  switch (move) {
  case MC_PATH_MOVE_LENS:
    return mut_perturb_applies(&P->mp, MUT_PERTURB_LENS, x);
  case MC_PATH_MOVE_MULTICHAIN:
    return mut_perturb_applies(&P->mp, MUT_PERTURB_MULTICHAIN, x);
  case MC_PATH_MOVE_CAUSTIC:
    return mut_perturb_applies(&P->mp, MUT_PERTURB_CAUSTIC, x);
  case MC_PATH_MOVE_LENSSUB:
    return mut_lenssub_m(&P->ctx, x) > 0;
  case MC_PATH_MOVE_MANIFOLD:
    return mut_manifold_applies(&P->mm, x);
  case MC_PATH_MOVE_HSLT:
    return mut_manifold_applies(&P->mh, x);
  default:
    return 1;
  }
}

/* The selection weights at x (the opening comment): w[j] the chain's
 * probability of kernel j when its move applies to x, else 0; returns
 * their sum. */
static double path__weights(const mc_chain *c, const ps_path *x, double *w) {
  const path__space *P = c->target->ctx;
  double sum = 0.0;
  for (int j = 0; j < c->n_kernels; j++) {
    w[j] = path__applies(P, c->kernels[j].coord, x) ? c->cdf[j] - (j > 0 ? c->cdf[j - 1] : 0.0)
                                                     : 0.0;
    sum += w[j];
  }
  return sum;
}

/* The kernel selected at x, and its probability P_ki(x). */
static int path__pick(mc_chain *c, const ps_path *x, double *OUT_p) {
  double w[MC_MAX_KERNELS], sum = path__weights(c, x, w);
  double u = rng_uniform(&c->r), acc = 0.0;
  int last = 0;
  *OUT_p = 0.0;
  for (int j = 0; j < c->n_kernels; j++) {
    double p = sum > 0.0 ? w[j] / sum : 0.0;
    if (!(p > 0.0)) continue;
    last = j;
    acc += p;
    *OUT_p = p;
    if (u < acc) return j;
  }
  return last;
}

/* Move ki's proposal y from x and its ratio, selection included; 0 when
 * it makes none. */
static int path__propose(const path__space *P, mc_chain *c, int ki, double p_x, const ps_path *x,
                         ps_path *y, double *OUT_ratio) {
  int move = c->kernels[ki].coord, ok;
  double ratio = 0.0;
  if (move == MC_PATH_MOVE_BIDIR) {
    mut_bidir_record rec;
    ok = mut_bidir_propose(&P->mb, &c->r, x, y, &rec, &ratio) == MUT_BIDIR_OK;
  } else if (move == MC_PATH_MOVE_LENSSUB) {
    ok = mut_lenssub_propose(&P->ml, &c->r, x, y, &ratio, &y->rays);
  } else if (move == MC_PATH_MOVE_PSS) {
    path__chain *pc = c->own;
    if (!pc->pss_v) pc->pss_v = malloc(MUT_PSS_SCRATCH * sizeof *pc->pss_v);
    mut_pss_tally ty = {0, 0, 0};
    ok = pc->pss_v && mut_pss_propose(&P->mq, &c->r, x, y, &ratio, pc->pss_v, &y->rays, &ty);
    c->stats[ki].inverted += ty.inverted;
    c->stats[ki].refused += ty.refused, c->stats[ki].elsewhere += ty.elsewhere;
  } else if (move == MC_PATH_MOVE_MANIFOLD || move == MC_PATH_MOVE_HSLT) {
    mut_manifold_tally ty = {0, 0, 0, 0};
    ok = mut_manifold_propose(move == MC_PATH_MOVE_HSLT ? &P->mh : &P->mm, &c->r, x, y, &ratio,
                              &y->rays, &ty);
    c->stats[ki].walks += ty.walks, c->stats[ki].walked += ty.walked;
    c->stats[ki].irreversible += ty.irreversible;
  } else {
    mut_perturb_kind kind = move == MC_PATH_MOVE_LENS         ? MUT_PERTURB_LENS
                            : move == MC_PATH_MOVE_MULTICHAIN ? MUT_PERTURB_MULTICHAIN
                                                              : MUT_PERTURB_CAUSTIC;
    ok = mut_perturb_propose(&P->mp, kind, &c->r, x, y, &ratio, &y->rays, NULL);
  }
  *OUT_ratio = 0.0;
  if (!ok) return 0;
  if (ratio > 0.0) {
    double w[MC_MAX_KERNELS], sum = path__weights(c, y, w);
    ratio *= (sum > 0.0 ? w[ki] / sum : 0.0) / p_x;
  }
  *OUT_ratio = isfinite(ratio) ? ratio : 0.0;
  return 1;
}

static int path__chain_step(mc_chain *c, mc_splat_fn splat, void *ctx) {
  const path__space *P = c->target->ctx;
  path__chain *pc = c->own;
  ps_path *x = &pc->buf[pc->cur], *y = &pc->buf[1 - pc->cur];
  double p_x;
  int ki = path__pick(c, x, &p_x);
  double ratio = 0.0;
  y->rays = 0;
  int ok = path__propose(P, c, ki, p_x, x, y, &ratio);
  pc->rays += y->rays;
  double a = ok ? fmin(1.0, ratio) : 0.0;
  c->stats[ki].proposed++;
  c->stats[ki].accept_sum += a;
  c->steps++;
  if (splat) {
    if (a > 0.0) {
      mc_value vy = path__value(y);
      splat(ctx, &vy, a / y->lum);
    }
    if (a < 1.0 && x->lum > 0.0) {
      mc_value vx = path__value(x);
      splat(ctx, &vx, (1.0 - a) / x->lum);
    }
  }
  if (a > 0.0 && rng_uniform(&c->r) < a) {
    pc->cur = 1 - pc->cur;
    c->stats[ki].accepted++;
  }
  return ki;
}

static int64_t path__chain_rays(const mc_chain *c) {
  return c->own ? ((const path__chain *)c->own)->rays : 0;
}

/* ---- The space ----------------------------------------------------------------- */

/* The space's own settings (its flag table). */
typedef struct path__settings {
  double glossy_rough; /* --glossy-roughness */
  double hslt_step;    /* --hslt-step */
} path__settings;

static const path__settings path__defaults = {0.1, 0.1};

static const lmc_opt path__opts[] = {
    {"glossy-roughness", LMC_OPT_DOUBLE, offsetof(path__settings, glossy_rough), 0, 0, 1, NULL,
     NULL, 0, "R", NULL,
     "the perturbations and the lens subpath mutation retrace glossy vertices of roughness "
     "<= R by sampling their BSDFs, as they retrace specular ones (0: Veach's, joining "
     "through them)",
     NULL},
    {"hslt-step", LMC_OPT_DOUBLE, offsetof(path__settings, hslt_step), 0, 1e-3, 1e3, NULL, NULL, 0,
     "F", NULL,
     "HSLT's half-vector perturbation: each vertex's half vector moves by a normal step of F "
     "times its roughness (at most 0.25; a diffuse vertex 0.25)",
     NULL},
};

const lmc_opt_table mc_space_path_options = {"The path states (--states path, mlt)", path__opts,
                                             2, &path__defaults, sizeof path__defaults};

static void path__space_destroy(mc_space *sp) {
  free(sp->ctx);
  sp->ctx = NULL;
}

lmc_status mc_space_path_create(mc_space *OUT, const scene *s, const render_settings *rs,
                                lmc_error *err) {
  path__space *P = calloc(1, sizeof *P);
  if (!P) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the path states");
  OUT->ctx = P;
  OUT->destroy = path__space_destroy;
  ps_context_init(&P->ctx, s, rs);
  mut_bidir_init(&P->mb, &P->ctx);
  mut_perturb_init(&P->mp, &P->ctx);
  path__settings ps;
  lmc_status st = lmc_opt_read(&mc_space_path_options, rs, &ps, err);
  if (st) return st;
  P->ctx.glossy_rough = ps.glossy_rough;
  mut_lenssub_init(&P->ml, &P->ctx);
  mut_manifold_init(&P->mm, &P->ctx, &P->mp);
  mut_manifold_init_hslt(&P->mh, &P->ctx, &P->mp, ps.hslt_step);
  mut_pss_init(&P->mq, &P->ctx, mc_light_u1_scale(s));
  if (rs->maxdepth < 0 && !rs->quiet)
    fprintf(stderr, "lmc: %s renders paths of at most %d segments (set --maxdepth)\n",
            rs->integrator, P->ctx.kmax);
  if (P->ctx.kmin > P->ctx.kmax)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "%s: no path length in [%d, %d]",
                         rs->integrator, P->ctx.kmin, P->ctx.kmax);
  P->kind = (mc_chain_kind){P,
                            path__chain_create,
                            path__chain_destroy,
                            path__chain_start,
                            path__chain_step,
                            path__chain_rays};
  mc_target *t = &P->fam.target;
  t->dim = t->stream_dim[LMC_STREAM_CAMERA] = 2;
  t->ctx = P;
  t->eval = path__eval;
  t->scratch_create = path__scratch_create;
  t->scratch_destroy = path__scratch_destroy;
  t->scratch_rays = path__scratch_rays;
  t->chain_kind = &P->kind;
  P->fam.length = 0;
  P->fam.technique = -1;
  OUT->name = "path";
  OUT->n_fam = 1;
  OUT->fam = &P->fam;
  OUT->kmin = P->ctx.kmin;
  OUT->kmax = P->ctx.kmax;
  OUT->pool_large = 0;
  OUT->b_note = "whole paths of the path space";
  return LMC_OK;
}
