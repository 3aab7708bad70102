/*
 * test_sunsky.c: Mitsuba's sunsky, sky and sun emitters
 * (src/render/lights/sunsky.c and their loader in io/scene_xml.c).
 *
 * What is checked:
 *  - sun position: the PSA algorithm against the NOAA solar calculator's
 *    formulas (Meeus' low-precision solar coordinates and the equation of
 *    time), written independently here, for four dates and places in both
 *    hemispheres; zenith angle and azimuth (as an arc, times sin zenith)
 *    agree within 0.05 degrees (both claim about 0.01);
 *  - sky model: the interpolated state equals the dataset's control points
 *    at the ends of the Bezier curve (elevation 0 and pi/2, albedo 0 and 1,
 *    turbidity 1, 3 and 10); it is linear in albedo and in turbidity within
 *    a unit step (2.5 is the mean of 2 and 3) and continuous across an
 *    integer turbidity; the radiance equals the paper's formula written
 *    here with named parameters; channel c depends on albedo[c] only; the
 *    sky brightens towards the sun along its almucantar; the map is finite
 *    and non-negative, black below the horizon (stretch 1), black only
 *    below theta = stretch pi/2 with stretch, faded below with `extend`,
 *    and proportional to skyScale;
 *  - sun spectrum: zero outside 380-750 nm, at most the extraterrestrial
 *    value, darker at lower elevation;
 *  - sun power: the rasterized sun integrated over the sphere (pixel values
 *    times their exact solid angle) equals L_sun Omega_sun for
 *    sunRadiusScale 1 and 5, three positions and two resolutions. The
 *    tolerance is derived, not tuned: a splat's weight assumes the solid
 *    angle 2 pi^2 sin(theta_sample) / (W H) of a pixel whose exact value is
 *    2 pi^2 sin(xi) / (W H) for some xi in the pixel's row, so the ratio of
 *    the integral to L_sun Omega_sun lies between the smallest and largest
 *    ratio of sines within the rows hit (plus float rounding);
 *  - loader: sunDirection gives one envmap light and no warning; sky and
 *    sun maps add up to the sunsky map; sunRadiusScale 0 gives an envmap
 *    and a directional light of the disk's irradiance; toWorld carries the
 *    sun to the world direction given; the default date and place give
 *    the PSA position; bad values fail naming file and line;
 *  - render sanity: tests/data/sunsky/plane_sphere.xml with pt and bdpt
 *    (16 spp): finite, not black, and the two image means agree: per pixel
 *    the difference of two independent estimates has mean 0, so the mean
 *    difference over the image lies within 5 standard errors.
 * Every test counts its checks and asserts the count.
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

#include "render/integrators/integrator.h"
#include "render/io/io.h"
#include "render/lights/light.h"
#include "render/lights/sunsky.h"
#include "render/scene.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static double rad(double d) { return d * M_PI / 180.0; }
static double deg(double r) { return r * 180.0 / M_PI; }

/* ---- Sun position. ------------------------------------------------------ */

/* The NOAA solar calculator's formulas (after Meeus, Astronomical
 * Algorithms): zenith angle and azimuth from north through east, in
 * degrees, without refraction. */
