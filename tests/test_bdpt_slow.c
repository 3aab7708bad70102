/*
 * test_bdpt_slow.c: bidirectional path tracing against path tracing, and
 * the bookkeeping of BDPT's MIS weights.
 *
 * Agreement. Four small scenes are built in code and rendered at 32x24
 * with "pt" and with "bdpt", each with NSEEDS independent seeds:
 *   1 a diffuse box lit by an area light, with a smooth plastic sphere
 *     (delta lobes, smooth shading normals), unbounded depth (Russian roulette);
 *   2 a rough conductor sphere on a diffuse floor under a point light, maxdepth 4;
 *   3 a rough glass sphere (alpha 0.3) under an area light, with a constant
 *     and an environment-map light (two infinite lights), maxdepth 8;
 *   4 a spot light and a directional light on diffuse and glossy (phong)
 *     surfaces, maxdepth 5, mindepth 2.
 * The image mean and the means of a 4x3 grid of regions are compared.
 * The variance of each mean is estimated from the spread over the seeds
 * (sample variance / NSEEDS, per integrator), and the difference must stay
 * below 4.5 combined standard deviations. 13 comparisons per scene, 52 in
 * all: with normal errors P(|z| > 4.5) = 6.8e-6 per comparison, so even a
 * Bonferroni bound over all 52 (3.5e-4) is far from a false alarm; with
 * NSEEDS = 8 the estimated sigma has ~14 degrees of freedom, for which the
 * t tail at 4.5 is ~5e-4 per comparison, 2.6 % for the family, still
 * acceptable with fixed seeds (the outcome is deterministic).
 *
 * MIS bookkeeping. For random paths of scene 1 and scene 3, every strategy
 * (s, t) that BDPT evaluates with a nonzero contribution is re-split at
 * every other s' of the same full path; the densities are recomputed from
 * the geometry (bdpt_path_pdfs), and the weights bdpt_mis_weight gives to
 * the strategies that can produce the path must sum to one. The densities
 * the random walks stored must also equal the recomputed ones.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "render/integrators/integrator.h"
#include "render/io/io.h"
#include "render/scene.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define W 32
#define H 24
#define NSEEDS 8
#define GX 4
#define GY 3

/* ---- scene building ------------------------------------------------------- */

static int add_bsdf(scene *sc, const char *type, rgb refl) {
  bsdf b;
  bsdf_init_defaults(&b, type);
  b.diffuse = tex_constant(refl);
  int i = scene_add_bsdf(sc, &b, NULL);
  assert_true(i >= 0);
  return i;
}

static int add_bsdf_full(scene *sc, const bsdf *b) {
  int i = scene_add_bsdf(sc, b, NULL);
  assert_true(i >= 0);
  return i;
}

/* Quad a, b, c, d (a planar loop) whose geometric normal points to the
 * side of `side` (the winding is reversed when needed). */
static int add_quad(scene *sc, vec3 a, vec3 b, vec3 c, vec3 d, vec3 side, int bsdf_index,
                    int light_index) {
  if (v3_dot(v3_cross(v3_sub(b, a), v3_sub(c, a)), side) < 0.0) {
    vec3 tmp = b;
    b = d;
    d = tmp;
  }
  mesh m;
  memset(&m, 0, sizeof m);
  assert_int_equal(mesh_alloc(&m, 4, 2, 0, 0, NULL), LMC_OK);
  vec3 v[4] = {a, b, c, d};
  for (int i = 0; i < 4; i++) {
    m.p[3 * i] = (float)v[i].x;
    m.p[3 * i + 1] = (float)v[i].y;
    m.p[3 * i + 2] = (float)v[i].z;
  }
  uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
  memcpy(m.idx, idx, sizeof idx);
  m.bsdf = bsdf_index;
  m.light = light_index;
  snprintf(m.name, sizeof m.name, "quad");
  int k = scene_add_mesh(sc, &m, NULL);
  assert_true(k >= 0);
  return k;
}

static int add_sphere(scene *sc, vec3 c, double r, int bsdf_index) {
  mesh m;
  memset(&m, 0, sizeof m);
  assert_int_equal(shape_sphere(c, r, &m, NULL), LMC_OK);
  m.bsdf = bsdf_index;
  m.light = -1;
  int k = scene_add_mesh(sc, &m, NULL);
  assert_true(k >= 0);
  return k;
}

