/*
 * test_tex_filter.c: texture filtering in a scene (texture.h's footprints,
 * scene_tex_footprint, the loader's bitmap parameters, the path tracer's
 * camera hits).
 *
 * What is checked:
 * - The footprint of a camera hit on a square facing the camera
 *   (tests/data/texfilter/plane.xml): the film maps linearly onto the
 *   plane, so every pixel spans 2 d tan(fov / 2) / W in x and y, and
 *   |du/dx| = |dv/dy| = that over the square's width 2.4, the cross terms
 *   0 (to 1e-6 relative: the mesh stores its positions in floats). Signs:
 *   the film's x grows to the right, towards camera space's -x, which
 *   lookat turns to world +x here, along u; its y grows downwards, towards
 *   world -y, against v: du/dx > 0, dv/dy < 0.
 * - The loader: filterType and wrapMode(U/V) by Mitsuba's names, the MIP
 *   levels stored after the image (trilinear, ewa) or not (bilinear,
 *   nearest), maxAnisotropy; an unknown filter or wrap mode, or an
 *   anisotropy below 1, is an error naming the file and line.
 * - The path tracer filters its camera hits: one sample per pixel of a
 *   checker of single texels (0 and 1), each pixel 1.46 texels wide. With
 *   EWA or trilinear each pixel reads about the local mean 1/2; with
 *   bilinear it reads the checker at a random point, whose spread is a
 *   sizeable fraction of 1/4. The same seed draws the same numbers, so the
 *   renders differ in the texture alone: the filtered images' variance
 *   across pixels is below half of the bilinear one's, and their means
 *   agree with it within 4 standard errors of the paired difference (the
 *   filters keep the mean; the checker's mean is 1/2).
 * Each test counts its checks and asserts the count.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "test_util.h"

#include "render/image.h"
#include "render/integrators/integrator.h"
#include "render/io/io.h"
#include "render/scene.h"
#include "load_scene.h"

#define TEXFILE LMC_TEST_TMP "/lmc_tex_filter_checker.png"
#define PLANE "data/texfilter/plane.xml"

/* The 64 x 64 checker of single texels, 0 and 1. */
static int write_checker(void **state) {
  (void)state;
  lmc_image img;
  lmc_error err;
  if (image_init(&img, 64, 64, 3, &err)) return -1;
  for (int y = 0; y < 64; y++)
    for (int x = 0; x < 64; x++)
      for (int c = 0; c < 3; c++) img.data[3 * (y * 64 + x) + c] = (float)((x + y) % 2);
  lmc_status st = image_write_png(TEXFILE, &img, 1.0, &err);
  image_free(&img);
  return st == LMC_OK ? 0 : -1;
}

static scene *load_plane(const char *filter) {
  char def[64];
  snprintf(def, sizeof def, "filter=%s", filter);
  const char *defs[2] = {"texfile=" TEXFILE, def};
  scene *s = try_load_scene_defs(PLANE, defs, 2);
  assert_non_null(s);
  return s;
}

static void test_footprint(void **state) {
  (void)state;
  int checks = 0;
  scene *s = load_plane("ewa");
  /* One pixel on the plane, in texture coordinates. */
  double step = 2.0 * 2.0 * tan(20.0 * 3.14159265358979323846 / 180.0) / 32.0 / 2.4;
  rng r;
  rng_seed(&r, 5, 0);
  for (int i = 0; i < 50; i++) {
    double rx = 32.0 * rng_uniform(&r), ry = 32.0 * rng_uniform(&r);
    vec3 org, dir, o, dx, dy;
    camera_generate_ray(&s->cam, rx, ry, &org, &dir);
    camera_generate_ray(&s->cam, rx + 1.0, ry, &o, &dx);
    camera_generate_ray(&s->cam, rx, ry + 1.0, &o, &dy);
    surface_hit h;
    assert_true(scene_intersect(s, org, dir, 0.0, INFINITY, &h));
    tex_footprint fp;
    assert_true(scene_tex_footprint(s, &h, org, dx, dy, &fp));
    assert_near(fp.dudx, step, 1e-6 * step);
    assert_near(fp.dvdy, -step, 1e-6 * step);
    assert_near(fp.dvdx, 0.0, 1e-6 * step);
    assert_near(fp.dudy, 0.0, 1e-6 * step);
    checks += 4;
  }
  scene_destroy(s);
  assert_int_equal(checks, 200);
}

/* The diffuse texture of the plane's only BSDF that has one. */
static const texture *plane_texture(const scene *s) {
  for (int i = 0; i < s->n_bsdfs; i++)
    if (s->bsdfs[i].diffuse.type == TEX_BITMAP) return &s->bsdfs[i].diffuse;
  fail();
  return NULL;
}