static void noaa_sun(int year, int month, int day, double local_hours, double lat, double lon,
                     double tz, double *OUT_zen, double *OUT_az) {
  /* Julian day of the UT instant (Gregorian calendar). */
  int y = year, m = month;
  if (m <= 2) {
    y -= 1;
    m += 12;
  }
  int a = y / 100, b = 2 - a + a / 4;
  double jd = floor(365.25 * (y + 4716)) + floor(30.6001 * (m + 1)) + day + b - 1524.5 +
              (local_hours - tz) / 24.0;
  double T = (jd - 2451545.0) / 36525.0;

  /* The sun's apparent longitude and the obliquity. */
  double L0 = fmod(280.46646 + T * (36000.76983 + T * 0.0003032), 360.0);
  double M = 357.52911 + T * (35999.05029 - 0.0001537 * T);
  double e = 0.016708634 - T * (0.000042037 + 0.0000001267 * T);
  double C = sin(rad(M)) * (1.914602 - T * (0.004817 + 0.000014 * T)) +
             sin(rad(2 * M)) * (0.019993 - 0.000101 * T) + sin(rad(3 * M)) * 0.000289;
  double omega = 125.04 - 1934.136 * T;
  double lambda = L0 + C - 0.00569 - 0.00478 * sin(rad(omega));
  double eps0 =
      23.0 + (26.0 + (21.448 - T * (46.815 + T * (0.00059 - T * 0.001813))) / 60.0) / 60.0;
  double eps = eps0 + 0.00256 * cos(rad(omega));
  double dec = asin(sin(rad(eps)) * sin(rad(lambda)));

  /* Equation of time (minutes), true solar time and hour angle. */
  double yy = tan(rad(eps) / 2.0) * tan(rad(eps) / 2.0);
  double eqt = 4.0 * deg(yy * sin(2 * rad(L0)) - 2 * e * sin(rad(M)) +
                         4 * e * yy * sin(rad(M)) * cos(2 * rad(L0)) -
                         0.5 * yy * yy * sin(4 * rad(L0)) - 1.25 * e * e * sin(2 * rad(M)));
  double tst = fmod(local_hours * 60.0 + eqt + 4.0 * lon - 60.0 * tz, 1440.0);
  if (tst < 0.0) tst += 1440.0;
  double ha = tst / 4.0 < 0.0 ? tst / 4.0 + 180.0 : tst / 4.0 - 180.0;

  double cz = sin(rad(lat)) * sin(dec) + cos(rad(lat)) * cos(dec) * cos(rad(ha));
  double zen = acos(cz);
  double ca = (sin(rad(lat)) * cos(zen) - sin(dec)) / (cos(rad(lat)) * sin(zen));
  ca = ca < -1.0 ? -1.0 : (ca > 1.0 ? 1.0 : ca);
  double az = ha > 0.0 ? fmod(deg(acos(ca)) + 180.0, 360.0) : fmod(540.0 - deg(acos(ca)), 360.0);
  *OUT_zen = deg(zen);
  *OUT_az = az;
}

static void test_sun_position(void **state) {
  (void)state;
  static const struct {
    sunsky_time t;
    sunsky_place p;
  } cases[] = {
      /* Mitsuba's default: Tokyo, 10 July 2010, 3 PM. */
      {{2010, 7, 10, 15, 0, 0}, {35.6894, 139.6917, 9}},
      /* Plataforma Solar de Almeria (the PSA), a spring morning. */
      {{2004, 3, 21, 9, 30, 0}, {37.0916, -2.3636, 1}},
      /* Sydney, summer, mid-morning with seconds. */
      {{2020, 12, 1, 9, 15, 30}, {-33.8688, 151.2093, 10}},
      /* Boulder (NOAA), January afternoon, west of Greenwich. */
      {{1999, 1, 15, 14, 45, 0}, {40.015, -105.27, -7}},
  };
  int checks = 0;
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    sunsky_coords c = sunsky_sun_position(&cases[i].t, &cases[i].p);
    double hours = cases[i].t.hour + cases[i].t.minute / 60.0 + cases[i].t.second / 3600.0;
    double zen, az;
    noaa_sun(cases[i].t.year, cases[i].t.month, cases[i].t.day, hours, cases[i].p.latitude,
             cases[i].p.longitude, cases[i].p.timezone, &zen, &az);
    double daz = fmod(deg(c.phi) - az + 540.0, 360.0) - 180.0;
    print_message("case %zu: PSA zenith %.4f azimuth %.4f, NOAA %.4f %.4f\n", i, deg(c.theta),
                  deg(c.phi), zen, az);
    assert_near(deg(c.theta), zen, 0.05);
    assert_near(daz * sin(rad(zen)), 0.0, 0.05);
    checks += 2;
  }
  /* Coordinates and directions are inverse; azimuth 90 degrees is +x (east). */
  sunsky_coords c = {rad(60.0), rad(90.0)};
  vec3 d = sunsky_to_dir(c);
  assert_near(d.x, sin(rad(60.0)), 1e-12);
  assert_near(d.y, 0.5, 1e-12);
  assert_near(d.z, 0.0, 1e-12);
  sunsky_coords back = sunsky_from_dir(v3_scale(d, 3.0));
  assert_near(back.theta, c.theta, 1e-12);
  assert_near(back.phi, c.phi, 1e-12);
  checks += 5;
  assert_int_equal(checks, 4 * 2 + 5);
}

/* ---- Sky model. --------------------------------------------------------- */

/* The paper's radiance formula with named parameters (stored order
 * A, B, C, D, E, F, G, I, H). */
