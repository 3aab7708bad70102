/*
 * test_perturb.c: the lens, multi-chain and caustic perturbations of
 * path-space MLT (src/lmc/path/mut_perturb.c) on three small scenes:
 * `diffuse` (a dark plastic floor, whose coating is a mixed BSDF's delta
 * lobe, a diffuse wall and sphere under an area light: lens perturbations of
 * E D D.. paths, caustic perturbations of E D (D|L) ones), `delta` (a
 * mirror and a glass sphere over a diffuse floor, a point light: lens
 * perturbations through specular chains, multi-chain perturbations of
 * E D S D.. and E S D S D.. paths) and `caustic` (a point light above a
 * glass sphere over a floor: caustic perturbations of E D S S L).
 * Paths of 1 .. KMAX = 4 segments from the whole-path sampler.
 *
 *  - offsets: each perturbation's offset, measured on its proposals (the
 *    raster offset's length and angle; the turn of x_m's direction; the
 *    turn at a chain's start), against its density by chi-square; and
 *    mut_perturb_log_sample against mut_perturb_log_pdf.
 *  - reverse: from a proposal y, the same perturbation with x's choices
 *    (x's raster point, x's directions) gives back x: its vertices to
 *    1e-6 of the scene's size, f to 1e-5.
 *  - balance: on random pairs, every cache of y against a fresh
 *    evaluation, and detailed balance f(x) T(x -> y) a(x -> y) = f(y)
 *    T(y -> x) a(y -> x), the reverse ratio computed anew from y, to 1e-9.
 *  - invariance / invariance_detects_bias: the one-step invariance test of
 *    test_pathspace.c (its statistic is stated there) for each
 *    perturbation as a kernel of its own (a path it does not apply to
 *    stays), and with its Jacobians raised to a wrong power, which it must
 *    reject.
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

#include "chi2.h"
#include "lmc/path/mut_bidir.h"
#include "lmc/path/mut_lenssub.h"
#include "lmc/path/mut_perturb.h"
#include "lmc/path/mut_pss.h"
#include "pathspace_test.h"
#include "render/io/io.h"
#include "test_util.h"

#define KMAX 4
#define PI 3.14159265358979323846

static const char *diffuse_xml =
    "<scene version=\"0.6.0\">\n"
    "  <sensor type=\"perspective\">\n"
    "    <float name=\"fov\" value=\"50\"/>\n"
    "    <transform name=\"toWorld\"><lookat origin=\"0, 1.5, 6\" target=\"0, 1, 0\" up=\"0, 1, 0\"/></transform>\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"24\"/>"
    "<rfilter type=\"box\"/></film>\n"
    "  </sensor>\n"
    "  <bsdf type=\"diffuse\" id=\"white\"><rgb name=\"reflectance\" value=\"0.7, 0.7, 0.7\"/></bsdf>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/>"
    "<scale x=\"30\" y=\"1\" z=\"30\"/></transform>"
    "<bsdf type=\"plastic\"><rgb name=\"diffuseReflectance\" value=\"0.1\"/></bsdf></shape>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><scale x=\"30\" y=\"30\" z=\"1\"/>"
    "<translate x=\"0\" y=\"2\" z=\"-2\"/></transform><ref id=\"white\"/></shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0.6\" y=\"0.6\" z=\"0\"/><float name=\"radius\" value=\"0.6\"/>"
    "<ref id=\"white\"/></shape>\n"
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
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"24\"/>"
    "<rfilter type=\"box\"/></film>\n"
    "  </sensor>\n"
    "  <bsdf type=\"diffuse\" id=\"white\"><rgb name=\"reflectance\" value=\"0.7, 0.7, 0.7\"/></bsdf>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/>"
    "<scale x=\"3\" y=\"1\" z=\"3\"/></transform><ref id=\"white\"/></shape>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><scale x=\"3\" y=\"2\" z=\"1\"/>"
    "<translate x=\"0\" y=\"2\" z=\"-2\"/></transform><bsdf type=\"conductor\"/></shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"-0.8\" y=\"0.7\" z=\"0\"/><float name=\"radius\" value=\"0.7\"/>"
    "<bsdf type=\"conductor\"><string name=\"material\" value=\"Ag\"/></bsdf></shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0.9\" y=\"0.5\" z=\"0.8\"/><float name=\"radius\" value=\"0.5\"/>"
    "<bsdf type=\"dielectric\"><float name=\"intIOR\" value=\"1.5\"/></bsdf></shape>\n"
    "  <emitter type=\"point\"><point name=\"position\" x=\"0.5\" y=\"2.5\" z=\"1.5\"/>"
    "<rgb name=\"intensity\" value=\"8, 8, 7\"/></emitter>\n"
    "</scene>\n";

static const char *caustic_xml =
    "<scene version=\"0.6.0\">\n"
    "  <sensor type=\"perspective\">\n"
    "    <float name=\"fov\" value=\"40\"/>\n"
    "    <transform name=\"toWorld\"><lookat origin=\"0, 3, 3\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"24\"/>"
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

/* Glossy spheres (rough glass and metal of alpha 0.03 and 0.05: G
 * vertices, which the lens perturbation retraces by sampling their BSDFs)
 * over a diffuse floor under an area light. */
