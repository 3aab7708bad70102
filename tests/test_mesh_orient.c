/*
 * test_mesh_orient.c: which side a mesh faces when its winding disagrees
 * with its vertex normals (issue 56). Mitsuba 0.6 turns a hit's geometric
 * normal to agree with the interpolated shading normal (KDTree::
 * fillIntersectionRecord: "Ensure that the geometric & shading normals face
 * the same direction"), so the vertex normals decide; `faceNormals` drops
 * them (the winding decides) and `flipNormals` negates them (or, without
 * vertex normals, reverses the winding) before any hit is made. mesh.h's
 * mesh_hit_normals is lmc's rule; these tests check it where a side is
 * decided. The meshes are OBJ squares written into the build's scratch
 * folder, with vertex normals up or down and wound up or down.
 *
 *  - hits: scene_intersect's normals on the four combinations and under
 *    faceNormals / flipNormals;
 *  - floor: a one-sided diffuse floor whose vertex normals point up but
 *    whose winding faces down, lit by an area light above, renders as the
 *    same floor wound up (image means over seeds, within their standard
 *    errors) with pt, bdpt, pssmlt, lmc and mlt, far from black; with
 *    faceNormals or flipNormals it faces down and renders black;
 *  - emitter: an area light on such a mesh emits on the normals' side:
 *    light sampling (light_sample_li, light_sample_le, their densities and
 *    inverses) agrees with hitting the light, and in renders a receiver on
 *    the normals' side is lit as with the consistent winding while one on
 *    the winding's side stays exactly black;
 *  - gradients: path_eval_pt and path_eval_bdpt through such a floor and
 *    such an emitter (tilted vertex normals, so the shading normal moves
 *    with u) agree with pt_li and bdpt_connect and with central
 *    differences, and the floor's winding changes no path's value or
 *    gradient.
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

#include "lmc/mcmc.h"
#include "render/integrators/path_internal.h" /* (the arena's size) */
#include "render/io/io.h"
#include "render/integrators/path.h"
#include "test_util.h"
#include "path_grad_util.h"
#include "load_scene.h"

/* ---------------------------------------------------------------------------
 * Scenes written at run time.
 */

/* Writes an OBJ square of half-size `half` at height y, centred on the y
 * axis: its vertex normals point up (normals_up) or down, leaned outwards
 * by `tilt` at the corners; its two triangles are wound to face up
 * (wound_up) or down. */
static void write_square(const char *path, double y, double half, int normals_up, int wound_up,
                         double tilt) {
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  static const int corner[4][2] = {{-1, -1}, {-1, 1}, {1, 1}, {1, -1}};
  for (int k = 0; k < 4; k++)
    fprintf(f, "v %.17g %.17g %.17g\n", corner[k][0] * half, y, corner[k][1] * half);
  for (int k = 0; k < 4; k++) {
    vec3 n = v3_normalize(v3(corner[k][0] * tilt, normals_up ? 1.0 : -1.0, corner[k][1] * tilt));
    fprintf(f, "vn %.17g %.17g %.17g\n", n.x, n.y, n.z);
  }
  /* (a, b, c) = corners 1, 2, 3: (b - a) x (c - a) points up. */
  if (wound_up)
    fputs("f 1//1 2//2 3//3\nf 1//1 3//3 4//4\n", f);
  else
    fputs("f 1//1 3//3 2//2\nf 1//1 4//4 3//3\n", f);
  fclose(f);
}

/* A path in the scratch folder: LMC_TEST_TMP/lmc_orient_<pid>_<name>. */
static void tmp_path(char *buf, size_t size, const char *name) {
  snprintf(buf, size, "%s/lmc_orient_%d_%s", LMC_TEST_TMP, (int)getpid(), name);
}

/* Writes `xml` (with every "@DIR@" replaced by the scratch folder's prefix)
 * and loads it. */
static scene *load_xml(const char *name, const char *xml) {
  char path[1024], prefix[1024];
  tmp_path(path, sizeof path, name);
  tmp_path(prefix, sizeof prefix, "");
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  for (const char *p = xml; *p;) {
    if (strncmp(p, "@DIR@", 5) == 0) {
      fputs(prefix, f);
      p += 5;
    } else {
      fputc(*p++, f);
    }
  }
  fclose(f);
  scene *s = load_scene(path);
  remove(path);
  return s;
}