static double paper_radiance(const double *p, double LM, double theta, double gamma) {
  double A = p[0], B = p[1], C = p[2], D = p[3], E = p[4], F = p[5], G = p[6], I = p[7], H = p[8];
  double chi = (1.0 + cos(gamma) * cos(gamma)) / pow(1.0 + H * H - 2.0 * H * cos(gamma), 1.5);
  return LM * (1.0 + A * exp(B / (cos(theta) + 0.01))) *
         (C + D * exp(E * gamma) + F * cos(gamma) * cos(gamma) + G * chi + I * sqrt(cos(theta)));
}

static void test_sky_state(void **state) {
  (void)state;
  int checks = 0;
  /* The curve's ends are its first and last control points. */
  static const int turbs[3] = {1, 3, 10};
  for (int ti = 0; ti < 3; ti++)
    for (int a = 0; a < 2; a++)
      for (int end = 0; end < 2; end++) {
        sunsky_sky_state st;
        sunsky_sky_init(&st, turbs[ti], rgb_gray(a), end ? M_PI / 2.0 : 0.0);
        int k = end ? 5 : 0;
        for (int c = 0; c < 3; c++) {
          for (int i = 0; i < 9; i++)
            assert_near(st.config[c][i], sunsky__rgb_coeffs[c][a][turbs[ti] - 1][k][i],
                        1e-12 * (1.0 + fabs(sunsky__rgb_coeffs[c][a][turbs[ti] - 1][k][i])));
          assert_near(st.radiance[c], sunsky__rgb_radiances[c][a][turbs[ti] - 1][k],
                      1e-12 * (1.0 + fabs(sunsky__rgb_radiances[c][a][turbs[ti] - 1][k])));
          checks++;
        }
      }

  /* Linear in albedo, and in turbidity within a unit step. */
  double elev = rad(27.0);
  sunsky_sky_state s0, s1, sa, s2, s3, s25, s3m;
  sunsky_sky_init(&s0, 4.0, rgb_gray(0.0), elev);
  sunsky_sky_init(&s1, 4.0, rgb_gray(1.0), elev);
  sunsky_sky_init(&sa, 4.0, rgb_gray(0.3), elev);
  sunsky_sky_init(&s2, 2.0, rgb_gray(0.2), elev);
  sunsky_sky_init(&s3, 3.0, rgb_gray(0.2), elev);
  sunsky_sky_init(&s25, 2.5, rgb_gray(0.2), elev);
  sunsky_sky_init(&s3m, 3.0 - 1e-9, rgb_gray(0.2), elev);
  for (int c = 0; c < 3; c++) {
    for (int i = 0; i < 9; i++) {
      double scale = 1.0 + fabs(s3.config[c][i]);
      assert_near(sa.config[c][i], 0.7 * s0.config[c][i] + 0.3 * s1.config[c][i], 1e-12 * scale);
      assert_near(s25.config[c][i], 0.5 * (s2.config[c][i] + s3.config[c][i]), 1e-12 * scale);
      assert_near(s3m.config[c][i], s3.config[c][i], 1e-7 * scale);
    }
    assert_near(s25.radiance[c], 0.5 * (s2.radiance[c] + s3.radiance[c]), 1e-12 * s3.radiance[c]);
    assert_near(s3m.radiance[c], s3.radiance[c], 1e-7 * s3.radiance[c]);
    checks += 2;
  }

  /* The radiance is the paper's formula. */
  static const double tg[4][2] = {{0.1, 0.2}, {0.7, 1.3}, {1.4, 0.05}, {1.5, 2.9}};
  for (int c = 0; c < 3; c++)
    for (int j = 0; j < 4; j++) {
      double want = paper_radiance(s25.config[c], s25.radiance[c], tg[j][0], tg[j][1]);
      assert_near(sunsky_sky_model(&s25, c, tg[j][0], tg[j][1]), want, 1e-12 * fabs(want));
      checks++;
    }
  assert_int_equal(checks, 3 * 2 * 2 * 3 + 3 * 2 + 3 * 4);
}

/* The pixel of a w x h map that holds direction c. */
static size_t map_index(const lmc_image *img, sunsky_coords c) {
  int x = (int)(c.phi / (2.0 * M_PI) * img->width), y = (int)(c.theta / M_PI * img->height);
  if (x >= img->width) x = img->width - 1;
  if (y >= img->height) y = img->height - 1;
  return 3 * ((size_t)y * img->width + x);
}

