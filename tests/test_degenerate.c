/*
 * test_degenerate.c: degenerate input gives a warning or a clear error
 * naming the file and line, never a crash or a NaN image (issue 6).
 *
 * Each case writes a small scene (and its mesh) into a private temporary
 * folder and loads it with scene_load_xml. The element at fault always
 * sits on line DG_LINE of the scene file, so every message must carry
 * "<scene>.xml:DG_LINE". Cases that must fail check the status, the error's
 * file and line and a word of the message. Cases that load with a warning
 * capture stderr while loading (the warning must name file and line), then
 * render a few samples with pt and with bdpt and check that every pixel of
 * the developed image is finite and that no sample had to be dropped.
 *
 * Geometry: zero-area triangles (dropped), NaN and Inf vertices (errors),
 * indices out of range in OBJ and PLY (errors), an empty mesh and a mesh
 * whose triangles are all degenerate (left out, also with an area emitter
 * on it). Parameters: negative and zero roughness (errors), IOR 1 for
 * dielectric, roughdielectric and plastic (warnings; renders finite), zero
 * or negative film size (errors), fov 0, 180 and negative (errors), fov
 * just below 180 (loads, finite).
 */
#define _POSIX_C_SOURCE 200809L
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "render/integrators/integrator.h"
#include "render/io/io.h"
#include "test_util.h"
#include "tmp_dir.h"

#define DG_LINE 6

static char dg_dir[256];

/* Writes text to dg_dir/name. */
static void dg_write(const char *name, const char *text) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s", dg_dir, name);
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  assert_int_equal(fclose(f), 0);
}

/* A scene whose line DG_LINE is `element`; fov and film size as given.
 * An area light behind the scene keeps the image from being black. */
static void dg_scene(const char *name, const char *element, const char *fov, const char *width,
                     const char *height) {
  char text[4096];
  snprintf(text, sizeof text,
           "<scene version=\"0.5.0\">\n"
           " <sensor type=\"perspective\"><float name=\"fov\" value=\"%s\"/>\n"
           "  <transform name=\"toWorld\"><lookat origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/></transform>\n"
           "  <film type=\"hdrfilm\"><integer name=\"width\" value=\"%s\"/><integer name=\"height\" value=\"%s\"/></film></sensor>\n"
           " <shape type=\"rectangle\"><transform name=\"toWorld\"><translate z=\"-1\"/><scale value=\"3\"/></transform><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>\n"
           " %s\n"
           " <emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"0\" z=\"4\"/><spectrum name=\"intensity\" value=\"3\"/></emitter>\n"
           "</scene>\n",
           fov, width, height, element);
  dg_write(name, text);
}

/* Loads dg_dir/name with stderr captured into `log` (size bytes). */
static lmc_status dg_load(const char *name, scene **s, lmc_error *err, char *log, size_t size) {
  char path[512], log_path[512];
  snprintf(path, sizeof path, "%s/%s", dg_dir, name);
  snprintf(log_path, sizeof log_path, "%s/stderr.txt", dg_dir);
  fflush(stderr);
  int saved = dup(STDERR_FILENO);
  FILE *lf = fopen(log_path, "w+");
  assert_non_null(lf);
  dup2(fileno(lf), STDERR_FILENO);
  lmc_error_clear(err);
  lmc_status st = scene_load_xml(path, NULL, 0, s, err);
  fflush(stderr);
  dup2(saved, STDERR_FILENO);
  close(saved);
  rewind(lf);
  size_t n = fread(log, 1, size - 1, lf);
  log[n] = '\0';
  fclose(lf);
  return st;
}

/* The scene must fail to load, with the error at name:DG_LINE and `word`
 * in the message. */
static void dg_expect_error(const char *name, const char *word) {
  scene *s = NULL;
  lmc_error err;
  char log[4096];
  lmc_status st = dg_load(name, &s, &err, log, sizeof log);
  if (st == LMC_OK) {
    print_error("%s loaded, expected an error about '%s'\n", name, word);
    scene_destroy(s);
    fail();
  }
  assert_null(s);
  char msg[2048];
  lmc_error_format(&err, msg, sizeof msg);
  char where[300];
  snprintf(where, sizeof where, "%s:%d:", name, DG_LINE);
  if (!strstr(msg, where) || !strstr(msg, word)) {
    print_error("error '%s' should contain '%s' and '%s'\n", msg, where, word);
    fail();
  }
}

/* Renders s with `integrator` (4 spp, 2 threads); every pixel finite, no
 * sample dropped, and (when `lit`) some light seen. */
