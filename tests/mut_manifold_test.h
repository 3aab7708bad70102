/*
 * mut_manifold_test.h: what the tests of the manifold perturbation
 * (test_mut_manifold.c, test_mut_manifold_slow.c) share: their seven
 * scenes, the moves of a path space, and the one-step invariance test of
 * test_pathspace.c with the move as a kernel of its own. Include after
 * <cmocka.h>.
 */
#ifndef LMC_TESTS_MUT_MANIFOLD_TEST_H
#define LMC_TESTS_MUT_MANIFOLD_TEST_H

#include <stdio.h>
#include <stdlib.h>

#include "lmc/path/mut_bidir.h"
#include "lmc/path/mut_manifold.h"
#include "pathspace_test.h"

#define KMAX 5

/* The scenes: a floor and a sphere of glass, smooth or rough, optionally a
 * mirror wall behind, smooth or rough, and a light. */
static const char *scene_head =
    "<scene version=\"0.6.0\">\n"
    "  <sensor type=\"perspective\">\n"
    "    <float name=\"fov\" value=\"40\"/>\n"
    "    <transform name=\"toWorld\"><lookat origin=\"0, 3, 3\" target=\"0, 0, 0\" "
    "up=\"0, 1, 0\"/></transform>\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer "
    "name=\"height\" value=\"24\"/><rfilter type=\"box\"/></film>\n"
    "  </sensor>\n"
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/>"
    "<scale x=\"2\" y=\"1\" z=\"2\"/></transform>"
    "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.7\"/></bsdf></shape>\n";

static const char *sphere_smooth =
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"0.8\" z=\"0\"/><float "
    "name=\"radius\" value=\"0.5\"/>"
    "<bsdf type=\"dielectric\"><float name=\"intIOR\" value=\"1.5\"/></bsdf></shape>\n";
static const char *sphere_rough =
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"0.8\" z=\"0\"/><float "
    "name=\"radius\" value=\"0.5\"/>"
    "<bsdf type=\"roughdielectric\"><float name=\"intIOR\" value=\"1.5\"/>"
    "<float name=\"alpha\" value=\"0.05\"/></bsdf></shape>\n";

#define MIRROR_SHAPE                                                                             \
  "  <shape type=\"rectangle\"><transform name=\"toWorld\"><scale x=\"2\" y=\"1.5\" z=\"1\"/>" \
  "<rotate x=\"1\" angle=\"25\"/><translate x=\"0\" y=\"1\" z=\"-1.5\"/></transform>"
static const char *mirror_smooth = MIRROR_SHAPE "<bsdf type=\"conductor\"/></shape>\n";
static const char *mirror_rough =
    MIRROR_SHAPE "<bsdf type=\"roughconductor\"><float name=\"alpha\" value=\"0.05\"/></bsdf>"
                 "</shape>\n";

static const char *light_point =
    "  <emitter type=\"point\"><point name=\"position\" x=\"0.2\" y=\"2\" z=\"0\"/>"
    "<rgb name=\"intensity\" value=\"8, 8, 7\"/></emitter>\n";
static const char *light_area =
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"90\"/>"
    "<scale value=\"0.2\"/><translate x=\"0.2\" y=\"2\"/></transform>"
    "<emitter type=\"area\"><rgb name=\"radiance\" value=\"40\"/></emitter></shape>\n";
static const char *light_sky =
    "  <emitter type=\"constant\"><rgb name=\"radiance\" value=\"1, 1, 1\"/></emitter>\n";

/* S chains (smooth glass and mirror) and G chains (rough: ps_glossy). */
enum { POINT = 0, AREA, SKY, MIRROR, R_POINT, R_SKY, R_MIRROR, N_SCENES };
static const char *const scene_names[N_SCENES] = {"point",       "area",     "sky",     "mirror",
                                                  "rough point", "rough sky", "rough mirror"};

typedef struct fixture {
  scene *sc[N_SCENES];
} fixture;

