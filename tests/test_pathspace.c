/*
 * test_pathspace.c: path-space states (src/lmc/path/pathspace.c) and
 * Veach's bidirectional mutation (mut_bidir.c) on two small built-in
 * scenes: `diffuse`, a diffuse box lit by an area light, with a plastic
 * sphere (a mixed BSDF: a vertex on it scatters through its coating's delta
 * lobe or its diffuse base, pathspace.h), `delta`, a
 * diffuse floor and wall with a mirror sphere, a glass sphere and a point
 * light (delta lobes, a delta-position light, the pinhole), and `caustic`,
 * a point light above a glass sphere over a floor (light subpaths through
 * refractions), and `env`, spheres under a constant environment (endpoints
 * at infinity). Paths of 1 to KMAX = 4 segments.
 *
 *  - f_matches_bdpt: a state made from a BDPT sample's strategy (s, t)
 *    (s != 1) has f / p equal to bdpt_connect's unweighted contribution
 *    (times W H, the film-wide raster density, for t >= 2), p the product
 *    of the state's own densities along the strategy; where no delta lobe
 *    is involved p is also bdpt's own product of pdf_fwd. To 1e-9 relative
 *    (the walks' throughputs use the sampled directions, the state the
 *    directions between the hit points). Every strategy has a density in
 *    this space; on `caustic`, hundreds whose light subpath refracts through
 *    the glass check the change of measure of a light-side refraction
 *    (pathspace.h) against bdpt's own throughput.
 *  - cached_vs_scratch: on chains of mutations, T(x -> y) and T(y -> x)
 *    from the states' caches against bdpt_path_pdfs on the re-split paths,
 *    f(y) by partial evaluation against f from scratch, and every cache of
 *    y against a fresh evaluation, to 1e-9 relative; detailed balance
 *    f(x) T(x -> y) a(x -> y) = f(y) T(y -> x) a(y -> x) with the reverse
 *    ratio computed anew from y (scratch densities). The moves' shapes
 *    (kd, ka, lc, mc) are counted: many distinct ones, whole-path deletions
 *    among them.
 *  - invariance / invariance_detects_bias: the one-step test below.
 * Every check is counted and the counts asserted.
 */
#include <limits.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "chi2.h"
#include "lmc/path/mut_bidir.h"
#include "pathspace_test.h"
#include "render/io/io.h"
#include "test_util.h"

#define KMAX 4

static const char *diffuse_xml =
    "<scene version=\"0.6.0\">\n"
    "  <sensor type=\"perspective\">\n"
    "    <float name=\"fov\" value=\"50\"/>\n"
    "    <transform name=\"toWorld\"><lookat origin=\"0, 1.5, 6\" target=\"0, 1, 0\" up=\"0, 1, 0\"/></transform>\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer name=\"height\" value=\"12\"/>"
    "<rfilter type=\"box\"/></film>\n"
    "  </sensor>\n"
    "  <bsdf type=\"diffuse\" id=\"white\"><rgb name=\"reflectance\" value=\"0.7, 0.7, 0.7\"/></bsdf>\n"
    "  <bsdf type=\"diffuse\" id=\"red\"><rgb name=\"reflectance\" value=\"0.7, 0.2, 0.2\"/></bsdf>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/>"
    "<scale x=\"2\" y=\"1\" z=\"2\"/></transform><ref id=\"white\"/></shape>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><scale x=\"2\" y=\"2\" z=\"1\"/>"
    "<translate x=\"0\" y=\"2\" z=\"-2\"/></transform><ref id=\"white\"/></shape>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate y=\"1\" angle=\"90\"/>"
    "<scale x=\"1\" y=\"2\" z=\"2\"/><translate x=\"-2\" y=\"2\" z=\"0\"/></transform><ref id=\"red\"/></shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0.6\" y=\"0.6\" z=\"0\"/><float name=\"radius\" value=\"0.6\"/>"
    "<ref id=\"white\"/></shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"-0.9\" y=\"0.4\" z=\"0.9\"/><float name=\"radius\" value=\"0.4\"/>"
    "<bsdf type=\"plastic\"><rgb name=\"diffuseReflectance\" value=\"0.2, 0.4, 0.6\"/></bsdf></shape>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"90\"/><scale x=\"0.5\" y=\"1\" z=\"0.5\"/>"
    "<translate x=\"0\" y=\"3\" z=\"0\"/></transform>\n"
    "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"10, 9, 8\"/></emitter>\n"
    "  </shape>\n"
    "</scene>\n";