static void dg_render_finite(const scene *s, const char *integrator, int lit) {
  render_settings rs = render_settings_default();
  snprintf(rs.integrator, sizeof rs.integrator, "%s", integrator);
  rs.spp = 4;
  rs.set |= SET_SPP;
  rs.threads = 2;
  rs.quiet = 1;
  rs.maxdepth = 6;
  film f;
  render_stats st;
  lmc_error err;
  assert_int_equal(render_run(s, &rs, &f, &st, &err), LMC_OK);
  lmc_image img;
  assert_int_equal(film_develop(&f, &img, &err), LMC_OK);
  int64_t n = (int64_t)img.width * img.height * img.channels, bad = 0;
  double sum = 0.0;
  for (int64_t i = 0; i < n; i++) {
    if (!isfinite(img.data[i])) bad++;
    else sum += img.data[i];
  }
  assert_int_equal(bad, 0);
  if (lit) assert_true(sum > 0.0); /* the light behind is seen: the render did something */
  assert_int_equal(st.nan_samples, 0);
  image_free(&img);
  film_free(&f);
}

/* The scene must load with a warning at name:DG_LINE containing `word`,
 * and render finite images with pt and bdpt. */
static void dg_expect_warning(const char *name, const char *word) {
  scene *s = NULL;
  lmc_error err;
  char log[4096];
  int before = lmc_warning_count();
  lmc_status st = dg_load(name, &s, &err, log, sizeof log);
  if (st != LMC_OK) {
    char msg[2048];
    lmc_error_format(&err, msg, sizeof msg);
    print_error("%s failed to load: %s\n", name, msg);
    fail();
  }
  assert_true(lmc_warning_count() > before);
  char where[300];
  snprintf(where, sizeof where, "%s:%d:", name, DG_LINE);
  if (!strstr(log, where) || !strstr(log, word)) {
    print_error("warnings '%s' should contain '%s' and '%s'\n", log, where, word);
    fail();
  }
  dg_render_finite(s, "pt", 1);
  dg_render_finite(s, "bdpt", 1);
  scene_destroy(s);
}

static const char *dg_obj_shape(const char *file, char *buf, size_t size, int emitter) {
  snprintf(buf, size, "<shape type=\"obj\"><string name=\"filename\" value=\"%s\"/>%s</shape>",
           file, emitter ? "<emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter>" : "");
  return buf;
}

/* ---- geometry ------------------------------------------------------------ */

static void test_zero_area_triangles(void **state) {
  (void)state;
  char b[512];
  dg_write("zero_area.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n");
  dg_scene("zero_area.xml", dg_obj_shape("zero_area.obj", b, sizeof b, 0), "45", "16", "12");
  dg_expect_warning("zero_area.xml", "zero-area");
}