static const char *glossy_xml =
    "<scene version=\"0.6.0\">\n"
    "  <sensor type=\"perspective\">\n"
    "    <float name=\"fov\" value=\"40\"/>\n"
    "    <transform name=\"toWorld\"><lookat origin=\"0, 1.2, 5\" target=\"0, 0.6, 0\" up=\"0, 1, 0\"/></transform>\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"24\"/>"
    "<rfilter type=\"box\"/></film>\n"
    "  </sensor>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/>"
    "<scale x=\"30\" y=\"1\" z=\"30\"/></transform>"
    "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.6\"/></bsdf></shape>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><scale x=\"30\" y=\"30\" z=\"1\"/>"
    "<translate x=\"0\" y=\"2\" z=\"-2\"/></transform>"
    "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5, 0.6, 0.7\"/></bsdf></shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"-0.6\" y=\"0.6\" z=\"0\"/><float name=\"radius\" value=\"0.6\"/>"
    "<bsdf type=\"roughdielectric\"><float name=\"alpha\" value=\"0.03\"/></bsdf></shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0.7\" y=\"0.5\" z=\"0.3\"/><float name=\"radius\" value=\"0.5\"/>"
    "<bsdf type=\"roughconductor\"><float name=\"alpha\" value=\"0.05\"/></bsdf></shape>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"90\"/>"
    "<scale value=\"0.5\"/><translate y=\"3\"/></transform>"
    "<emitter type=\"area\"><rgb name=\"radiance\" value=\"12\"/></emitter></shape>\n"
    "</scene>\n";

/* For the primary-sample step alone: paths that end in a sky (a constant
 * emitter), whose last vertex is a direction. */
static const char *sky_xml =
    "<scene version=\"0.6.0\">\n"
    "  <sensor type=\"perspective\">\n"
    "    <float name=\"fov\" value=\"60\"/>\n"
    "    <transform name=\"toWorld\"><lookat origin=\"0, 2, 5\" target=\"0, 0.5, 0\" up=\"0, 1, 0\"/></transform>\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"24\"/>"
    "<rfilter type=\"box\"/></film>\n"
    "  </sensor>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/>"
    "<scale x=\"2\" y=\"1\" z=\"2\"/></transform>"
    "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.6\"/></bsdf></shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"0.6\" z=\"0\"/><float name=\"radius\" value=\"0.6\"/>"
    "<bsdf type=\"roughconductor\"><float name=\"alpha\" value=\"0.3\"/></bsdf></shape>\n"
    "  <emitter type=\"constant\"><rgb name=\"radiance\" value=\"1, 1, 1\"/></emitter>\n"
    "</scene>\n";

enum { DIFFUSE = 0, DELTA, CAUSTIC, GLOSSY, N_SCENES };
static const char *const scene_names[N_SCENES] = {"diffuse", "delta", "caustic", "glossy"};
static const char *const kind_names[3] = {"lens", "multichain", "caustic"};

typedef struct fixture {
  scene *sc[N_SCENES];
} fixture;

static int setup(void **state) {
  fixture *fx = calloc(1, sizeof *fx);
  fx->sc[DIFFUSE] = try_load_scene_text(diffuse_xml, "ps_diffuse");
  fx->sc[DELTA] = try_load_scene_text(delta_xml, "ps_delta");
  fx->sc[CAUSTIC] = try_load_scene_text(caustic_xml, "ps_caustic");
  fx->sc[GLOSSY] = try_load_scene_text(glossy_xml, "ps_glossy");
  for (int q = 0; q < N_SCENES; q++)
    if (!fx->sc[q]) return -1;
  *state = fx;
  return 0;
}

static int teardown(void **state) {
  fixture *fx = *state;
  for (int q = 0; q < N_SCENES; q++) scene_destroy(fx->sc[q]);
  free(fx);
  return 0;
}

/* The path space of a scene and its moves. */
typedef struct movers {
  ps_context ctx;
  mut_bidir mb;
  mut_perturb mp;
  mut_lenssub ml;
} movers;

static void movers_init(movers *mv, const scene *sc) {
  ps_test_context(sc, KMAX, &mv->ctx);
  mut_bidir_init(&mv->mb, &mv->ctx);
  mut_perturb_init(&mv->mp, &mv->ctx);
  mut_lenssub_init(&mv->ml, &mv->ctx);
}

/* A path with f > 0 that perturbation `kind` applies to (whole-path
 * samples of lengths 1 .. KMAX), or 0 after many tries. */