static const char *delta_xml =
    "<scene version=\"0.6.0\">\n"
    "  <sensor type=\"perspective\">\n"
    "    <float name=\"fov\" value=\"50\"/>\n"
    "    <transform name=\"toWorld\"><lookat origin=\"0, 1.5, 6\" target=\"0, 0.8, 0\" up=\"0, 1, 0\"/></transform>\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer name=\"height\" value=\"12\"/>"
    "<rfilter type=\"box\"/></film>\n"
    "  </sensor>\n"
    "  <bsdf type=\"diffuse\" id=\"white\"><rgb name=\"reflectance\" value=\"0.7, 0.7, 0.7\"/></bsdf>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/>"
    "<scale x=\"3\" y=\"1\" z=\"3\"/></transform><ref id=\"white\"/></shape>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><scale x=\"3\" y=\"2\" z=\"1\"/>"
    "<translate x=\"0\" y=\"2\" z=\"-2\"/></transform><ref id=\"white\"/></shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"-0.8\" y=\"0.7\" z=\"0\"/><float name=\"radius\" value=\"0.7\"/>"
    "<bsdf type=\"conductor\"><string name=\"material\" value=\"Ag\"/></bsdf></shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0.9\" y=\"0.5\" z=\"0.8\"/><float name=\"radius\" value=\"0.5\"/>"
    "<bsdf type=\"dielectric\"><float name=\"intIOR\" value=\"1.5\"/></bsdf></shape>\n"
    "  <emitter type=\"point\"><point name=\"position\" x=\"0.5\" y=\"2.5\" z=\"1.5\"/>"
    "<rgb name=\"intensity\" value=\"8, 8, 7\"/></emitter>\n"
    "</scene>\n";

/* A point light above a glass sphere over a diffuse floor, seen from
 * above: its caustic, whose paths leave the light through refractions. */
static const char *caustic_xml =
    "<scene version=\"0.6.0\">\n"
    "  <sensor type=\"perspective\">\n"
    "    <float name=\"fov\" value=\"40\"/>\n"
    "    <transform name=\"toWorld\"><lookat origin=\"0, 3, 3\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer name=\"height\" value=\"12\"/>"
    "<rfilter type=\"box\"/></film>\n"
    "  </sensor>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/>"
    "<scale x=\"2\" y=\"1\" z=\"2\"/></transform>"
    "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.7\"/></bsdf></shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"0.8\" z=\"0\"/><float name=\"radius\" value=\"0.5\"/>"
    "<bsdf type=\"dielectric\"><float name=\"intIOR\" value=\"1.5\"/></bsdf></shape>\n"
    "  <emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"2\" z=\"0\"/>"
    "<rgb name=\"intensity\" value=\"8, 8, 7\"/></emitter>\n"
    "</scene>\n";

/* A diffuse floor, a diffuse and a mirror sphere under a constant
 * environment, a directional light and a small area light: endpoints at
 * infinity, reached by camera walks that escape and sampled by light walks
 * from the environment's disk, and the directional light's, which only
 * its light walks reach. */
