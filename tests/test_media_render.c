/*
 * test_media_render.c: rendering participating media (pt through media,
 * integrator.h's pt_li_media) against scenes whose pixel values are known
 * exactly (tests/data/media), and the scene's parts that media use.
 *
 *  slab.xml            an absorbing slab behind an index-matched boundary
 *                      in front of a uniform emitter: L exp(-sigma_a);
 *  furnace.xml         a closed box emitting L inwards, filled with fogs
 *                      that scatter and do not absorb (the camera's
 *                      medium, a sphere behind an index-matched boundary,
 *                      a glass sphere's interior): exactly L;
 *  single_scatter.xml  single scattering of a directional light through a
 *                      slab towards the camera (maxDepth 2): sigma_s p(0)
 *                      E exp(-sigma_t).
 * Every pixel of these scenes has the same expectation and the pixels are
 * independent, so the spread of their values gives the standard error of
 * the image mean; each channel's mean must lie within 5 SE (plus the
 * scene's stated geometric error) of the exact value: 3 scenes x 2
 * samplers x 3 channels = 18 comparisons, a false alarm about 1e-5.
 *
 * pt and bdpt render each, with both samplers. bdpt's subpaths through the
 * furnace keep the densities its MIS weights recompute (each vertex's
 * pdf_fwd and pdf_rev, free flight included, to 1e-9). In a fog that no shape
 * encloses (ambient_fog.xml: the camera's medium, a point light in it) pt
 * and bdpt agree pixel by pixel (the mean difference within 5 SE; a
 * control with the light's paths started in vacuum fails at 7 SE).
 *
 * Also: the index-matched boundary is seen only by scene_intersect_media,
 * render_transmittance multiplies each medium's transmittance along a
 * shadow ray across boundaries (against exp of the pieces, 1e-12) and a
 * surface blocks it, and the integrators that do not render media say so
 * (render_media_note). Fixed seeds; checks counted.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "render/integrators/integrator.h"
#include "render/io/io.h"
#include "load_scene.h"
#include "test_util.h"

/* Renders path with integrator and checks the image mean of every channel against
 * expect within 5 SE + rel_tol; the number of checks. */
static int check_uniform(const char *path, const char *integrator, int sampler, int64_t spp,
                         rgb expect, double rel_tol) {
  scene *s = load_scene(path);
  assert_true(s->n_media > 0);
  render_stats rst;
  lmc_image img;
  render_image(s, integrator, sampler, spp, 11, &img, &rst);
  assert_int_equal(rst.nan_samples, 0);
  const double ex[3] = {expect.r, expect.g, expect.b};
  int n = img.width * img.height, checks = 0;
  for (int c = 0; c < 3; c++) {
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < n; i++) {
      double v = img.data[3 * i + c];
      sum += v;
      sum2 += v * v;
    }
    double mean = sum / n, var = fmax(0.0, (sum2 - n * mean * mean) / (n - 1.0));
    double se = sqrt(var / n), tol = 5.0 * se + rel_tol * ex[c];
    printf("%s %s (sampler %d) channel %d: mean %.6f, exact %.6f, SE %.2e\n", path, integrator,
           sampler, c, mean, ex[c], se);
    if (!(fabs(mean - ex[c]) <= tol))
      fail_msg("%s %s (sampler %d) channel %d: mean %.6f, exact %.6f (SE %.2e)", path, integrator,
               sampler, c, mean, ex[c], se);
    checks++;
  }
  image_free(&img);
  scene_destroy(s);
  return checks;
}

static const char *const integrators[2] = {"pt", "bdpt"};

static void test_slab(void **state) {
  (void)state;
  rgb ex = rgb_make(2.0 * exp(-0.5), 3.0 * exp(-1.0), 4.0 * exp(-2.0));
  int checks = 0;
  for (int it = 0; it < 2; it++)
    for (int smp = LMC_SAMPLER_INDEPENDENT; smp <= LMC_SAMPLER_SOBOL; smp++)
      checks += check_uniform("data/media/slab.xml", integrators[it], smp, 256, ex, 1e-4);
  assert_int_equal(checks, 12);
}