static void test_sky_map(void **state) {
  (void)state;
  int checks = 0;
  lmc_error err;
  sunsky_params p;
  sunsky_params_default(&p);
  p.sun = 0;
  p.resolution = 128;
  p.sun_dir.theta = rad(60.0);
  p.sun_dir.phi = rad(200.0);

  /* Channel c depends on albedo[c] only. */
  sunsky_sky_state mixed, grey[3];
  const double alb[3] = {0.1, 0.5, 0.9};
  sunsky_sky_init(&mixed, 3.0, rgb_make(alb[0], alb[1], alb[2]), M_PI / 2.0 - p.sun_dir.theta);
  for (int c = 0; c < 3; c++) {
    sunsky_sky_init(&grey[c], 3.0, rgb_gray(alb[c]), M_PI / 2.0 - p.sun_dir.theta);
    assert_near(sunsky_sky_model(&mixed, c, 0.8, 0.6), sunsky_sky_model(&grey[c], c, 0.8, 0.6),
                1e-12 * fabs(sunsky_sky_model(&grey[c], c, 0.8, 0.6)));
    checks++;
  }

  /* Brighter towards the sun along its almucantar. */
  sunsky_sky_state st;
  sunsky_sky_init(&st, p.turbidity, p.albedo, M_PI / 2.0 - p.sun_dir.theta);
  for (int c = 0; c < 3; c++) {
    double prev = INFINITY;
    for (int k = 0; k < 4; k++) {
      static const double dphi[4] = {5.0, 20.0, 45.0, 80.0};
      sunsky_coords v = {p.sun_dir.theta, p.sun_dir.phi + rad(dphi[k])};
      rgb r = sunsky_sky_radiance(&st, &p, v);
      double L = c == 0 ? r.r : (c == 1 ? r.g : r.b);
      assert_true(L < prev && L > 0.0);
      prev = L;
      checks++;
    }
  }

  /* The map: finite, non-negative, black exactly below theta = stretch pi/2. */
  static const double stretches[3] = {1.0, 1.5, 2.0};
  for (int si = 0; si < 3; si++) {
    p.stretch = stretches[si];
    lmc_image img;
    assert_int_equal(sunsky_rasterize(&p, &img, &err), LMC_OK);
    int bad = 0;
    for (int y = 0; y < img.height; y++) {
      double theta = (y + 0.5) * M_PI / img.height;
      int below = cos(theta / p.stretch) <= 0.0;
      for (int x = 0; x < img.width; x++)
        for (int c = 0; c < 3; c++) {
          float v = img.data[3 * ((size_t)y * img.width + x) + c];
          if (!isfinite(v) || v < 0.0f || (below && v != 0.0f) || (!below && !(v > 0.0f))) bad++;
        }
    }
    assert_int_equal(bad, 0);
    checks++;
    image_free(&img);
  }
  p.stretch = 1.0;

  /* `extend`: below the horizon the horizon's value, faded to 0 at the nadir. */
  p.extend = 1;
  lmc_image ext, base, twice;
  assert_int_equal(sunsky_rasterize(&p, &ext, &err), LMC_OK);
  p.extend = 0;
  assert_int_equal(sunsky_rasterize(&p, &base, &err), LMC_OK);
  int h = ext.height, w = ext.width, mismatch = 0;
  for (int y = 0; y < h; y++) {
    double theta = (y + 0.5) * M_PI / h;
    for (int i = 0; i < 3 * w; i++) {
      double e = ext.data[(size_t)y * 3 * w + i], b = base.data[(size_t)y * 3 * w + i];
      if (theta < M_PI / 2.0 ? fabs(e - b) > 1e-6 * b : !(e > 0.0)) mismatch++;
    }
  }
  /* The row just below the horizon is the horizon's value times its fade. */
  sunsky_coords just = {M_PI / 2.0 - 1e-4, 0.5 * 2.0 * M_PI / w};
  rgb hz = sunsky_sky_radiance(&st, &p, just);
  double fade0 = 2.0 - 2.0 * (h / 2 + 0.5) * M_PI / h / M_PI;
  fade0 = fade0 * fade0 * (3.0 - 2.0 * fade0);
  assert_near(ext.data[(size_t)(h / 2) * 3 * w], hz.r * fade0, 1e-5 * hz.r);
  assert_int_equal(mismatch, 0);
  checks += 2;

  /* Proportional to skyScale. */
  p.sky_scale = 2.5;
  assert_int_equal(sunsky_rasterize(&p, &twice, &err), LMC_OK);
  mismatch = 0;
  for (size_t i = 0; i < (size_t)3 * w * h; i++)
    if (fabs(twice.data[i] - 2.5 * base.data[i]) > 1e-6 * twice.data[i]) mismatch++;
  assert_int_equal(mismatch, 0);
  checks++;
  image_free(&ext);
  image_free(&base);
  image_free(&twice);

  /* Out of range: an error, no image. */
  p.turbidity = 11.0;
  lmc_image none;
  assert_int_equal(sunsky_rasterize(&p, &none, &err), LMC_EINVAL);
  assert_null(none.data);
  checks++;
  assert_int_equal(checks, 3 + 3 * 4 + 3 + 2 + 1 + 1);
}