static const char *env_xml =
    "<scene version=\"0.6.0\">\n"
    "  <sensor type=\"perspective\">\n"
    "    <float name=\"fov\" value=\"50\"/>\n"
    "    <transform name=\"toWorld\"><lookat origin=\"0, 1.5, 5\" target=\"0, 0.5, 0\" up=\"0, 1, 0\"/></transform>\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer name=\"height\" value=\"12\"/>"
    "<rfilter type=\"box\"/></film>\n"
    "  </sensor>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/>"
    "<scale x=\"3\" y=\"1\" z=\"3\"/></transform>"
    "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.6\"/></bsdf></shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"-0.7\" y=\"0.6\" z=\"0\"/><float name=\"radius\" value=\"0.6\"/>"
    "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.3, 0.5, 0.7\"/></bsdf></shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0.8\" y=\"0.5\" z=\"0.3\"/><float name=\"radius\" value=\"0.5\"/>"
    "<bsdf type=\"conductor\"><string name=\"material\" value=\"Ag\"/></bsdf></shape>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"90\"/>"
    "<scale value=\"0.3\"/><translate y=\"2.5\"/></transform>"
    "<emitter type=\"area\"><rgb name=\"radiance\" value=\"20\"/></emitter></shape>\n"
    "  <emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.4, 0.5, 0.6\"/></emitter>\n"
    "  <emitter type=\"directional\"><vector name=\"direction\" x=\"0.3\" y=\"-1\" z=\"-0.4\"/>"
    "<rgb name=\"irradiance\" value=\"2, 1.8, 1.5\"/></emitter>\n"
    "</scene>\n";

typedef struct fixture {
  scene *sc[4]; /* diffuse, delta, caustic, env */
} fixture;

static int setup(void **state) {
  fixture *fx = calloc(1, sizeof *fx);
  fx->sc[0] = try_load_scene_text(diffuse_xml, "ps_diffuse");
  fx->sc[1] = try_load_scene_text(delta_xml, "ps_delta");
  fx->sc[2] = try_load_scene_text(caustic_xml, "ps_caustic");
  fx->sc[3] = try_load_scene_text(env_xml, "ps_env");
  if (!fx->sc[0] || !fx->sc[1] || !fx->sc[2] || !fx->sc[3]) return -1;
  *state = fx;
  return 0;
}

static int teardown(void **state) {
  fixture *fx = *state;
  scene_destroy(fx->sc[0]);
  scene_destroy(fx->sc[1]);
  scene_destroy(fx->sc[2]);
  scene_destroy(fx->sc[3]);
  free(fx);
  return 0;
}

static void context(const scene *sc, ps_context *ctx) { ps_test_context(sc, KMAX, ctx); }

/* ---- f against BDPT's strategies --------------------------------------------- */

