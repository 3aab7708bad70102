/*
 * test_bsdf_models.c: the BSDF models as records (bsdf_model.h) and their
 * registry (bsdf_models.c).
 *
 * What is checked:
 *   - the registry: every model is found by its name and by no other, no
 *     two share a name, an unknown name gives NULL (and bsdf_init_defaults
 *     returns 0 with a diffuse model); the count is the length of Mitsuba's
 *     list below, each of whose names is registered;
 *   - each record is whole: every operation in both forms, eval_pdf in
 *     both forms or in neither, a lobe, a roughness only for a
 *     model without delta lobes, a model that refracts has transmission;
 *     the front end reads the record (bsdf_flags, bsdf_is_delta,
 *     bsdf_is_rough, bsdf_is);
 *   - every model with a non-delta lobe is among the chi-square and
 *     inverse configurations (bsdf_configs.h), so a new model cannot skip
 *     the sampling tests;
 *   - Mitsuba 0.6's defaults for the models that change the common ones;
 *   - the loader finds every registered model by its name in a scene and
 *     the model reads its own parameters (difftrans's transmittance);
 *     a bad parameter fails naming its line.
 * Each test counts its checks and asserts the count.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "test_util.h"

#include "bsdf_configs.h"
#include "load_scene.h"
#include "render/bsdf/bsdf_model.h"
#include "render/scene.h"

/* The models of Mitsuba 0.6 that lmc registers (bsdf.h lists them). */
static const char *const mitsuba_names[] = {
    "diffuse",        "phong",   "conductor",    "roughconductor", "dielectric", "roughdielectric",
    "thindielectric", "plastic", "roughplastic", "roughdiffuse",   "ward",       "difftrans",
    "blendbsdf"};
#define N_NAMES ((int)(sizeof mitsuba_names / sizeof mitsuba_names[0]))

static void test_registry(void **state) {
  (void)state;
  int n, checks = 0;
  const bsdf_model *const *list = bsdf_model_list(&n);
  assert_int_equal(n, N_NAMES);
  for (int i = 0; i < n; i++) {
    assert_non_null(list[i]->name);
    assert_ptr_equal(bsdf_model_find(list[i]->name), list[i]);
    for (int j = 0; j < i; j++) assert_true(strcmp(list[i]->name, list[j]->name) != 0);
    checks++;
  }
  for (int k = 0; k < N_NAMES; k++) {
    const bsdf_model *m = bsdf_model_find(mitsuba_names[k]);
    assert_non_null(m);
    bsdf b;
    assert_int_equal(bsdf_init_defaults(&b, mitsuba_names[k]), 1);
    assert_ptr_equal(b.model, m);
    assert_true(bsdf_is(&b, mitsuba_names[k]));
    checks++;
  }
  assert_null(bsdf_model_find("blendbsdf-not-a-model"));
  assert_null(bsdf_model_find(NULL));
  bsdf b;
  assert_int_equal(bsdf_init_defaults(&b, "no-such-model"), 0);
  assert_true(bsdf_is(&b, "diffuse"));
  assert_int_equal(checks, 2 * N_NAMES);
}

static void test_records_whole(void **state) {
  (void)state;
  int n, checks = 0;
  /* Nested BSDFs for the models made of others: two diffuse ones. */
  static bsdf parts[2];
  bsdf_init_defaults(&parts[0], "diffuse");
  bsdf_init_defaults(&parts[1], "diffuse");
  const bsdf_model *const *list = bsdf_model_list(&n);
  for (int i = 0; i < n; i++) {
    const bsdf_model *m = list[i];
    assert_non_null(m->eval);
    assert_non_null(m->pdf);
    assert_non_null(m->sample);
    assert_non_null(m->invert);
    assert_non_null(m->eval_ad);
    assert_non_null(m->pdf_ad);
    assert_non_null(m->sample_ad);
    assert_int_equal(m->eval_pdf != NULL, m->eval_pdf_ad != NULL);
    assert_true(m->flags & (BSDF_REFLECTION | BSDF_TRANSMISSION));
    if (m->roughness) assert_false(m->flags & BSDF_DELTA);
    if (m->refracts) assert_true(m->flags & BSDF_TRANSMISSION);
    if (m->chain) assert_true(m->flags & BSDF_GLOSSY);
    /* The front end answers from the record. */
    bsdf b;
    bsdf_init_model(&b, m);
    b.nested_bsdf[0] = &parts[0], b.nested_bsdf[1] = &parts[1];
    int lobes = m->lobes ? m->lobes(&b) : m->flags;
    assert_int_equal(lobes & ~m->flags, 0); /* flags: every lobe it can have */
    assert_int_equal(bsdf_flags(&b), lobes);
    assert_int_equal(bsdf_is_delta(&b), (lobes & (BSDF_DIFFUSE_LOBE | BSDF_GLOSSY)) == 0);
    assert_int_equal(bsdf_is_rough(&b, 0.0), m->roughness != NULL);
    b.masked = 1;
    assert_int_equal(bsdf_flags(&b), lobes | BSDF_TRANSMISSION | BSDF_DELTA);
    assert_false(bsdf_is_rough(&b, 0.0));
    checks++;
  }
  assert_int_equal(checks, N_NAMES);
}