/* An area light on a quad facing down (normal -y) at height y. */
static void add_area_light_quad(scene *sc, double x0, double x1, double z0, double z1, double y,
                                rgb radiance) {
  light l;
  memset(&l, 0, sizeof l);
  l.type = LIGHT_AREA;
  l.value = radiance;
  l.mesh = sc->n_meshes;
  int li = scene_add_light(sc, &l, NULL);
  assert_true(li >= 0);
  int black = add_bsdf(sc, "diffuse", rgb_gray(0.0));
  add_quad(sc, v3(x0, y, z0), v3(x0, y, z1), v3(x1, y, z1), v3(x1, y, z0), v3(0, -1, 0), black, li);
}

static void set_camera(scene *sc, vec3 origin, vec3 target, double fov) {
  assert_true(xform_lookat(origin, target, v3(0, 1, 0), &sc->cam.to_world));
  assert_true(camera_set_fov(&sc->cam, fov, "x", W, H));
}

/* Scene 1: box [-1,1]^3 open towards the camera side... closed; camera inside. */
static scene *scene_box(void) {
  scene *sc;
  assert_int_equal(scene_create(&sc, NULL), LMC_OK);
  int white = add_bsdf(sc, "diffuse", rgb_gray(0.6));
  int red = add_bsdf(sc, "diffuse", rgb_make(0.6, 0.1, 0.1));
  int green = add_bsdf(sc, "diffuse", rgb_make(0.1, 0.6, 0.1));
  bsdf pl;
  bsdf_init_defaults(&pl, "plastic");
  pl.diffuse = tex_constant(rgb_make(0.2, 0.3, 0.6));
  int plastic = add_bsdf_full(sc, &pl);
  /* Walls with normals pointing inwards. */
  add_quad(sc, v3(-1, -1, -1), v3(1, -1, -1), v3(1, -1, 1), v3(-1, -1, 1), v3(0, 1, 0), white, -1); /* floor */
  add_quad(sc, v3(-1, 1, -1), v3(-1, 1, 1), v3(1, 1, 1), v3(1, 1, -1), v3(0, -1, 0), white, -1); /* ceiling */
  add_quad(sc, v3(-1, -1, 1), v3(1, -1, 1), v3(1, 1, 1), v3(-1, 1, 1), v3(0, 0, -1), white, -1); /* back */
  add_quad(sc, v3(-1, -1, -1), v3(-1, 1, -1), v3(1, 1, -1), v3(1, -1, -1), v3(0, 0, 1), white, -1); /* front */
  add_quad(sc, v3(-1, -1, -1), v3(-1, -1, 1), v3(-1, 1, 1), v3(-1, 1, -1), v3(1, 0, 0), red, -1); /* left */
  add_quad(sc, v3(1, -1, -1), v3(1, 1, -1), v3(1, 1, 1), v3(1, -1, 1), v3(-1, 0, 0), green, -1); /* right */
  add_sphere(sc, v3(0.3, -0.6, 0.3), 0.4, plastic);
  add_area_light_quad(sc, -0.3, 0.3, -0.3, 0.3, 0.99, rgb_gray(8.0));
  set_camera(sc, v3(0, 0, -0.95), v3(0, 0, 1), 70.0);
  assert_int_equal(scene_finalize(sc, NULL), LMC_OK);
  return sc;
}

/* Scene 2: rough conductor sphere on a floor, point light. */
static scene *scene_conductor(void) {
  scene *sc;
  assert_int_equal(scene_create(&sc, NULL), LMC_OK);
  int white = add_bsdf(sc, "diffuse", rgb_gray(0.5));
  bsdf rc;
  bsdf_init_defaults(&rc, "roughconductor");
  rc.dist = MF_GGX;
  rc.alpha = 0.2;
  int metal = add_bsdf_full(sc, &rc);
  add_quad(sc, v3(-3, 0, -3), v3(-3, 0, 3), v3(3, 0, 3), v3(3, 0, -3), v3(0, 1, 0), white, -1); /* floor */
  add_quad(sc, v3(-3, 0, 2), v3(3, 0, 2), v3(3, 3, 2), v3(-3, 3, 2), v3(0, 0, -1), white, -1); /* back wall */
  add_sphere(sc, v3(0, 0.7, 0.5), 0.7, metal);
  light l;
  memset(&l, 0, sizeof l);
  l.type = LIGHT_POINT;
  l.value = rgb_gray(6.0);
  l.pos = v3(-1.0, 2.5, -0.5);
  assert_true(scene_add_light(sc, &l, NULL) >= 0);
  set_camera(sc, v3(0, 1.2, -3.0), v3(0, 0.6, 0.5), 50.0);
  assert_int_equal(scene_finalize(sc, NULL), LMC_OK);
  return sc;
}

