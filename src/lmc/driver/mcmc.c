/*
 * mcmc.c: the MCMC driver, which runs every MCMC integrator (method.h) on
 * every state space (space.h) and names none of them.
 *
 * One render: the direct pass (--direct separate), the state space and its
 * families, the integrator's run, the bootstrap and b, the chains'
 * allocation and starting states, the rounds with their splats, snapshots
 * and budgets, and the statistics; each is a function below, over one
 * mcmc_render (mcmc_internal.h). The bootstrap and the normalisation b
 * are in mcmc_b.c.
 *
 * Normalisation. For a family g with target f_g, b_g = E[f_g(u)] over
 * uniform u is estimated by the bootstrap, or by the space's own
 * estimator (space.h's estimate_b: the mmlt states' b_k from whole BDPT
 * samples, independent of those that pick the starting states); the
 * family's n_g chains each make m mutations, and its image is b_g / (n_g m) times the sum of its splats
 * value / f (expected-value splatting, chain.c). Families add.
 *
 * Refining b with the large steps (Kelemen et al. 2002 do the same; on
 * spaces with pool_large, see mcmc__refine_b). A large step proposes a
 * fresh uniform state y, so f_g(y) is one more independent sample of
 * exactly what the bootstrap averages (the mmlt states' large step of a
 * length-k chain samples b_k too, but with a far heavier tail than their
 * estimator's samples, so they keep its b). The
 * chains tally sum f(y), sum f(y)^2 and the count of their large-step
 * proposals (chain.h, mc_kernel_stats), and the image uses
 * b_g = (bootstrap sum + large-step
 * sum) / (bootstrap count + large-step count), reduced in chain order so
 * that under --spp the image stays bit-identical for any --threads. The
 * splats are therefore kept apart from b: one family multiplies the film
 * by b at the end (film.splat_scale); several keep one splat buffer per
 * family and sum b_k times it into the film at every snapshot and at the
 * end (when those buffers would exceed MCMC_FAMILY_FILM_BYTES, it falls
 * back to the estimate of b_k before the chains, baked into the splats as they are made).
 * Bias: b_g is an unbiased estimate of b_g, but the image is b_g times the
 * normalised splat histogram, and the large-step proposals that refine b_g
 * also drive the chains, so the two factors are (weakly) correlated: like
 * every ratio estimator the product has an O(1/N) bias, N the number of
 * samples of b_g, far below its O(1/sqrt N) noise (and the bootstrap-only
 * b has the same caveat through the starting states).
 *
 * Bootstrap (bootstrap.h). Sample j of family g is the large step drawn
 * from the stream (seed, hash(g, j)). --bootstrap N draws exactly N per
 * family, all in b_g. Otherwise a pilot of MCMC_BOOT_BATCH per family,
 * then a main phase in batches shared among the families by Neyman
 * allocation (in proportion to sigma_g / sqrt(c_g), c_g the rays per
 * sample: on ring-caustics about half the samples of an even split for
 * the same error), at most MCMC_BOOT_CAP samples in all. Under --time it
 * runs for a tenth of the time left, on the pilot's shares, and b_g is the
 * mean of all its samples; under --spp it runs a planning and an
 * estimating stream side by side until the estimating stream's standard
 * error, by the planning stream's figures, is 1% of sum_g b_g
 * (--bootstrap-error), and b_g is the estimating stream's mean. Either
 * way the number of samples behind b_g does not depend on their values,
 * so b_g is exactly unbiased (the earlier rule, pooled samples and a stop
 * once their running error fell below 1%, came out low under heavy
 * tails). All samples serve the starting states: they are chosen by
 * systematic resampling in proportion to f, so chains start in the
 * stationary distribution (no burn-in, no start-up bias, up to the
 * bootstrap's finite size).
 *
 * Allocation (spaces of several families: one per length). A family's share of the
 * mutations should follow b_g, as it does in Hachisuka et al.'s single
 * multiplexed chain. Chains are shared in proportion to b_g, but at least
 * MCMC_MIN_CHAINS per family, so a length with a tiny b (on ring-caustics
 * lengths 6-8 hold 0.03% of b) would otherwise get 16 full chains' worth of
 * its costliest mutations. Each family's chains therefore make m_g of every
 * round's MCMC_ROUND mutations, m_g = MCMC_ROUND (b_g / n_g) / max_h (b_h / n_h)
 * rounded, at least 1; its buffer is normalised by its own count (any
 * count is unbiased: a family's image is b_g times its chains' normalised
 * histogram). --allocate even gives every chain MCMC_ROUND (the old rule).
 *
 * Determinism. The number of chains is fixed (--chains, default
 * MCMC_CHAINS, shared among the families in proportion to b_g, at least
 * MCMC_MIN_CHAINS each), not tied to threads. Each chain owns its random stream seeded from (seed, family,
 * chain). Chains advance in rounds of MCMC_ROUND mutations each; a round's
 * splats are recorded per chain and then added to the film in chain order
 * (each thread adds the records falling in its band of rows), so under
 * --spp the image is bit-identical for any --threads. Under --time the
 * rounds continue until the clock says stop: the chains of a family make the
 * same number of mutations (the budget is split across chains by rounds).
 * A stop request (Ctrl-C) or the time limit abandons the round in flight;
 * the film always holds whole rounds and is correctly normalised.
 *
 * --direct separate (the default, as in Mitsuba's pssmlt and in the LMC
 * paper's implementation): pt renders paths of length <= 2 first (with
 * --spp samples per pixel, or the scene's directSamples, or 15% of
 * --time), into the same film, and MCMC only paths of length >= 3.
 * --direct mcmc leaves every path to MCMC.
 */