static inline int mm_setup(void **state) {
  static const struct {
    int rough, mirror;
    const char **light;
  } parts[N_SCENES] = {{0, 0, &light_point}, {0, 0, &light_area}, {0, 0, &light_sky},
                       {0, 1, &light_point}, {1, 0, &light_point}, {1, 0, &light_sky},
                       {1, 1, &light_point}};
  fixture *fx = calloc(1, sizeof *fx);
  for (int q = 0; q < N_SCENES; q++) {
    char xml[4096], tag[32];
    snprintf(xml, sizeof xml, "%s%s%s%s</scene>\n", scene_head,
             parts[q].rough ? sphere_rough : sphere_smooth,
             parts[q].mirror ? (parts[q].rough ? mirror_rough : mirror_smooth) : "",
             *parts[q].light);
    snprintf(tag, sizeof tag, "mm_%d", q);
    fx->sc[q] = try_load_scene_text(xml, tag);
    if (!fx->sc[q]) return -1;
  }
  *state = fx;
  return 0;
}

static inline int mm_teardown(void **state) {
  fixture *fx = *state;
  for (int q = 0; q < N_SCENES; q++) scene_destroy(fx->sc[q]);
  free(fx);
  return 0;
}

/* ---- The seven and three more (ext_setup) -------------------------------------- */

/* `wall`: a diffuse wall behind the rough sphere under the small area light
 * (E D D L: a diffuse vertex in HSLT's chains); `lit mirror` and `lit
 * rough mirror`: a mirror, smooth or rough, lying on the floor, in which
 * the camera sees a large area light above and behind it (E S L, E G L:
 * the manifold perturbation's sky form reaching an area light; the light
 * fills a third of the image). */
#define WALL N_SCENES
#define LIT_MIRROR (N_SCENES + 1)
#define LIT_R_MIRROR (N_SCENES + 2)
#define N_ALL (N_SCENES + 3)

static const char *wall_shape =
    MIRROR_SHAPE "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.6\"/></bsdf>"
                 "</shape>\n";
#define FLOOR_MIRROR                                                                      \
  "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/>" \
  "<translate x=\"0\" y=\"0.01\" z=\"0.6\"/></transform>"
static const char *floor_mirror[2] = {
    FLOOR_MIRROR "<bsdf type=\"conductor\"/></shape>\n",
    FLOOR_MIRROR "<bsdf type=\"roughconductor\"><float name=\"alpha\" value=\"0.05\"/></bsdf>"
                 "</shape>\n"};
static const char *light_above =
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"90\"/>"
    "<translate x=\"0\" y=\"2\" z=\"-1\"/></transform>"
    "<emitter type=\"area\"><rgb name=\"radiance\" value=\"10\"/></emitter></shape>\n";

typedef struct hfixture {
  fixture *mm;
  scene *sc[N_ALL];
} hfixture;

static inline int ext_setup(void **state) {
  void *mm;
  if (mm_setup(&mm) != 0) return -1;
  hfixture *fx = calloc(1, sizeof *fx);
  fx->mm = mm;
  for (int q = 0; q < N_SCENES; q++) fx->sc[q] = fx->mm->sc[q];
  static const char *const tags[3] = {"ext_wall", "ext_lit_mirror", "ext_lit_rough_mirror"};
  for (int e = 0; e < 3; e++) {
    char xml[4096];
    if (e == 0)
      snprintf(xml, sizeof xml, "%s%s%s%s</scene>\n", scene_head, sphere_rough, wall_shape,
               light_area);
    else
      snprintf(xml, sizeof xml, "%s%s%s</scene>\n", scene_head, floor_mirror[e - 1],
               light_above);
    fx->sc[N_SCENES + e] = try_load_scene_text(xml, tags[e]);
    if (!fx->sc[N_SCENES + e]) return -1;
  }
  *state = fx;
  return 0;
}

static inline int ext_teardown(void **state) {
  hfixture *fx = *state;
  for (int q = N_SCENES; q < N_ALL; q++) scene_destroy(fx->sc[q]);
  void *mm = fx->mm;
  mm_teardown(&mm);
  free(fx);
  return 0;
}

static inline const char *name_of(int q) {
  static const char *const ext[3] = {"wall", "lit mirror", "lit rough mirror"};
  return q >= N_SCENES ? ext[q - N_SCENES] : scene_names[q];
}

typedef struct movers {
  ps_context ctx;
  mut_bidir mb;
  mut_perturb mp;
  mut_manifold mm;
  mut_manifold mh; /* HSLT's half-vector perturbation, step 1 */
} movers;

static inline void movers_init(movers *mv, const scene *sc) {
  ps_test_context(sc, KMAX, &mv->ctx);
  mut_bidir_init(&mv->mb, &mv->ctx);
  mut_perturb_init(&mv->mp, &mv->ctx);
  mut_manifold_init(&mv->mm, &mv->ctx, &mv->mp);
  mut_manifold_init_hslt(&mv->mh, &mv->ctx, &mv->mp, 1.0);
}