/* Scene 3: rough glass sphere, area light, constant and envmap lights. */
static scene *scene_glass(void) {
  scene *sc;
  assert_int_equal(scene_create(&sc, NULL), LMC_OK);
  int white = add_bsdf(sc, "diffuse", rgb_gray(0.5));
  bsdf rd;
  bsdf_init_defaults(&rd, "roughdielectric");
  rd.dist = MF_GGX;
  rd.alpha = 0.3;
  int glass = add_bsdf_full(sc, &rd);
  add_quad(sc, v3(-2, 0, -2), v3(-2, 0, 2), v3(2, 0, 2), v3(2, 0, -2), v3(0, 1, 0), white, -1);
  add_sphere(sc, v3(0, 0.6, 0), 0.6, glass);
  add_area_light_quad(sc, -0.5, 0.5, -0.5, 0.5, 2.0, rgb_gray(5.0));
  light c;
  memset(&c, 0, sizeof c);
  c.type = LIGHT_CONSTANT;
  c.value = rgb_make(0.15, 0.2, 0.3);
  assert_true(scene_add_light(sc, &c, NULL) >= 0);
  /* A small lat-long map: bright band above the horizon, dimmer below. */
  light e;
  memset(&e, 0, sizeof e);
  e.type = LIGHT_ENVMAP;
  e.scale = 1.0;
  e.to_world = xform_identity();
  assert_int_equal(image_init(&e.image, 16, 8, 3, NULL), LMC_OK);
  for (int y = 0; y < 8; y++)
    for (int x = 0; x < 16; x++) {
      float *p = e.image.data + 3 * (y * 16 + x);
      double v = y < 3 ? 0.2 + 0.6 * (x < 4) : 0.05;
      p[0] = (float)v;
      p[1] = (float)(0.8 * v);
      p[2] = (float)(0.5 * v + 0.02);
    }
  assert_true(scene_add_light(sc, &e, NULL) >= 0);
  set_camera(sc, v3(0, 1.3, -2.6), v3(0, 0.5, 0), 55.0);
  assert_int_equal(scene_finalize(sc, NULL), LMC_OK);
  return sc;
}

/* Scene 4: spot light and directional light, diffuse and phong. */
static scene *scene_spot(void) {
  scene *sc;
  assert_int_equal(scene_create(&sc, NULL), LMC_OK);
  int white = add_bsdf(sc, "diffuse", rgb_gray(0.6));
  bsdf ph;
  bsdf_init_defaults(&ph, "phong");
  ph.diffuse = tex_constant(rgb_make(0.3, 0.4, 0.2));
  ph.specular = tex_constant(rgb_gray(0.3));
  ph.exponent = 20.0;
  int phong = add_bsdf_full(sc, &ph);
  add_quad(sc, v3(-3, 0, -3), v3(-3, 0, 3), v3(3, 0, 3), v3(3, 0, -3), v3(0, 1, 0), white, -1);
  add_quad(sc, v3(-3, 0, 2), v3(3, 0, 2), v3(3, 3, 2), v3(-3, 3, 2), v3(0, 0, -1), white, -1);
  add_sphere(sc, v3(0.3, 0.5, 0.6), 0.5, phong);
  light l;
  memset(&l, 0, sizeof l);
  l.type = LIGHT_SPOT;
  l.value = rgb_gray(10.0);
  l.pos = v3(-1.0, 2.5, -0.5);
  l.frm.n = v3_normalize(v3(0.8, -2.0, 1.0));
  l.cutoff = 30.0 * M_PI / 180.0;
  l.beam_width = 20.0 * M_PI / 180.0;
  assert_true(scene_add_light(sc, &l, NULL) >= 0);
  light d;
  memset(&d, 0, sizeof d);
  d.type = LIGHT_DIRECTIONAL;
  d.value = rgb_make(0.3, 0.3, 0.4);
  d.frm.n = v3_normalize(v3(1.0, -1.5, 0.8));
  assert_true(scene_add_light(sc, &d, NULL) >= 0);
  set_camera(sc, v3(0, 1.2, -3.0), v3(0, 0.6, 0.5), 50.0);
  assert_int_equal(scene_finalize(sc, NULL), LMC_OK);
  return sc;
}