/* The squares the scenes use, written once. */
static int setup(void **state) {
  (void)state;
  char p[1024];
  /* Floors at y = 0, half-size 4, normals up: wound up, wound down. */
  tmp_path(p, sizeof p, "floor_up.obj");
  write_square(p, 0.0, 4.0, 1, 1, 0.0);
  tmp_path(p, sizeof p, "floor_down.obj");
  write_square(p, 0.0, 4.0, 1, 0, 0.0);
  /* Emitters at y = 0, half-size 1, normals up. */
  tmp_path(p, sizeof p, "lamp_up.obj");
  write_square(p, 0.0, 1.0, 1, 1, 0.0);
  tmp_path(p, sizeof p, "lamp_down.obj");
  write_square(p, 0.0, 1.0, 1, 0, 0.0);
  /* For the gradients: tilted normals; a floor (normals up) either way and
   * a ceiling light at y = 3 (normals down, wound up). */
  tmp_path(p, sizeof p, "gfloor_up.obj");
  write_square(p, 0.0, 4.0, 1, 1, 0.35);
  tmp_path(p, sizeof p, "gfloor_down.obj");
  write_square(p, 0.0, 4.0, 1, 0, 0.35);
  tmp_path(p, sizeof p, "glamp.obj");
  write_square(p, 3.0, 0.6, 0, 1, 0.25);
  return 0;
}

static int teardown(void **state) {
  (void)state;
  static const char *const names[] = {"floor_up.obj", "floor_down.obj", "lamp_up.obj",
                                      "lamp_down.obj", "gfloor_up.obj", "gfloor_down.obj",
                                      "glamp.obj"};
  char p[1024];
  for (size_t i = 0; i < sizeof names / sizeof *names; i++) {
    tmp_path(p, sizeof p, names[i]);
    remove(p);
  }
  return 0;
}

/* The floor scene: a diffuse floor from `obj` (with `extra` properties)
 * seen from above, lit by a 1 x 1 area light at y = 2 facing down. */
static scene *floor_scene(const char *obj, const char *extra) {
  char xml[4096];
  snprintf(xml, sizeof xml,
           "<scene version=\"0.6.0\">\n"
           "  <integrator type=\"path\"><integer name=\"maxDepth\" value=\"4\"/></integrator>\n"
           "  <sensor type=\"perspective\">\n"
           "    <float name=\"fov\" value=\"40\"/>\n"
           "    <transform name=\"toWorld\"><lookat origin=\"0, 3, 3\" target=\"0, 0, 0\" "
           "up=\"0, 1, 0\"/></transform>\n"
           "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/>"
           "<integer name=\"height\" value=\"24\"/><rfilter type=\"box\"/></film>\n"
           "  </sensor>\n"
           "  <shape type=\"obj\"><string name=\"filename\" value=\"@DIR@%s\"/>%s\n"
           "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5, 0.5, 0.5\"/></bsdf>\n"
           "  </shape>\n"
           "  <shape type=\"rectangle\">\n"
           "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"90\"/>"
           "<scale x=\"0.5\" y=\"1\" z=\"0.5\"/><translate y=\"2\"/></transform>\n"
           "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"10, 10, 10\"/></emitter>\n"
           "  </shape>\n"
           "</scene>\n",
           obj, extra);
  return load_xml("floor.xml", xml);
}

/* The emitter scene: an area light from `obj` at y = 0, a diffuse 1 x 1
 * receiver above it facing down (y = 1) and one below it facing up
 * (y = -1), seen from the side. */
static scene *lamp_scene(const char *obj) {
  char xml[4096];
  snprintf(xml, sizeof xml,
           "<scene version=\"0.6.0\">\n"
           "  <integrator type=\"path\"><integer name=\"maxDepth\" value=\"4\"/></integrator>\n"
           "  <sensor type=\"perspective\">\n"
           "    <float name=\"fov\" value=\"80\"/>\n"
           "    <transform name=\"toWorld\"><lookat origin=\"2, 0, 0\" target=\"0, 0, 0\" "
           "up=\"0, 1, 0\"/></transform>\n"
           "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/>"
           "<integer name=\"height\" value=\"32\"/><rfilter type=\"box\"/></film>\n"
           "  </sensor>\n"
           "  <shape type=\"obj\"><string name=\"filename\" value=\"@DIR@%s\"/>\n"
           "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"5, 5, 5\"/></emitter>\n"
           "  </shape>\n"
           "  <shape type=\"rectangle\" id=\"above\">\n"
           "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"90\"/>"
           "<scale x=\"0.5\" y=\"1\" z=\"0.5\"/><translate y=\"1\"/></transform>\n"
           "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.8, 0.8, 0.8\"/></bsdf>\n"
           "  </shape>\n"
           "  <shape type=\"rectangle\" id=\"below\">\n"
           "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/>"
           "<scale x=\"0.5\" y=\"1\" z=\"0.5\"/><translate y=\"-1\"/></transform>\n"
           "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.8, 0.8, 0.8\"/></bsdf>\n"
           "  </shape>\n"
           "</scene>\n",
           obj);
  return load_xml("lamp.xml", xml);
}