static void test_furnace(void **state) {
  (void)state;
  int checks = 0;
  for (int it = 0; it < 2; it++)
    for (int smp = LMC_SAMPLER_INDEPENDENT; smp <= LMC_SAMPLER_SOBOL; smp++)
      checks += check_uniform("data/media/furnace.xml", integrators[it], smp, 64,
                              rgb_make(1.0, 2.0, 3.0), 1e-9);
  assert_int_equal(checks, 12);
}

static void test_single_scatter(void **state) {
  (void)state;
  double g = 0.3, p0 = (1.0 + g) / (4.0 * 3.14159265358979323846 * (1.0 - g) * (1.0 - g));
  rgb ex = rgb_make(0.3 * p0 * 1.0 * exp(-0.4), 0.6 * p0 * 2.0 * exp(-0.7),
                    1.2 * p0 * 3.0 * exp(-1.3));
  int checks = 0;
  for (int it = 0; it < 2; it++)
    for (int smp = LMC_SAMPLER_INDEPENDENT; smp <= LMC_SAMPLER_SOBOL; smp++)
      checks += check_uniform("data/media/single_scatter.xml", integrators[it], smp, 64, ex, 1e-4);
  assert_int_equal(checks, 12);
}

/* A fog no shape encloses (the camera's, the ambient medium), a point
 * light in it: bdpt's light paths start in the fog as pt's camera paths
 * do, so the two images agree. Each pixel's difference pt - bdpt has
 * expectation 0 and the pixels are independent, so the mean difference
 * must lie within 5 of its standard errors (their spread over the pixels)
 * in each channel. */
static void test_ambient_fog(void **state) {
  (void)state;
  scene *s = load_scene("data/media/ambient_fog.xml");
  assert_int_equal(s->ambient_medium, 1);
  lmc_image img[2];
  for (int it = 0; it < 2; it++) {
    render_stats rst;
    render_image(s, integrators[it], LMC_SAMPLER_INDEPENDENT, it ? 256 : 1024, 13, &img[it], &rst);
  }
  int n = img[0].width * img[0].height, checks = 0;
  for (int c = 0; c < 3; c++, checks++) {
    double sum = 0.0, sum2 = 0.0, mean_pt = 0.0;
    for (int i = 0; i < n; i++) {
      double d = img[0].data[3 * i + c] - img[1].data[3 * i + c];
      sum += d, sum2 += d * d;
      mean_pt += img[0].data[3 * i + c] / n;
    }
    double md = sum / n, se = sqrt(fmax(0.0, (sum2 - n * md * md) / (n - 1.0)) / n);
    printf("ambient fog channel %d: pt mean %.5f, pt - bdpt %.2e (SE %.1e)\n", c, mean_pt, md,
           se);
    if (!(fabs(md) <= 5.0 * se))
      fail_msg("ambient fog channel %d: pt - bdpt = %.3e, SE %.2e", c, md, se);
  }
  assert_int_equal(checks, 3);
  image_free(&img[0]);
  image_free(&img[1]);
  scene_destroy(s);
}

/* Two nested boxes of media, each behind an index-matched boundary, and a
 * diffuse wall: what surfaces the queries see, and the transmittance of
 * shadow rays through them. */