#include "lmc/mcmc.h"

#include <math.h>
#include <omp.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/driver/mcmc_internal.h"
#include "render/dist.h"

int mcmc_is_integrator(const char *name) {
  return mc_method_find(name) != NULL;
}

/* --- the driver's flags ------------------------------------------------------ */

static const char *const mcmc__small_steps[] = {"kelemen", "gauss", NULL};
static const char *const mcmc__direct_modes[] = {"separate", "mcmc", NULL};
static const int mcmc__direct_values[] = {1, 0};
static const char *const mcmc__allocations[] = {"b", "even", NULL};

static const lmc_opt mcmc__opts[] = {
    {"states", LMC_OPT_CHOICE, offsetof(mcmc_settings, states), 0, 0, 0, mc_space_names,
     mc_space_ids, 0, NULL, "the integrator's: mmlt for mmlt, path for mlt, else bdpt",
     "the chains' states: bdpt (a BDPT sample and one of its strategies, every length in one "
     "family), mmlt (one family per path length, a strategy coordinate), pt (a path tracer's "
     "numbers) or path (whole light paths: mlt's, and mlt only)", NULL},
    {"lmc-states", LMC_OPT_CHOICE, offsetof(mcmc_settings, states), 0, 0, 0, mc_space_names,
     mc_space_ids, 0, NULL, "the integrator's",
     "the same as --states (the name it had for lmc alone)", NULL},
    {"largestep", LMC_OPT_DOUBLE, offsetof(mcmc_settings, largestep), 0, 0, 1, NULL, NULL,
     0, "P", NULL, "large-step probability", "pLarge largestepprob"},
    {"largestep-scale", LMC_OPT_DOUBLE, offsetof(mcmc_settings, largestep_scale), 0, 0, 1e6, NULL,
     NULL, 0, "X", NULL,
     "the large-step probability times X after the first tenth of the budget (the LMC paper's "
     "largestepscale)", "largestepscale"},
    {"small-step", LMC_OPT_CHOICE, offsetof(mcmc_settings, small_gauss), 0, 0, 0,
     mcmc__small_steps, NULL, 0, NULL, NULL,
     "kelemen: offsets log-uniform in (1/1024, S]; gauss: normal offsets of standard deviation S", NULL},
    {"technique-prob", LMC_OPT_DOUBLE, offsetof(mcmc_settings, technique_prob), 0, 0, 1, NULL,
     NULL, 0, "P", NULL,
     "per-length states: the technique mutation's share of the steps that are not large",
     NULL},
    {"technique-jump", LMC_OPT_DOUBLE, offsetof(mcmc_settings, jump_prob), 0, 0, 1, NULL, NULL,
     0, "P", "0",
     "bdpt and mmlt states: share of the mutations that are not large steps made reversible "
     "jumps, the path kept, its strategy redrawn by the MIS weights and its numbers found by "
     "inverting the subpaths (exact)",
     NULL},
    {"path-mutations", LMC_OPT_DOUBLE, offsetof(mcmc_settings, path_prob), 0, 0, 1, NULL, NULL, 0,
     "P", "0",
     "bdpt and mmlt states: share of the mutations that are not large steps made path-space "
     "mutations of the state's path (bidirectional, lens, multi-chain, caustic, lens subpath; "
     "on the bdpt states free to change its length), mapped back to a strategy's numbers "
     "(exact)",
     NULL},
    {"sigma", LMC_OPT_DOUBLE, offsetof(mcmc_settings, sigma), 0, 1e-9, 1, NULL, NULL, 0,
     "S", "1/64; mmlt states 0.05; gauss 0.01", "the small step's scale S", NULL},
    {"chains", LMC_OPT_INT, offsetof(mcmc_settings, chains), 0, 1, 1 << 20, NULL, NULL,
     0, "N", "256", "Markov chains", "numchains"},
    {"bootstrap", LMC_OPT_INT64, offsetof(mcmc_settings, bootstrap), 0, 1, (double)(INT64_MAX / 2),
     NULL, NULL, 0, "N", "a tenth of --time, or under --spp enough for --bootstrap-error",
     "independent paths that estimate the normalisation b", "numinitsamples"},
    {"bootstrap-error", LMC_OPT_DOUBLE, offsetof(mcmc_settings, bootstrap_error), 0, 1e-4, 1, NULL,
     NULL, 0, "E", NULL, "without --bootstrap, under --spp: b's target relative standard error", NULL},
    {"direct", LMC_OPT_CHOICE, offsetof(mcmc_settings, direct_separate), 0, 0, 0,
     mcmc__direct_modes, mcmc__direct_values, 0, NULL, NULL,
     "separate: pt renders the paths of one and two segments, MCMC the longer ones; mcmc: MCMC "
     "renders every path", NULL},
    {"direct-spp", LMC_OPT_INT64, offsetof(mcmc_settings, direct_spp), 0, 0, (double)(INT64_MAX / 2),
     NULL, NULL, 0, "N", "--spp",
     "--direct separate under --spp: the path-traced pass's samples per pixel (Mitsuba's "
     "directSamples)", NULL},
    {"allocate", LMC_OPT_CHOICE, offsetof(mcmc_settings, even), 0, 0, 0, mcmc__allocations,
     NULL, 0, NULL, NULL,
     "per-length states: mutations per length in proportion to its b, or the same for every "
     "chain", NULL},
};