/* ---- agreement -------------------------------------------------------------- */

/* Renders and returns the image mean and the GX x GY region means
 * (average of the three channels). */
static void render_means(const scene *sc, const char *integrator, int64_t spp, int maxdepth,
                         int mindepth, uint64_t seed, double out[GX * GY + 1]) {
  render_settings rs = render_settings_default();
  snprintf(rs.integrator, sizeof rs.integrator, "%s", integrator);
  rs.spp = spp;
  rs.set |= SET_SPP;
  rs.maxdepth = maxdepth;
  rs.mindepth = mindepth;
  rs.seed = seed;
  rs.threads = 2;
  rs.quiet = 1;
  film f;
  render_stats st;
  lmc_error err;
  assert_int_equal(render_run(sc, &rs, &f, &st, &err), LMC_OK);
  lmc_image img;
  assert_int_equal(film_develop(&f, &img, &err), LMC_OK);
  film_free(&f);
  memset(out, 0, sizeof(double) * (GX * GY + 1));
  for (int y = 0; y < H; y++)
    for (int x = 0; x < W; x++) {
      const float *p = img.data + 3 * (y * W + x);
      double v = (p[0] + p[1] + p[2]) / 3.0;
      out[GX * GY] += v / (W * H);
      int r = (y * GY / H) * GX + (x * GX / W);
      out[r] += v / ((W / GX) * (H / GY));
    }
  image_free(&img);
}

/* Compares pt and bdpt on one scene; returns the number of comparisons
 * made and counts the failures. */
static int compare_scene(const char *name, scene *sc, int64_t spp_pt, int64_t spp_bdpt,
                         int maxdepth, int mindepth, int *failures) {
  enum { N = GX * GY + 1 };
  double m[2][N], v[2][N];
  const char *integ[2] = {"pt", "bdpt"};
  int64_t spp[2] = {spp_pt, spp_bdpt};
  for (int k = 0; k < 2; k++) {
    double sum[N] = {0}, sum2[N] = {0};
    for (int sd = 0; sd < NSEEDS; sd++) {
      double r[N];
      render_means(sc, integ[k], spp[k], maxdepth, mindepth, 1000 + 17 * sd + 5 * k, r);
      for (int i = 0; i < N; i++) {
        sum[i] += r[i];
        sum2[i] += r[i] * r[i];
      }
    }
    for (int i = 0; i < N; i++) {
      m[k][i] = sum[i] / NSEEDS;
      /* variance of the mean = sample variance / NSEEDS */
      v[k][i] = fmax(0.0, (sum2[i] - NSEEDS * m[k][i] * m[k][i]) / (NSEEDS - 1)) / NSEEDS;
    }
  }
  int compared = 0;
  double zmax = 0.0;
  for (int i = 0; i < N; i++) {
    double sigma = sqrt(v[0][i] + v[1][i]);
    double diff = m[0][i] - m[1][i];
    /* Regions a scene leaves black in both images compare exactly. */
    double z = sigma > 0.0 ? fabs(diff) / sigma : (diff == 0.0 ? 0.0 : INFINITY);
    compared++;
    if (z > zmax) zmax = z;
    if (!(z < 4.5)) {
      (*failures)++;
      printf("  %s region %d: pt %.6g +- %.3g, bdpt %.6g +- %.3g, z = %.2f\n", name, i, m[0][i],
             sqrt(v[0][i]), m[1][i], sqrt(v[1][i]), z);
    }
  }
  printf("%s: mean pt %.6g +- %.2g, bdpt %.6g +- %.2g, max |z| over %d means = %.2f\n", name,
         m[0][N - 1], sqrt(v[0][N - 1]), m[1][N - 1], sqrt(v[1][N - 1]), compared, zmax);
  return compared;
}