static void test_sampling_coverage(void **state) {
  (void)state;
  static config cfg[MAX_CONFIGS];
  int nc = make_configs(cfg), n, covered = 0, needed = 0;
  const bsdf_model *const *list = bsdf_model_list(&n);
  for (int i = 0; i < n; i++) {
    if (!(list[i]->flags & (BSDF_DIFFUSE_LOBE | BSDF_GLOSSY))) continue;
    needed++;
    int found = 0;
    for (int k = 0; k < nc; k++) found += cfg[k].b.model == list[i];
    if (!found) print_error("model %s has no chi-square configuration\n", list[i]->name);
    covered += found > 0;
  }
  assert_int_equal(needed, 10); /* all but the smooth conductor and dielectrics */
  assert_int_equal(covered, needed);
}

static void test_defaults(void **state) {
  (void)state;
  const double air = 1.000277;
  bsdf b;
  int checks = 0;
  bsdf_init_defaults(&b, "phong");
  assert_true(tex_mean(&b.specular).g == 0.2);
  checks++;
  assert_true(b.exponent == 30.0);
  checks++;
  bsdf_init_defaults(&b, "ward");
  assert_true(tex_mean(&b.specular).g == 0.2);
  checks++;
  assert_int_equal(b.variant, WARD_BALANCED);
  checks++;
  const char *glass[] = {"dielectric", "roughdielectric", "thindielectric"};
  for (int k = 0; k < 3; k++) {
    bsdf_init_defaults(&b, glass[k]);
    assert_near(b.eta, 1.5046 / air, 1e-15);
    checks++;
  }
  const char *plastics[] = {"plastic", "roughplastic"};
  for (int k = 0; k < 2; k++) {
    bsdf_init_defaults(&b, plastics[k]);
    assert_near(b.eta, 1.49 / air, 1e-15);
    checks++;
  }
  bsdf_init_defaults(&b, "roughdiffuse");
  assert_true(b.alpha == 0.2);
  checks++;
  bsdf_init_defaults(&b, "roughconductor");
  assert_true(b.alpha == 0.1);
  checks++;
  assert_int_equal(b.dist, MF_BECKMANN);
  checks++;
  /* Cu against air: Mitsuba's conductor default. */
  assert_near(b.cond_eta.r, 0.2004376970 / air, 1e-12);
  checks++;
  assert_int_equal(checks, 13);
}

/* A one-shape scene whose sphere has the BSDF element `element`. */
static scene *scene_with(const char *element, const char *tag) {
  char xml[1024];
  snprintf(xml, sizeof xml,
           "<scene version=\"0.6.0\">\n"
           "  <sensor type=\"perspective\"><film type=\"hdrfilm\">"
           "<integer name=\"width\" value=\"4\"/><integer name=\"height\" value=\"4\"/>"
           "</film></sensor>\n"
           "  <shape type=\"sphere\">\n    %s\n  </shape>\n"
           "  <emitter type=\"constant\"/>\n"
           "</scene>\n",
           element);
  return try_load_scene_text(xml, tag);
}

static void test_loader(void **state) {
  (void)state;
  int n, checks = 0;
  const bsdf_model *const *list = bsdf_model_list(&n);
  for (int i = 0; i < n; i++) {
    char el[128];
    /* A model made of others gets two. */
    snprintf(el, sizeof el, "<bsdf type=\"%s\">%s</bsdf>", list[i]->name,
             list[i]->lobes ? "<bsdf type=\"diffuse\"/><bsdf type=\"roughconductor\"/>" : "");
    scene *s = scene_with(el, "models");
    assert_non_null(s);
    assert_int_equal(s->n_bsdfs, list[i]->lobes ? 3 : 1);
    assert_ptr_equal(s->bsdfs[s->meshes[0].bsdf].model, list[i]);
    scene_destroy(s);
    checks++;
  }
  scene *s = scene_with(
      "<bsdf type=\"difftrans\"><rgb name=\"transmittance\" value=\"0.3, 0.2, 0.1\"/></bsdf>",
      "difftrans");
  assert_non_null(s);
  rgb t = tex_mean(&s->bsdfs[0].transmittance);
  assert_true(t.r == 0.3 && t.g == 0.2 && t.b == 0.1);
  scene_destroy(s);
  /* A blend: its weight and its two BSDFs, linked to the scene's. */
  s = scene_with(
      "<bsdf type=\"blendbsdf\"><float name=\"weight\" value=\"0.25\"/>"
      "<bsdf type=\"diffuse\"/><bsdf type=\"dielectric\"/></bsdf>",
      "blend");
  assert_non_null(s);
  const bsdf *bl = &s->bsdfs[s->meshes[0].bsdf];
  assert_true(tex_mean(&bl->diffuse).g == 0.25);
  assert_true(bsdf_is(bl->nested_bsdf[0], "diffuse") && bsdf_is(bl->nested_bsdf[1], "dielectric"));
  assert_int_equal(bsdf_flags(bl),
                   BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_DIFFUSE_LOBE | BSDF_DELTA);
  scene_destroy(s);
  /* A blend of one BSDF, and one that contains itself: errors. */
  assert_null(scene_with("<bsdf type=\"blendbsdf\"><bsdf type=\"diffuse\"/></bsdf>", "blend1"));
  assert_null(scene_with(
      "<bsdf type=\"blendbsdf\" id=\"me\"><bsdf type=\"diffuse\"/><ref id=\"me\"/></bsdf>",
      "blendself"));
  /* A parameter out of range: an error naming the element's line. */
  assert_null(
      scene_with("<bsdf type=\"roughdiffuse\"><float name=\"alpha\" value=\"-1\"/></bsdf>", "bad"));
  checks++;
  assert_int_equal(checks, n + 1);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_registry),
      cmocka_unit_test(test_records_whole),
      cmocka_unit_test(test_sampling_coverage),
      cmocka_unit_test(test_defaults),
      cmocka_unit_test(test_loader),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