static const mcmc_settings mcmc__defaults = {
    .states = MCMC_STATES_DEFAULT,
    .largestep = 0.3,
    .largestep_scale = 1.0,
    .technique_prob = 0.1,
    .sigma = 1.0 / 64.0,
    .bootstrap_error = 0.01,
    .direct_separate = 1, /* as Mitsuba's pssmlt and the LMC paper's code; see README */
};

const lmc_opt_table mcmc_driver_options = {
    "MCMC (pssmlt, mmlt, lmc, h2mc, mlt; --spp counts mutations per pixel)", mcmc__opts,
    (int)(sizeof mcmc__opts / sizeof mcmc__opts[0]), &mcmc__defaults, sizeof mcmc__defaults};

/* Whether method M with the driver's settings ms renders media. */
static int mcmc__media(const mc_method *M, const mcmc_settings *ms) {
  int id = ms->states != MCMC_STATES_DEFAULT ? ms->states : M->default_states;
  return id >= 0 && id < 32 && ((M->media_states >> id) & 1u) && !(ms->jump_prob > 0.0) &&
         !(ms->path_prob > 0.0);
}

int mcmc_renders_media(const render_settings *rs) {
  const mc_method *M = mc_method_find(rs->integrator);
  mcmc_settings ms;
  lmc_error err;
  if (!M || lmc_opt_read(&mcmc_driver_options, rs, &ms, &err) != LMC_OK) return 0;
  return mcmc__media(M, &ms);
}

/* --- splat records ----------------------------------------------------------- */

static void mcmc__record(void *ctx, const mc_value *v, double weight) {
  mcmc_chain_slot *sl = ctx;
  if (sl->n_rec == sl->cap_rec) {
    /* A labelled large step splats every strategy of its sample: grow
     * (rarely: the buffer keeps its size across rounds). */
    mcmc_splat *r = realloc(sl->rec, 2 * (size_t)sl->cap_rec * sizeof *r);
    if (!r) {
      sl->rec_failed = 1;
      return;
    }
    sl->rec = r;
    sl->cap_rec *= 2;
  }
  mcmc_splat *r = &sl->rec[sl->n_rec++];
  r->rx = v->rx;
  r->ry = v->ry;
  r->v = rgb_scale(v->value, weight * sl->scale);
}

/* Adds record r to rows [y_lo, y_hi) of splat, a film's splat array or a
 * buffer of its size (film_splat's rule), and k2 times r to buffer splat2
 * (NULL: none). */
static void mcmc__splat_rows(const film *f, double *splat, double *splat2, double k2,
                             const film_filter *filter, const mcmc_splat *r, int y_lo, int y_hi) {
  if (!rgb_isfinite(r->v)) return;
  int x0 = (int)floor(r->rx - 0.5 - filter->radius), x1 = (int)ceil(r->rx - 0.5 + filter->radius);
  int y0 = (int)floor(r->ry - 0.5 - filter->radius), y1 = (int)ceil(r->ry - 0.5 + filter->radius);
  if (x0 < 0) x0 = 0;
  if (y0 < y_lo) y0 = y_lo;
  if (x1 > f->width - 1) x1 = f->width - 1;
  if (y1 > y_hi - 1) y1 = y_hi - 1;
  for (int y = y0; y <= y1; y++) {
    for (int x = x0; x <= x1; x++) {
      double w = filter_eval(filter, (x + 0.5) - r->rx, (y + 0.5) - r->ry);
      if (w == 0.0) continue;
      double *s = splat + 3 * ((int64_t)y * f->width + x);
      s[0] += w * r->v.r;
      s[1] += w * r->v.g;
      s[2] += w * r->v.b;
      if (!splat2) continue;
      double *s2 = splat2 + 3 * ((int64_t)y * f->width + x), w2 = k2 * w;
      s2[0] += w2 * r->v.r;
      s2[1] += w2 * r->v.g;
      s2[2] += w2 * r->v.b;
    }
  }
}

/* Mutations a chain of family F makes in a round of m (m for a family at
 * the full rate, else in proportion, rounded up and at least one). Rounded
 * up, the rounds of a --spp render add up to at least its budget (the
 * number of rounds is the budget over the families' full-round weight,
 * rounded up); rounded to the nearest, a short last round could leave a
 * render a few mutations short. */