static void test_pt_bdpt_agreement(void **state) {
  (void)state;
  lmc_warn_set_quiet(1);
  int failures = 0, compared = 0;
  scene *sc;
  sc = scene_box();
  compared += compare_scene("box", sc, 64, 32, -1, -1, &failures);
  scene_destroy(sc);
  sc = scene_conductor();
  compared += compare_scene("conductor", sc, 64, 32, 4, -1, &failures);
  scene_destroy(sc);
  sc = scene_glass();
  compared += compare_scene("glass", sc, 64, 32, 8, -1, &failures);
  scene_destroy(sc);
  sc = scene_spot();
  compared += compare_scene("spot", sc, 64, 32, 5, 2, &failures);
  scene_destroy(sc);
  assert_int_equal(compared, 4 * (GX * GY + 1));
  assert_int_equal(failures, 0);
}

/* ---- MIS weights sum to one ---------------------------------------------------- */

/* Could strategy (s', t') of the full path f[0..n-1] (f[0] the light end)
 * produce it? (Veach: no connection touching a vertex that scattered
 * through a delta lobe; s' = 0 needs an emitter that rays can hit.) */
static int strategy_possible(const scene *sc, bdpt_vertex *const *f, int n, int sp) {
  int tp = n - sp;
  if (tp < 1 || (sp == 1 && tp == 1)) return 0;
  if (sp == 0) {
    const bdpt_vertex *e = f[0];
    if (e->type == BDPT_VERTEX_LIGHT) return e->light < 0 || !light_is_delta(&sc->lights[e->light]);
    return e->type == BDPT_VERTEX_SURFACE && e->light >= 0;
  }
  return !f[sp - 1]->delta && !f[sp]->delta;
}

static int rel_close(double a, double b, double tol) {
  return fabs(a - b) <= tol * fmax(fabs(a), fabs(b)) + 1e-300;
}

/* For random subpaths of sc, checks stored densities and the weight sums.
 * Returns the number of full paths checked. */