/* The index of the mesh named `name`. */
static int find_mesh(const scene *s, const char *name) {
  for (int i = 0; i < s->n_meshes; i++)
    if (strcmp(s->meshes[i].name, name) == 0) return i;
  fail_msg("no mesh named %s", name);
  return -1;
}

/* ---------------------------------------------------------------------------
 * Renders.
 */

/* Settings for `integrator` with `spp` samples (mutations) per pixel. */
static render_settings settings(const scene *s, const char *integrator, int64_t spp,
                                uint64_t seed) {
  render_settings rs = s->settings;
  snprintf(rs.integrator, sizeof rs.integrator, "%s", integrator);
  rs.spp = spp;
  rs.set |= SET_SPP;
  rs.time_limit = 0.0;
  rs.threads = 2;
  rs.seed = seed;
  rs.quiet = 1;
  if (mcmc_is_integrator(integrator)) {
    lmc_error err;
    assert_int_equal(mcmc_set(&rs, "bootstrap", "16384", &err), LMC_OK);
    /* The chains render every path, the direct light included. */
    assert_int_equal(mcmc_set(&rs, "direct", "mcmc", &err), LMC_OK);
  }
  return rs;
}

/* The mesh pixel (x, y) sees at its corners and centre: its index, -1 when
 * they disagree, -2 when it sees nothing. */
static int pixel_mesh(const scene *s, int x, int y) {
  static const double off[5][2] = {{0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}, {1.0, 1.0}, {0.5, 0.5}};
  int g = -3;
  for (int k = 0; k < 5; k++) {
    vec3 o, d;
    camera_generate_ray(&s->cam, x + off[k][0], y + off[k][1], &o, &d);
    surface_hit h;
    int gk = scene_intersect(s, o, d, 0.0, INFINITY, &h) ? h.mesh : -2;
    if (g == -3) g = gk;
    else if (g != gk) return -1;
  }
  return g;
}

/* Renders s once and writes the mean over the channels of the pixels that
 * see mesh group[g] alone (pixel_mesh in `seen`; group NULL: every pixel)
 * into OUT_mean[g]. */
static void render_means(const scene *s, const char *integrator, int64_t spp, uint64_t seed,
                         const int *seen, const int *group, int n_groups, double *OUT_mean) {
  render_settings rs = settings(s, integrator, spp, seed);
  film f;
  render_stats st;
  lmc_error err;
  lmc_error_clear(&err);
  lmc_status rc = mcmc_is_integrator(integrator) ? mcmc_render_run(s, &rs, &f, &st, &err)
                                                 : render_run(s, &rs, &f, &st, &err);
  if (rc) print_error("%s: %s\n", integrator, err.msg);
  assert_int_equal(rc, LMC_OK);
  lmc_image img;
  assert_int_equal(film_develop(&f, &img, &err), LMC_OK);
  for (int g = 0; g < n_groups; g++) {
    double sum = 0.0;
    int n = 0;
    for (int y = 0; y < img.height; y++)
      for (int x = 0; x < img.width; x++) {
        if (group && seen[y * img.width + x] != group[g]) continue;
        const float *p = img.data + 3 * ((size_t)y * img.width + x);
        sum += (p[0] + p[1] + p[2]) / 3.0;
        n++;
      }
    assert_true(n >= 30);
    OUT_mean[g] = sum / n;
  }
  image_free(&img);
  film_free(&f);
}

#define SEEDS 5

/* Mean and standard error over SEEDS renders (seeds seed0, seed0 + 1, ...). */
typedef struct mean_se {
  double mean[2], se[2];
} mean_se;