static int64_t mcmc__family_steps(const mcmc_family *F, int64_t m) {
  if (F->m_round >= MCMC_ROUND) return m;
  int64_t k = (m * F->m_round + MCMC_ROUND - 1) / MCMC_ROUND;
  return k < 1 ? 1 : k;
}

/* Mutations the chains of every family have made so far. */
static int64_t mcmc__mutations(const mcmc_render *R) {
  int64_t n = 0;
  for (int g = 0; g < R->n_fam; g++) n += R->fam[g].done * R->fam[g].n_chains;
  return n;
}

/* Chain i's kernels from the integrator, with --largestep-scale once it is
 * in force; returns their count. */
static int mcmc__kernels(mcmc_render *R, int i, mc_kernel *k, double *p) {
  const mcmc_family *F = &R->fam[R->slots[i].family];
  int n = R->M->chain_kernels(R->mrun, &R->setup, i, F->sf, k, p);
  if (R->moves) n = R->sp.moves->add_kernels(R->moves, i, k, p, n);
  if (!R->ls_pending && R->ms.largestep_scale != 1.0)
    mc_kernels_scale_large(k, p, n, R->ms.largestep_scale);
  return n;
}

/* Gives every chain its kernels again (the schedule of --largestep-scale,
 * a restart). */
static lmc_status mcmc__rekernel(mcmc_render *R, lmc_error *err) {
  for (int i = 0; i < R->n_slots; i++) {
    mc_kernel k[MC_MAX_KERNELS];
    double p[MC_MAX_KERNELS];
    int n = mcmc__kernels(R, i, k, p);
    lmc_status st = mc_chain_set_kernels(R->slots[i].chain, k, p, n, err);
    if (st) return st;
  }
  return LMC_OK;
}

/* Direct lighting by pt first, when asked (--direct separate), into the
 * film; else an empty film. Sets *OUT_done when the render ends here
 * (interrupted, or no path is long enough for the chains). */
static lmc_status mcmc__direct(mcmc_render *R, int *OUT_done, lmc_error *err) {
  const render_settings *rs = R->rs;
  *OUT_done = 0;
  R->crs = *rs;
  /* The chains and the direct pass see the media, or neither does. */
  R->crs.no_media = rs->no_media || !mcmc__media(R->M, &R->ms);
  if (!R->ms.direct_separate) return film_init(R->out, R->s->cam.width, R->s->cam.height, err);
  progress_phase(&R->bar, "direct light", 0.0);
  render_settings prs = *rs;
  snprintf(prs.integrator, sizeof prs.integrator, "pt");
  prs.maxdepth = rs->maxdepth >= 0 && rs->maxdepth < 2 ? rs->maxdepth : 2;
  prs.snapshot = 0.0;
  prs.snapshot_fn = NULL;
  if (R->ms.direct_spp > 0) prs.spp = R->ms.direct_spp;
  if (R->timed) {
    prs.time_limit = 0.15 * rs->time_limit;
    if (!(rs->set & SET_SPP)) prs.set &= ~(unsigned)SET_SPP;
  }
  prs.quiet = 1;
  prs.no_media = R->crs.no_media;
  render_stats pst;
  lmc_status status = render_run(R->s, &prs, R->out, &pst, err);
  if (status) return status;
  R->st->rays += pst.rays;
  R->st->rank_rays += pst.rank_rays;
  R->st->nan_samples += pst.nan_samples;
  if (pst.interrupted) {
    R->st->interrupted = 1;
    *OUT_done = 1;
    return LMC_OK;
  }
  R->crs.mindepth = rs->mindepth > 3 ? rs->mindepth : 3;
  if (rs->maxdepth >= 0 && rs->maxdepth < 3) *OUT_done = 1;
  return LMC_OK;
}

/* The state space (--states, else the integrator's), the small step's
 * scale and the integrator's run. */
static lmc_status mcmc__setup(mcmc_render *R, lmc_error *err) {
  const render_settings *rs = R->rs;
  int id = R->ms.states != MCMC_STATES_DEFAULT ? R->ms.states : R->M->default_states;
  const mc_space_type *type = mc_space_find(id);
  if (!type) return lmc_error_set(err, LMC_EINVAL, NULL, 0, "%s: unknown states", rs->integrator);
  lmc_status status = type->create(&R->sp, R->s, &R->crs, err);
  if (status) return status;
  R->n_fam = R->sp.n_fam;
  R->fam = calloc((size_t)(R->n_fam > 0 ? R->n_fam : 1), sizeof *R->fam);
  R->cnt = calloc((size_t)R->nthreads, sizeof *R->cnt);
  R->ws = calloc((size_t)R->nthreads * (size_t)(R->n_fam > 0 ? R->n_fam : 1), sizeof *R->ws);
  if (!R->fam || !R->cnt || !R->ws) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the bootstrap");
  for (int g = 0; g < R->n_fam; g++) R->fam[g].sf = &R->sp.fam[g];
  /* Kelemen's s2: --sigma, else the space's default (or 1/64), 0.01 for
   * --small-step gauss. */
  if (!lmc_opt_value(rs, "sigma"))
    R->ms.sigma = R->ms.small_gauss ? MCMC_GAUSS_SIGMA : R->sp.sigma > 0.0 ? R->sp.sigma : R->ms.sigma;
  R->setup = (mc_method_setup){R->s, &R->crs, &R->ms, &R->sp};
  if ((R->ms.jump_prob > 0.0 || R->ms.path_prob > 0.0) && !R->sp.moves)
    return lmc_error_set(err, LMC_EUNSUPPORTED, NULL, 0,
                         "--technique-jump and --path-mutations move the bdpt and the mmlt "
                         "states (--states bdpt or mmlt), not the %s states",
                         R->sp.name);
  if (R->ms.jump_prob + R->ms.path_prob > 1.0)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0,
                         "--technique-jump %g and --path-mutations %g share the mutations that "
                         "are not large steps: together at most 1",
                         R->ms.jump_prob, R->ms.path_prob);
  if (R->M->create) return R->M->create(&R->mrun, &R->setup, err);
  return LMC_OK;
}