/* ---- Sun. --------------------------------------------------------------- */

static void test_sun_spectrum(void **state) {
  (void)state;
  int checks = 0;
  double wl[SUNSKY_SUN_SAMPLES], high[SUNSKY_SUN_SAMPLES], low[SUNSKY_SUN_SAMPLES];
  sunsky_sun_spectrum(rad(20.0), 3.0, wl, high);
  sunsky_sun_spectrum(rad(80.0), 3.0, wl, low);
  for (int i = 0; i < SUNSKY_SUN_SAMPLES; i++) {
    assert_near(wl[i], 350.0 + 5.0 * i, 0.0);
    if (wl[i] < 380.0 || wl[i] > 750.0) {
      assert_true(high[i] == 0.0 && low[i] == 0.0);
    } else {
      /* Below the extraterrestrial maximum, and darker lower in the sky. */
      assert_true(high[i] > 0.0 && high[i] < 30663.7);
      assert_true(low[i] > 0.0 && low[i] < high[i]);
    }
    checks++;
  }
  rgb a = sunsky_sun_radiance(rad(20.0), 3.0, SPECTRUM_INTERP_LINEAR);
  rgb b = sunsky_sun_radiance(rad(20.0), 8.0, SPECTRUM_INTERP_LINEAR);
  assert_true(a.r > 0.0 && a.g > 0.0 && a.b > 0.0);
  /* Hazier air dims blue more than red. */
  assert_true(b.b / a.b < b.r / a.r);
  checks += 2;
  assert_int_equal(checks, SUNSKY_SUN_SAMPLES + 2);
}

static void test_sun_power(void **state) {
  (void)state;
  int checks = 0;
  lmc_error err;
  static const double thetas[3] = {20.0, 55.0, 85.0}, radius_scales[2] = {1.0, 5.0};
  static const int resolutions[2] = {512, 256};
  for (int ti = 0; ti < 3; ti++)
    for (int ri = 0; ri < 2; ri++)
      for (int si = 0; si < 2; si++) {
        sunsky_params p;
        sunsky_params_default(&p);
        p.sky = 0;
        p.resolution = resolutions[ri];
        p.sun_radius_scale = radius_scales[si];
        p.sun_dir.theta = rad(thetas[ti]);
        p.sun_dir.phi = rad(123.0);
        lmc_image img;
        assert_int_equal(sunsky_rasterize(&p, &img, &err), LMC_OK);

        /* Integrate with each pixel's exact solid angle, and bound the
         * ratio of sines over the rows hit. */
        int w = img.width, h = img.height;
        double sum[3] = {0, 0, 0}, worst = 1.0;
        for (int y = 0; y < h; y++) {
          double t0 = y * M_PI / h, t1 = (y + 1) * M_PI / h;
          double domega = 2.0 * M_PI / w * (cos(t0) - cos(t1));
          int hit = 0;
          for (int x = 0; x < w; x++)
            for (int c = 0; c < 3; c++) {
              double v = img.data[3 * ((size_t)y * w + x) + c];
              sum[c] += v * domega;
              hit |= v != 0.0;
            }
          if (hit) {
            double s0 = sin(t0), s1 = sin(t1);
            worst = fmax(worst, fmax(s0, s1) / fmin(s0, s1));
          }
        }
        rgb L = sunsky_sun_radiance(p.sun_dir.theta, p.turbidity, SPECTRUM_INTERP_LINEAR);
        double omega = 2.0 * M_PI * (1.0 - cos(rad(SUNSKY_SUN_APP_RADIUS / 2.0)));
        double want[3] = {L.r * omega, L.g * omega, L.b * omega};
        double tol = worst - 1.0 + 1e-5;
        print_message("theta %4.0f res %d radius x%.0f: power / (L Omega) = %.6f %.6f %.6f "
                      "(tolerance %.2e)\n",
                      thetas[ti], p.resolution, p.sun_radius_scale, sum[0] / want[0],
                      sum[1] / want[1], sum[2] / want[2], tol);
        for (int c = 0; c < 3; c++, checks++) assert_near(sum[c] / want[c], 1.0, tol);

        /* The pixel towards the sun's centre is lit. */
        assert_true(img.data[map_index(&img, p.sun_dir) + 1] > 0.0f);
        checks++;
        image_free(&img);
      }
  assert_int_equal(checks, 3 * 2 * 2 * 4);
}