static mean_se render_seeds(const scene *s, const char *integrator, int64_t spp, uint64_t seed0,
                            const int *group, int n_groups) {
  double sum[2] = {0.0, 0.0}, sum2[2] = {0.0, 0.0};
  int *seen = malloc((size_t)s->cam.width * s->cam.height * sizeof *seen);
  assert_non_null(seen);
  for (int y = 0; y < s->cam.height; y++)
    for (int x = 0; x < s->cam.width; x++) seen[y * s->cam.width + x] = pixel_mesh(s, x, y);
  for (int r = 0; r < SEEDS; r++) {
    double m[2];
    render_means(s, integrator, spp, seed0 + (uint64_t)r, seen, group, n_groups, m);
    for (int g = 0; g < n_groups; g++) {
      sum[g] += m[g];
      sum2[g] += m[g] * m[g];
    }
  }
  free(seen);
  mean_se out = {{0.0, 0.0}, {0.0, 0.0}};
  for (int g = 0; g < n_groups; g++) {
    out.mean[g] = sum[g] / SEEDS;
    double var = fmax(0.0, (sum2[g] - SEEDS * out.mean[g] * out.mean[g]) / (SEEDS - 1));
    out.se[g] = sqrt(var / SEEDS);
  }
  return out;
}

/* The integrators and their budgets (short renders). */
static const char *const integrators[] = {"pt", "bdpt", "pssmlt", "lmc", "mlt"};
static const int64_t budgets[] = {256, 32, 64, 32, 64};
#define N_INTEGRATORS 5

/* Two estimates agree within 4.5 standard errors of their difference (and
 * a rounding's worth). */
static void assert_agree(const char *what, double a, double se_a, double b, double se_b) {
  double tol = 4.5 * sqrt(se_a * se_a + se_b * se_b) + 1e-9 * fabs(b);
  if (!(fabs(a - b) <= tol))
    fail_msg("%s: %.6f (SE %.2g) against %.6f (SE %.2g), tolerance %.2g", what, a, se_a, b, se_b,
             tol);
}

/* ---------------------------------------------------------------------------
 * Hits.
 */

/* The normals scene_intersect gives the floor hit straight down from
 * (0.3, 1, 0.2). */
static void floor_hit(const scene *s, surface_hit *h) {
  assert_true(scene_intersect(s, v3(0.3, 1.0, 0.2), v3(0.0, -1.0, 0.0), 0.0, INFINITY, h));
  assert_true(h->sh.n.y * h->ng.y > 0.0); /* the two normals agree */
}

static void test_hit_normals(void **state) {
  (void)state;
  /* Which way (+1 up, -1 down) each floor faces, as Mitsuba's rules say:
   * vertex normals decide; faceNormals: the winding; flipNormals: the
   * vertex normals negated (with faceNormals: the winding reversed). */
  static const struct {
    const char *obj, *extra;
    int faces;
  } cases[] = {
      {"floor_up.obj", "", 1},
      {"floor_down.obj", "", 1},
      {"floor_up.obj", "<boolean name=\"faceNormals\" value=\"true\"/>", 1},
      {"floor_down.obj", "<boolean name=\"faceNormals\" value=\"true\"/>", -1},
      {"floor_up.obj", "<boolean name=\"flipNormals\" value=\"true\"/>", -1},
      {"floor_down.obj", "<boolean name=\"flipNormals\" value=\"true\"/>", -1},
      {"floor_down.obj",
       "<boolean name=\"faceNormals\" value=\"true\"/><boolean name=\"flipNormals\" value=\"true\"/>",
       1},
  };
  int checked = 0;
  for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
    scene *s = floor_scene(cases[i].obj, cases[i].extra);
    surface_hit h;
    floor_hit(s, &h);
    if (!(h.ng.y * cases[i].faces > 0.999999))
      fail_msg("case %zu (%s %s): ng.y = %g, expected %d", i, cases[i].obj, cases[i].extra, h.ng.y,
               cases[i].faces);
    assert_near(h.sh.n.y, cases[i].faces, 1e-12);
    /* The mesh's winding normal is unchanged (mesh_face_normal). */
    const mesh *m = &s->meshes[h.mesh];
    double wind = strcmp(cases[i].obj, "floor_up.obj") == 0 ? 1.0 : -1.0;
    assert_near(mesh_face_normal(m, h.prim).y, m->flip_normals ? -wind : wind, 1e-12);
    scene_destroy(s);
    checked++;
  }
  print_message("hit normals: %d cases\n", checked);
  assert_int_equal(checked, 7);
}

/* ---------------------------------------------------------------------------
 * The floor.
 */