/* A path with f > 0 that move m applies to, or 0 after many tries. */
static inline int draw_state_for(const movers *mv, const mut_manifold *m, rng *r, ps_path *x) {
  for (int tries = 0; tries < 2000000; tries++) {
    int k = 1 + (int)(rng_uniform(r) * KMAX);
    if (mut_bidir_sample_whole(&mv->mb, r, k, x) != MUT_BIDIR_OK || !(x->lum > 0.0)) continue;
    if (mut_manifold_applies(m, x)) return 1;
  }
  return 0;
}

static inline int draw_state(const movers *mv, rng *r, ps_path *x) {
  return draw_state_for(mv, &mv->mm, r, x);
}

/* A chain vertex: S (delta) or G. */
static inline int specular(const movers *mv, const ps_path *x, int j) {
  return x->x[j].delta || ps_glossy(&mv->ctx, x, j);
}

/* mf_path_chain_fits says what mf_chain_from_path would, on every range of
 * x under the chain flags 0 .. n_flags - 1; adds the ranges checked and
 * those that make a chain to *checked and *ok. */
static inline void check_chain_fits(const movers *mv, const ps_path *x, unsigned n_flags,
                                    int *checked, int *ok) {
  for (int a0 = 0; a0 < x->k; a0++)
    for (int b0 = a0 + 2; b0 <= x->k; b0++)
      for (unsigned fl = 0; fl < n_flags; fl++) {
        mf_chain ch;
        int full = mf_chain_from_path(&mv->ctx, x, a0, b0, fl, &ch);
        int fits = mf_path_chain_fits(&mv->ctx, x, a0, b0, fl);
        if (full == MF_OK) assert_int_equal(fits, MF_OK);
        if (fits != MF_OK) assert_int_equal(full, fits);
        (*checked)++, *ok += full == MF_OK;
      }
}

/* ---- Reverse moves, caches, detailed balance (both tests) ---------------------- */

/* Whether x has a G vertex before its x_c (the manifold perturbation's form). */
static inline int glossy_chain(const movers *mv, const ps_path *x) {
  int b, c, n = 0;
  if (!mut_manifold_form(&mv->mm, x, &b, &c)) return 0;
  for (int j = 1; j < c; j++) n += ps_glossy(&mv->ctx, x, j);
  return n > 0;
}

/* On n random pairs (x drawn whole by draw, NULL: draw_state_for; y
 * proposed by the manifold perturbation or, when hslt is set, by HSLT's): every cache of y against a fresh
 * evaluation; the move from y through x's raster point (and x's half
 * vectors) gives back x, vertices to 1e-6 of the scene's size (the
 * manifold perturbation: f to 1e-5, 1e-3 through G vertices, whose narrow
 * lobes feel the walk's tolerance); the reverse walk returns; detailed
 * balance to 1e-9, the reverse ratio computed anew from y. Counts the
 * pairs reversed and balanced, and the mean acceptance. */
typedef int (*draw_fn)(const movers *mv, const mut_manifold *m, rng *r, ps_path *x);