static int n_delta(const ps_path *x) {
  int nd = 0;
  for (int j = 1; j < x->k; j++) nd += x->x[j].delta;
  return nd;
}

/* As draw_state, with a delta or G vertex when `specular`. */
static int draw_state_s(const movers *mv, mut_perturb_kind kind, int specular, rng *r,
                        ps_path *x) {
  for (int tries = 0; tries < 2000000; tries++) {
    int k = 1 + (int)(rng_uniform(r) * KMAX);
    if (mut_bidir_sample_whole(&mv->mb, r, k, x) != MUT_BIDIR_OK || !(x->lum > 0.0)) continue;
    int glossy = 0;
    for (int j = 1; j < x->k; j++) glossy |= mut_perturb_glossy(&mv->mp, x, j);
    if (mut_perturb_applies(&mv->mp, kind, x) && (!specular || n_delta(x) > 0 || glossy))
      return 1;
  }
  return 0;
}

static int draw_state(const movers *mv, mut_perturb_kind kind, rng *r, ps_path *x) {
  return draw_state_s(mv, kind, 0, r, x);
}

static double angle(vec3 a, vec3 b) { return 2.0 * asin(fmin(1.0, 0.5 * v3_len(v3_sub(a, b)))); }

/* ---- Offsets ----------------------------------------------------------------- */

#define OFF_BINS 12

/* The bin of t on [lo, hi] among OFF_BINS of equal probability under the
 * 1/t density (equal widths in log t), -1 outside. */
static int log_bin(double lo, double hi, double t) {
  if (!(t > lo && t < hi)) return -1;
  int b = (int)(OFF_BINS * log(t / lo) / log(hi / lo));
  return b < OFF_BINS ? b : OFF_BINS - 1;
}

static double chi2_uniform(const double *obs, int n, double total) {
  double e[OFF_BINS * 2];
  for (int i = 0; i < n; i++) e[i] = total / n;
  return chi2_pvalue(obs, e, n, 5.0, NULL, NULL);
}

static void test_log_sample(void **state) {
  (void)state;
  double obs[OFF_BINS] = {0};
  rng r;
  rng_seed(&r, 7, 1);
  int n = 200000;
  for (int i = 0; i < n; i++) {
    double t = mut_perturb_log_sample(0.1, 30.0, rng_uniform(&r));
    int b = log_bin(0.1, 30.0, t);
    assert_true(b >= 0);
    obs[b]++;
  }
  double p = chi2_uniform(obs, OFF_BINS, n);
  /* The density integrates to one: a midpoint sum over log-spaced cells. */
  double sum = 0.0;
  for (int i = 0; i < 10000; i++) {
    double a = 0.1 * pow(300.0, i / 10000.0), b = 0.1 * pow(300.0, (i + 1) / 10000.0);
    sum += mut_perturb_log_pdf(0.1, 30.0, sqrt(a * b)) * (b - a);
  }
  print_message("log-uniform lengths: p %.3g; integral of the density %.6f\n", p, sum);
  assert_true(p > 1e-3);
  assert_near(sum, 1.0, 1e-4);
  assert_true(mut_perturb_log_pdf(0.1, 30.0, 0.05) == 0.0 && mut_perturb_log_pdf(0.1, 30.0, 31) == 0.0);
}

/* One perturbation's choices on its proposals: `len` histograms the
 * offset's size on its range (log bins), `az` its azimuth (uniform bins);
 * for the proposals made, the geometry is checked to realise the choice. */
typedef struct offsets {
  double len[OFF_BINS], az[OFF_BINS];
  int n, outside, made, realised;
} offsets;

static void offsets_add(offsets *o, double lo, double hi, double t, double phi) {
  int b = log_bin(lo, hi, t);
  if (b < 0) {
    o->outside++;
    return;
  }
  o->len[b]++;
  double a01 = phi / (2.0 * PI);
  a01 -= floor(a01);
  int a = (int)(OFF_BINS * a01);
  o->az[a < OFF_BINS ? a : OFF_BINS - 1]++;
  o->n++;
}

static void offsets_check(const offsets *o, const char *what, int min_n) {
  double p_len = chi2_uniform(o->len, OFF_BINS, o->n), p_az = chi2_uniform(o->az, OFF_BINS, o->n);
  print_message("%s: %d choices (%d outside the range), %d proposals made, %d realised the choice; "
                "p %.3g (size), %.3g (azimuth)\n",
                what, o->n, o->outside, o->made, o->realised, p_len, p_az);
  assert_true(o->n >= min_n && o->outside == 0);
  assert_true(o->made >= min_n / 2 && o->realised == o->made);
  assert_true(p_len > 1e-3 && p_az > 1e-3);
}

/* The azimuth of b around a, in the frame frame_from_z(a). */
static double azimuth(vec3 a, vec3 b) {
  frame f = frame_from_z(a);
  vec3 l = frame_to_local(&f, b);
  return atan2(l.y, l.x);
}