static void test_all_degenerate_mesh(void **state) {
  (void)state;
  char b[512];
  dg_write("line.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
  dg_scene("line.xml", dg_obj_shape("line.obj", b, sizeof b, 0), "45", "16", "12");
  dg_expect_warning("line.xml", "no triangles");
  /* With an area emitter on it: the light is left out too (it has no area). */
  dg_scene("line_lamp.xml", dg_obj_shape("line.obj", b, sizeof b, 1), "45", "16", "12");
  dg_expect_warning("line_lamp.xml", "emitter on an empty mesh");
}

static void test_empty_mesh(void **state) {
  (void)state;
  char b[512];
  dg_write("empty.obj", "# no geometry at all\n");
  dg_scene("empty.xml", dg_obj_shape("empty.obj", b, sizeof b, 0), "45", "16", "12");
  dg_expect_warning("empty.xml", "no triangles");
  dg_write("empty.ply",
           "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
           "property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n");
  dg_scene("empty_ply.xml",
           "<shape type=\"ply\"><string name=\"filename\" value=\"empty.ply\"/></shape>", "45", "16",
           "12");
  dg_expect_warning("empty_ply.xml", "no triangles");
}

static void test_nonfinite_vertices(void **state) {
  (void)state;
  char b[512];
  dg_write("nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n");
  dg_scene("nan.xml", dg_obj_shape("nan.obj", b, sizeof b, 0), "45", "16", "12");
  dg_expect_error("nan.xml", "non-finite position");
  dg_write("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 -inf 0\nf 1 2 3\n");
  dg_scene("inf.xml", dg_obj_shape("inf.obj", b, sizeof b, 0), "45", "16", "12");
  dg_expect_error("inf.xml", "non-finite position");
  /* A float overflow (1e39 does not fit a float) is an Inf too. */
  dg_write("big.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n");
  dg_scene("big.xml", dg_obj_shape("big.obj", b, sizeof b, 0), "45", "16", "12");
  dg_expect_error("big.xml", "non-finite position");
}

static void test_index_out_of_range(void **state) {
  (void)state;
  char b[512];
  dg_write("oob.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
  dg_scene("oob.xml", dg_obj_shape("oob.obj", b, sizeof b, 0), "45", "16", "12");
  dg_expect_error("oob.xml", "out of range");
  dg_write("oob.ply",
           "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
           "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
           "0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n");
  dg_scene("oob_ply.xml", "<shape type=\"ply\"><string name=\"filename\" value=\"oob.ply\"/></shape>",
           "45", "16", "12");
  dg_expect_error("oob_ply.xml", "out of range");
}

/* ---- parameters ------------------------------------------------------------ */

static void test_bad_roughness(void **state) {
  (void)state;
  dg_scene("negrough.xml",
           "<shape type=\"sphere\"><bsdf type=\"roughconductor\"><float name=\"alpha\" value=\"-0.3\"/></bsdf></shape>",
           "45", "16", "12");
  dg_expect_error("negrough.xml", "alpha");
  dg_scene("negrough_d.xml",
           "<shape type=\"sphere\"><bsdf type=\"roughdielectric\"><float name=\"alpha\" value=\"-1\"/></bsdf></shape>",
           "45", "16", "12");
  dg_expect_error("negrough_d.xml", "alpha");
  dg_scene("zerorough.xml",
           "<shape type=\"sphere\"><bsdf type=\"roughconductor\"><float name=\"alpha\" value=\"0\"/></bsdf></shape>",
           "45", "16", "12");
  dg_expect_error("zerorough.xml", "alpha");
}

static void test_ior_one(void **state) {
  (void)state;
  static const char *const types[] = {"dielectric", "roughdielectric", "plastic"};
  for (int i = 0; i < 3; i++) {
    char element[512], name[64];
    snprintf(element, sizeof element,
             "<shape type=\"sphere\"><bsdf type=\"%s\"><float name=\"intIOR\" value=\"1\"/>"
             "<float name=\"extIOR\" value=\"1\"/></bsdf></shape>",
             types[i]);
    snprintf(name, sizeof name, "ior1_%s.xml", types[i]);
    dg_scene(name, element, "45", "16", "12");
    dg_expect_warning(name, "eta = 1");
  }
}

/* As dg_expect_error, for elements on another line than DG_LINE (the
 * sensor's fov is on line 2, the film's size on line 4). */
static void dg_expect_error_at(const char *name, int line, const char *word) {
  scene *s = NULL;
  lmc_error err;
  char log[4096];
  assert_int_not_equal(dg_load(name, &s, &err, log, sizeof log), LMC_OK);
  char msg[2048], where[300];
  lmc_error_format(&err, msg, sizeof msg);
  snprintf(where, sizeof where, "%s:%d:", name, line);
  if (!strstr(msg, where) || !strstr(msg, word)) {
    print_error("error '%s' should contain '%s' and '%s'\n", msg, where, word);
    fail();
  }
}

static void test_bad_film_size(void **state) {
  (void)state;
  dg_scene("film_w0.xml", "<shape type=\"sphere\"/>", "45", "0", "12");
  dg_expect_error_at("film_w0.xml", 4, "film size");
  dg_scene("film_h0.xml", "<shape type=\"sphere\"/>", "45", "16", "0");
  dg_expect_error_at("film_h0.xml", 4, "film size");
  dg_scene("film_neg.xml", "<shape type=\"sphere\"/>", "45", "-4", "12");
  dg_expect_error_at("film_neg.xml", 4, "film size");
}

static void test_bad_fov(void **state) {
  (void)state;
  static const char *const bad[] = {"0", "180", "-10", "200"};
  for (int i = 0; i < 4; i++) {
    char name[64];
    snprintf(name, sizeof name, "fov_%d.xml", i);
    dg_scene(name, "<shape type=\"sphere\"/>", bad[i], "16", "12");
    dg_expect_error_at(name, 2, "fov");
  }
  /* Just inside the range: loads (no warning needed) and renders finite. */
  dg_scene("fov_wide.xml", "<shape type=\"sphere\"/>", "179.5", "16", "12");
  scene *s = NULL;
  lmc_error err;
  char log[4096];
  assert_int_equal(dg_load("fov_wide.xml", &s, &err, log, sizeof log), LMC_OK);
  /* At this width a pixel spans far more than the scene: it may well be black. */
  dg_render_finite(s, "pt", 0);
  dg_render_finite(s, "bdpt", 0);
  scene_destroy(s);
}

/* Removes the temporary folder's files and the folder. */
static int dg_teardown(void **state) {
  (void)state;
  return tmp_dir_remove(dg_dir);
}

static int dg_setup(void **state) {
  (void)state;
  return tmp_dir_make(dg_dir, sizeof dg_dir, "lmc-degenerate");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_zero_area_triangles), cmocka_unit_test(test_all_degenerate_mesh),
      cmocka_unit_test(test_empty_mesh),          cmocka_unit_test(test_nonfinite_vertices),
      cmocka_unit_test(test_index_out_of_range),  cmocka_unit_test(test_bad_roughness),
      cmocka_unit_test(test_ior_one),             cmocka_unit_test(test_bad_film_size),
      cmocka_unit_test(test_bad_fov),
  };
  return cmocka_run_group_tests(tests, dg_setup, dg_teardown);
}