/* ---- Loader. ------------------------------------------------------------ */

static void write_text(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
}

#define HEAD                                                                       \
  "<?xml version=\"1.0\"?>\n<scene version=\"0.6.0\">\n" /* lines 1-2 */          \
  "  <sensor type=\"perspective\">\n  <float name=\"fov\" value=\"40\"/>\n" \
  "  </sensor>\n" /* lines 3-5 */

/* Loads `xml` from `path` with warnings silenced: the status, the scene in
 * *OUT_s (NULL on failure), the warning count in *OUT_warnings. */
static lmc_status load(const char *path, const char *xml, scene **OUT_s, int *OUT_warnings,
                       lmc_error *err) {
  write_text(path, xml);
  lmc_warn_set_quiet(1);
  int before = lmc_warning_count();
  lmc_error_clear(err);
  *OUT_s = NULL;
  lmc_status st = scene_load_xml(path, NULL, 0, OUT_s, err);
  *OUT_warnings = lmc_warning_count() - before;
  lmc_warn_set_quiet(0);
  return st;
}

/* Loads one emitter element (the file's lines 6 on) into a scene. */
static scene *load_emitter(const char *name, const char *emitter, int *OUT_warnings) {
  char path[256], xml[4096];
  snprintf(path, sizeof path, "/tmp/lmc_sunsky_%s.xml", name);
  snprintf(xml, sizeof xml, HEAD "%s</scene>\n", emitter);
  scene *s;
  lmc_error err;
  lmc_status st = load(path, xml, &s, OUT_warnings, &err);
  if (st != LMC_OK) print_error("%s:%d: %s\n", err.file, err.line, err.msg);
  assert_int_equal(st, LMC_OK);
  return s;
}