static int same_angle(double a, double b, double tol) {
  double d = fmod(fabs(a - b), 2.0 * PI);
  return fmin(d, 2.0 * PI - d) <= tol;
}

static void offsets_run(const scene *sc, mut_perturb_kind kind, uint64_t seed, int n,
                        const char *what) {
  movers mv;
  movers_init(&mv, sc);
  ps_path *x = malloc(sizeof *x), *y = malloc(sizeof *y);
  rng r;
  rng_seed(&r, seed, 1);
  offsets o;
  memset(&o, 0, sizeof o);
  for (int i = 0; i < n; i++) {
    if (!draw_state(&mv, kind, &r, x)) fail();
    mut_perturb_choice ch;
    double ratio;
    int made = mut_perturb_propose(&mv.mp, kind, &r, x, y, &ratio, NULL, &ch);
    int ok = 1, m = mut_perturb_caustic_m(&mv.mp, x);
    if (kind == MUT_PERTURB_CAUSTIC) {
      double s = mut_perturb_caustic_scale(&mv.mp, x, m);
      offsets_add(&o, mv.mp.theta1 * s, mv.mp.theta2 * s, ch.size, ch.phi);
      if (made) {
        vec3 a = ps_dir(x, m, m - 1), b = ps_dir(y, m, m - 1);
        ok = rel_close(angle(a, b), ch.size, 1e-5) && same_angle(azimuth(a, b), ch.phi, 1e-4);
      }
    } else {
      offsets_add(&o, mv.mp.r1, mv.mp.r2, ch.size, ch.phi);
      if (made) {
        double dx = y->rx - x->rx, dy = y->ry - x->ry;
        ok = fabs(hypot(dx, dy) - ch.size) < 1e-6 && same_angle(atan2(dy, dx), ch.phi, 1e-4);
      }
      if (made && kind == MUT_PERTURB_MULTICHAIN) {
        /* Hit points carry single-precision noise: the turn to 2% of
         * the smallest one's. */
        int ends[MUT_PERTURB_MAX_CHAINS];
        mut_perturb_chains(&mv.mp, x, ends);
        vec3 a = ps_dir(x, ends[0], ends[0] + 1), b = ps_dir(y, ends[0], ends[0] + 1);
        ok = ok && fabs(angle(a, b) - ch.turn) < 0.02 * mv.mp.mc_theta1 + 1e-3 * ch.turn;
      }
    }
    o.made += made;
    if (made && !ok) print_message("%s: a proposal that does not realise its choice\n", what);
    o.realised += made && ok;
  }
  offsets_check(&o, what, n);
  free(x), free(y);
}

static void test_offsets(void **state) {
  fixture *fx = *state;
  offsets_run(fx->sc[DIFFUSE], MUT_PERTURB_LENS, 41, 20000, "lens on diffuse");
  offsets_run(fx->sc[DELTA], MUT_PERTURB_LENS, 42, 20000, "lens on delta");
  offsets_run(fx->sc[DELTA], MUT_PERTURB_MULTICHAIN, 43, 10000, "multi-chain on delta");
  offsets_run(fx->sc[DIFFUSE], MUT_PERTURB_CAUSTIC, 44, 20000, "caustic on diffuse");
  offsets_run(fx->sc[CAUSTIC], MUT_PERTURB_CAUSTIC, 45, 20000, "caustic on caustic");
}

/* ---- Reverse moves, caches, detailed balance -------------------------------------- */

/* y back to x by the same perturbation with x's choices. */
static int reverse(const mut_perturb *mp, mut_perturb_kind kind, const ps_path *x,
                   const ps_path *y, ps_path *z) {
  if (kind == MUT_PERTURB_CAUSTIC) {
    int m = mut_perturb_caustic_m(mp, x);
    return mut_perturb_caustic_generate(mp, y, ps_dir(x, m, m - 1), NULL, z, NULL);
  }
  int ends[MUT_PERTURB_MAX_CHAINS];
  int nc = mut_perturb_chains(mp, x, ends);
  vec3 dirs[MUT_PERTURB_MAX_CHAINS];
  for (int j = 0; j + 1 < nc; j++) dirs[j] = ps_dir(x, ends[j], ends[j] + 1);
  return mut_perturb_lens_generate(mp, y, x->rx, x->ry, dirs, NULL, z, NULL);
}

static double g_acc_sum;
static int g_acc_n, g_inner_glossy;