static void test_floor_renders(void **state) {
  (void)state;
  scene *up = floor_scene("floor_up.obj", "");
  scene *down = floor_scene("floor_down.obj", "");
  int checked = 0;
  for (int k = 0; k < N_INTEGRATORS; k++) {
    const char *in = integrators[k];
    mean_se a = render_seeds(up, in, budgets[k], 100, NULL, 1);
    mean_se b = render_seeds(down, in, budgets[k], 200, NULL, 1);
    print_message("floor %-6s: wound up %.5f (SE %.2g), wound down %.5f (SE %.2g), "
                  "difference %.2f SE\n",
                  in, a.mean[0], a.se[0], b.mean[0], b.se[0],
                  (b.mean[0] - a.mean[0]) / fmax(1e-300, hypot(a.se[0], b.se[0])));
    assert_agree(in, b.mean[0], b.se[0], a.mean[0], a.se[0]);
    /* Far from black: the floor is lit. */
    assert_true(a.mean[0] > 0.05);
    assert_true(b.mean[0] > 0.5 * a.mean[0]);
    assert_true(b.mean[0] > 20.0 * b.se[0]);
    checked++;
  }
  scene_destroy(up);
  scene_destroy(down);

  /* The floor faces down (seen from its back: black) when the winding
   * decides, or when its normals are flipped; faceNormals and flipNormals
   * together reverse the downward winding: lit again. */
  static const struct {
    const char *obj, *extra;
    int lit;
  } cases[] = {
      {"floor_down.obj", "<boolean name=\"faceNormals\" value=\"true\"/>", 0},
      {"floor_down.obj", "<boolean name=\"flipNormals\" value=\"true\"/>", 0},
      {"floor_up.obj", "<boolean name=\"flipNormals\" value=\"true\"/>", 0},
      {"floor_down.obj",
       "<boolean name=\"faceNormals\" value=\"true\"/><boolean name=\"flipNormals\" value=\"true\"/>",
       1},
  };
  up = floor_scene("floor_up.obj", "");
  mean_se ref = render_seeds(up, "pt", 32, 300, NULL, 1);
  scene_destroy(up);
  for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
    scene *s = floor_scene(cases[i].obj, cases[i].extra);
    for (int k = 0; k < 2; k++) {
      mean_se m = render_seeds(s, integrators[k], budgets[k] / 8, 400, NULL, 1);
      print_message("floor %s %s, %s: %.5f (SE %.2g)\n", cases[i].obj, cases[i].extra,
                    integrators[k], m.mean[0], m.se[0]);
      if (cases[i].lit)
        assert_agree("faceNormals and flipNormals", m.mean[0], m.se[0], ref.mean[0], ref.se[0]);
      else
        assert_true(m.mean[0] == 0.0);
      checked++;
    }
    scene_destroy(s);
  }
  assert_int_equal(checked, N_INTEGRATORS + 8);
}

/* ---------------------------------------------------------------------------
 * The emitter.
 */

/* Light sampling agrees with hitting the light, on the emitter whose
 * winding (down) disagrees with its normals (up). */
