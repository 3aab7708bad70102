/*
 * test_bdpt_states.c: the bdpt states' labelled target (src/lmc/
 * bdpt_states.c) on a small built-in scene with rough and smooth
 * surfaces, a tent filter (the film margin) and a constant environment,
 * for the lengths 1 .. 5 at once:
 *
 *  - relabel: a fresh BDPT sample, evaluated whole (eval_all), then each
 *    of its strategies j in j's own coordinates (relabel: absolute
 *    directions at rough vertices): eval_label there gives f_j times the
 *    Jacobian relabel returned, f_large = f_j, the same raster position
 *    and colour; the evaluation with the gradient gives the same values;
 *    and eval_all from label j's coordinates gives every strategy of the
 *    sample again (the same path: the large-step ratio's F of the current
 *    state is the F the state had when proposed). To 1e-7 relative (the
 *    directions go through spherical coordinates and back).
 *  - the gradient of f in a label's own coordinates against
 *    Richardson-extrapolated central differences of the plain f, where
 *    those converge.
 *    The same through participating media (data/media/rough_glass_fog.xml),
 *    where each vertex's numbers begin with its free flight's two and no
 *    gradient is given yet.
 *  - without absolute directions (rough_min 2) relabel is absent and
 *    eval_label in the large step's coordinates gives f_j itself.
 *  - a chain's ray tallies (chain.h): the kernels' rays sum to the rays
 *    its scratches traced, the labels' tallies to its steps and its small
 *    steps' rays, and a small step from a state of length k traces
 *    between 1 and k rays (its two subpaths and one connection).
 * Every check is counted and the counts asserted.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "lmc/kernels/chain.h"
#include "lmc/states/bdpt_states.h"
#include "load_scene.h"
#include "render/io/io.h"
#include "test_util.h"

static const char *scene_xml =
    "<scene version=\"0.6.0\">\n"
    "  <sensor type=\"perspective\">\n"
    "    <float name=\"fov\" value=\"45\"/>\n"
    "    <transform name=\"toWorld\"><lookat origin=\"0, 2, 5\" target=\"0, 0.5, 0\" up=\"0, 1, 0\"/></transform>\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"24\"/>"
    "<rfilter type=\"tent\"/></film>\n"
    "  </sensor>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/><scale x=\"4\" y=\"1\" z=\"4\"/></transform>\n"
    "    <bsdf type=\"phong\"><rgb name=\"diffuseReflectance\" value=\"0.5, 0.4, 0.3\"/>"
    "<rgb name=\"specularReflectance\" value=\"0.3, 0.3, 0.3\"/><float name=\"exponent\" value=\"40\"/></bsdf>\n"
    "  </shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0.8\" y=\"0.6\" z=\"0.2\"/><float name=\"radius\" value=\"0.6\"/>\n"
    "    <bsdf type=\"roughconductor\"><string name=\"material\" value=\"Au\"/>"
    "<string name=\"distribution\" value=\"ggx\"/><float name=\"alpha\" value=\"0.2\"/></bsdf>\n"
    "  </shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"-0.9\" y=\"0.5\" z=\"0.4\"/><float name=\"radius\" value=\"0.5\"/>\n"
    "    <bsdf type=\"roughdielectric\"><float name=\"intIOR\" value=\"1.5\"/><float name=\"alpha\" value=\"0.03\"/></bsdf>\n"
    "  </shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0.0\" y=\"0.4\" z=\"1.3\"/><float name=\"radius\" value=\"0.4\"/>\n"
    "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.7, 0.7, 0.6\"/></bsdf>\n"
    "  </shape>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"90\"/><scale x=\"0.5\" y=\"1\" z=\"0.5\"/>"
    "<translate x=\"0.3\" y=\"3\" z=\"0.5\"/></transform>\n"
    "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"20, 18, 15\"/></emitter>\n"
    "  </shape>\n"
    "  <emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.2, 0.25, 0.3\"/></emitter>\n"
    "</scene>\n";

static int KMAX = 5;

typedef struct fixture {
  scene *sc;
} fixture;

static int setup(void **state) {
  fixture *fx = calloc(1, sizeof *fx);
  const char *env = getenv("LMC_TEST_SCENE"); /* any scene instead (for diagnosis) */
  if (getenv("LMC_TEST_KMAX")) KMAX = atoi(getenv("LMC_TEST_KMAX"));
  fx->sc = env ? try_load_scene(env) : try_load_scene_text(scene_xml, "bdpt_states");
  if (!fx->sc) return -1;
  *state = fx;
  return 0;
}

