/*
 * test_mmlt_jump.c: the moves of src/lmc/states/mmlt_jump.h on the mmlt
 * states, the strategy jump and the fused path move (each of path-space
 * MLT's moves), leave the target invariant.
 *
 * One-step invariance. Independent uniform states u_i (a chain started by
 * mc_chain_start draws one as a large step does), weighted by f(u_i), are
 * a weighted sample of the target; one move from each gives u'_i. If the
 * move leaves the target invariant, every class q of states is as
 * frequent, weighted, before and after:
 *     E[ f(u) (1{u' in q} - 1{u in q}) ] = 0,
 * for the classes: the strategy, a 4 x 3 grid of the film (the raster
 * point) and f's quintiles (from a pilot). Each such mean is compared with
 * 0 in units of its standard error over 400000 independent starts, on
 * tests/data/invert/mixed.xml (glossy, rough, delta and mixed lobes, area,
 * point and infinite lights) at lengths 2, 3 and 4, for both moves, and
 * for each of the fused move's path moves alone at lengths 3 and 4: |z|
 * below the normal quantile of a Sidak level of 1% over all of them. The
 * moves must move the weighted states (at least 5%; a path move alone at
 * least 0.1%), and negative controls, the same moves with every proposal
 * accepted, must fail the same test (|z| > 8 for the jump, > 5 for the
 * path moves, whose ratio is mostly near 1, and the bidirectional
 * mutation alone beyond the critical |z|). The same on the bdpt states
 * (test_invariance_bdpt). The moves hand the chain their proposal's value:
 * each state a move reached is evaluated again through the target, and
 * must agree bit for bit. This test found that an area
 * light hit by the camera walk, re-split as a light endpoint, must take
 * the light walk's record (bdpt_resplit) for its MIS weight.
 * LMC_TEST_SCENE=FILE runs it on another scene (for diagnosis).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "chi2.h"
#include "lmc/kernels/chain.h"
#include "lmc/states/bdpt_states.h"
#include "lmc/states/mmlt_jump.h"
#include "lmc/states/mmlt_states.h"
#include "render/io/io.h"
#include "test_util.h"
#include "load_scene.h"

static scene *g_sc;

static int setup(void **state) {
  (void)state;
  const char *env = getenv("LMC_TEST_SCENE"); /* any scene instead (for diagnosis) */
  g_sc = try_load_scene(env ? env : LMC_SOURCE_DIR "/tests/data/invert/mixed.xml");
  return g_sc ? 0 : -1;
}

static int teardown(void **state) {
  (void)state;
  scene_destroy(g_sc);
  return 0;
}

/* The jump wrapped: it records the strategy coordinate before the move,
 * and (accept_all) makes every proposal accepted. */
typedef struct wrap {
  mc_kernel inner;
  int off;
  double tech_before, rx_before, ry_before;
  int label_before;
  int accept_all;
} wrap;

static double wrap_propose(void *self, rng *r, const mc_state *x, double *OUT_y) {
  wrap *w = self;
  w->tech_before = x->u[w->off];
  w->label_before = x->label;
  w->rx_before = x->v.rx, w->ry_before = x->v.ry;
  return w->inner.propose(w->inner.self, r, x, OUT_y);
}

static int wrap_label(void *self) {
  wrap *w = self;
  return w->inner.label(w->inner.self);
}

static double wrap_log_density(void *self, const mc_state *from, const double *to_u) {
  wrap *w = self;
  double l = w->inner.log_density(w->inner.self, from, to_u);
  return w->accept_all && l > -INFINITY ? INFINITY : l;
}

static int strategy(double tech, int n) {
  int i = (int)(tech * n);
  return i < n ? i : n - 1;
}