static void check_pairs(const scene *sc, mut_perturb_kind kind, int specular, uint64_t seed,
                        int *OUT_reverse, int *OUT_balance, int *OUT_specular) {
  movers mv;
  movers_init(&mv, sc);
  ps_path *x = malloc(sizeof *x), *y = malloc(sizeof *y), *z = malloc(sizeof *z);
  rng r;
  rng_seed(&r, seed, 3);
  for (int i = 0; i < 3000; i++) {
    if (!draw_state_s(&mv, kind, specular, &r, x)) fail();
    double ratio;
    if (!mut_perturb_propose(&mv.mp, kind, &r, x, y, &ratio, NULL, NULL)) continue;
    assert_true(ps_test_caches_fresh(&mv.ctx, y, z));
    int glossy = 0;
    for (int j = 1; j < x->k; j++) glossy |= mut_perturb_glossy(&mv.mp, x, j);
    *OUT_specular += n_delta(y) > 0 || glossy;
    if (kind == MUT_PERTURB_CAUSTIC)
      for (int j = 2; j < mut_perturb_caustic_m(&mv.mp, x); j++)
        if (mut_perturb_glossy(&mv.mp, x, j)) {
          g_inner_glossy++; /* a G vertex inside the retraced chain */
          break;
        }
    /* The reverse move reproduces x (not through G vertices, which sample
     * their BSDFs). */
    if (!glossy) assert_true(reverse(&mv.mp, kind, x, y, z));
    if (glossy) goto balance;
    for (int j = 0; j <= x->k; j++) {
      double d = v3_len(v3_sub(z->x[j].v.p, x->x[j].v.p));
      if (!(d < 1e-6)) print_message("%s: vertex %d of %d back at %.3g\n", kind_names[kind], j, x->k, d);
      assert_true(d < 1e-6);
    }
    if (y->lum > 0.0) assert_true(rel_close(z->lum, x->lum, 1e-5));
    (*OUT_reverse)++;
  balance:
    /* Detailed balance, T and the reverse ratio from y anew. */
    if (!(y->lum > 0.0)) continue;
    double tf = mut_perturb_density(&mv.mp, kind, x, y), tr = mut_perturb_density(&mv.mp, kind, y, x);
    double ratio_rev = y->lum > 0.0 ? x->lum * tf / (y->lum * tr) : 0.0;
    /* Both sides over f(x) T(x -> y), which keeps them clear of underflow
     * where a G vertex's density is tiny. */
    double lhs = fmin(1.0, ratio), rhs = y->lum * tr / (x->lum * tf) * fmin(1.0, ratio_rev);
    if (!rel_close(lhs, rhs, 1e-9)) print_message("balance %.17g vs %.17g\n", lhs, rhs);
    assert_true(tf > 0.0 && rel_close(lhs, rhs, 1e-9));
    *OUT_balance += lhs > 0.0;
    g_acc_sum += fmin(1.0, ratio);
    g_acc_n++;
  }
  free(x), free(y), free(z);
}

static void test_reverse_and_balance(void **state) {
  fixture *fx = *state;
  static const struct {
    int scene;
    mut_perturb_kind kind;
    int min_specular;
  } cases[] = {{DIFFUSE, MUT_PERTURB_LENS, 0},      {DELTA, MUT_PERTURB_LENS, 300},
               {GLOSSY, MUT_PERTURB_LENS, 1000},
               {DELTA, MUT_PERTURB_MULTICHAIN, 1000}, {DIFFUSE, MUT_PERTURB_CAUSTIC, 0},
               {CAUSTIC, MUT_PERTURB_CAUSTIC, 1000}, {GLOSSY, MUT_PERTURB_CAUSTIC, 1000}};
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    int rev = 0, bal = 0, spec = 0;
    check_pairs(fx->sc[cases[c].scene], cases[c].kind, cases[c].min_specular > 0, 51 + c, &rev,
                &bal, &spec);
    print_message("%s on %s: %d reversed, %d balanced, %d through delta or G vertices (%d "
                  "retracing a G vertex); mean acceptance %.3f\n",
                  kind_names[cases[c].kind], scene_names[cases[c].scene], rev, bal, spec,
                  g_inner_glossy, g_acc_sum / g_acc_n);
    if (cases[c].scene == GLOSSY && cases[c].kind == MUT_PERTURB_CAUSTIC)
      assert_true(g_inner_glossy >= 500);
    g_acc_sum = 0.0, g_acc_n = 0, g_inner_glossy = 0;
    assert_true((cases[c].scene == GLOSSY || rev >= 1500) && bal >= 1000 &&
                spec >= cases[c].min_specular);
  }
}

/* ---- One-step invariance (test_pathspace.c states the test) ------------------------ */

#define INV_COLS 8
#define INV_ROWS 12
#define INV_BINS (KMAX * INV_COLS * INV_ROWS)
_Static_assert(INV_BINS <= PS_INV_MAX_BINS, "the bins fit ps_inv");

/* (length) x (a raster cell of 4 x 2 pixels): the perturbations move
 * paths by a few pixels. */
static int inv_bin(const scene *sc, const ps_path *x) {
  return ps_inv_raster_bin(sc, x, INV_COLS, INV_ROWS);
}