static void test_loader(void **state) {
  (void)state;
  int checks = 0, warnings;

  /* sunDirection: one envmap light of Mitsuba's default size, no warning;
   * the map's brightest pixel is towards the sun. */
  scene *s = load_emitter("dir",
                          "  <emitter type=\"sunsky\">\n"
                          "    <vector name=\"sunDirection\" x=\"0.3\" y=\"0.8\" z=\"-0.4\"/>\n"
                          "  </emitter>\n",
                          &warnings);
  assert_int_equal(warnings, 0);
  assert_int_equal(s->n_lights, 1);
  const light *l = &s->lights[0];
  assert_int_equal(l->type, LIGHT_ENVMAP);
  assert_int_equal(l->image.width, 512);
  assert_int_equal(l->image.height, 256);
  assert_near(l->scale, 1.0, 0.0);
  size_t brightest = 0;
  for (size_t i = 0; i < (size_t)3 * 512 * 256; i += 3)
    if (l->image.data[i + 1] > l->image.data[brightest + 1]) brightest = i;
  assert_int_equal(brightest, map_index(&l->image, sunsky_from_dir(v3(0.3, 0.8, -0.4))));
  checks += 6;
  scene_destroy(s);

  /* sky + sun = sunsky, pixel by pixel. */
  const char *common = "    <vector name=\"sunDirection\" x=\"-0.2\" y=\"0.5\" z=\"0.7\"/>\n"
                       "    <float name=\"turbidity\" value=\"4.5\"/>\n"
                       "    <integer name=\"resolution\" value=\"128\"/>\n";
  char xml[1024];
  snprintf(xml, sizeof xml,
           "  <emitter type=\"sunsky\">\n%s    <float name=\"sunRadiusScale\" value=\"3\"/>\n"
           "  </emitter>\n",
           common);
  scene *both = load_emitter("both", xml, &warnings);
  assert_int_equal(warnings, 0);
  snprintf(xml, sizeof xml, "  <emitter type=\"sky\">\n%s  </emitter>\n", common);
  scene *sky = load_emitter("sky", xml, &warnings);
  assert_int_equal(warnings, 0);
  snprintf(xml, sizeof xml,
           "  <emitter type=\"sun\">\n%s    <float name=\"sunRadiusScale\" value=\"3\"/>\n"
           "  </emitter>\n",
           common);
  scene *sun = load_emitter("sun", xml, &warnings);
  assert_int_equal(warnings, 0);
  assert_int_equal(both->n_lights + sky->n_lights + sun->n_lights, 3);
  int mismatch = 0;
  size_t n = (size_t)3 * 128 * 64;
  for (size_t i = 0; i < n; i++) {
    double a = both->lights[0].image.data[i],
           b = sky->lights[0].image.data[i] + sun->lights[0].image.data[i];
    if (fabs(a - b) > 1e-6 * fabs(a)) mismatch++;
  }
  assert_int_equal(mismatch, 0);
  checks += 5;
  scene_destroy(both);
  scene_destroy(sky);
  scene_destroy(sun);

  /* sunRadiusScale 0: the sky's map and a directional sun travelling away
   * from the sun with the disk's irradiance. */
  scene *dirsun = load_emitter("radius0",
                               "  <emitter type=\"sunsky\">\n"
                               "    <vector name=\"sunDirection\" x=\"0\" y=\"1\" z=\"1\"/>\n"
                               "    <float name=\"sunRadiusScale\" value=\"0\"/>\n"
                               "    <float name=\"sunScale\" value=\"2\"/>\n"
                               "  </emitter>\n",
                               &warnings);
  assert_int_equal(warnings, 0);
  assert_int_equal(dirsun->n_lights, 2);
  const light *dl = dirsun->lights[0].type == LIGHT_DIRECTIONAL ? &dirsun->lights[0]
                                                                 : &dirsun->lights[1];
  assert_int_equal(dl->type, LIGHT_DIRECTIONAL);
  rgb L = sunsky_sun_radiance(M_PI / 4.0, 3.0, SPECTRUM_INTERP_LINEAR);
  double omega = 2.0 * M_PI * (1.0 - cos(rad(SUNSKY_SUN_APP_RADIUS / 2.0)));
  assert_near(dl->value.g, 2.0 * L.g * omega, 1e-9 * L.g * omega);
  assert_near(dl->frm.n.y, -sqrt(0.5), 1e-9);
  assert_near(dl->frm.n.z, -sqrt(0.5), 1e-9);
  checks += 5;
  scene_destroy(dirsun);

  /* toWorld: the sun is seen along the world direction given. */
  scene *rot = load_emitter("toworld",
                            "  <emitter type=\"sunsky\">\n"
                            "    <vector name=\"sunDirection\" x=\"0.2\" y=\"0.1\" z=\"0.9\"/>\n"
                            "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"90\"/>"
                            "</transform>\n"
                            "  </emitter>\n",
                            &warnings);
  assert_int_equal(warnings, 0);
  rgb at_sun = light_le_infinite(&rot->lights[0], v3_normalize(v3(0.2, 0.1, 0.9)));
  /* World (-0.5, -0.5, 0.5) is (-0.5, 0.5, 0.5) in the map's frame: sky. */
  rgb away = light_le_infinite(&rot->lights[0], v3_normalize(v3(-0.5, -0.5, 0.5)));
  assert_true(at_sun.g > 1e3 * away.g && away.g > 0.0);
  checks += 2;
  scene_destroy(rot);

  /* Defaults: Tokyo, 10 July 2010, 3 PM. */
  scene *def = load_emitter("default", "  <emitter type=\"sunsky\"/>\n", &warnings);
  assert_int_equal(warnings, 0);
  sunsky_time t = {2010, 7, 10, 15, 0, 0};
  sunsky_place pl = {35.6894, 139.6917, 9};
  const lmc_image *img = &def->lights[0].image;
  brightest = 0;
  for (size_t i = 0; i < (size_t)3 * img->width * img->height; i += 3)
    if (img->data[i + 1] > img->data[brightest + 1]) brightest = i;
  assert_int_equal(brightest, map_index(img, sunsky_sun_position(&t, &pl)));
  checks += 2;
  scene_destroy(def);

  /* Bad values: an error at the offending line. */
  static const struct {
    const char *name, *body, *needle;
    int line;
  } bad[] = {
      {"turbidity", "    <float name=\"turbidity\" value=\"11\"/>\n", "turbidity", 7},
      {"stretch", "    <float name=\"stretch\" value=\"2.5\"/>\n", "stretch", 7},
      {"albedo", "    <rgb name=\"albedo\" value=\"0.2, 1.5, 0.2\"/>\n", "albedo", 7},
      {"resolution", "    <integer name=\"resolution\" value=\"1\"/>\n", "resolution", 7},
      {"sunscale", "    <float name=\"sunScale\" value=\"-1\"/>\n", "sunScale", 7},
      {"radius", "    <float name=\"sunRadiusScale\" value=\"400\"/>\n", "sunRadiusScale", 7},
      {"month", "    <integer name=\"month\" value=\"13\"/>\n", "month", 7},
      {"below", "    <vector name=\"sunDirection\" x=\"0\" y=\"-0.2\" z=\"1\"/>\n", "horizon", 7},
      {"night", "    <float name=\"hour\" value=\"23\"/>\n", "horizon", 7},
      {"both", "    <vector name=\"sunDirection\" x=\"0\" y=\"1\" z=\"1\"/>\n"
               "    <float name=\"latitude\" value=\"10\"/>\n",
       "latitude", 8},
  };
  int good = 0, nbad = (int)(sizeof bad / sizeof bad[0]);
  for (int i = 0; i < nbad; i++) {
    char path[256];
    snprintf(path, sizeof path, "/tmp/lmc_sunsky_bad_%s.xml", bad[i].name);
    snprintf(xml, sizeof xml, HEAD "  <emitter type=\"sunsky\">\n%s  </emitter>\n</scene>\n",
             bad[i].body);
    scene *b;
    lmc_error err;
    lmc_status st = load(path, xml, &b, &warnings, &err);
    int ok = st == LMC_EPARSE && b == NULL && strstr(err.file, path + 5) != NULL &&
             err.line == bad[i].line && strstr(err.msg, bad[i].needle) != NULL;
    if (!ok)
      print_error("case %s: status %d line %d (want %d): %s\n", bad[i].name, (int)st, err.line,
                  bad[i].line, err.msg);
    good += ok;
    scene_destroy(b);
  }
  assert_int_equal(good, nbad);
  checks++;
  assert_int_equal(checks, 6 + 5 + 5 + 2 + 2 + 1);
}