/* Chains: --chains (MCMC_CHAINS) shared in proportion to b_g (at least
 * MCMC_MIN_CHAINS per family that has any contribution), where the splats
 * go, and each family's mutations per round (see Allocation above: in
 * proportion to b_g per chain, per-family buffers only, since the other
 * two normalisations share one mutation count). */
static void mcmc__allocate(mcmc_render *R) {
  const render_settings *rs = R->rs;
  const int W = R->s->cam.width, H = R->s->cam.height;
  for (int g = 0; g < R->n_fam; g++) {
    mcmc_family *F = &R->fam[g];
    if (!(F->bt.b > 0.0)) continue;
    int n_chains = R->ms.chains > 0 ? R->ms.chains : MCMC_CHAINS;
    int nc = (int)floor(n_chains * F->bt.b / R->b_total + 0.5);
    F->n_chains = nc < MCMC_MIN_CHAINS ? MCMC_MIN_CHAINS : nc;
    F->first_chain = R->n_slots;
    R->n_slots += F->n_chains;
  }
  R->norm = R->n_fam == 1 ? MCMC_NORM_SCALE : MCMC_NORM_BUFFERS;
  if (R->norm == MCMC_NORM_BUFFERS) {
    int n_active = 0;
    for (int g = 0; g < R->n_fam; g++) n_active += R->fam[g].n_chains > 0;
    if ((int64_t)n_active * 3 * W * H * (int64_t)sizeof(double) > MCMC_FAMILY_FILM_BYTES)
      R->norm = MCMC_NORM_BOOT;
    for (int g = 0; g < R->n_fam && R->norm == MCMC_NORM_BUFFERS; g++) {
      if (R->fam[g].n_chains == 0) continue;
      R->fam[g].splat = calloc(3 * (size_t)W * (size_t)H, sizeof(double));
      if (!R->fam[g].splat) R->norm = MCMC_NORM_BOOT;
    }
    if (R->norm == MCMC_NORM_BOOT) {
      for (int g = 0; g < R->n_fam; g++) free(R->fam[g].splat), R->fam[g].splat = NULL;
      if (!rs->quiet)
        fprintf(stderr, "lmc: no memory for per-family splat buffers; b from before the chains\n");
    }
  }
  double top = 0.0;
  for (int g = 0; g < R->n_fam; g++)
    if (R->fam[g].n_chains > 0) top = fmax(top, R->fam[g].bt.b / R->fam[g].n_chains);
  for (int g = 0; g < R->n_fam; g++) {
    mcmc_family *F = &R->fam[g];
    F->m_round = MCMC_ROUND;
    F->done = 0;
    if (R->norm != MCMC_NORM_BUFFERS || R->ms.even || F->n_chains == 0) continue;
    double w = F->bt.b / F->n_chains / top;
    int m = (int)floor(MCMC_ROUND * w + 0.5);
    F->m_round = m < 1 ? 1 : m > MCMC_ROUND ? MCMC_ROUND : m;
  }
}

/* Points slot i's chain at thread tid's workspace for its family, made on
 * first use (out of memory: the chain keeps its own scratch). Only thread
 * tid makes or binds its workspaces, so the chains of a parallel loop may
 * bind concurrently. */
static void mcmc__bind(mcmc_render *R, int i, int tid) {
  mcmc_chain_slot *sl = &R->slots[i];
  const mc_target *T = &R->fam[sl->family].sf->target;
  if (!T->workspace_create) return;
  void **ws = &R->ws[(size_t)tid * (size_t)R->n_fam + (size_t)sl->family];
  if (!*ws) *ws = T->workspace_create(T);
  mc_chain_bind(sl->chain, *ws);
}

/* The chains, their kernels (the integrator's) and their starting states,
 * by systematic resampling of the bootstrap in proportion to f. */