static int teardown(void **state) {
  fixture *fx = *state;
  scene_destroy(fx->sc);
  free(fx);
  return 0;
}

/* A sampler over a state's coordinate vector (the target's layout). */
typedef struct vec_smp {
  lmc_sampler base;
  const mc_target *T;
  double *u;
  int stream, pos[LMC_STREAM_COUNT];
} vec_smp;

static double vec_next(lmc_sampler *self) {
  vec_smp *v = (vec_smp *)self;
  int k = v->stream, p = v->pos[k]++;
  if (p >= v->T->stream_dim[k]) return 0.5;
  return v->u[mc_target_stream_offset(v->T, k) + p];
}

static void vec_stream(lmc_sampler *self, int stream) { ((vec_smp *)self)->stream = stream; }

static vec_smp vec_at(const mc_target *T, double *u) {
  vec_smp v = {{vec_next, vec_stream, NULL}, T, u, 0, {0}};
  return v;
}

static int rel_equal(double a, double b, double tol) {
  return fabs(a - b) <= tol * fmax(fabs(a), fabs(b)) || (a == 0.0 && b == 0.0);
}

static mc_target make_target(fixture *fx, mc_bdpt_states *ctx, double rough_min) {
  render_settings rs = fx->sc->settings;
  rs.maxdepth = KMAX;
  mc_target T;
  lmc_error err;
  assert_int_equal(mc_bdpt_states_init(&T, ctx, fx->sc, &rs, rough_min, 1, KMAX, &err), LMC_OK);
  return T;
}

/* The relabel checks on scene sc (grads: with the gradient's
 * evaluation too; without, through media, eval_label refuses it). */