static void test_loader_params(void **state) {
  (void)state;
  int checks = 0;
  const char *names[4] = {"ewa", "trilinear", "bilinear", "nearest"};
  const tex_filter want[4] = {TEX_FILTER_EWA, TEX_FILTER_TRILINEAR, TEX_FILTER_BILINEAR,
                              TEX_FILTER_NEAREST};
  for (int k = 0; k < 4; k++) {
    scene *s = load_plane(names[k]);
    const texture *t = plane_texture(s);
    assert_int_equal(t->filter, want[k]);
    /* 64 x 64: 7 levels, stored after the image, for the MIP filters. */
    int levels = k < 2 ? 7 : 1;
    assert_int_equal(t->levels, levels);
    assert_int_equal(s->n_images, levels);
    assert_int_equal(s->tex_filtered, k < 2);
    assert_true(t->max_aniso == 20.0 && t->wrap_u == TEX_WRAP_REPEAT);
    if (levels > 1) assert_int_equal(t->image[6].width, 1);
    checks += 5;
    scene_destroy(s);
  }
  /* Wrap modes, anisotropy and errors, on a scene written here. */
  static const struct {
    const char *params;
    int ok;
    tex_wrap u, v;
  } cases[] = {
      {"<string name=\"wrapMode\" value=\"clamp\"/>", 1, TEX_WRAP_CLAMP, TEX_WRAP_CLAMP},
      {"<string name=\"wrapMode\" value=\"mirror\"/><string name=\"wrapModeV\" value=\"zero\"/>", 1,
       TEX_WRAP_MIRROR, TEX_WRAP_ZERO},
      {"<string name=\"wrapModeU\" value=\"black\"/><string name=\"wrapModeV\" value=\"one\"/>", 1,
       TEX_WRAP_ZERO, TEX_WRAP_ONE},
      {"<string name=\"filterType\" value=\"bicubic\"/>", 0, 0, 0},
      {"<string name=\"wrapMode\" value=\"wrap\"/>", 0, 0, 0},
      {"<float name=\"maxAnisotropy\" value=\"0.5\"/>", 0, 0, 0},
  };
  const char *path = LMC_TEST_TMP "/lmc_tex_filter_params.xml";
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f,
            "<scene version=\"0.6.0\">\n"
            "<sensor type=\"perspective\"><film type=\"hdrfilm\"/></sensor>\n"
            "<emitter type=\"constant\"/>\n"
            "<shape type=\"rectangle\"><bsdf type=\"diffuse\">\n"
            "<texture type=\"bitmap\" name=\"reflectance\">\n"
            "<string name=\"filename\" value=\"%s\"/>\n"
            "%s\n"
            "</texture></bsdf></shape></scene>\n",
            TEXFILE, cases[i].params);
    fclose(f);
    scene *s = NULL;
    lmc_error err;
    lmc_error_clear(&err);
    lmc_status st = scene_load_xml(path, NULL, 0, &s, &err);
    if (cases[i].ok) {
      assert_int_equal(st, LMC_OK);
      const texture *t = plane_texture(s);
      assert_int_equal(t->wrap_u, cases[i].u);
      assert_int_equal(t->wrap_v, cases[i].v);
      scene_destroy(s);
    } else {
      /* The error names the file and the parameter's line (line 7). */
      assert_int_equal(st, LMC_EPARSE);
      assert_non_null(strstr(err.file, "lmc_tex_filter_params.xml"));
      assert_int_equal(err.line, 7);
    }
    checks++;
  }
  assert_int_equal(checks, 20 + 6);
}

/* The per-pixel values (red) of a 1-spp pt render of the plane. */
static double *render_plane(const char *filter) {
  scene *s = load_plane(filter);
  render_settings rs = s->settings;
  snprintf(rs.integrator, sizeof rs.integrator, "pt");
  rs.spp = 1;
  rs.set |= SET_SPP;
  rs.threads = 1;
  rs.seed = 3;
  rs.quiet = 1;
  film f;
  render_stats rst;
  lmc_error err;
  assert_int_equal(render_run(s, &rs, &f, &rst, &err), LMC_OK);
  lmc_image img;
  assert_int_equal(film_develop(&f, &img, &err), LMC_OK);
  double *v = malloc(32 * 32 * sizeof *v);
  assert_non_null(v);
  for (int i = 0; i < 32 * 32; i++) v[i] = img.data[3 * i];
  image_free(&img);
  film_free(&f);
  scene_destroy(s);
  return v;
}

static void test_pt_filters_camera_hits(void **state) {
  (void)state;
  int checks = 0;
  const int n = 32 * 32;
  double *bil = render_plane("bilinear");
  double vb = 0.0, mb = 0.0;
  for (int i = 0; i < n; i++) mb += bil[i] / n;
  for (int i = 0; i < n; i++) vb += (bil[i] - mb) * (bil[i] - mb) / (n - 1);
  const char *filters[2] = {"ewa", "trilinear"};
  for (int k = 0; k < 2; k++) {
    double *flt = render_plane(filters[k]);
    double mf = 0.0, vf = 0.0, md = 0.0, vd = 0.0;
    for (int i = 0; i < n; i++) mf += flt[i] / n, md += (flt[i] - bil[i]) / n;
    for (int i = 0; i < n; i++) {
      vf += (flt[i] - mf) * (flt[i] - mf) / (n - 1);
      vd += (flt[i] - bil[i] - md) * (flt[i] - bil[i] - md) / (n - 1);
    }
    double se = sqrt(vd / n);
    if (!(vf < 0.5 * vb) || !(fabs(md) < 4.0 * se))
      print_error("%s: variance %g (bilinear %g), mean difference %g (se %g)\n", filters[k], vf,
                  vb, md, se);
    assert_true(vf < 0.5 * vb);
    assert_true(fabs(md) < 4.0 * se);
    checks += 2;
    free(flt);
  }
  free(bil);
  assert_int_equal(checks, 4);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_footprint),
      cmocka_unit_test(test_loader_params),
      cmocka_unit_test(test_pt_filters_camera_hits),
  };
  return cmocka_run_group_tests(tests, write_checker, NULL);
}