static void check_f_bdpt(const scene *sc, uint64_t seed, int *OUT_checks, int *OUT_delta,
                         int *OUT_pdf_checks, int *OUT_skipped, int *OUT_light_delta,
                         int *OUT_inf, int *OUT_sun) {
  ps_context ctx;
  context(sc, &ctx);
  ps_path *x = malloc(sizeof *x);
  lmc_indep_sampler smp;
  indep_sampler_init(&smp, seed, 1);
  render_counters cnt;
  memset(&cnt, 0, sizeof cnt);
  bdpt_vertex cam[KMAX + 2], lp[KMAX + 1];
  double wh = (double)sc->cam.width * sc->cam.height;
  for (int n = 0; n < 20000; n++) {
    double rx = sampler_next(&smp.base) * sc->cam.width;
    double ry = sampler_next(&smp.base) * sc->cam.height;
    int nc = bdpt_camera_subpath(sc, &ctx.rs, &smp.base, rx, ry, KMAX + 1, cam, &cnt);
    int nl = bdpt_light_subpath(sc, &ctx.rs, &smp.base, KMAX, lp, &cnt);
    for (int t = 1; t <= nc; t++) {
      for (int s = 0; s <= nl; s++) {
        if (s == 1 || s + t - 1 < 1 || s + t - 1 > KMAX || (s == 0 && t == 1)) continue;
        double w = 0.0, prx = 0.0, pry = 0.0;
        rgb c = bdpt_connect(sc, cam, t, lp, s, NULL, &prx, &pry, &w, &cnt);
        if (rgb_is_black(c) || !(w > 0.0)) continue;
        if (!ps_from_bdpt(&ctx, cam, t, lp, s, x)) continue;
        /* The state's density of this strategy, and bdpt's. */
        double p = 1.0, pb = 1.0;
        int delta = 0;
        for (int i = 0; i < t; i++) p *= x->x[i].pdf_cam, pb *= cam[i].pdf_fwd;
        for (int j = 0; j < s; j++) p *= x->x[x->k - j].pdf_light, pb *= lp[j].pdf_fwd;
        for (int i = 1; i < x->k; i++) delta |= x->x[i].delta;
        *OUT_inf += x->x[x->k].inf;
        *OUT_sun += x->x[x->k].inf && x->x[x->k].v.light >= 0 &&
                    sc->lights[x->x[x->k].v.light].type == LIGHT_DIRECTIONAL;
        int light_delta = 0;
        for (int j = 1; j < s; j++) light_delta |= lp[j].delta;
        /* A strategy the path space gives no density (none expected). */
        if (!(p > 0.0)) {
          (*OUT_skipped)++;
          continue;
        }
        rgb want = rgb_scale(c, (t >= 2 ? wh : 1.0) / w);
        rgb got = rgb_scale(x->f, 1.0 / p);
        if (!rgb_close(got, want, 1e-9))
          print_message("s %d t %d: f/p = (%.12g %.12g %.12g), bdpt (%.12g %.12g %.12g)\n", s, t,
                        got.r, got.g, got.b, want.r, want.g, want.b);
        assert_true(rgb_close(got, want, 1e-9));
        if (t == 1) {
          assert_near(x->rx, prx, 1e-6);
          assert_near(x->ry, pry, 1e-6);
        }
        (*OUT_checks)++;
        *OUT_delta += delta;
        *OUT_light_delta += light_delta;
        if (!delta) {
          assert_true(rel_close(p, pb, 1e-9));
          (*OUT_pdf_checks)++;
        }
      }
    }
  }
  free(x);
}

static void test_f_matches_bdpt(void **state) {
  fixture *fx = *state;
  int checks[4] = {0}, delta[4] = {0}, pdfs[4] = {0}, skipped[4] = {0}, light_delta[4] = {0};
  int inf[4] = {0}, sun[4] = {0};
  for (int q = 0; q < 4; q++)
    check_f_bdpt(fx->sc[q], 11 + q, &checks[q], &delta[q], &pdfs[q], &skipped[q],
                 &light_delta[q], &inf[q], &sun[q]);
  print_message("f vs bdpt: diffuse %d (densities %d), delta %d (%d through delta lobes, "
                "densities %d), caustic %d (%d with light subpaths through the glass), env %d "
                "(%d ending at infinity, %d of them at the directional light, densities %d); %d, "
                "%d, %d, %d without a density\n",
                checks[0], pdfs[0], checks[1], delta[1], pdfs[1], checks[2], light_delta[2],
                checks[3], inf[3], sun[3], pdfs[3], skipped[0], skipped[1], skipped[2], skipped[3]);
  for (int q = 0; q < 4; q++) assert_int_equal(skipped[q], 0);
  /* The plastic sphere's coating (a mixed BSDF's delta lobe) among them. */
  assert_true(checks[0] >= 2000 && delta[0] >= 100 && pdfs[0] + delta[0] == checks[0]);
  assert_true(checks[1] >= 1000 && delta[1] >= 50 && pdfs[1] >= 500);
  /* The light side's refractions carry the change of measure between the
   * two directions' Diracs: f / p against bdpt's own throughput. */
  assert_true(checks[2] >= 1000 && light_delta[2] >= 200);
  /* Endpoints at infinity: the camera's escapes and the environment's
   * own light walks, against bdpt's. */
  assert_true(checks[3] >= 1000 && inf[3] >= 500 && pdfs[3] >= 500 && sun[3] >= 200);
}