static void test_emitter_sampling(void **state) {
  (void)state;
  scene *s = lamp_scene("lamp_down.obj");
  int mi = -1;
  for (int i = 0; i < s->n_meshes; i++)
    if (s->meshes[i].light >= 0) mi = i;
  assert_true(mi >= 0);
  const light *l = &s->lights[s->meshes[mi].light];
  rgb L = l->value;
  rng r;
  rng_seed(&r, 21, 0);
  int n_li = 0, n_le = 0, refused = 0;
  for (int i = 0; i < 500; i++) {
    double u1 = rng_uniform(&r), u2 = rng_uniform(&r);
    /* From above: the sample is taken, its normal faces up, and a ray to
     * it hits the light with the same normal, radiance and density. */
    vec3 ref = v3(0.7 * (rng_uniform(&r) - 0.5), 0.3 + 0.6 * rng_uniform(&r),
                  0.7 * (rng_uniform(&r) - 0.5));
    light_li_sample ls;
    assert_true(light_sample_li(l, s, ref, u1, u2, &ls));
    assert_near(ls.n.y, 1.0, 1e-12);
    surface_hit h;
    assert_true(scene_intersect(s, ref, ls.wi, 0.0, INFINITY, &h));
    assert_int_equal(h.mesh, mi);
    assert_near(v3_dot(h.ng, ls.n), 1.0, 1e-12);
    rgb le = light_le_area(l, h.ng, v3_neg(ls.wi));
    assert_near(le.r, L.r, 0.0);
    assert_near(light_pdf_li(l, s, ref, ls.wi, h.p, h.ng), ls.pdf, 1e-7 * ls.pdf);
    /* The inverse finds the numbers back. */
    double rr[2] = {0.5, 0.5}, u[2];
    assert_true(light_invert_li(l, s, ref, ls.wi, ls.p, ls.tri, rr, u));
    assert_near(u[0], u1, 1e-6);
    assert_near(u[1], u2, 1e-6);
    n_li++;
    /* From below (the winding's side) nothing is emitted. */
    vec3 below = v3(ref.x, -ref.y, ref.z);
    refused += !light_sample_li(l, s, below, u1, u2, &ls);
    assert_true(scene_intersect(s, below, v3(0.0, 1.0, 0.0), 0.0, INFINITY, &h));
    if (h.mesh == mi) assert_true(rgb_is_black(light_le_area(l, h.ng, v3(0.0, -1.0, 0.0))));

    /* Emission: upwards from a point whose normal is a hit's there. */
    light_le_sample es;
    double u3 = rng_uniform(&r), u4 = rng_uniform(&r);
    assert_true(light_sample_le(l, s, u1, u2, u3, u4, &es));
    assert_near(es.n.y, 1.0, 1e-12);
    assert_true(es.dir.y > 0.0);
    assert_true(scene_intersect(s, v3_fma(es.p, v3(0, 1, 0), 0.5), v3(0, -1, 0), 0.0, INFINITY, &h));
    assert_near(v3_dot(h.ng, es.n), 1.0, 1e-12);
    double pdf_pos, pdf_dir;
    light_pdf_le(l, s, es.p, h.ng, es.dir, &pdf_pos, &pdf_dir);
    assert_near(pdf_pos, es.pdf_pos, 1e-12 * es.pdf_pos);
    assert_near(pdf_dir, es.pdf_dir, 1e-9 * es.pdf_dir);
    double r4[4] = {0.5, 0.5, 0.5, 0.5}, v[4];
    assert_true(light_invert_le(l, s, es.p, es.dir, es.tri, r4, v));
    assert_near(v[2], u3, 1e-6);
    assert_near(v[3], u4, 1e-6);
    assert_true(!light_invert_le(l, s, es.p, v3_neg(es.dir), es.tri, r4, v));
    n_le++;
  }
  print_message("emitter sampling: %d direct samples, %d emission samples, %d refused below\n",
                n_li, n_le, refused);
  assert_int_equal(n_li, 500);
  assert_int_equal(n_le, 500);
  assert_int_equal(refused, 500);
  scene_destroy(s);
}

/* Renders: the receiver above (the normals' side) is lit as with the
 * consistent winding, the one below (the winding's side) is black. */
static void test_emitter_renders(void **state) {
  (void)state;
  scene *up = lamp_scene("lamp_up.obj");
  scene *down = lamp_scene("lamp_down.obj");
  int groups[2] = {find_mesh(down, "above"), find_mesh(down, "below")};
  assert_int_equal(groups[0], find_mesh(up, "above"));
  assert_int_equal(groups[1], find_mesh(up, "below"));
  int checked = 0;
  for (int k = 0; k < N_INTEGRATORS; k++) {
    const char *in = integrators[k];
    mean_se a = render_seeds(up, in, budgets[k], 500, groups, 2);
    mean_se b = render_seeds(down, in, budgets[k], 600, groups, 2);
    print_message("emitter %-6s: receiver above %.5f (SE %.2g) wound down, %.5f (SE %.2g) "
                  "wound up; below %.5f and %.5f\n",
                  in, b.mean[0], b.se[0], a.mean[0], a.se[0], b.mean[1], a.mean[1]);
    assert_agree(in, b.mean[0], b.se[0], a.mean[0], a.se[0]);
    assert_true(b.mean[0] > 0.1);
    assert_true(b.mean[0] > 20.0 * b.se[0]);
    assert_true(a.mean[1] == 0.0 && b.mean[1] == 0.0);
    checked++;
  }
  scene_destroy(up);
  scene_destroy(down);
  assert_int_equal(checked, N_INTEGRATORS);
}

/* ---------------------------------------------------------------------------
 * Gradients.
 */

/* A floor (`floor`: wound up or down, normals up and tilted), a ceiling
 * light whose normals face down while its winding faces up, and a rough
 * gold sphere. */