static lmc_status mcmc__start_chains(mcmc_render *R, lmc_error *err) {
  const render_settings *crs = &R->crs;
  R->slots = calloc((size_t)R->n_slots, sizeof *R->slots);
  int *family = malloc((size_t)R->n_slots * sizeof *family);
  if (!R->slots || !family) {
    free(family);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the chains");
  }
  for (int g = 0; g < R->n_fam; g++)
    for (int i = 0; i < R->fam[g].n_chains; i++) {
      family[R->fam[g].first_chain + i] = g;
      R->slots[R->fam[g].first_chain + i].family = g;
    }
  lmc_status status = R->M->set_chains ? R->M->set_chains(R->mrun, R->n_slots, family, err) : LMC_OK;
  if (!status && R->sp.moves && (R->ms.jump_prob > 0.0 || R->ms.path_prob > 0.0))
    status = R->sp.moves->create(&R->moves, &R->sp, R->n_slots, family, R->ms.jump_prob,
                                 R->ms.path_prob, err);
  free(family);
  if (status) return status;
  const mcmc_settings *ms = &R->ms;
  if (!(ms->sigma > (ms->small_gauss ? 0.0 : 1.0 / 1024.0) && ms->sigma < 0.5))
    return lmc_error_set(err, LMC_EINVAL, NULL, 0,
                         ms->small_gauss ? "--sigma must lie in (0, 1/2)"
                                          : "--sigma must lie in (1/1024, 1/2)");
  for (int g = 0; g < R->n_fam; g++) {
    mcmc_family *F = &R->fam[g];
    if (F->n_chains == 0) continue;
    rng pick;
    rng_seed(&pick, crs->seed, mcmc__chain_seq(g, -1));
    double u0 = rng_uniform(&pick), acc = 0.0, total = 0.0;
    for (int64_t q = 0; q < F->bt.n; q++) total += F->bt.f[q]; /* (b may come from elsewhere) */
    int64_t j = 0;
    for (int i = 0; i < F->n_chains; i++) {
      mcmc_chain_slot *sl = &R->slots[F->first_chain + i];
      sl->scale = (R->norm == MCMC_NORM_BOOT ? F->bt.b : 1.0) / F->n_chains;
      mc_kernel k[MC_MAX_KERNELS];
      double p[MC_MAX_KERNELS];
      int nk = mcmc__kernels(R, F->first_chain + i, k, p);
      status = mc_chain_create(&sl->chain, &F->sf->target, k, p, nk, err);
      if (status) return status;
      sl->cap_rec = 2 * MCMC_ROUND;
      sl->rec = malloc((size_t)sl->cap_rec * sizeof(mcmc_splat));
      if (!sl->rec) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the splats");
      double target = (i + u0) / F->n_chains * total;
      while (j < F->bt.n - 1 && acc + F->bt.f[j] <= target) acc += F->bt.f[j++];
      while (j < F->bt.n - 1 && !(F->bt.f[j] > 0.0)) j++;
      sl->start_seq = mcmc__boot_seq(g, j);
      mcmc__bind(R, F->first_chain + i, 0);
      mc_chain_start(sl->chain, crs->seed, sl->start_seq, mcmc__chain_seq(g, i));
    }
  }
  for (int g = 0; g < R->n_fam; g++) mc_boot_free(&R->fam[g].bt);
  return LMC_OK;
}

/* One round: every chain here (mcmc_chain_here) makes its family's share
 * of m mutations, then the records are added in chain order, each thread
 * to its band of rows. Returns 1 when the round was abandoned (Ctrl-C, the
 * time limit; over several ranks by any of them: then every rank drops
 * it, so that the films of all ranks hold the same rounds). */
static int mcmc__round(mcmc_render *R, int64_t m) {
  const int H = R->s->cam.height;
  volatile int abandon = 0;
#pragma omp parallel for num_threads(R->nthreads) schedule(dynamic, 1)
  for (int i = 0; i < R->n_slots; i++) {
    mcmc_chain_slot *sl = &R->slots[i];
    sl->n_rec = 0;
    if (abandon || !mcmc_chain_here(i)) continue;
    mcmc__bind(R, i, omp_get_thread_num());
    int64_t r0 = mc_chain_rays(sl->chain);
    int64_t mg = mcmc__family_steps(&R->fam[sl->family], m);
    for (int64_t q = 0; q < mg; q++) mc_chain_step(sl->chain, mcmc__record, sl);
    R->cnt[omp_get_thread_num()].rays += mc_chain_rays(sl->chain) - r0;
    if (render_stop_signal() || (R->timed && omp_get_wtime() - R->t0 >= R->rs->time_limit))
      abandon = 1;
  }
  if (dist_any(abandon)) return 1;
#pragma omp parallel num_threads(R->nthreads)
  {
    int tid = omp_get_thread_num(), nt = omp_get_num_threads();
    int y_lo = (int)((int64_t)H * tid / nt), y_hi = (int)((int64_t)H * (tid + 1) / nt);
    const size_t n = 3 * (size_t)R->out->width * (size_t)H;
    for (int i = 0; i < R->n_slots; i++) {
      const mcmc_chain_slot *sl = &R->slots[i];
      const mcmc_family *F = &R->fam[sl->family];
      double *dst = F->splat ? F->splat : R->out->splat;
      double *grp = R->egroup ? R->egroup + (size_t)sl->group * n : NULL;
      for (int q = 0; q < sl->n_rec; q++)
        mcmc__splat_rows(R->out, dst, grp, sl->gscale, &R->s->filter, &sl->rec[q], y_lo, y_hi);
    }
  }
  return 0;
}