/* ---- Cached against scratch, detailed balance --------------------------------- */

/* A starting state of length 1 .. KMAX with f > 0 (whole-path samples). */
static int start_state(const mut_bidir *mb, rng *r, ps_path *x) {
  for (int tries = 0; tries < 100000; tries++) {
    int k = 1 + (int)(rng_uniform(r) * KMAX);
    if (mut_bidir_sample_whole(mb, r, k, x) == MUT_BIDIR_OK && x->lum > 0.0) return 1;
  }
  return 0;
}

/* Every cache of y against a fresh evaluation of a copy. */
static void check_caches(const ps_context *ctx, const ps_path *y, ps_path *tmp) {
  assert_true(ps_test_caches_fresh(ctx, y, tmp));
}

static void check_chains(const scene *sc, uint64_t seed, int *OUT_checks, int *OUT_shapes,
                         int *OUT_whole, int *OUT_balance, int *OUT_delta) {
  ps_context ctx;
  context(sc, &ctx);
  mut_bidir mb;
  mut_bidir_init(&mb, &ctx);
  ps_path *x = malloc(sizeof *x), *y = malloc(sizeof *y), *tmp = malloc(sizeof *tmp);
  static unsigned char seen[KMAX + 3][KMAX + 3][KMAX + 3];
  memset(seen, 0, sizeof seen);
  rng r;
  rng_seed(&r, seed, 3);
  for (int chain = 0; chain < 300; chain++) {
    assert_true(start_state(&mb, &r, x));
    for (int step = 0; step < 150; step++) {
      mut_bidir_record rec;
      double ratio;
      if (mut_bidir_propose(&mb, &r, x, y, &rec, &ratio) != MUT_BIDIR_OK) continue;
      check_caches(&ctx, y, tmp);
      /* T both ways, cached and from scratch. */
      double tf = mut_bidir_density(&mb, x->k, y, rec.l, rec.kd, rec.ka, 0);
      double tfs = mut_bidir_density(&mb, x->k, y, rec.l, rec.kd, rec.ka, 1);
      double tr = mut_bidir_density(&mb, y->k, x, rec.l, rec.ka, rec.kd, 0);
      double trs = mut_bidir_density(&mb, y->k, x, rec.l, rec.ka, rec.kd, 1);
      if (!rel_close(tf, tfs, 1e-9) || !rel_close(tr, trs, 1e-9))
        print_message("T(x->y) %.17g / %.17g, T(y->x) %.17g / %.17g (l %d m %d ka %d)\n", tf, tfs,
                      tr, trs, rec.l, rec.m, rec.ka);
      if (!(tf > 0.0))
        print_message("T = 0: k %d -> %d, l %d m %d kd %d ka %d lc %d mc %d\n", x->k, y->k, rec.l,
                      rec.m, rec.kd, rec.ka, rec.lc, rec.mc);
      assert_true(tf > 0.0);
      assert_true(rel_close(tf, tfs, 1e-9) && rel_close(tr, trs, 1e-9));
      (*OUT_checks)++;
      seen[rec.kd][rec.ka][rec.lc] = 1;
      /* Moves that sampled or kept-and-extended a delta vertex. */
      int nd = 0;
      for (int i = rec.l > 0 ? rec.l : 1; i <= rec.l + rec.ka && i < y->k; i++) nd += y->x[i].delta;
      *OUT_delta += nd > 0;
      if (rec.l == -1 && rec.m == x->k + 1) (*OUT_whole)++;
      /* Detailed balance, the reverse ratio computed anew from y. */
      if (y->lum > 0.0) {
        mut_bidir_record rev = {rec.l, rec.l + rec.ka, rec.ka, rec.kd, 0, 0, MUT_BIDIR_OK};
        double ratio_rev = mut_bidir_ratio(&mb, y, x, &rev, 1);
        double lhs = x->lum * tf * fmin(1.0, ratio);
        double rhs = y->lum * trs * fmin(1.0, ratio_rev);
        if (!rel_close(lhs, rhs, 1e-9)) print_message("balance %.17g vs %.17g\n", lhs, rhs);
        assert_true(rel_close(lhs, rhs, 1e-9));
        /* (Both sides are 0 when no split can undo the move, e.g. a mirror
         * vertex that every reverse split would have to connect.) */
        *OUT_balance += lhs > 0.0;
      }
      if (rng_uniform(&r) < ratio) {
        ps_path *sw = x;
        x = y, y = sw;
      }
    }
  }
  for (int a = 0; a < KMAX + 3; a++)
    for (int b = 0; b < KMAX + 3; b++)
      for (int c = 0; c < KMAX + 3; c++) *OUT_shapes += seen[a][b][c];
  free(x), free(y), free(tmp);
}