static void relabel_consistency(scene *sc, int grads, int min_samples) {
  fixture fxs = {sc}, *fx = &fxs;
  mc_bdpt_states ctx;
  mc_target T = make_target(fx, &ctx, 0.05);
  assert_non_null(T.relabel);
  assert_int_equal(ctx.media, !grads);
  void *scratch = T.scratch_create(&T);
  mc_contrib *all = calloc((size_t)T.n_labels, sizeof *all);
  mc_contrib *again = calloc((size_t)T.n_labels, sizeof *again);
  double *u = malloc((size_t)T.dim * sizeof *u), *v = malloc((size_t)T.dim * sizeof *v);
  double *grad = malloc((size_t)T.dim * sizeof *grad);
  rng r, fresh;
  rng_seed(&r, 17, 1);
  rng_seed(&fresh, 17, 2);
  int samples = 0, labels = 0, moved = 0, rough_labels = 0, with_grad = 0, resampled = 0;
  for (int n = 0; n < 4000; n++) {
    for (int i = 0; i < T.dim; i++) u[i] = rng_uniform(&r);
    vec_smp s = vec_at(&T, u);
    int na = T.eval_all(&T, scratch, &s.base, -1, all);
    if (na <= 0) continue;
    samples++;
    for (int j = 0; j < na; j++) {
      /* (Subnormal contributions lose their relative precision.) */
      if (all[j].v.f < 1e-250) continue;
      /* Label j's coordinates: relabel right after the sample's eval_all
       * (its scratch holds the subpaths). */
      s = vec_at(&T, u);
      T.eval_all(&T, scratch, &s.base, -1, again);
      memcpy(v, u, (size_t)T.dim * sizeof *v);
      double jac = T.relabel(&T, scratch, all[j].label, v, &fresh);
      assert_true(jac > 0.0 && isfinite(jac));
      if (memcmp(u, v, (size_t)T.dim * sizeof *u)) moved++;
      if (jac != 1.0) rough_labels++;
      /* f there, without and with the gradient. */
      mc_value a, b;
      s = vec_at(&T, v);
      assert_int_equal(T.eval_label(&T, scratch, &s.base, all[j].label, &a, NULL, NULL), 0);
      int ok = 0;
      s = vec_at(&T, v);
      if (grads) {
        assert_int_equal(T.eval_label(&T, scratch, &s.base, all[j].label, &b, grad, &ok), 0);
      } else {
        assert_int_equal(T.eval_label(&T, scratch, &s.base, all[j].label, &b, grad, &ok), -1);
        s = vec_at(&T, v);
        assert_int_equal(T.eval_label(&T, scratch, &s.base, all[j].label, &b, NULL, NULL), 0);
      }
      labels++;
      int good = rel_equal(a.f, all[j].v.f * jac, 1e-7) && rel_equal(a.f_large, all[j].v.f, 1e-7) &&
                 rel_equal(a.value.g, all[j].v.value.g * jac, 1e-7) &&
                 fabs(a.rx - all[j].v.rx) < 1e-7 && fabs(a.ry - all[j].v.ry) < 1e-7 &&
                 rel_equal(b.f, a.f, 1e-9) && rel_equal(b.f_large, a.f_large, 1e-9) &&
                 fabs(b.rx - a.rx) < 1e-9 && fabs(b.ry - a.ry) < 1e-9;
      if (!good)
        print_message("sample %d label %d (s %d, t %d): f %.12g x jac %.12g = %.12g; label's "
                      "own %.12g (f_large %.12g), with the gradient %.12g (f_large %.12g)\n",
                      n, all[j].label, ctx.strat[all[j].label].s, ctx.strat[all[j].label].t,
                      all[j].v.f, jac, all[j].v.f * jac, a.f, a.f_large, b.f, b.f_large);
      assert_true(good);
      with_grad += ok;
      /* The whole sample again from label j's coordinates. */
      s = vec_at(&T, v);
      int nb = T.eval_all(&T, scratch, &s.base, all[j].label, again);
      assert_int_equal(nb, na);
      for (int q = 0; q < na; q++) {
        assert_int_equal(again[q].label, all[q].label);
        if (all[q].v.f < 1e-250) continue;
        if (!rel_equal(again[q].v.f, all[q].v.f, 1e-7))
          print_message("sample %d from label %d: label %d f %.12g, first %.12g\n", n,
                        all[j].label, all[q].label, again[q].v.f, all[q].v.f);
        assert_true(rel_equal(again[q].v.f, all[q].v.f, 1e-7));
        resampled++;
      }
    }
  }
  print_message("%d samples, %d labels (%d with rough vertices, %d rewritten), %d with a "
                "gradient, %d strategies re-evaluated\n",
                samples, labels, rough_labels, moved, with_grad, resampled);
  assert_true(samples >= min_samples);
  assert_true(labels >= 4 * min_samples);
  assert_true(rough_labels >= min_samples);
  assert_true(moved >= rough_labels);
  assert_true(grads ? with_grad >= labels / 2 : with_grad == 0);
  assert_true(resampled >= labels + 2 * min_samples); /* samples with several strategies */
  free(all), free(again), free(u), free(v), free(grad);
  T.scratch_destroy(scratch);
  mc_bdpt_states_free(&ctx);
}

static void test_relabel_consistency(void **state) {
  fixture *fx = *state;
  relabel_consistency(fx->sc, 1, 500);
}

/* The same through media (tests/data/media/rough_glass_fog.xml: a rough
 * glass sphere of fog in a fog): each vertex's numbers begin with its
 * flight's, and relabel writes the rough directions after them. */
static void test_relabel_through_media(void **state) {
  (void)state;
  scene *sc = load_scene("data/media/rough_glass_fog.xml");
  relabel_consistency(sc, 0, 300);
  scene_destroy(sc);
}