/* The integrator asked for a restart (stage 1 of lmc --adapt cache ended:
 * its chains ran a fixed kernel, so its image stays; they restart from
 * their bootstrap states with kernels asked again). */
static lmc_status mcmc__restart(mcmc_render *R, lmc_error *err) {
  mcmc__sync_chains(R);
  for (int i = 0; i < R->n_slots && R->M->note_restart_chain; i++)
    R->M->note_restart_chain(R->mrun, R->slots[i].chain);
  lmc_status status = mcmc__rekernel(R, err);
  if (status) return status;
  for (int i = 0; i < R->n_slots; i++) {
    mcmc__bind(R, i, 0);
    mc_chain_start(R->slots[i].chain, R->crs.seed, R->slots[i].start_seq,
                   mcmc__chain_seq(R->slots[i].family, R->n_slots + i));
  }
  return LMC_OK;
}

/* The chains in rounds of MCMC_ROUND mutations until the budget (--spp:
 * per_chain mutations per chain), the time limit or a stop request. */
static lmc_status mcmc__rounds(mcmc_render *R, lmc_error *err) {
  const render_settings *rs = R->rs;
  const int W = R->s->cam.width, H = R->s->cam.height;
  R->per_chain = INT64_MAX;
  if (R->by_spp) {
    /* The budget in full-round mutations: sum_g n_g m_g / MCMC_ROUND chains' worth. */
    int64_t total = rs->spp * (int64_t)W * H, weight = 0;
    for (int g = 0; g < R->n_fam; g++) weight += (int64_t)R->fam[g].n_chains * R->fam[g].m_round;
    R->per_chain = (total * MCMC_ROUND + weight - 1) / weight;
  }
  double t_chain0 = omp_get_wtime(), next_snapshot = rs->snapshot;
  /* Under --spp the ETA is the chains' own (the bar's clock restarts). */
  if (!R->timed) R->bar.start = t_chain0;
  progress_phase(&R->bar, "chains", R->timed ? (t_chain0 - R->t0) / rs->time_limit : 0.0);
  R->done_per_chain = 0;
  while (R->done_per_chain < R->per_chain) {
    int64_t m = R->per_chain - R->done_per_chain < MCMC_ROUND ? R->per_chain - R->done_per_chain
                                                              : MCMC_ROUND;
    if (R->M->round_limit) {
      int64_t lim = R->M->round_limit(R->mrun, R->done_per_chain, R->per_chain);
      if (m > lim) m = lim;
    }
    /* An abandoned round is dropped (its chains moved on, which is
     * harmless: the render ends here). */
    if (mcmc__round(R, m)) break;
    R->done_per_chain += m;
    for (int g = 0; g < R->n_fam; g++) R->fam[g].done += mcmc__family_steps(&R->fam[g], m);
    /* The clocks of the render and of the chains as every rank agrees on
     * them (the latest rank's): every decision below is taken from them. */
    double el[2] = {omp_get_wtime() - R->t0, omp_get_wtime() - t_chain0};
    dist_max_n(el, 2);
    if (R->ls_pending) {
      /* --largestep-scale: from MCMC_LARGESTEP_SCALE_AFTER of the chains'
       * budget on (of their mutations under --spp, of their time under --time). */
      double share = R->by_spp ? (double)R->done_per_chain / (double)R->per_chain
                               : el[1] / fmax(1e-9, rs->time_limit - (el[0] - el[1]));
      if (share >= MCMC_LARGESTEP_SCALE_AFTER) {
        R->ls_pending = 0;
        lmc_status status = mcmc__rekernel(R, err);
        if (status) return status;
      }
    }
    mcmc__publish(R, R->done_per_chain, 0);
    if (R->M->after_round &&
        R->M->after_round(R->mrun, R->done_per_chain, R->per_chain, el[0], el[1])) {
      lmc_status status = mcmc__restart(R, err);
      if (status) return status;
    }
    int stop = dist_any(render_stop_signal() || (R->timed && el[0] >= rs->time_limit));
    if (rs->snapshot > 0.0 && rs->snapshot_fn && el[0] >= next_snapshot) {
      mcmc__snapshot(R, el[0]);
      while (next_snapshot <= el[0]) next_snapshot += rs->snapshot;
    }
    double frac = R->by_spp ? (double)R->done_per_chain / (double)R->per_chain : 0.0;
    if (R->timed) frac = fmax(frac, el[0] / rs->time_limit);
    progress_update_rate(&R->bar, frac, (double)mcmc__mutations(R) / fmax(el[1], 1e-9),
                         "mutations/s");
    if (stop) break;
  }
  progress_finish(&R->bar);
  /* The final image with the refined b (also after an interruption: the
   * film holds whole rounds, and the tallies of the abandoned round are
   * still independent samples of b), every rank's on rank 0. */
  mcmc__sync_chains(R);
  mcmc__publish(R, R->done_per_chain, 1);
  if (dist_active()) dist_sum_to_root(R->out->splat, 3 * (size_t)W * (size_t)H);
  if (R->norm != MCMC_NORM_BOOT) {
    double v = 0.0;
    R->st->mcmc_b = mcmc__refine_b(R, &v);
    R->st->mcmc_b_se = sqrt(v);
  }
  mcmc__error_develop(R);
  if (dist_any(render_stop_signal())) R->st->interrupted = 1;
  else if (R->timed && R->done_per_chain < R->per_chain) R->st->timed_out = 1;
  R->st->samples = mcmc__mutations(R);
  R->st->passes = R->st->samples / ((int64_t)W * H);
  R->chain_seconds = omp_get_wtime() - t_chain0;
  return LMC_OK;
}

