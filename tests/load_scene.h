/*
 * load_scene.h: the tests' way of loading a scene: scene_load_xml on a
 * file (a path, one under the source tree, or XML text written to a
 * scratch file), the loader's file, line and message on stderr when it
 * fails. The try_ forms return NULL then (for fixtures, which return -1);
 * the others fail the test. The scene is the caller's (scene_destroy).
 * Include after <cmocka.h>.
 */
#ifndef LMC_TESTS_LOAD_SCENE_H
#define LMC_TESTS_LOAD_SCENE_H

#include <stdarg.h>
#include <stdio.h>
#include <unistd.h>

#include "render/io/io.h"

/* The scene at path with the <default> overrides defs[0 .. n_defs-1]
 * ("name=value"), or NULL. */
static inline scene *try_load_scene_defs(const char *path, const char *const *defs, int n_defs) {
  scene *s = NULL;
  lmc_error err;
  lmc_error_clear(&err);
  lmc_status st = scene_load_xml(path, defs, n_defs, &s, &err);
  if (st == LMC_OK) return s;
  fprintf(stderr, "%s: %s:%d: %s\n", path, err.file, err.line, err.msg);
  return NULL;
}

/* The scene at path, or NULL. */
static inline scene *try_load_scene(const char *path) { return try_load_scene_defs(path, NULL, 0); }

/* The scene of the XML text xml, written to a scratch file named after
 * tag (removed again), or NULL. */
static inline scene *try_load_scene_text(const char *xml, const char *tag) {
  char path[160];
  snprintf(path, sizeof path, "/tmp/lmc_test_%s_%d.xml", tag, (int)getpid());
  FILE *f = fopen(path, "w");
  if (!f) {
    fprintf(stderr, "%s: cannot write\n", path);
    return NULL;
  }
  fputs(xml, f);
  fclose(f);
  scene *s = try_load_scene(path);
  remove(path);
  return s;
}

/* The scene at path; the test fails when it does not load. */
static inline scene *load_scene(const char *path) {
  scene *s = try_load_scene(path);
  assert_non_null(s);
  return s;
}

/* The scene at LMC_SOURCE_DIR/<fmt with its arguments, as printf>, e.g.
 * load_source_scene("scenes/%s/scene.xml", folder); the test fails when it
 * does not load. */
static inline scene *load_source_scene(const char *fmt, ...) {
  char rel[1024], path[2048];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(rel, sizeof rel, fmt, ap);
  va_end(ap);
  snprintf(path, sizeof path, "%s/%s", LMC_SOURCE_DIR, rel);
  return load_scene(path);
}

/* One of the analytic scenes, tests/data/analytic/<name>. */
static inline scene *load_analytic_scene(const char *name) {
  return load_source_scene("tests/data/analytic/%s", name);
}

#ifdef LMC_RENDER_INTEGRATOR_H
/* s rendered by a pixel integrator (render_run: pt, bdpt, direct) on 2
 * threads with the scene's settings but these, developed into *OUT (the
 * caller's: image_free); the test fails when the render does, or takes
 * other than spp passes. */
static inline void render_image(const scene *s, const char *integrator, int sampler, int64_t spp,
                                uint64_t seed, lmc_image *OUT, render_stats *OUT_stats) {
  lmc_error err;
  render_settings rs = s->settings;
  snprintf(rs.integrator, sizeof rs.integrator, "%s", integrator);
  rs.spp = spp;
  rs.set |= SET_SPP;
  rs.threads = 2;
  rs.seed = seed;
  rs.sampler = sampler;
  rs.quiet = 1;
  film f;
  assert_int_equal(render_run(s, &rs, &f, OUT_stats, &err), LMC_OK);
  assert_int_equal(OUT_stats->passes, spp);
  assert_int_equal(film_develop(&f, OUT, &err), LMC_OK);
  film_free(&f);
}
#endif

#endif