static int check_weights(const scene *sc, int n_samples, int *bad_sum, int *bad_pdf,
                         int *bad_weight, int *pdf_checked) {
  render_settings rs = render_settings_default();
  rs.maxdepth = 6;
  int max_cam, max_light;
  bdpt_subpath_limits(&rs, &max_cam, &max_light);
  render_counters cnt = {0};
  static bdpt_vertex cam[BDPT_MAX_VERTICES], lp[BDPT_MAX_VERTICES];
  static bdpt_vertex full[2 * BDPT_MAX_VERTICES], c2[2 * BDPT_MAX_VERTICES],
      l2[2 * BDPT_MAX_VERTICES];
  int paths = 0;
  for (int k = 0; k < n_samples; k++) {
    lmc_indep_sampler smp;
    indep_sampler_init(&smp, 77, (uint64_t)k);
    double rx = W * sampler_next(&smp.base), ry = H * sampler_next(&smp.base);
    int nc = bdpt_camera_subpath(sc, &rs, &smp.base, rx, ry, max_cam, cam, &cnt);
    int nl = bdpt_light_subpath(sc, &rs, &smp.base, max_light, lp, &cnt);
    for (int t = 1; t <= nc; t++)
      for (int s = 0; s <= nl; s++) {
        if (s == 1 || s + t < 2 || s + t - 1 > rs.maxdepth) continue; /* s = 1 resamples its light */
        double rx2, ry2, w;
        rgb c = bdpt_connect(sc, cam, t, lp, s, NULL, &rx2, &ry2, &w, &cnt);
        if (rgb_is_black(c)) continue;
        paths++;
        /* The full path from the light end; connection vertices did not
         * scatter through a delta lobe. */
        int n = s + t;
        bdpt_vertex *f[2 * BDPT_MAX_VERTICES];
        for (int i = 0; i < s; i++) full[i] = lp[i];
        for (int j = 0; j < t; j++) full[s + j] = cam[t - 1 - j];
        if (s > 0) full[s - 1].delta = 0;
        full[s].delta = 0;
        if (full[0].type == BDPT_VERTEX_SURFACE) {
          /* s = 0 on an area light: as a light endpoint, it is a light vertex. */
          full[0].type = BDPT_VERTEX_LIGHT;
          full[0].delta = 0;
        }
        for (int i = 0; i < n; i++) f[i] = &full[i];

        /* Stored densities against recomputed ones (all but the reverse
         * densities of the two vertices before each end of the connection). */
        for (int i = 0; i < s; i++) l2[i] = full[i];
        for (int j = 0; j < t; j++) c2[j] = cam[j];
        if (s > 0) l2[s - 1].delta = 0;
        c2[t - 1].delta = 0;
        bdpt_path_pdfs(sc, c2, t, l2, s);
        for (int i = 0; i < s; i++) {
          (*pdf_checked)++;
          if (!rel_close(l2[i].pdf_fwd, lp[i].pdf_fwd, 1e-3)) (*bad_pdf)++;
          if (i <= s - 3) {
            (*pdf_checked)++;
            if (!rel_close(l2[i].pdf_rev, lp[i].pdf_rev, 1e-3)) (*bad_pdf)++;
          }
        }
        for (int j = 1; j < t; j++) {
          (*pdf_checked)++;
          if (!rel_close(c2[j].pdf_fwd, cam[j].pdf_fwd, 1e-3)) {
            (*bad_pdf)++;
            printf("  cam pdf_fwd %d/%d: %g vs %g\n", j, t, c2[j].pdf_fwd, cam[j].pdf_fwd);
          }
          if (j <= t - 3) {
            (*pdf_checked)++;
            if (!rel_close(c2[j].pdf_rev, cam[j].pdf_rev, 1e-3)) {
              (*bad_pdf)++;
              printf("  cam pdf_rev %d/%d: %g vs %g\n", j, t, c2[j].pdf_rev, cam[j].pdf_rev);
            }
          }
        }

        /* Re-split at every s' and sum the weights of the possible strategies. */
        double sum = 0.0, w_same = -1.0;
        for (int sp = 0; sp < n; sp++) {
          if (!strategy_possible(sc, f, n, sp)) continue;
          int tp = n - sp;
          for (int i = 0; i < sp; i++) l2[i] = full[i];
          for (int j = 0; j < tp; j++) c2[j] = full[n - 1 - j];
          bdpt_path_pdfs(sc, c2, tp, l2, sp);
          double wp = bdpt_mis_weight(sc, c2, tp, l2, sp, NULL);
          sum += wp;
          if (sp == s) w_same = wp;
        }
        if (!(fabs(sum - 1.0) < 1e-9)) {
          (*bad_sum)++;
          printf("  (s=%d,t=%d): weights sum to %.12g\n", s, t, sum);
        }
        if (!rel_close(w_same, w, 1e-3)) {
          (*bad_weight)++;
          printf("  (s=%d,t=%d): weight %g, re-split %g\n", s, t, w, w_same);
        }
      }
  }
  return paths;
}

static void test_mis_weights_sum_to_one(void **state) {
  (void)state;
  lmc_warn_set_quiet(1);
  int bad_sum = 0, bad_pdf = 0, bad_weight = 0, pdf_checked = 0, paths = 0;
  scene *sc = scene_box();
  paths += check_weights(sc, 3000, &bad_sum, &bad_pdf, &bad_weight, &pdf_checked);
  scene_destroy(sc);
  sc = scene_glass();
  paths += check_weights(sc, 3000, &bad_sum, &bad_pdf, &bad_weight, &pdf_checked);
  scene_destroy(sc);
  printf("MIS: %d full paths, %d stored densities checked (%d off by > 1e-3), %d bad sums, %d "
         "bad weights\n", paths, pdf_checked, bad_pdf, bad_sum, bad_weight);
  assert_true(paths > 1000);
  assert_true(pdf_checked > 1000);
  assert_int_equal(bad_sum, 0);
  assert_int_equal(bad_weight, 0);
  /* Densities of rough lobes are sensitive to the float positions of hits:
   * allow a tiny fraction of mismatches at the 1e-3 level. */
  assert_true(bad_pdf <= pdf_checked / 1000);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_mis_weights_sum_to_one),
      cmocka_unit_test(test_pt_bdpt_agreement),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