/* f of label lab at v with coordinate i set to x. */
static double f_at(const mc_target *T, void *scratch, double *v, int lab, int i, double x) {
  double old = v[i];
  v[i] = x;
  vec_smp s = vec_at(T, v);
  mc_value a;
  T->eval_label(T, scratch, &s.base, lab, &a, NULL, NULL);
  v[i] = old;
  return a.f;
}

static void test_gradients(void **state) {
  fixture *fx = *state;
  mc_bdpt_states ctx;
  mc_target T = make_target(fx, &ctx, 0.05);
  void *scratch = T.scratch_create(&T);
  mc_contrib *all = calloc((size_t)T.n_labels, sizeof *all);
  double *u = malloc((size_t)T.dim * sizeof *u), *v = malloc((size_t)T.dim * sizeof *v);
  double *grad = malloc((size_t)T.dim * sizeof *grad);
  rng r, fresh;
  rng_seed(&r, 23, 1);
  rng_seed(&fresh, 23, 2);
  int states = 0, compared = 0, passed = 0, absolute = 0;
  for (int n = 0; n < 3000 && states < 200; n++) {
    for (int i = 0; i < T.dim; i++) u[i] = rng_uniform(&r);
    vec_smp s = vec_at(&T, u);
    int na = T.eval_all(&T, scratch, &s.base, -1, all);
    if (na <= 0) continue;
    int j = (int)(rng_uniform(&r) * na);
    memcpy(v, u, (size_t)T.dim * sizeof *v);
    double jac = T.relabel(&T, scratch, all[j].label, v, &fresh);
    int lab = all[j].label, ok = 0;
    mc_value a;
    s = vec_at(&T, v);
    T.eval_label(&T, scratch, &s.base, lab, &a, grad, &ok);
    if (!ok) continue;
    states++;
    absolute += jac != 1.0;
    for (int i = 0; i < T.dim; i++) {
      double x = v[i], est[3];
      int valid = 1;
      for (int e = 0; e < 3 && valid; e++) {
        double h = 1e-5 * pow(0.1, e);
        if (x - 2 * h < 0.0 || x + 2 * h >= 1.0) {
          valid = 0;
          break;
        }
        double d1 = (f_at(&T, scratch, v, lab, i, x + h) - f_at(&T, scratch, v, lab, i, x - h)) / (2 * h);
        double d2 =
            (f_at(&T, scratch, v, lab, i, x + 2 * h) - f_at(&T, scratch, v, lab, i, x - 2 * h)) / (4 * h);
        est[e] = (4.0 * d1 - d2) / 3.0;
      }
      if (!valid) continue;
      double scale = fmax(fabs(est[1]), 1e-6 * a.f);
      if (fabs(est[0] - est[1]) > 1e-3 * scale || fabs(est[2] - est[1]) > 1e-3 * scale) continue;
      compared++;
      if (fabs(grad[i] - est[1]) <= 1e-3 * fmax(fabs(est[1]), 1e-5 * a.f))
        passed++;
      else
        print_message("label %d (s %d, t %d) coordinate %d: gradient %.10g, differences %.10g (f %g)\n",
                      lab, ctx.strat[lab].s, ctx.strat[lab].t, i, grad[i], est[1], a.f);
    }
  }
  print_message("%d states (%d with absolute directions), %d of %d derivatives agree\n", states,
                absolute, passed, compared);
  assert_true(states >= 150);
  assert_true(absolute >= 40);
  assert_true(compared >= 1000);
  assert_true(passed >= 0.99 * compared);
  free(all), free(u), free(v), free(grad);
  T.scratch_destroy(scratch);
  mc_bdpt_states_free(&ctx);
}