static void test_cached_vs_scratch(void **state) {
  fixture *fx = *state;
  static const char *const names[4] = {"diffuse", "delta", "caustic", "env"};
  for (int q = 0; q < 4; q++) {
    int checks = 0, shapes = 0, whole = 0, balance = 0, delta = 0;
    check_chains(fx->sc[q], 21 + q, &checks, &shapes, &whole, &balance, &delta);
    print_message("%s: %d proposals checked, %d shapes (kd, ka, lc), %d whole-path, %d balance, "
                  "%d with delta vertices in the changed range\n",
                  names[q], checks, shapes, whole, balance, delta);
    assert_true(checks >= 1000 && shapes >= 30 && whole >= 10 && balance >= 300);
    assert_true(delta >= (q == 0 ? 20 : 100)); /* diffuse: the plastic's coating alone */
  }
}

/* ---- One-step invariance ---------------------------------------------------- *
 *
 * Hypotheses. H0: one step of the kernel K (a proposal of mut_bidir_propose
 * accepted with probability min(1, ratio)) leaves pi, proportional to
 * lum f over the paths of 1 .. KMAX segments, invariant. Samples x_i of
 * q, the whole-path sampler (length uniform, mut_bidir_sample_whole), with
 * importance weights w_i = lum f(x_i) / q(x_i) stand for pi; each is moved
 * once, y_i ~ K(x_i, .). For every bin b of (length) x (image quadrant of
 * (rx, ry)) x (height of x_1 in three bands) x (delta vertices: 0, 1, 2+),
 * Z_ib = w_i (1_b(y_i) - 1_b(x_i)) are iid with mean 0 under H0
 * (pi K = pi), so
 *   z_b^2 = (sum_i Z_ib)^2 / sum_i Z_ib^2
 * (the self-normalised statistic, its variance estimated from the same
 * samples) is asymptotically chi^2(1). H0 is rejected when a bin's p-value
 * falls below the Sidak level 1 - (1 - alpha)^(1/B), alpha = 1e-3, B the
 * bins with moves. q > 0 wherever the chain can go: a path the mutation
 * can reach has a split with positive densities, which the whole-path
 * sampler also uses.
 * H1 (the negative control, second test): T with one term halved in both
 * directions' T (mut_bidir.test_bias: in `diffuse` the densities of new
 * light-side vertices sampled by a BSDF, in `delta` those of vertices
 * sampled through a delta lobe) is not pi-invariant: the same test with the
 * same sample size and seeds must reject it. (A factor above one is
 * weaker: min(1, ratio) caps the moves it would favour.)
 */

#define INV_BINS (KMAX * 4 * 3 * 3)
_Static_assert(INV_BINS <= PS_INV_MAX_BINS, "the bins fit ps_inv");

/* (length) x (quadrant of (rx, ry)) x (height band of x_1) x (delta
 * vertices: 0, 1, 2 or more). */