/* A start for the invariance tests: a whole path of length k_only (0: a
 * length uniform in 1 .. KMAX) from the bidirectional sampler, with its
 * weight C(x) / q(x) in *OUT_w (q the sampler's density, the length's
 * probability included); 0 when none was drawn. */
static int draw_start(const movers *mv, rng *r, int k_only, ps_path *x, double *OUT_w) {
  int k = k_only ? k_only : 1 + (int)(rng_uniform(r) * KMAX);
  if (mut_bidir_sample_whole(&mv->mb, r, k, x) != MUT_BIDIR_OK || !(x->lum > 0.0)) return 0;
  double q = mut_bidir_whole_pdf(&mv->mb, x, 0) / (k_only ? 1 : KMAX);
  assert_true(q > 0.0);
  *OUT_w = x->lum / q;
  return 1;
}

static ps_inv *invariance(const scene *sc, mut_perturb_kind kind, int k_only, uint64_t seed,
                             double power, int n) {
  movers mv;
  movers_init(&mv, sc);
  mv.mp.test_jac_power = power;
  /* Larger moves than the defaults: more power against a wrong density
   * (the kernel is exact at any size). */
  double scale = 4.0;
  mv.mp.r1 *= scale, mv.mp.r2 *= scale, mv.mp.theta1 *= scale, mv.mp.theta2 *= scale;
  mv.mp.mc_theta1 *= scale, mv.mp.mc_theta2 *= scale;
  ps_path *x = malloc(sizeof *x), *y = malloc(sizeof *y);
  ps_inv *res = calloc(1, sizeof *res);
  rng r;
  rng_seed(&r, seed, 5);
  for (int i = 0; i < n; i++) {
    double w, ratio = 0.0;
    if (!draw_start(&mv, &r, k_only, x, &w)) continue;
    res->samples++;
    int moved = mut_perturb_applies(&mv.mp, kind, x) &&
                mut_perturb_propose(&mv.mp, kind, &r, x, y, &ratio, NULL, NULL) &&
                rng_uniform(&r) < ratio;
    int b0 = inv_bin(sc, x), b1 = moved ? inv_bin(sc, y) : b0;
    ps_inv_add(res, w, b0, b1);
  }
  ps_inv_finish(res);
  free(x), free(y);
  return res;
}

/* The multi-chain perturbation's paths, E D S D L, are all of length 4
 * (KMAX): only those are drawn (pi restricted to a set that the kernel
 * never leaves is invariant under it too). The negative control runs on
 * the scenes with curved specular surfaces, where the Jacobians change
 * fastest (`control`). */
static const struct {
  int scene;
  mut_perturb_kind kind;
  int k_only, n, control;
} inv_cases[] = {{DIFFUSE, MUT_PERTURB_LENS, 0, 1000000, 0},
                 {DELTA, MUT_PERTURB_LENS, 0, 1000000, 1},
                 {DELTA, MUT_PERTURB_MULTICHAIN, KMAX, 4000000, 0},
                 {DIFFUSE, MUT_PERTURB_CAUSTIC, 0, 1000000, 0},
                 {CAUSTIC, MUT_PERTURB_CAUSTIC, 0, 2000000, 1},
                 {GLOSSY, MUT_PERTURB_LENS, 0, 1000000, 1},
                 {GLOSSY, MUT_PERTURB_CAUSTIC, 0, 1000000, 1}};

static void test_invariance(void **state) {
  fixture *fx = *state;
  for (size_t c = 0; c < sizeof inv_cases / sizeof inv_cases[0]; c++) {
    ps_inv *r = invariance(fx->sc[inv_cases[c].scene], inv_cases[c].kind,
                              inv_cases[c].k_only, 61 + c, 1.0, inv_cases[c].n);
    print_message("%s on %s: %d samples, %d moved, %d bins, min p %.3g (level %.3g)\n",
                  kind_names[inv_cases[c].kind], scene_names[inv_cases[c].scene], r->samples,
                  r->moved, r->bins, r->min_p, r->level);
    assert_true(r->samples >= 20000 && r->moved >= inv_cases[c].n / 8000 && r->bins >= 20);
    assert_true(r->min_p >= r->level);
    free(r);
  }
}

static void test_invariance_detects_bias(void **state) {
  fixture *fx = *state;
  int controls = 0;
  for (size_t c = 0; c < sizeof inv_cases / sizeof inv_cases[0]; c++) {
    if (!inv_cases[c].control) continue;
    controls++;
    ps_inv *r = invariance(fx->sc[inv_cases[c].scene], inv_cases[c].kind,
                              inv_cases[c].k_only, 61 + c, 0.0, inv_cases[c].n);
    print_message("%s on %s, Jacobians left out: %d samples, %d moved, %d bins, min p %.3g (level "
                  "%.3g)\n",
                  kind_names[inv_cases[c].kind], scene_names[inv_cases[c].scene], r->samples,
                  r->moved, r->bins, r->min_p, r->level);
    assert_true(r->samples >= 20000 && r->moved >= 5000 && r->bins >= 20);
    assert_true(r->min_p < r->level);
    free(r);
  }
  assert_int_equal(controls, 4);
}