static void test_boundaries(void **state) {
  (void)state;
  static const char xml[] =
      "<scene version=\"0.6.0\">"
      "  <sensor type=\"perspective\"><film type=\"hdrfilm\"><integer name=\"width\" "
      "    value=\"8\"/><integer name=\"height\" value=\"8\"/></film></sensor>"
      "  <medium type=\"homogeneous\" id=\"outer\"><rgb name=\"sigmaA\" value=\"0.1, 0.2, 0.3\"/>"
      "    <rgb name=\"sigmaS\" value=\"0, 0, 0\"/></medium>"
      "  <medium type=\"homogeneous\" id=\"inner\"><rgb name=\"sigmaA\" value=\"1, 0.5, 0\"/>"
      "    <rgb name=\"sigmaS\" value=\"0.5, 0, 0\"/></medium>"
      "  <shape type=\"cube\"><transform name=\"toWorld\"><scale value=\"2\"/></transform>"
      "    <ref name=\"interior\" id=\"outer\"/></shape>"
      "  <shape type=\"cube\"><transform name=\"toWorld\"><scale value=\"1\"/></transform>"
      "    <ref name=\"interior\" id=\"inner\"/><ref name=\"exterior\" id=\"outer\"/></shape>"
      "  <shape type=\"rectangle\"><transform name=\"toWorld\"><translate z=\"-5\"/></transform>"
      "  </shape>"
      "  <emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"0\" z=\"8\"/></emitter>"
      "</scene>";
  scene *s = try_load_scene_text(xml, "media_boundaries");
  assert_non_null(s);
  int checks = 0;
  assert_int_equal(s->n_meshes, 3);
  assert_int_equal(s->meshes[0].bsdf, -1);
  assert_int_equal(s->meshes[1].bsdf, -1);
  assert_true(s->meshes[2].bsdf >= 0);
  assert_non_null(s->accel_media);
  /* From z = 4 down the axis: the integrators without media see only the
   * wall; with media, the outer box's face at z = 2 (no BSDF) first. */
  surface_hit h;
  vec3 o = v3(0.1, 0.05, 4.0), d = v3(0.0, 0.0, -1.0);
  assert_true(scene_intersect(s, o, d, 0.0, INFINITY, &h));
  assert_int_equal(h.mesh, 2);
  assert_non_null(h.bsdf);
  assert_true(scene_intersect_media(s, o, d, 0.0, INFINITY, &h));
  assert_int_equal(h.mesh, 0);
  assert_null(h.bsdf);
  assert_near(h.t, 2.0, 1e-9);
  /* Entering along -z (against the outer face's normal): the interior;
   * leaving it again along +z: the exterior (none). */
  assert_int_equal(scene_medium_after(s, &h, 0, d), 1);
  assert_int_equal(scene_medium_after(s, &h, 1, v3_neg(d)), 0);
  checks += 4;
  /* A shadow ray from inside the inner box (z = 0.5, in "inner") up to
   * z = 3: 0.5 in inner, 1 in outer, 1 in vacuum. */
  render_counters cnt = {0};
  rgb T;
  vec3 p = v3(0.1, 0.05, 0.5), lp = v3(0.1, 0.05, 3.0);
  assert_true(render_transmittance(s, &cnt, p, v3(0, 0, 1), lp, 2.5, 2, &T));
  const double ia[3] = {1.5, 0.5, 0.0}, oa[3] = {0.1, 0.2, 0.3};
  double Tc[3] = {T.r, T.g, T.b};
  for (int c = 0; c < 3; c++) {
    assert_near(Tc[c], exp(-0.5 * ia[c] - 1.0 * oa[c]), 1e-12);
    checks++;
  }
  assert_int_equal(cnt.rays, 3); /* two boundaries crossed, then the free rest */
  /* Towards infinity along +z: through both media, out of the scene. */
  assert_true(render_transmittance(s, &cnt, p, v3(0, 0, 1), v3(0, 0, 0), INFINITY, 2, &T));
  assert_near(T.b, exp(-0.3), 1e-12);
  /* Down to the wall and beyond: blocked. */
  assert_false(render_transmittance(s, &cnt, p, v3(0, 0, -1), v3(0.1, 0.05, -6.0), 6.5, 2, &T));
  checks += 2;
  assert_int_equal(checks, 9);
  scene_destroy(s);
}

/* The free-flight density with which a segment of transmittance T ends at
 * x (medium.h's track): scattering there, or passing on. */
static double flight_pdf(const scene *s, const bdpt_vertex *x, rgb T) {
  int scat = x->type == BDPT_VERTEX_MEDIUM;
  return medium_track_pdf(scat ? scene_medium(s, x->med) : NULL, scat, T);
}