static int inv_bin(const scene *sc, const ps_path *x) {
  int qx = x->rx < 0.5 * sc->cam.width ? 0 : 1, qy = x->ry < 0.5 * sc->cam.height ? 0 : 1;
  double h = x->x[1].v.p.y;
  int hb = h < 0.5 ? 0 : h < 1.5 ? 1 : 2, nd = 0;
  for (int i = 1; i < x->k; i++) nd += x->x[i].delta;
  return (((x->k - 1) * 4 + 2 * qy + qx) * 3 + hb) * 3 + (nd < 2 ? nd : 2);
}

static ps_inv *invariance(const scene *sc, uint64_t seed, mut_bidir_bias_term term, double bias,
                             int n) {
  ps_context ctx;
  context(sc, &ctx);
  mut_bidir mb0, mb;
  mut_bidir_init(&mb0, &ctx);
  mut_bidir_init(&mb, &ctx);
  mb.test_bias_term = term;
  mb.test_bias = bias;
  ps_path *x = malloc(sizeof *x), *y = malloc(sizeof *y);
  ps_inv *res = calloc(1, sizeof *res);
  rng r;
  rng_seed(&r, seed, 5);
  for (int i = 0; i < n; i++) {
    int k = 1 + (int)(rng_uniform(&r) * KMAX);
    if (mut_bidir_sample_whole(&mb0, &r, k, x) != MUT_BIDIR_OK || !(x->lum > 0.0)) continue;
    double q = mut_bidir_whole_pdf(&mb0, x, 0) / KMAX;
    assert_true(q > 0.0);
    double w = x->lum / q;
    res->samples++;
    mut_bidir_record rec;
    double ratio;
    int moved = mut_bidir_propose(&mb, &r, x, y, &rec, &ratio) == MUT_BIDIR_OK &&
                rng_uniform(&r) < ratio;
    int b0 = inv_bin(sc, x), b1 = moved ? inv_bin(sc, y) : b0;
    ps_inv_add(res, w, b0, b1);
  }
  ps_inv_finish(res);
  free(x), free(y);
  return res;
}

static void test_invariance(void **state) {
  fixture *fx = *state;
  static const char *const names[4] = {"diffuse", "delta", "caustic", "env"};
  for (int q = 0; q < 4; q++) {
    /* The caustic scene's whole paths carry light more rarely: more draws. */
    ps_inv *r = invariance(fx->sc[q], 31 + q, MUT_BIDIR_BIAS_NONE, 1.0, q == 2 ? 6000000 : 2000000);
    print_message("%s: %d samples, %d moved, %d bins, min p %.3g (level %.3g)\n", names[q],
                  r->samples, r->moved, r->bins, r->min_p, r->level);
    assert_true(r->samples >= 50000 && r->moved >= 10000 && r->bins >= 20);
    assert_true(r->min_p >= r->level);
    free(r);
  }
}

static void test_invariance_detects_bias(void **state) {
  fixture *fx = *state;
  for (int q = 0; q < 2; q++) {
    mut_bidir_bias_term term = q ? MUT_BIDIR_BIAS_DELTA : MUT_BIDIR_BIAS_LIGHT_BSDF;
    ps_inv *r = invariance(fx->sc[q], 31 + q, term, 0.5, 2000000);
    print_message("%s, biased T: %d samples, %d moved, %d bins, min p %.3g (level %.3g)\n",
                  q ? "delta" : "diffuse", r->samples, r->moved, r->bins, r->min_p, r->level);
    assert_true(r->samples >= 50000 && r->moved >= 10000 && r->bins >= 20);
    assert_true(r->min_p < r->level);
    free(r);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_f_matches_bdpt),
      cmocka_unit_test(test_cached_vs_scratch),
      cmocka_unit_test(test_invariance),
      cmocka_unit_test(test_invariance_detects_bias),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