static inline void check_pairs(const scene *sc, int hslt, draw_fn draw, uint64_t seed, int n,
                               int *OUT_reverse, int *OUT_balance, double *OUT_acc) {
  movers mv;
  movers_init(&mv, sc);
  const mut_manifold *m = hslt ? &mv.mh : &mv.mm;
  ps_path *x = malloc(sizeof *x), *y = malloc(sizeof *y), *z = malloc(sizeof *z);
  rng r;
  rng_seed(&r, seed, 3);
  double acc = 0.0;
  int n_acc = 0;
  mut_manifold_tally t = {0, 0, 0, 0};
  for (int i = 0; i < n; i++) {
    if (!(draw ? draw : draw_state_for)(&mv, m, &r, x)) fail();
    double ratio;
    if (!mut_manifold_propose(m, &r, x, y, &ratio, NULL, &t)) continue;
    assert_true(ps_test_caches_fresh(&mv.ctx, y, z));
    if (!(y->lum > 0.0) || !(ratio > 0.0)) continue;
    double hx[2 * PS_MAX_VERTICES];
    if (hslt) assert_true(mut_manifold_half_vectors(m, x, hx));
    assert_true(mut_manifold_generate(m, y, x->rx, x->ry, hslt ? hx : NULL, z, NULL, NULL));
    for (int j = 0; j <= x->k; j++) {
      /* (A direction at infinity: its point stands beyond the scene.) */
      double d = x->x[j].inf ? sc->radius * v3_len(v3_sub(z->x[j].v.dir, x->x[j].v.dir))
                             : v3_len(v3_sub(z->x[j].v.p, x->x[j].v.p));
      if (!(d < 1e-6 * sc->radius)) print_message("vertex %d of %d back at %.3g\n", j, x->k, d);
      assert_true(d < 1e-6 * sc->radius);
    }
    if (!hslt) assert_true(rel_close(z->lum, x->lum, glossy_chain(&mv, x) ? 1e-3 : 1e-5));
    assert_true(mut_manifold_reversible(m, y, x, NULL, NULL));
    (*OUT_reverse)++;
    double tf = mut_manifold_density(m, x, y), tr = mut_manifold_density(m, y, x);
    assert_true(tf > 0.0 && tr > 0.0);
    double ratio_rev = x->lum * tf / (y->lum * tr);
    double lhs = fmin(1.0, ratio), rhs = y->lum * tr / (x->lum * tf) * fmin(1.0, ratio_rev);
    if (!rel_close(lhs, rhs, 1e-9)) print_message("balance %.17g vs %.17g\n", lhs, rhs);
    assert_true(rel_close(lhs, rhs, 1e-9));
    (*OUT_balance)++;
    acc += fmin(1.0, ratio);
    n_acc++;
  }
  *OUT_acc = n_acc > 0 ? acc / n_acc : 0.0;
  print_message("  walks %lld, reached %lld, %.2f projections each, %lld refused as irreversible\n",
                (long long)t.walks, (long long)t.walked,
                t.walks > 0 ? (double)t.traces / (double)t.walks : 0.0, (long long)t.irreversible);
  /* (A draw of the sky form alone makes no walk.) */
  if (!draw) assert_true(t.walks > 0 && t.walked >= t.walks / (hslt ? 4 : 2));
  free(x), free(y), free(z);
}

/* ---- One-step invariance (test_pathspace.c states the test) ------------------------ */

#define INV_COLS 8
#define INV_ROWS 12
#define INV_BINS (KMAX * INV_COLS * INV_ROWS)
_Static_assert(INV_BINS <= PS_INV_MAX_BINS, "the bins fit ps_inv");

static inline int inv_bin(const scene *sc, const ps_path *x) {
  return ps_inv_raster_bin(sc, x, INV_COLS, INV_ROWS);
}

/* Weighted whole paths of length k_only (their weight C(x) / q(x), q the
 * sampler's density), each moved once by the manifold perturbation, or by
 * HSLT's when hslt is set. */
static inline ps_inv *invariance_of(const scene *sc, int hslt, int k_only, uint64_t seed,
                                    double power, double glossy_power, int n) {
  movers mv;
  movers_init(&mv, sc);
  mut_manifold *m = hslt ? &mv.mh : &mv.mm;
  m->test_jac_power = power;
  m->test_glossy_power = glossy_power;
  /* Larger moves than the defaults: more power against a wrong density. */
  mv.mp.r1 *= 4.0, mv.mp.r2 *= 4.0;
  ps_path *x = malloc(sizeof *x), *y = malloc(sizeof *y);
  ps_inv *res = calloc(1, sizeof *res);
  rng r;
  rng_seed(&r, seed, 5);
  for (int i = 0; i < n; i++) {
    if (mut_bidir_sample_whole(&mv.mb, &r, k_only, x) != MUT_BIDIR_OK || !(x->lum > 0.0)) continue;
    double q = mut_bidir_whole_pdf(&mv.mb, x, 0);
    assert_true(q > 0.0);
    double w = x->lum / q, ratio = 0.0;
    res->samples++;
    int moved = mut_manifold_applies(m, x) && mut_manifold_propose(m, &r, x, y, &ratio, NULL, NULL) &&
                rng_uniform(&r) < ratio;
    int b0 = inv_bin(sc, x), b1 = moved ? inv_bin(sc, y) : b0;
    ps_inv_add(res, w, b0, b1);
  }
  ps_inv_finish(res);
  free(x), free(y);
  return res;
}

static inline ps_inv *invariance(const scene *sc, int k_only, uint64_t seed, double power,
                                 double glossy_power, int n) {
  return invariance_of(sc, 0, k_only, seed, power, glossy_power, n);
}

#endif