static void test_without_absolute(void **state) {
  fixture *fx = *state;
  mc_bdpt_states ctx;
  mc_target T = make_target(fx, &ctx, 2.0);
  assert_null(T.relabel);
  void *scratch = T.scratch_create(&T);
  mc_contrib *all = calloc((size_t)T.n_labels, sizeof *all);
  double *u = malloc((size_t)T.dim * sizeof *u);
  rng r;
  rng_seed(&r, 29, 1);
  int checked = 0;
  for (int n = 0; n < 1000; n++) {
    for (int i = 0; i < T.dim; i++) u[i] = rng_uniform(&r);
    vec_smp s = vec_at(&T, u);
    int na = T.eval_all(&T, scratch, &s.base, -1, all);
    for (int j = 0; j < na; j++) {
      mc_value a;
      s = vec_at(&T, u);
      T.eval_label(&T, scratch, &s.base, all[j].label, &a, NULL, NULL);
      assert_true(rel_equal(a.f, all[j].v.f, 1e-12));
      checked++;
    }
  }
  print_message("%d labels checked\n", checked);
  assert_true(checked >= 500);
  free(all), free(u);
  T.scratch_destroy(scratch);
  mc_bdpt_states_free(&ctx);
}

/* One evaluation with gradient and Hessian (eval_hess) of state u, label lab. */
typedef struct hess_eval {
  mc_value v;
  int grad_ok, hn, hess_ok;
  double *grad, *hess;
  int hidx[MC_HESS_MAX];
} hess_eval;

static void eval_hess_at(const mc_target *T, void *scratch, double *u, int lab, hess_eval *OUT) {
  vec_smp s = vec_at(T, u);
  OUT->grad_ok = OUT->hess_ok = OUT->hn = 0;
  T->eval_hess(T, scratch, &s.base, lab, &OUT->v, OUT->grad, &OUT->grad_ok, &OUT->hn, OUT->hidx,
               OUT->hess, &OUT->hess_ok);
}

/* Chains that one thread drives share its workspace (scratch_bind): two
 * scratches bound to one workspace and evaluated in turn give, state for
 * state, what a scratch with its own gives, bit for bit (value, gradient,
 * Hessian); a scratch unbound again uses its own. Counts: 200 states with
 * a Hessian. */
static void test_shared_workspace(void **state) {
  fixture *fx = *state;
  mc_bdpt_states ctx;
  mc_target T = make_target(fx, &ctx, 0.05);
  assert_non_null(T.eval_hess);
  assert_non_null(T.workspace_create);
  void *own = T.scratch_create(&T), *sa = T.scratch_create(&T), *sb = T.scratch_create(&T);
  void *ws = T.workspace_create(&T);
  assert_non_null(ws);
  T.scratch_bind(sa, ws);
  T.scratch_bind(sb, ws);
  mc_contrib *all = calloc((size_t)T.n_labels, sizeof *all);
  double *u = malloc((size_t)T.dim * sizeof *u);
  size_t hsz = (size_t)MC_HESS_MAX * (MC_HESS_MAX + 1) / 2;
  hess_eval e[2];
  for (int k = 0; k < 2; k++) {
    e[k].grad = malloc((size_t)T.dim * sizeof(double));
    e[k].hess = malloc(hsz * sizeof(double));
  }
  rng r;
  rng_seed(&r, 31, 1);
  int compared = 0;
  for (int n = 0; n < 5000 && compared < 200; n++) {
    for (int i = 0; i < T.dim; i++) u[i] = rng_uniform(&r);
    vec_smp s = vec_at(&T, u);
    int na = T.eval_all(&T, own, &s.base, -1, all);
    if (na <= 0) continue;
    int lab = all[(int)(rng_uniform(&r) * na)].label;
    /* The bound scratches in turn, then the one with its own workspace. */
    eval_hess_at(&T, (n & 1) ? sa : sb, u, lab, &e[0]);
    eval_hess_at(&T, own, u, lab, &e[1]);
    assert_memory_equal(&e[0].v.f, &e[1].v.f, sizeof e[0].v.f);
    assert_int_equal(e[0].grad_ok, e[1].grad_ok);
    assert_int_equal(e[0].hess_ok, e[1].hess_ok);
    if (!e[0].hess_ok) continue;
    assert_memory_equal(e[0].grad, e[1].grad, (size_t)T.dim * sizeof(double));
    assert_int_equal(e[0].hn, e[1].hn);
    assert_memory_equal(e[0].hidx, e[1].hidx, (size_t)e[0].hn * sizeof(int));
    assert_memory_equal(e[0].hess, e[1].hess,
                        (size_t)e[0].hn * (size_t)(e[0].hn + 1) / 2 * sizeof(double));
    compared++;
  }
  print_message("%d states with their Hessian the same in shared and own workspaces\n", compared);
  assert_int_equal(compared, 200);
  /* Unbound again, sa works with a workspace of its own. */
  T.scratch_bind(sa, NULL);
  T.workspace_destroy(ws);
  eval_hess_at(&T, sa, u, all[0].label, &e[0]);
  eval_hess_at(&T, own, u, all[0].label, &e[1]);
  assert_memory_equal(&e[0].v.f, &e[1].v.f, sizeof e[0].v.f);
  for (int k = 0; k < 2; k++) free(e[k].grad), free(e[k].hess);
  free(all), free(u);
  T.scratch_destroy(own), T.scratch_destroy(sa), T.scratch_destroy(sb);
  mc_bdpt_states_free(&ctx);
}