/* bdpt's subpaths through the furnace's fogs: every density the walks keep
 * (pdf_fwd of each vertex, pdf_rev of each vertex the walk went back to)
 * against the density functions the MIS weights recompute them with
 * (bdpt_vertex_pdf*, integrator.h), times the segment's free flight,
 * to 1e-9. Medium vertices and surfaces, on both subpaths, are counted. */
static void test_bdpt_densities(void **state) {
  (void)state;
  scene *s = load_scene("data/media/furnace.xml");
  render_settings rs = s->settings;
  render_counters cnt = {0};
  int checks = 0, medium_checks = 0;
  for (int k = 0; k < 400; k++) {
    lmc_indep_sampler smp;
    indep_sampler_init(&smp, 5, (uint64_t)k);
    bdpt_vertex cam[BDPT_MAX_VERTICES], lp[BDPT_MAX_VERTICES];
    int nc, nl;
    bdpt_subpaths(s, &rs, &smp.base, 3.5 + 0.04 * k, 9.5, 1, cam, &nc, lp, &nl, &cnt);
    for (int side = 0; side < 2; side++) {
      const bdpt_vertex *x = side ? lp : cam;
      int n = side ? nl : nc;
      for (int i = 1; i < n; i++) {
        const bdpt_vertex *v = &x[i], *prev = &x[i - 1];
        if (v->type == BDPT_VERTEX_LIGHT) continue; /* (an escaped ray) */
        double want = i == 1 && side ? bdpt_vertex_pdf_light(s, prev, v)
                                     : bdpt_vertex_pdf(s, prev, i > 1 ? &x[i - 2] : NULL, v);
        want *= flight_pdf(s, v, v->tseg);
        assert_near(v->pdf_fwd, want, 1e-9 * want);
        checks++;
        medium_checks += v->type == BDPT_VERTEX_MEDIUM;
        /* The walk went on from v: prev's reverse density, from v. */
        if (i + 1 < n && !v->delta && !(i == 1 && side == 0)) {
          double rev = bdpt_vertex_pdf(s, v, &x[i + 1], prev) * flight_pdf(s, prev, v->tseg);
          assert_near(prev->pdf_rev, rev, 1e-9 * rev);
          checks++;
        }
      }
    }
  }
  printf("bdpt densities: %d checked, %d at medium vertices\n", checks, medium_checks);
  assert_true(checks > 2000 && medium_checks > 500);
  scene_destroy(s);
}

/* pt and bdpt render media; the others (with settings under which they do
 * not) say so, naming the medium's file and line, once per call. */
static void test_media_note(void **state) {
  (void)state;
  scene *s = load_scene("data/media/slab.xml");
  assert_true(render_integrator_media("pt") && render_integrator_media("bdpt"));
  int w0 = lmc_warning_count();
  assert_int_equal(render_media_note(s, "pt", render_integrator_media("pt")), 0);
  assert_int_equal(render_media_note(s, "bdpt", render_integrator_media("bdpt")), 0);
  assert_int_equal(lmc_warning_count(), w0);
  /* (the MCMC integrators: test_media_mcmc.c) */
  static const char *const others[] = {"direct", "pssmlt", "mmlt", "lmc", "h2mc", "mlt"};
  for (int i = 0; i < 6; i++) {
    assert_false(render_integrator_media(others[i]));
    assert_int_equal(render_media_note(s, others[i], 0), 1);
    assert_int_equal(lmc_warning_count(), w0 + i + 1);
  }
  assert_true(strstr(s->media[0].file, "slab.xml") != NULL);
  assert_int_equal(s->media[0].line, 27);
  scene_destroy(s);
  /* No media: nothing to say. */
  s = load_scene("data/analytic/furnace.xml");
  assert_int_equal(render_media_note(s, "pssmlt", 0), 0);
  scene_destroy(s);
}

int main(void) {
  lmc_warn_set_quiet(1);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_slab),           cmocka_unit_test(test_furnace),
      cmocka_unit_test(test_single_scatter), cmocka_unit_test(test_boundaries),
      cmocka_unit_test(test_media_note),     cmocka_unit_test(test_bdpt_densities),
      cmocka_unit_test(test_ambient_fog),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
