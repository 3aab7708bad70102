/*
 * test_analytic.c: every pixel integrator against scenes whose pixel values
 * are known exactly.
 *
 *  furnace.xml         lossless spheres (white diffuse, smooth glass,
 *                      perfect mirror, white diffuse transmitter, a
 *                      blend of that transmitter and glass) in a
 *                      constant environment of 1:
 *                      every pixel's expectation is exactly 1.
 *  diffuse_sphere.xml  a convex diffuse sphere of albedo 0.5 in a constant
 *                      environment L = (1, 2, 4): covered pixels have the
 *                      expectation 0.5 L, background pixels L.
 *  mask.xml            Mitsuba's mask: a lone masked square (see through
 *                      it: exactly a 0.5 L + (1 - a) L) and a lossless
 *                      masked sphere (exactly L) in the same environment.
 *
 * Pixels are grouped by what their four corners and centre see (found with
 * the scene's own ray queries, independent of shading): one object, or the
 * environment; mixed pixels are left out. Within a group all pixels share
 * one expectation, so the spread of their values estimates the standard
 * error of the group mean: SE = sd / sqrt(n). Each group mean must lie
 * within 5 SE of the exact value (two integrators x two samplers x ~4
 * groups x 3 channels = ~48 comparisons; at 5 sigma the chance of a false
 * alarm is about 48 * 5.7e-7). With the Sobol sampler the pixels are still
 * independent of one another (each has its own scrambles), so the spread
 * across a group still gives the SE. Groups of zero variance (pure environment) must be
 * exact to rounding.
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

#define MAX_GROUPS 8

typedef struct group_stats {
  int n;
  double sum[3], sum2[3];
} group_stats;

/* Group of pixel (x, y): the mesh index every probe ray hits, MAX_GROUPS - 1
 * for the environment, -1 when the probes disagree. */
static int pixel_group(const scene *s, int x, int y) {
  static const double off[5][2] = {{0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}, {1.0, 1.0}, {0.5, 0.5}};
  int g = -2;
  for (int k = 0; k < 5; k++) {
    vec3 o, d;
    camera_generate_ray(&s->cam, x + off[k][0], y + off[k][1], &o, &d);
    surface_hit h;
    int gk = scene_intersect(s, o, d, 0.0, INFINITY, &h) ? h.mesh : MAX_GROUPS - 1;
    if (g == -2) g = gk;
    else if (g != gk) return -1;
  }
  return g;
}

/* Renders `path` with `integrator` and checks every group against `expect`
 * (per group, per channel). Returns the number of group-channel checks. */
static int check_scene(const char *path, const char *integrator, int sampler, int64_t spp,
                       const rgb expect[MAX_GROUPS], int min_groups, double *OUT_var0) {
  scene *s = load_scene(path);
  render_stats rst;
  lmc_image img;
  render_image(s, integrator, sampler, spp, 7, &img, &rst);

  /* Accumulate group statistics. */
  group_stats gs[MAX_GROUPS];
  memset(gs, 0, sizeof gs);
  for (int y = 0; y < img.height; y++)
    for (int x = 0; x < img.width; x++) {
      int g = pixel_group(s, x, y);
      if (g < 0) continue;
      gs[g].n++;
      for (int c = 0; c < 3; c++) {
        double v = img.data[3 * (y * img.width + x) + c];
        gs[g].sum[c] += v;
        gs[g].sum2[c] += v * v;
      }
    }

  /* Compare each group's mean with the exact value. */
  int checks = 0, groups = 0;
  for (int g = 0; g < MAX_GROUPS; g++) {
    if (gs[g].n < 8) continue;
    groups++;
    const double ex[3] = {expect[g].r, expect[g].g, expect[g].b};
    for (int c = 0; c < 3; c++) {
      double n = gs[g].n, mean = gs[g].sum[c] / n;
      double var = fmax(0.0, (gs[g].sum2[c] - n * mean * mean) / (n - 1.0));
      double se = sqrt(var / n);
      if (g == 0 && OUT_var0) OUT_var0[c] = var;
      double tol = fmax(5.0 * se, 1e-6 * fabs(ex[c]));
      if (fabs(mean - ex[c]) > tol)
        fail_msg("%s with %s (sampler %d): group %d channel %d: mean %.6f, expected %.6f "
                 "(SE %.2e, %d pixels)",
                 path, integrator, sampler, g, c, mean, ex[c], se, gs[g].n);
      checks++;
    }
  }
  assert_true(groups >= min_groups);
  image_free(&img);
  scene_destroy(s);
  return checks;
}