/* ---- The lens subpath mutation ------------------------------------------------ */

/* A path with f > 0 that the lens subpath mutation applies to. */
static int draw_lenssub(const movers *mv, rng *r, ps_path *x) {
  for (int tries = 0; tries < 2000000; tries++) {
    int k = 1 + (int)(rng_uniform(r) * KMAX);
    if (mut_bidir_sample_whole(&mv->mb, r, k, x) != MUT_BIDIR_OK || !(x->lum > 0.0)) continue;
    if (mut_lenssub_m(&mv->ctx, x) > 0) return 1;
  }
  return 0;
}

/* Caches, T both ways from y's and x's caches against fresh evaluations,
 * and detailed balance, on proposals; the length changes counted. */
static const int lenssub_scenes[3] = {DIFFUSE, DELTA, GLOSSY};

static void test_lenssub_balance(void **state) {
  fixture *fx = *state;
  for (int c = 0; c < 3; c++) {
    int q = lenssub_scenes[c];
    movers mv;
    movers_init(&mv, fx->sc[q]);
    ps_path *x = malloc(sizeof *x), *y = malloc(sizeof *y), *z = malloc(sizeof *z);
    rng r;
    rng_seed(&r, 71 + q, 3);
    int made = 0, balanced = 0, longer = 0, shorter = 0, specular = 0;
    for (int i = 0; i < 4000; i++) {
      if (!draw_lenssub(&mv, &r, x)) fail();
      double ratio;
      if (!mut_lenssub_propose(&mv.ml, &r, x, y, &ratio, NULL)) continue;
      made++;
      assert_true(ps_test_caches_fresh(&mv.ctx, y, z));
      assert_int_equal(y->k - x->k, mut_lenssub_m(&mv.ctx, y) - mut_lenssub_m(&mv.ctx, x));
      longer += y->k > x->k, shorter += y->k < x->k, specular += mut_lenssub_m(&mv.ctx, y) > 1;
      if (!(y->lum > 0.0)) continue;
      double tf = mut_lenssub_density(&mv.ml, y), tr = mut_lenssub_density(&mv.ml, x);
      double ratio_rev = x->lum * tf / (y->lum * tr);
      double lhs = x->lum * tf * fmin(1.0, ratio), rhs = y->lum * tr * fmin(1.0, ratio_rev);
      assert_true(tf > 0.0 && tr > 0.0 && rel_close(lhs, rhs, 1e-9));
      balanced++;
    }
    print_message("lens subpath on %s: %d proposals, %d balanced, %d longer, %d shorter, %d "
                  "through delta lobes or G vertices\n",
                  scene_names[q], made, balanced, longer, shorter, specular);
    assert_true(made >= 1500 && balanced >= 500 && specular >= 100);
    if (q != DIFFUSE) assert_true(longer >= 50 && shorter >= 50);
    free(x), free(y), free(z);
  }
}

/* One-step invariance (test_pathspace.c's statistic), and its negative
 * control: P_smooth left out of T (power 0), on the plastic sphere. */
static ps_inv *lenssub_invariance(const scene *sc, uint64_t seed, double power, int n) {
  movers mv;
  movers_init(&mv, sc);
  mv.ml.test_smooth_power = power;
  ps_path *x = malloc(sizeof *x), *y = malloc(sizeof *y);
  ps_inv *res = calloc(1, sizeof *res);
  rng r;
  rng_seed(&r, seed, 5);
  for (int i = 0; i < n; i++) {
    double w, ratio = 0.0;
    if (!draw_start(&mv, &r, 0, x, &w)) continue;
    res->samples++;
    int moved = mut_lenssub_m(&mv.ctx, x) > 0 && mut_lenssub_propose(&mv.ml, &r, x, y, &ratio, NULL) &&
                rng_uniform(&r) < ratio;
    ps_inv_add(res, w, inv_bin(sc, x), moved ? inv_bin(sc, y) : inv_bin(sc, x));
  }
  ps_inv_finish(res);
  free(x), free(y);
  return res;
}

static void test_lenssub_invariance(void **state) {
  fixture *fx = *state;
  for (int c = 0; c < 3; c++) {
    int q = lenssub_scenes[c];
    for (int control = 0; control < 2; control++) {
      if (control && q != DIFFUSE) continue;
      ps_inv *r = lenssub_invariance(fx->sc[q], 81 + q, control ? 0.0 : 1.0, 1000000);
      print_message("lens subpath on %s%s: %d samples, %d moved, %d bins, min p %.3g (level "
                    "%.3g)\n",
                    scene_names[q], control ? ", P_smooth left out" : "", r->samples, r->moved,
                    r->bins, r->min_p, r->level);
      assert_true(r->samples >= 20000 && r->moved >= 2000 && r->bins >= 20);
      if (control)
        assert_true(r->min_p < r->level);
      else
        assert_true(r->min_p >= r->level);
      free(r);
    }
  }
}