/* f's class among the NFB value classes split at fq[0 .. NFB - 2]. */
enum { NFB = 5 };
static int f_class(double f, const double *fq) {
  int c = 0;
  while (c < NFB - 1 && f >= fq[c]) c++;
  return c;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* The chains' own streams after their start, apart from the streams that
 * drew the starting numbers (the same stream would make the move's random
 * choices copies of the state's numbers). */
#define CHAIN_STREAMS (1ull << 40)

/* A coarse cell of the film (4 x 3, the margin folded into the border cells). */
enum { NCX = 4, NCY = 3 };
static int film_cell(double rx, double ry) {
  int cx = (int)(rx / g_sc->cam.width * NCX), cy = (int)(ry / g_sc->cam.height * NCY);
  cx = cx < 0 ? 0 : cx >= NCX ? NCX - 1 : cx;
  cy = cy < 0 ? 0 : cy >= NCY ? NCY - 1 : cy;
  return cy * NCX + cx;
}

/* A sampler over a state's coordinates, stream by stream (0.5 past a
 * block), for evaluating a state through the target. */
typedef struct vec_smp {
  lmc_sampler base;
  const mc_target *t;
  const double *u;
  int stream, pos[LMC_STREAM_COUNT];
} vec_smp;

static double vec_next(lmc_sampler *self) {
  vec_smp *v = (vec_smp *)self;
  int k = v->stream, p = v->pos[k]++;
  return p < v->t->stream_dim[k] ? v->u[mc_target_stream_offset(v->t, k) + p] : 0.5;
}

static void vec_stream(lmc_sampler *self, int stream) { ((vec_smp *)self)->stream = stream; }

/* The largest |z| over the strategies and the film cells after N starts
 * and one move each (perturb: the fused path perturbation, else the
 * strategy jump), on the mmlt states of length k (kmax 0) or on the bdpt
 * states of lengths k .. kmax (absolute directions above roughness 0.3);
 * *OUT_moved: the weighted share of states that moved (changed strategy;
 * or for perturb, raster point). A bdpt state started as a large step
 * starts it (a fresh u, a label drawn in proportion to its f, relabelled)
 * is a sample of density f(u, l) / F(u) relative to the target: weighted
 * by F(u), the chain's sum_x. */
static double worst_z(int k, int kmax, int n_starts, int accept_all, int perturb, int kind,
                      uint64_t seed, double *OUT_moved) {
  render_settings rs = render_settings_default();
  rs.maxdepth = 6;
  mc_target T;
  mc_mmlt_states ctx;
  mc_bdpt_states bctx;
  lmc_error err;
  int bdpt = kmax > 0;
  if (bdpt)
    assert_int_equal(mc_bdpt_states_init(&T, &bctx, g_sc, &rs, 0.3, k, kmax, &err), LMC_OK);
  else
    assert_int_equal(mc_mmlt_states_init(&T, &ctx, g_sc, &rs, k, &err), LMC_OK);
  mc_mmlt_jump j;
  assert_int_equal(mc_mmlt_jump_init(&j, &T, perturb, &err), LMC_OK);
  j.test_kind = kind;
  wrap w = {mc_mmlt_jump_kernel(&j), mc_target_stream_offset(&T, LMC_STREAM_CONNECT), 0.0, 0.0,
            0.0, -1, accept_all};
  mc_kernel kw = w.inner;
  kw.self = &w;
  kw.propose = wrap_propose;
  kw.log_density = wrap_log_density;
  if (bdpt) {
    assert_non_null(w.inner.label);
    kw.label = wrap_label;
  }
  double prob = 1.0;
  mc_chain *c;
  assert_int_equal(mc_chain_create(&c, &T, &kw, &prob, 1, &err), LMC_OK);
  int n = bdpt ? bctx.n_labels : ctx.n_strategies, nq = n + NCX * NCY + NFB;
  assert_true(n <= 16);
  double sum[16 + NCX * NCY + NFB] = {0}, sum2[16 + NCX * NCY + NFB] = {0}, moved = 0.0,
         total = 0.0;
  /* The value classes: f's quintiles over a pilot of states. */
  double fs[2000], fq[NFB - 1];
  int np = 0;
  for (int i = 0; np < 2000 && i < 200000; i++) {
    double f = mc_chain_start(c, seed + 1, (uint64_t)i, (uint64_t)i + CHAIN_STREAMS);
    if (f > 0.0) fs[np++] = f;
  }
  qsort(fs, (size_t)np, sizeof fs[0], cmp_double);
  for (int q = 0; q < NFB - 1; q++) fq[q] = fs[(q + 1) * np / NFB];
  int used = 0, compared = 0, same = 0;
  void *scr = T.scratch_create ? T.scratch_create(&T) : NULL;
  for (int i = 0; i < n_starts; i++) {
    double f = mc_chain_start(c, seed, (uint64_t)i, (uint64_t)i + CHAIN_STREAMS);
    if (!(f > 0.0)) continue;
    double wt = bdpt ? c->sum_x : f;
    w.tech_before = -1.0;
    mc_chain_step(c, NULL, NULL);
    if (w.tech_before < 0.0) continue; /* (the kernel always proposes: never here) */
    int a = bdpt ? w.label_before : strategy(w.tech_before, n);
    int b = bdpt ? c->x.label : strategy(c->x.u[w.off], n);
    int ca = n + film_cell(w.rx_before, w.ry_before), cb = n + film_cell(c->x.v.rx, c->x.v.ry);
    int va = n + NCX * NCY + f_class(f, fq), vb = n + NCX * NCY + f_class(c->x.v.f, fq);
    for (int q = 0; q < nq; q++) {
      double d = wt * ((b == q || cb == q || vb == q) - (a == q || ca == q || va == q));
      sum[q] += d;
      sum2[q] += d * d;
    }
    /* An accepted move redraws the strategy coordinate in its interval
     * (bdpt states: moves the label or the raster point). */
    int did = bdpt ? a != b || c->x.v.rx != w.rx_before || c->x.v.ry != w.ry_before
                   : c->x.u[w.off] != w.tech_before;
    moved += wt * did;
    total += wt;
    used++;
    /* The moves hand the chain the value of their proposal
     * (mc_kernel.value): the target's own, bit for bit. */
    if (did && c->x.v.f > 0.0) {
      vec_smp vs = {{vec_next, vec_stream, NULL}, &T, c->x.u, LMC_STREAM_CAMERA, {0}};
      mc_value v;
      int rc = bdpt ? T.eval_label(&T, scr, &vs.base, c->x.label, &v, NULL, NULL)
                    : T.eval(&T, scr, &vs.base, &v, NULL, NULL);
      assert_int_equal(rc, 0);
      same += v.f == c->x.v.f && v.rx == c->x.v.rx && v.ry == c->x.v.ry;
      compared++;
    }
  }
  if (scr) T.scratch_destroy(scr);
  assert_true(used > 3000);
  assert_int_equal(same, compared);
  if (!accept_all && kind != MC_PATH_MOVE_MULTICHAIN && kind != MC_PATH_MOVE_LENSSUB)
    assert_true(compared > 1000);
  double worst = 0.0;
  for (int q = 0; q < nq; q++) {
    double mean = sum[q] / n_starts;
    double var = sum2[q] / n_starts - mean * mean;
    double z = var > 0.0 ? mean / sqrt(var / n_starts) : 0.0;
    if (fabs(z) > worst) worst = fabs(z);
  }
  static const char *const kinds[MC_PATH_MOVE_FUSED] = {"bidirectional", "lens", "multi-chain",
                                                        "caustic", "lens subpath"};
  print_message("%s%s%s, %s states, length %d%s%s: %d states with f > 0, %.1f%% (weighted) "
                "moved, worst |z| %.2f; no move %lld, refused %lld, walked elsewhere %lld; %d values "
                "checked\n",
                perturb ? "path move" : "jump", kind >= 0 ? ": " : "",
                kind >= 0 ? kinds[kind] : "", bdpt ? "bdpt" : "mmlt", k, bdpt ? " and longer" : "",
                accept_all ? " (accept all)" : "", used, 100.0 * moved / total, worst,
                (long long)j.st.lone, (long long)j.st.refused, (long long)j.st.mismatch, compared);
  *OUT_moved = moved / total;
  mc_chain_destroy(c);
  mc_mmlt_jump_free(&j);
  if (bdpt)
    mc_bdpt_states_free(&bctx);
  else
    mc_mmlt_states_free(&ctx);
  return worst;
}

/* The critical |z| of m two-sided normal tests at an overall 1% (Sidak). */
static double critical_z(int m) {
  double alpha = chi2_sidak(0.01, m);
  for (double z = 0.0; z < 10.0; z += 1e-3)
    if (erfc(z / sqrt(2.0)) < alpha) return z;
  return 10.0;
}

static void test_invariance(void **state) {
  (void)state;
  /* Strategies, film cells and value classes: (3 + 4 + 5) + 3 x (12 + 5)
   * means per move at lengths 2 .. 4, and (4 + 5) + 2 x (12 + 5) for each
   * path move alone at lengths 3 and 4. */
  double zc = critical_z(2 * (12 + 3 * (NCX * NCY + NFB)) +
                         MC_PATH_MOVE_FUSED * (9 + 2 * (NCX * NCY + NFB)));
  int checked = 0;
  for (int perturb = 0; perturb < 2; perturb++)
    for (int k = 2; k <= 4; k++) {
      double moved;
      double z = worst_z(k, 0, 400000, 0, perturb, -1, 300 + (uint64_t)(10 * perturb + k), &moved);
      assert_true(z < zc);
      assert_true(moved > 0.05);
      checked++;
    }
  /* Each of the fused move's path moves alone, at lengths 3 and 4: its own
   * ratio (the multi-chain perturbation needs two chains: length 4). */
  for (int kind = 0; kind < MC_PATH_MOVE_FUSED; kind++) {
    double most = 0.0;
    for (int k = 3; k <= 4; k++) {
      double moved;
      double z = worst_z(k, 0, 400000, 0, 1, kind, 400 + (uint64_t)(10 * kind + k), &moved);
      assert_true(z < zc);
      most = moved > most ? moved : most;
      checked++;
    }
    assert_true(most > 0.001); /* multi-chain: 0.2% (few paths with two chains here) */
  }
  double moved;
  double zbad = worst_z(3, 0, 400000, 1, 0, -1, 999, &moved);
  double zbad2 = worst_z(2, 0, 400000, 1, 1, -1, 998, &moved);
  double zbad3 = worst_z(3, 0, 600000, 1, 1, MC_PATH_MOVE_BIDIR, 997, &moved);
  print_message("critical |z| %.2f; the controls' %.2f (jump), %.2f (path moves), %.2f "
                "(bidirectional)\n",
                zc, zbad, zbad2, zbad3);
  assert_int_equal(checked, 6 + 2 * MC_PATH_MOVE_FUSED);
  assert_true(zbad > 8.0);
  assert_true(zbad2 > 5.0);
  assert_true(zbad3 > zc); /* fails the test itself */
}

/* The same moves on the bdpt states: every length from 1 (or 2) to 4 in
 * one target, the path moves free to change the length, the labels'
 * rough directions absolute. */
static void test_invariance_bdpt(void **state) {
  (void)state;
  /* Labels (12 or 13), film cells and value classes for both moves over
   * lengths 1 .. 4 and 2 .. 4, and for each path move alone over 2 .. 4
   * (multi-chain: 4). */
  double zc = critical_z(2 * (25 + 2 * (NCX * NCY + NFB)) +
                         MC_PATH_MOVE_FUSED * (12 + NCX * NCY + NFB));
  int checked = 0;
  for (int perturb = 0; perturb < 2; perturb++)
    for (int kmin = 1; kmin <= 2; kmin++) {
      double moved;
      double z = worst_z(kmin, 4, 400000, 0, perturb, -1, 500 + (uint64_t)(10 * perturb + kmin),
                         &moved);
      assert_true(z < zc);
      assert_true(moved > 0.05);
      checked++;
    }
  for (int kind = 0; kind < MC_PATH_MOVE_FUSED; kind++) {
    /* (The multi-chain perturbation needs two chains: length 4 alone.) */
    double moved;
    int kmin = kind == MC_PATH_MOVE_MULTICHAIN ? 4 : 2;
    double z = worst_z(kmin, 4, 400000, 0, 1, kind, 600 + (uint64_t)kind, &moved);
    assert_true(z < zc);
    assert_true(moved > 0.001);
    checked++;
  }
  double moved;
  double zbad = worst_z(2, 4, 400000, 1, 0, -1, 699, &moved);
  double zbad2 = worst_z(2, 4, 400000, 1, 1, -1, 698, &moved);
  print_message("critical |z| %.2f; the controls' %.2f (jump), %.2f (path moves)\n", zc, zbad,
                zbad2);
  assert_int_equal(checked, 4 + MC_PATH_MOVE_FUSED);
  assert_true(zbad > 8.0);
  assert_true(zbad2 > 5.0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_invariance),
      cmocka_unit_test(test_invariance_bdpt),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