/* A chain of large and small steps on the bdpt states: every ray its
 * scratches traced after the start is in one kernel's tally; the labels'
 * tallies sum to the steps, the small steps and their rays; a small step
 * from label (s, t) of length k = s + t - 1 traces 1 to k rays (t - 1
 * camera and s - 1 light segments and the connection), so each label's
 * rays lie within [steps, k steps]. Counts: 20,000 steps, the labels
 * visited (at least 5). */
static void test_ray_tallies(void **state) {
  fixture *fx = *state;
  mc_bdpt_states ctx;
  mc_target T = make_target(fx, &ctx, 0.3);
  mc_kernel k[2] = {mc_kernel_large(), mc_kernel_small(1.0 / 1024.0, 1.0 / 64.0)};
  double p[2] = {0.2, 0.8};
  mc_chain *ch = NULL;
  lmc_error err;
  assert_int_equal(mc_chain_create(&ch, &T, k, p, 2, &err), LMC_OK);
  assert_non_null(ch->lab);
  int64_t r_start = 0;
  for (uint64_t seq = 1; seq < 100; seq++) /* a start that sees light */
    if (mc_chain_start(ch, 7, seq, 1000 + seq) > 0.0) break;
  assert_true(ch->x.v.f > 0.0);
  r_start = mc_chain_rays(ch);
  const int n_steps = 20000;
  for (int i = 0; i < n_steps; i++) mc_chain_step(ch, NULL, NULL);
  int64_t traced = mc_chain_rays(ch) - r_start;
  assert_int_equal(ch->stats[0].rays + ch->stats[1].rays, traced);
  assert_true(ch->stats[0].rays >= ch->sum_rays);
  int64_t steps = 0, small = 0, small_rays = 0;
  int visited = 0;
  for (int l = 0; l < T.n_labels; l++) {
    const int64_t *t = ch->lab + 3 * l;
    steps += t[0], small += t[1], small_rays += t[2];
    if (t[1] == 0) continue;
    int len = mc_bdpt_states_length(&ctx, l);
    if (t[2] < t[1] || t[2] > (int64_t)len * t[1])
      fail_msg("label %d (length %d): %lld rays in %lld small steps", l, len, (long long)t[2],
               (long long)t[1]);
    visited++;
  }
  print_message("%d steps, %d labels visited, %.3g rays a small step, %.3g a large one\n",
                n_steps, visited, (double)small_rays / (double)small,
                (double)ch->stats[0].rays / (double)ch->stats[0].proposed);
  assert_int_equal(steps, n_steps);
  assert_int_equal(small, ch->stats[1].proposed);
  assert_int_equal(small_rays, ch->stats[1].rays);
  assert_true(visited >= 5);
  mc_chain_destroy(ch);
  mc_bdpt_states_free(&ctx);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_ray_tallies),
      cmocka_unit_test(test_relabel_consistency),
      cmocka_unit_test(test_relabel_through_media),
      cmocka_unit_test(test_gradients),
      cmocka_unit_test(test_without_absolute),
      cmocka_unit_test(test_shared_workspace),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