static scene *grad_scene(const char *floor) {
  char xml[4096];
  snprintf(xml, sizeof xml,
           "<scene version=\"0.6.0\">\n"
           "  <integrator type=\"path\"><integer name=\"maxDepth\" value=\"5\"/></integrator>\n"
           "  <sensor type=\"perspective\">\n"
           "    <float name=\"fov\" value=\"45\"/>\n"
           "    <transform name=\"toWorld\"><lookat origin=\"0, 2, 5\" target=\"0, 0.5, 0\" "
           "up=\"0, 1, 0\"/></transform>\n"
           "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/>"
           "<integer name=\"height\" value=\"24\"/><rfilter type=\"box\"/></film>\n"
           "  </sensor>\n"
           "  <shape type=\"obj\" id=\"floor\"><string name=\"filename\" value=\"@DIR@%s\"/>\n"
           "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.6, 0.5, 0.4\"/></bsdf>\n"
           "  </shape>\n"
           "  <shape type=\"obj\"><string name=\"filename\" value=\"@DIR@glamp.obj\"/>\n"
           "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"20, 18, 15\"/></emitter>\n"
           "  </shape>\n"
           "  <shape type=\"sphere\"><point name=\"center\" x=\"0.8\" y=\"0.6\" z=\"0.2\"/>"
           "<float name=\"radius\" value=\"0.6\"/>\n"
           "    <bsdf type=\"roughconductor\"><string name=\"material\" value=\"Au\"/>"
           "<string name=\"distribution\" value=\"ggx\"/><float name=\"alpha\" value=\"0.2\"/></bsdf>\n"
           "  </shape>\n"
           "</scene>\n",
           floor);
  return load_xml("grad.xml", xml);
}

/* path_eval_pt gives pt_li's value, the same value and gradient for either
 * winding of the floor, and gradients that central differences confirm. */
static void test_pt_gradient(void **state) {
  (void)state;
  scene *sd = grad_scene("gfloor_down.obj"), *su = grad_scene("gfloor_up.obj");
  path_scratch *ps;
  lmc_error err;
  assert_int_equal(path_scratch_create(&ps, &err), LMC_OK);
  render_settings rs = sd->settings;
  rs.rrdepth = 3;
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 31, NULL);
  pg_fd_stats st = {0};
  int tries = 0, nonzero = 0, mismatched = 0, floor_first = 0, winding_same = 0;
  int floor_mesh = find_mesh(sd, "floor");
  while (st.paths < 250 && tries < 20000) {
    tries++;
    path_vec_sampler_clear(&vs);
    path_eval ev;
    path_eval_pt(sd, &rs, &vs.base, 1, ps, &ev, NULL);

    /* The same numbers through pt_li. */
    path_vec_sampler_rewind(&vs);
    double u0 = sampler_next(&vs.base), u1 = sampler_next(&vs.base);
    vec3 org, dir;
    camera_generate_ray(&sd->cam, u0 * sd->cam.width, u1 * sd->cam.height, &org, &dir);
    render_counters cnt = {0};
    rgb L = pt_li(sd, &rs, &vs.base, org, dir, NULL, &cnt);
    if (!pg_rgb_rel_equal(L, ev.value, 1e-9)) mismatched++;
    if (!ev.grad_ok || !(ev.lum > 0.0)) continue;
    nonzero++;

    /* The floor wound the other way: the same path, value and gradient. */
    surface_hit h;
    if (scene_intersect(sd, org, dir, 0.0, INFINITY, &h) && h.mesh == floor_mesh) floor_first++;
    static path_coord coords[512];
    int n = ev.n_coords;
    if (n > 512) continue;
    memcpy(coords, ev.coords, (size_t)n * sizeof *coords);
    path_eval eu;
    path_vec_sampler_rewind(&vs);
    path_eval_pt(su, &rs, &vs.base, 1, ps, &eu, NULL);
    int same = eu.grad_ok && eu.n_coords == n && pg_rgb_rel_equal(eu.value, ev.value, 1e-9);
    for (int k = 0; same && k < n; k++)
      same = fabs(eu.coords[k].dlum - coords[k].dlum) <=
             1e-7 * (fabs(coords[k].dlum) + ev.lum);
    if (!same)
      print_message("path %d: wound up %.10g, wound down %.10g\n", tries, eu.lum, ev.lum);
    winding_same += same;

    /* Central differences (pg_fd_check evaluates again into ps). */
    path_vec_sampler_rewind(&vs);
    path_eval_pt(sd, &rs, &vs.base, 1, ps, &ev, NULL);
    pg_fd_check(sd, ps, &rs, &vs, PG_PT, &ev, &st);
  }
  path_vec_sampler_free(&vs);
  print_message("pt: %d paths tried, %d mismatched with pt_li; %d non-zero (%d seeing the floor "
                "first), %d the same with the floor wound up\n",
                tries, mismatched, nonzero, floor_first, winding_same);
  print_message("pt gradient: %d paths, %d components (%d non-trivial), %d passed, %d skipped "
                "(topology)\n",
                st.paths, st.components, st.nontrivial, st.passed, st.skipped_topology);
  assert_int_equal(mismatched, 0);
  assert_int_equal(st.paths, 250);
  assert_int_equal(winding_same, nonzero);
  assert_true(floor_first >= 150);
  assert_true(st.components > 2500);
  assert_true(st.nontrivial > st.components / 4);
  assert_true(st.passed >= 0.995 * st.components);
  path_scratch_destroy(ps);
  scene_destroy(sd);
  scene_destroy(su);
}