/* ---- The primary-sample step (mut_pss.h) --------------------------------------- */

/* One-step invariance of the primary-sample step on a scene's paths of
 * lengths 1 .. KMAX, its ratio raised to `power` (1: its own; 0: every
 * proposal accepted, which must fail); *OUT_proposed counts the proposals. */
static ps_inv *pss_invariance(const scene *sc, uint64_t seed, double power, int n,
                              int *OUT_proposed, mut_pss_tally *OUT_tally) {
  movers mv;
  movers_init(&mv, sc);
  mut_pss mq;
  mut_pss_init(&mq, &mv.ctx, 1.0);
  mq.test_power = power;
  /* Larger steps than the default: more power against a wrong ratio (the
   * kernel is exact at any size). */
  mq.s1 *= 8.0, mq.s2 *= 8.0;
  bdpt_vertex *scratch = malloc(MUT_PSS_SCRATCH * sizeof *scratch);
  ps_path *x = malloc(sizeof *x), *y = malloc(sizeof *y);
  ps_inv *res = calloc(1, sizeof *res);
  rng r;
  rng_seed(&r, seed, 7);
  *OUT_proposed = 0;
  *OUT_tally = (mut_pss_tally){0, 0, 0};
  for (int i = 0; i < n; i++) {
    double w, ratio = 0.0;
    if (!draw_start(&mv, &r, 0, x, &w)) continue;
    res->samples++;
    int prop = mut_pss_propose(&mq, &r, x, y, &ratio, scratch, NULL, OUT_tally);
    *OUT_proposed += prop;
    int moved = prop && rng_uniform(&r) < ratio;
    int b0 = inv_bin(sc, x), b1 = moved ? inv_bin(sc, y) : b0;
    ps_inv_add(res, w, b0, b1);
  }
  ps_inv_finish(res);
  free(x), free(y), free(scratch);
  return res;
}

/* The step's invariance on scene sc (n paths), its tally checked: every
 * sample is proposed from, refused or walked elsewhere, and a round trip
 * fails at most once in a thousand. */
static void check_pss(const scene *sc, const char *name, uint64_t seed, int n) {
  int proposed;
  mut_pss_tally ty;
  ps_inv *r = pss_invariance(sc, seed, 1.0, n, &proposed, &ty);
  print_message("pss step on %s: %d samples, %d proposed, %d moved, %d bins, min p %.3g (level "
                "%.3g); %lld subpaths inverted, %lld refused, %lld walked elsewhere\n",
                name, r->samples, proposed, r->moved, r->bins, r->min_p, r->level,
                (long long)ty.inverted, (long long)ty.refused, (long long)ty.elsewhere);
  /* (Paths of one segment to a point light have no strategy: none.) */
  assert_true(r->samples >= 20000 && r->moved >= 5000 && r->bins >= 20);
  assert_true(proposed >= r->samples / 8);
  assert_int_equal(proposed + ty.refused + ty.elsewhere, r->samples);
  assert_true(ty.inverted >= proposed && 1000 * ty.elsewhere <= r->samples);
  assert_true(r->min_p >= r->level);
  free(r);
}

static void test_pss_invariance(void **state) {
  fixture *fx = *state;
  int checked = 0;
  for (int c = 0; c < N_SCENES; c++, checked++)
    check_pss(fx->sc[c], scene_names[c], 71 + (uint64_t)c, 400000);
  /* Paths that end in the sky: their numbers walk back to them (the end's
   * direction, not its far point, is the path's). */
  scene *sky = try_load_scene_text(sky_xml, "ps_sky");
  assert_non_null(sky);
  check_pss(sky, "sky", 83, 200000);
  scene_destroy(sky);
  checked++;
  /* Every proposal accepted: the walk in the numbers is then uniform in
   * them, not the target, and the test must see it. */
  int proposed;
  mut_pss_tally ty;
  ps_inv *r = pss_invariance(fx->sc[DIFFUSE], 79, 0.0, 400000, &proposed, &ty);
  print_message("pss step on diffuse, every proposal accepted: %d moved, min p %.3g (level "
                "%.3g)\n",
                r->moved, r->min_p, r->level);
  assert_true(r->moved >= 5000);
  assert_true(r->min_p < r->level);
  free(r);
  assert_int_equal(checked, N_SCENES + 1);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_log_sample),
      cmocka_unit_test(test_offsets),
      cmocka_unit_test(test_reverse_and_balance),
      cmocka_unit_test(test_invariance),
      cmocka_unit_test(test_invariance_detects_bias),
      cmocka_unit_test(test_lenssub_balance),
      cmocka_unit_test(test_lenssub_invariance),
      cmocka_unit_test(test_pss_invariance),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