static void test_furnace(void **state) {
  (void)state;
  rgb one[MAX_GROUPS];
  for (int g = 0; g < MAX_GROUPS; g++) one[g] = rgb_gray(1.0);
  int checks = 0;
  for (int smp = LMC_SAMPLER_INDEPENDENT; smp <= LMC_SAMPLER_SOBOL; smp++) {
    checks += check_scene("data/analytic/furnace.xml", "pt", smp, 32, one, 6, NULL);
    checks += check_scene("data/analytic/furnace.xml", "bdpt", smp, 32, one, 6, NULL);
  }
  assert_int_equal(checks, 2 * 2 * 6 * 3);
}

static void test_diffuse_sphere(void **state) {
  (void)state;
  rgb ex[MAX_GROUPS];
  for (int g = 0; g < MAX_GROUPS; g++) ex[g] = rgb_make(1.0, 2.0, 4.0);
  ex[0] = rgb_make(0.5, 1.0, 2.0); /* the sphere is mesh 0 */
  int checks = 0;
  double var[2][2][3]; /* [sampler][integrator][channel] of the sphere's pixels */
  for (int smp = LMC_SAMPLER_INDEPENDENT; smp <= LMC_SAMPLER_SOBOL; smp++) {
    checks += check_scene("data/analytic/diffuse_sphere.xml", "pt", smp, 32, ex, 2, var[smp][0]);
    checks += check_scene("data/analytic/diffuse_sphere.xml", "bdpt", smp, 32, ex, 2, var[smp][1]);
  }
  assert_int_equal(checks, 2 * 2 * 2 * 3);
  /* The Sobol sampler's pixels vary less. The sphere's pixel values are
   * independent and there are hundreds of them, so each variance is known
   * to within sqrt(2 / n) < 10%, and halving it cannot happen by chance
   * (measured: a fifth for pt and for bdpt). */
  for (int it = 0; it < 2; it++)
    for (int c = 0; c < 3; c++)
      if (!(var[LMC_SAMPLER_SOBOL][it][c] < 0.5 * var[LMC_SAMPLER_INDEPENDENT][it][c]))
        fail_msg("%s channel %d: Sobol pixel variance %.3g, independent %.3g", it ? "bdpt" : "pt",
                 c, var[LMC_SAMPLER_SOBOL][it][c], var[LMC_SAMPLER_INDEPENDENT][it][c]);
      else
        printf("%s channel %d: pixel variance %.3g (sobol) vs %.3g (independent)\n",
               it ? "bdpt" : "pt", c, var[LMC_SAMPLER_SOBOL][it][c],
               var[LMC_SAMPLER_INDEPENDENT][it][c]);
}

static void test_mask(void **state) {
  (void)state;
  rgb ex[MAX_GROUPS];
  for (int g = 0; g < MAX_GROUPS; g++) ex[g] = rgb_make(1.0, 2.0, 4.0);
  ex[0] = rgb_make(0.25 * 0.5 * 1.0 + 0.75 * 1.0, 0.5 * 0.5 * 2.0 + 0.5 * 2.0,
                   0.75 * 0.5 * 4.0 + 0.25 * 4.0); /* the square, mesh 0 */
  int checks = 0;
  for (int smp = LMC_SAMPLER_INDEPENDENT; smp <= LMC_SAMPLER_SOBOL; smp++) {
    checks += check_scene("data/analytic/mask.xml", "pt", smp, 32, ex, 3, NULL);
    checks += check_scene("data/analytic/mask.xml", "bdpt", smp, 32, ex, 3, NULL);
  }
  assert_int_equal(checks, 2 * 2 * 3 * 3);
}

int main(void) {
  lmc_warn_set_quiet(1);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_furnace),
      cmocka_unit_test(test_diffuse_sphere),
      cmocka_unit_test(test_mask),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