/* path_eval_bdpt gives bdpt_connect's value, and gradients that central
 * differences confirm, over strategies of every kind (the light's
 * emission and direct sampling from the disagreeing emitter included). */
static void test_bdpt_gradient(void **state) {
  (void)state;
  scene *sd = grad_scene("gfloor_down.obj");
  path_scratch *ps;
  lmc_error err;
  assert_int_equal(path_scratch_create(&ps, &err), LMC_OK);
  render_settings rs = sd->settings;
  rs.rrdepth = 3;
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 37, NULL);
  rng r;
  rng_seed(&r, 13, 3);
  pg_fd_stats st = {0};
  int paths[PG_GROUPS] = {0}, nonzero[PG_GROUPS] = {0};
  int tries = 0, mismatched = 0;
  while (st.paths < 240 && tries < 200000) {
    tries++;
    pg_strategy sg = pg_random_strategy(&r, rs.maxdepth);
    if (paths[pg_group(sg)] >= 60) continue;
    path_vec_sampler_clear(&vs);
    path_eval ev;
    path_eval_bdpt(sd, &rs, &vs.base, sg.s, sg.t, 1, ps, &ev, NULL);
    double rx, ry;
    rgb L = pg_bdpt_reference(sd, &rs, &vs, sg, &rx, &ry);
    int ok = pg_rgb_rel_equal(L, ev.value, 1e-9);
    if (sg.t == 1 && !rgb_is_black(L))
      ok = ok && pg_rel_equal(rx, ev.rx, 1e-9) && pg_rel_equal(ry, ev.ry, 1e-9);
    mismatched += !ok;
    nonzero[pg_group(sg)] += !rgb_is_black(L);
    if (!ev.grad_ok || !(ev.lum > 0.0)) continue;
    /* Exactly the continuous coordinates got a tangent slot. */
    assert_int_equal(ev.n_diff, pg_bdpt_n_diff(sg));
    path_vec_sampler_rewind(&vs);
    path_eval_bdpt(sd, &rs, &vs.base, sg.s, sg.t, 1, ps, &ev, NULL);
    pg_fd_check(sd, ps, &rs, &vs, sg, &ev, &st);
    paths[pg_group(sg)]++;
  }
  path_vec_sampler_free(&vs);
  print_message("bdpt: %d strategies tried, %d mismatched with bdpt_connect\n", tries,
                mismatched);
  for (int g = 0; g < PG_GROUPS; g++)
    print_message("    %-22s %4d non-zero, %3d gradients checked\n", pg_group_name(g), nonzero[g],
                  paths[g]);
  print_message("bdpt gradient: %d paths, %d components (%d non-trivial, %d raster), %d passed, "
                "%d skipped (topology)\n",
                st.paths, st.components, st.nontrivial, st.raster, st.passed,
                st.skipped_topology);
  assert_int_equal(mismatched, 0);
  assert_int_equal(st.paths, 240);
  for (int g = 0; g < PG_GROUPS; g++) assert_int_equal(paths[g], 60);
  assert_true(st.components > 2000);
  assert_true(st.nontrivial > st.components / 4);
  assert_true(st.raster >= 100);
  assert_true(st.passed >= 0.995 * st.components);
  path_scratch_destroy(ps);
  scene_destroy(sd);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_hit_normals),      cmocka_unit_test(test_floor_renders),
      cmocka_unit_test(test_emitter_sampling), cmocka_unit_test(test_emitter_renders),
      cmocka_unit_test(test_pt_gradient),      cmocka_unit_test(test_bdpt_gradient),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