/* Rays and non-finite contributions of every thread and chain, this
 * rank's own (rank_rays, rank_samples) and every rank's summed on rank 0. */
static void mcmc__count(mcmc_render *R) {
  int64_t own[2] = {0, 0}, mutations = 0;
  for (int t = 0; R->cnt && t < R->nthreads; t++) own[0] += R->cnt[t].rays;
  mc_counts c = {0};
  mcmc__counts_here(R, &c, &mutations);
  own[1] = c.nan_samples;
  R->st->rank_rays += own[0];
  R->st->rank_samples = mutations;
  dist_sum_to_root_i64(own, 2);
  R->st->rays += own[0];
  R->st->nan_samples += own[1];
}

static void mcmc__free(mcmc_render *R) {
  if (R->slots)
    for (int i = 0; i < R->n_slots; i++) {
      mc_chain_destroy(R->slots[i].chain);
      free(R->slots[i].rec);
    }
  free(R->slots);
  for (int g = 0; R->ws && g < R->n_fam; g++)
    for (int t = 0; t < R->nthreads; t++) {
      void *ws = R->ws[(size_t)t * (size_t)R->n_fam + (size_t)g];
      if (ws) R->fam[g].sf->target.workspace_destroy(ws); /* (made by that target) */
    }
  free(R->ws);
  if (R->M && R->M->destroy) R->M->destroy(R->mrun);
  if (R->moves) R->sp.moves->destroy(R->moves);
  for (int g = 0; R->fam && g < R->n_fam; g++) mc_boot_free(&R->fam[g].bt), free(R->fam[g].splat);
  free(R->fam);
  mc_space_free(&R->sp);
  free(R->cnt);
  free(R->egroup);
}

lmc_status mcmc_render_run(const scene *s, const render_settings *rs, film *out,
                           render_stats *st, lmc_error *err) {
  memset(st, 0, sizeof *st);
  mcmc_render R;
  memset(&R, 0, sizeof R);
  R.M = mc_method_find(rs->integrator);
  if (!R.M)
    return lmc_error_set(err, LMC_EUNSUPPORTED, NULL, 0,
                         "integrator %s is not built on this framework yet", rs->integrator);
  R.s = s, R.rs = rs, R.out = out, R.st = st;
  lmc_status status = lmc_opt_read(&mcmc_driver_options, rs, &R.ms, err);
  if (status) return status;
  R.nthreads = rs->threads > 0 ? rs->threads : omp_get_max_threads();
  R.timed = rs->time_limit > 0.0;
  R.by_spp = !R.timed || (rs->set & SET_SPP);
  R.ls_pending = R.ms.largestep_scale != 1.0;
  R.t0 = omp_get_wtime();
  /* One progress line over the phases: direct light, bootstrap, chains. */
  progress_init(&R.bar, rs->integrator, rs->quiet || dist_rank() != 0);
  int done = 0;
  status = mcmc__direct(&R, &done, err);
  if (status || done) {
    progress_end(&R.bar);
    st->seconds = omp_get_wtime() - R.t0;
    return status;
  }
  status = mcmc__setup(&R, err);
  if (!status) status = mcmc__bootstrap(&R, err);
  if (!status) mcmc__allocate(&R);
  if (!status && R.n_slots == 0) {
    status = mcmc__error_init(&R, err);
    /* No bootstrap path carried light (b = 0): the chains' part of the
     * image is black (all of it, or all but pt's direct light). Said
     * whatever --quiet (unless the loader said the scene has no emitter);
     * under --strict the render stops here. */
    if (s->n_lights > 0)
      lmc_warn(s->path, 0,
               "%s's bootstrap found no light on paths of %d or more segments (%lld paths, "
               "b = 0): %s", rs->integrator, R.crs.mindepth > 1 ? R.crs.mindepth : 1,
               (long long)st->mcmc_boot_paths,
               R.ms.direct_separate ? "the image is --direct separate's path-traced pass alone"
                                    : "the image is black");
    if (rs->strict)
      status = lmc_error_set(err, LMC_ESTRICT, s->path, 0,
                             "--strict: %s found nothing to explore (b = 0); not rendering",
                             rs->integrator);
  } else if (!status) {
    status = mcmc__start_chains(&R, err);
    if (!status) status = mcmc__error_init(&R, err);
    if (!status) status = mcmc__rounds(&R, err);
    if (!status) {
      mc_counts counts;
      mcmc__share_stats(&R, &counts);
      if (!rs->quiet && dist_rank() == 0) mcmc__report(&R, &counts);
    }
  }
  if (!status) mcmc__count(&R);
  progress_end(&R.bar);
  mcmc__free(&R);
  st->seconds = omp_get_wtime() - R.t0;
  if (status) film_free(out);
  return status;
}