/* ---- Render sanity. ----------------------------------------------------- */

/* Renders the test scene with `integrator` at 16 spp into *OUT_img. */
static void render(const char *integrator, lmc_image *OUT_img) {
  scene *s = NULL;
  lmc_error err;
  lmc_error_clear(&err);
  lmc_status st = scene_load_xml("data/sunsky/plane_sphere.xml", NULL, 0, &s, &err);
  if (st) print_error("%s:%d: %s\n", err.file, err.line, err.msg);
  assert_int_equal(st, LMC_OK);
  render_settings rs = s->settings;
  snprintf(rs.integrator, sizeof rs.integrator, "%s", integrator);
  rs.spp = 16;
  rs.set |= SET_SPP;
  rs.threads = 2;
  rs.seed = 11;
  rs.quiet = 1;
  film f;
  render_stats rst;
  assert_int_equal(render_run(s, &rs, &f, &rst, &err), LMC_OK);
  assert_int_equal(film_develop(&f, OUT_img, &err), LMC_OK);
  film_free(&f);
  scene_destroy(s);
}

static void test_render(void **state) {
  (void)state;
  int checks = 0;
  lmc_image pt, bdpt;
  render("pt", &pt);
  render("bdpt", &bdpt);
  assert_int_equal(pt.width * pt.height, 64 * 48);
  assert_int_equal(bdpt.width * bdpt.height, 64 * 48);
  checks += 2;
  size_t n = (size_t)pt.width * pt.height;
  for (int c = 0; c < 3; c++) {
    double sp = 0.0, sb = 0.0, sd = 0.0, sd2 = 0.0;
    int finite = 1;
    for (size_t i = 0; i < n; i++) {
      double a = pt.data[3 * i + c], b = bdpt.data[3 * i + c];
      finite &= isfinite(a) && isfinite(b) && a >= 0.0 && b >= 0.0;
      sp += a;
      sb += b;
      sd += a - b;
      sd2 += (a - b) * (a - b);
    }
    double mean = sd / n, var = (sd2 - n * mean * mean) / (n - 1.0), se = sqrt(var / n);
    print_message("channel %d: pt mean %.5f, bdpt mean %.5f, difference %.2e (SE %.2e)\n", c,
                  sp / n, sb / n, mean, se);
    assert_true(finite);
    assert_true(sp / n > 1e-3 && sb / n > 1e-3);
    assert_near(mean, 0.0, 5.0 * se);
    checks += 3;
  }
  image_free(&pt);
  image_free(&bdpt);
  assert_int_equal(checks, 2 + 3 * 3);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_sun_position), cmocka_unit_test(test_sky_state),
      cmocka_unit_test(test_sky_map),      cmocka_unit_test(test_sun_spectrum),
      cmocka_unit_test(test_sun_power),    cmocka_unit_test(test_loader),
      cmocka_unit_test(test_render),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
