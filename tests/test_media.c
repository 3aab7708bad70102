/*
 * test_media.c: the phase functions (render/media/phase.h: isotropic, hg)
 * and the homogeneous medium's free flight (render/media/medium.h).
 *
 * What is checked:
 *   - phase sampling against its density: chi-square over the sphere
 *     (chi2_sphere, 64 x 128 cells, 400,000 samples) for isotropic and hg
 *     at g = 0.8, 0.3, -0.5, 0.95 and below Mitsuba's Epsilon, at the Sidak
 *     level of 1e-3 over all the tests here; the density integrates to 1
 *     (within 2e-3 by the midpoint rule); each sample's density is eval's
 *     at the sample (1e-9) and eval is symmetric;
 *   - the phase inverse: sample(invert(wi)) = wi (1e-9) for 2,000
 *     directions per model;
 *   - duals: eval_ad and sample_ad give the plain values (1e-12) and
 *     derivatives in u1, u2 (the direction and the density) and in wo that
 *     agree with central differences of the plain functions;
 *   - free flights in a medium whose channels differ: the histogram of the
 *     distances over 40 bins of [0, t_max) and the cell of flights that
 *     reach t_max against the densities' integrals (chi-square); the
 *     weights' means are the transmittance (flights that reach t_max) and
 *     1 - transmittance in each channel (scattering, albedo 1), within 5
 *     standard errors; a clear channel never scatters;
 *   - the flight's inverse: outcomes of uniform numbers, inverted with
 *     fresh numbers, are made again by the sampler, and the numbers found
 *     are uniform (chi-square on a 16 x 16 grid);
 *   - the flight in duals: values as plain (1e-12), d t / d u_t and the
 *     weight's derivatives against central differences;
 *   - a track across pieces (two media and vacuum between them): where it
 *     scatters against the pieces' optical depths (chi-square), the mean
 *     weights (transmittance; 1 - it), the density of 1,000 outcomes
 *     against its closed form (1e-12);
 *   - the loader: Mitsuba's homogeneous medium from a preset (Skin1 by
 *     default, Regular Milk with its anisotropy), from sigmaA and sigmaS,
 *     from sigmaT and albedo, scaled; hg and isotropic phase functions; a
 *     shape's interior and exterior and the sensor's medium; errors at
 *     their lines (both parameter pairs, an unknown preset, hg's g out of
 *     range, a negative coefficient, a shape's medium without a name).
 * Fixed seeds; every test counts its checks and asserts the count.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "ad/dual_math.h"
#include "chi2.h"
#include "load_scene.h"
#include "render/frame.h"
#include "render/media/medium.h"
#include "render/rng.h"
#include "render/scene.h"
#include "render/warp.h"
#include "test_util.h"

/* 6 chi-square tests of phase functions (one a model), 1 of flights, 1 of
 * the inverse's uniformity: the Sidak level of 1e-3 over 8. */
#define N_CHI2 9
#define ALPHA 1e-3

static double g_buf[1 << 14];

/* The phase functions under test. */
static int make_phases(phase_fn *ph) {
  int n = 0;
  phase_init(&ph[n++], "isotropic");
  const double gs[] = {0.8, 0.3, -0.5, 0.95, 5e-5};
  for (int i = 0; i < 5; i++) {
    phase_init(&ph[n], "hg");
    ph[n++].g = gs[i];
  }
  return n;
}

typedef struct phase_ctx {
  const phase_fn *ph;
  vec3 wo;
} phase_ctx;

static int chi_sample(void *ctx, double u1, double u2, double u3, vec3 *w) {
  (void)u3;
  phase_ctx *c = ctx;
  double pdf;
  return phase_sample(c->ph, c->wo, u1, u2, w, &pdf);
}

static double chi_pdf(void *ctx, vec3 w) {
  phase_ctx *c = ctx;
  return phase_eval(c->ph, c->wo, w);
}

static void test_phase_sampling(void **state) {
  (void)state;
  phase_fn ph[8];
  int n = make_phases(ph), checks = 0;
  double level = chi2_sidak(ALPHA, N_CHI2);
  rng r;
  rng_seed(&r, 5, 1);
  for (int k = 0; k < n; k++) {
    phase_ctx c = {&ph[k], v3_normalize(v3(0.3, -0.5, 0.8))};
    chi2_result res = chi2_sphere(chi_sample, chi_pdf, &c, 64, 128, 4, 400000, 100 + (uint64_t)k);
    if (!(res.pvalue > level))
      fail_msg("phase %s g=%g: chi-square p = %g (level %g)", ph[k].model->name, ph[k].g,
               res.pvalue, level);
    assert_near(res.pdf_integral, 1.0, 2e-3);
    /* Each sample's density is eval's; eval is symmetric. */
    for (int i = 0; i < 1000; i++) {
      vec3 wi;
      double pdf;
      assert_true(phase_sample(&ph[k], c.wo, rng_uniform(&r), rng_uniform(&r), &wi, &pdf));
      assert_near(v3_len(wi), 1.0, 1e-12);
      double e = phase_eval(&ph[k], c.wo, wi);
      assert_near(pdf, e, 1e-9 * e);
      assert_near(phase_eval(&ph[k], wi, c.wo), e, 1e-12 * e);
      checks++;
    }
  }
  assert_int_equal(checks, 1000 * n);
}

static void test_phase_invert(void **state) {
  (void)state;
  phase_fn ph[8];
  int n = make_phases(ph), checks = 0;
  rng r;
  rng_seed(&r, 6, 1);
  for (int k = 0; k < n; k++)
    for (int i = 0; i < 2000; i++) {
      vec3 wo = warp_square_to_uniform_sphere(rng_uniform(&r), rng_uniform(&r));
      vec3 wi = warp_square_to_uniform_sphere(rng_uniform(&r), rng_uniform(&r));
      double u[2], pdf;
      vec3 back;
      assert_true(phase_invert(&ph[k], wo, wi, u));
      assert_true(u[0] >= 0.0 && u[0] < 1.0 && u[1] >= 0.0 && u[1] < 1.0);
      assert_true(phase_sample(&ph[k], wo, u[0], u[1], &back, &pdf));
      /* (the strongly forward hg loses digits where 1 - g u1 cancels) */
      assert_near(v3_len(v3_sub(back, wi)), 0.0, ph[k].g > 0.9 ? 1e-7 : 1e-9);
      checks++;
    }
  assert_int_equal(checks, 2000 * n);
}

/* Plain sample as a function of x = (u1, u2, wo.x, wo.y, wo.z) (wo
 * normalised): the direction and the density, 4 outputs. */
static void phase_plain(const phase_fn *ph, const double x[5], double out[4]) {
  vec3 wo = v3_normalize(v3(x[2], x[3], x[4])), wi;
  double pdf;
  phase_sample(ph, wo, x[0], x[1], &wi, &pdf);
  out[0] = wi.x, out[1] = wi.y, out[2] = wi.z, out[3] = pdf;
}

static void test_phase_duals(void **state) {
  (void)state;
  phase_fn ph[8];
  int n = make_phases(ph), checks = 0;
  rng r;
  rng_seed(&r, 7, 1);
  ad_arena A;
  for (int k = 0; k < n; k++)
    for (int i = 0; i < 200; i++) {
      double x[5] = {0.02 + 0.96 * rng_uniform(&r), rng_uniform(&r), 0.0, 0.0, 0.0};
      vec3 w0 = warp_square_to_uniform_sphere(rng_uniform(&r), rng_uniform(&r));
      x[2] = w0.x, x[3] = w0.y, x[4] = w0.z;
      assert_int_equal(ad_arena_init(&A, g_buf, sizeof g_buf / sizeof g_buf[0], 5), 0);
      ad v[5];
      for (int j = 0; j < 5; j++) v[j] = ad_var(&A, x[j], j);
      adv3 wo = adv3_normalize(&A, (adv3){v[2], v[3], v[4]});
      adv3 wi;
      ad pdf;
      assert_true(phase_sample_ad(&A, &ph[k], wo, v[0], v[1], &wi, &pdf));
      ad e = phase_eval_ad(&A, &ph[k], wo, wi);
      ad outs[4] = {wi.x, wi.y, wi.z, pdf};
      double plain[4];
      phase_plain(&ph[k], x, plain);
      for (int o = 0; o < 4; o++) assert_near(outs[o].v, plain[o], 1e-12 * (1.0 + fabs(plain[o])));
      assert_near(e.v, pdf.v, 1e-9 * pdf.v);
      for (int j = 0; j < 5; j++) {
        double h = 1e-6, xp[5], xm[5], op[4], om[4];
        memcpy(xp, x, sizeof xp), memcpy(xm, x, sizeof xm);
        xp[j] += h, xm[j] -= h;
        phase_plain(&ph[k], xp, op);
        phase_plain(&ph[k], xm, om);
        for (int o = 0; o < 4; o++) {
          double fd = (op[o] - om[o]) / (2.0 * h), d = ad_deriv(&A, outs[o], j);
          if (!(fabs(d - fd) <= 1e-5 * (1.0 + fabs(fd))))
            fail_msg("phase %s g=%g: d out%d / d x%d = %.10g, central difference %.10g",
                     ph[k].model->name, ph[k].g, o, j, d, fd);
        }
      }
      checks++;
    }
  assert_int_equal(checks, 200 * n);
}

/* A medium whose channels differ: sigma_t 0.5, 2, 0 (a clear channel). */
static medium test_medium(void) {
  medium m;
  medium_set(&m, rgb_make(0.0, 0.0, 0.0), rgb_make(0.5, 2.0, 0.0));
  return m;
}

static void test_flight_distribution(void **state) {
  (void)state;
  medium m = test_medium();
  const double t_max = 1.7;
  const int bins = 40;
  const int64_t n = 400000;
  double obs[41] = {0}, expct[41] = {0};
  double sum_reach[3] = {0}, sum2_reach[3] = {0}, sum_scat[3] = {0}, sum2_scat[3] = {0};
  rng r;
  rng_seed(&r, 8, 1);
  int64_t clear_scattered = 0;
  for (int64_t i = 0; i < n; i++) {
    double u_ch = rng_uniform(&r);
    medium_flight f;
    assert_true(medium_sample_flight(&m, t_max, u_ch, rng_uniform(&r), &f));
    int b = f.scattered ? (int)(f.t / t_max * bins) : bins;
    obs[b < bins ? b : bins - 1 + !f.scattered] += 1.0;
    if (f.scattered && u_ch >= 2.0 / 3.0) clear_scattered++;
    const double w[3] = {f.weight.r, f.weight.g, f.weight.b};
    for (int c = 0; c < 3; c++) {
      double reach = f.scattered ? 0.0 : w[c], scat = f.scattered ? w[c] : 0.0;
      sum_reach[c] += reach, sum2_reach[c] += reach * reach;
      /* albedo 1 (sigma_a 0): weight sigma_s T / p; its mean is 1 - T(t_max) */
      sum_scat[c] += scat, sum2_scat[c] += scat * scat;
    }
  }
  const double st[3] = {0.5, 2.0, 0.0};
  for (int b = 0; b < bins; b++) {
    double a = t_max * b / bins, e = t_max * (b + 1) / bins, p = 0.0;
    for (int c = 0; c < 3; c++) p += (exp(-st[c] * a) - exp(-st[c] * e)) / 3.0;
    expct[b] = p * (double)n;
  }
  double reach = 0.0;
  for (int c = 0; c < 3; c++) reach += exp(-st[c] * t_max) / 3.0;
  expct[bins] = reach * (double)n;
  double p = chi2_pvalue(obs, expct, bins + 1, 5.0, NULL, NULL);
  double level = chi2_sidak(ALPHA, N_CHI2);
  if (!(p > level)) fail_msg("flight distances: chi-square p = %g (level %g)", p, level);
  assert_int_equal(clear_scattered, 0);
  int checks = 0;
  for (int c = 0; c < 3; c++) {
    double T = exp(-st[c] * t_max);
    double mr = sum_reach[c] / n, sr = sqrt(fmax(0.0, sum2_reach[c] / n - mr * mr) / n);
    double ms = sum_scat[c] / n, ss = sqrt(fmax(0.0, sum2_scat[c] / n - ms * ms) / n);
    assert_near(mr, T, 5.0 * sr + 1e-12);
    assert_near(ms, 1.0 - T, 5.0 * ss + 1e-12);
    checks += 2;
  }
  assert_int_equal(checks, 6);
  /* Density of each outcome as the sampler's. */
  medium_flight f;
  assert_true(medium_sample_flight(&m, t_max, 0.1, 0.3, &f));
  assert_near(f.pdf, medium_flight_pdf(&m, f.scattered, f.t), 1e-15);
  assert_true(medium_sample_flight(&m, t_max, 0.9, 0.3, &f) && !f.scattered);
  assert_near(f.pdf, reach, 1e-15);
  /* Unbounded, a clear channel's flight has nothing to give. */
  assert_false(medium_sample_flight(&m, INFINITY, 0.9, 0.3, &f));
}

/* A track across three pieces: 0.8 in a medium, 0.3 of vacuum, 1.0 in
 * another whose channels differ (albedo 1 in both): where it scatters over
 * 42 bins of [0, 2.1) and the cell of tracks that pass, against the
 * channels' mean of exp(-tau_c) differences (chi-square); the weights'
 * means (passing: the transmittance; scattering: 1 - it, as albedo 1
 * gives) within 5 SE; the density medium_track_pdf gives each outcome
 * against its closed form. */
static void test_track_pieces(void **state) {
  (void)state;
  medium m1, m2;
  medium_set(&m1, rgb_make(0.0, 0.0, 0.0), rgb_make(1.5, 0.2, 0.7));
  medium_set(&m2, rgb_make(0.0, 0.0, 0.0), rgb_make(0.1, 2.5, 0.0));
  const medium *piece[3] = {&m1, NULL, &m2};
  const double len[3] = {0.8, 0.3, 1.0}, total = 2.1;
  const double s1[3] = {1.5, 0.2, 0.7}, s2[3] = {0.1, 2.5, 0.0};
  /* the optical depth of channel c at distance t */
#define TAU(c, t) \
  (s1[c] * fmin((t), 0.8) + s2[c] * fmax(0.0, (t) - 1.1))
  enum { BINS = 42 };
  const int64_t n = 400000;
  double obs[BINS + 1] = {0}, expct[BINS + 1] = {0};
  double sum_pass[3] = {0}, sum2_pass[3] = {0}, sum_scat[3] = {0}, sum2_scat[3] = {0};
  int pdf_checks = 0;
  rng r;
  rng_seed(&r, 9, 1);
  for (int64_t i = 0; i < n; i++) {
    medium_track k;
    medium_track_begin(rng_uniform(&r), rng_uniform(&r), &k);
    double start = 0.0, t = 0.0;
    int j = 0, scattered = 0;
    for (; j < 3; start += len[j], j++)
      if (medium_track_piece(piece[j], len[j], &k, &t)) {
        scattered = 1;
        break;
      }
    double pdf = medium_track_pdf(scattered ? piece[j] : NULL, scattered, k.T);
    double at = start + t, w[3] = {k.T.r, k.T.g, k.T.b};
    if (i < 1000) {
      /* the density in closed form: the channels' mean of sigma_t exp(-tau) */
      double want = 0.0;
      for (int c = 0; c < 3; c++)
        want += (scattered ? (j == 0 ? s1[c] : s2[c]) : 1.0) * exp(-TAU(c, scattered ? at : total));
      assert_near(pdf, want / 3.0, 1e-12 * want);
      pdf_checks++;
    }
    int b = scattered ? (int)(at / total * BINS) : BINS;
    obs[scattered && b >= BINS ? BINS - 1 : b] += 1.0;
    for (int c = 0; c < 3; c++) {
      double sig = scattered ? (j == 0 ? s1[c] : s2[c]) : 0.0;
      double pass = scattered ? 0.0 : w[c] / pdf, scat = scattered ? sig * w[c] / pdf : 0.0;
      sum_pass[c] += pass, sum2_pass[c] += pass * pass;
      sum_scat[c] += scat, sum2_scat[c] += scat * scat;
    }
  }
  assert_int_equal(pdf_checks, 1000);
  for (int b = 0; b < BINS; b++) {
    double a = total * b / BINS, e = total * (b + 1) / BINS, q = 0.0;
    for (int c = 0; c < 3; c++) q += (exp(-TAU(c, a)) - exp(-TAU(c, e))) / 3.0;
    expct[b] = q * (double)n;
  }
  double pass = 0.0;
  for (int c = 0; c < 3; c++) pass += exp(-TAU(c, total)) / 3.0;
  expct[BINS] = pass * (double)n;
  /* (the bins inside the vacuum expect nothing and see nothing) */
  int empty = 0;
  for (int b = 0; b < BINS; b++)
    if (expct[b] == 0.0) {
      assert_true(obs[b] == 0.0);
      empty++;
    }
  assert_int_equal(empty, 6);
  double p = chi2_pvalue(obs, expct, BINS + 1, 5.0, NULL, NULL);
  double level = chi2_sidak(ALPHA, N_CHI2);
  if (!(p > level)) fail_msg("track: chi-square p = %g (level %g)", p, level);
  int checks = 0;
  for (int c = 0; c < 3; c++) {
    double T = exp(-TAU(c, total));
    double mp = sum_pass[c] / n, sp = sqrt(fmax(0.0, sum2_pass[c] / n - mp * mp) / n);
    double ms = sum_scat[c] / n, ss = sqrt(fmax(0.0, sum2_scat[c] / n - ms * ms) / n);
    assert_near(mp, T, 5.0 * sp + 1e-12);
    assert_near(ms, 1.0 - T, 5.0 * ss + 1e-12);
    checks += 2;
  }
  assert_int_equal(checks, 6);
#undef TAU
}

static void test_flight_invert(void **state) {
  (void)state;
  medium m = test_medium();
  const double t_max = 1.3;
  double obs[256] = {0}, expct[256];
  rng r;
  rng_seed(&r, 9, 1);
  int64_t n = 200000, back = 0;
  for (int64_t i = 0; i < n; i++) {
    medium_flight f, g;
    double u_ch = rng_uniform(&r), u_t = rng_uniform(&r),
           rr[2] = {rng_uniform(&r), rng_uniform(&r)};
    double u[2];
    assert_true(medium_sample_flight(&m, t_max, u_ch, u_t, &f));
    if (!medium_invert_flight(&m, f.scattered, f.t, rr, u)) continue;
    assert_true(medium_sample_flight(&m, t_max, u[0], u[1], &g));
    assert_int_equal(g.scattered, f.scattered);
    assert_near(g.t, f.t, 1e-9 * (1.0 + f.t));
    obs[(int)(u[0] * 16) * 16 + (int)(u[1] * 16)] += 1.0;
    back++;
  }
  /* Refused only at the edges of a u_t interval: almost never. */
  assert_true(back >= n - 10);
  for (int k = 0; k < 256; k++) expct[k] = (double)back / 256.0;
  double p = chi2_pvalue(obs, expct, 256, 5.0, NULL, NULL);
  double level = chi2_sidak(ALPHA, N_CHI2);
  if (!(p > level)) fail_msg("inverted numbers: chi-square p = %g (level %g)", p, level);
}

/* The plain flight's t, pdf and weight of x = (u_t, t_max) at channel u_ch. */
static void flight_plain(const medium *m, double u_ch, const double x[2], double out[5]) {
  medium_flight f;
  medium_sample_flight(m, x[1], u_ch, x[0], &f);
  out[0] = f.t, out[1] = f.pdf, out[2] = f.weight.r, out[3] = f.weight.g, out[4] = f.weight.b;
}

static void test_flight_duals(void **state) {
  (void)state;
  medium m = test_medium();
  rng r;
  rng_seed(&r, 10, 1);
  ad_arena A;
  int checks = 0, scattered = 0;
  for (int i = 0; i < 400; i++) {
    double u_ch = 0.66 * rng_uniform(&r); /* the two channels that scatter */
    double x[2] = {0.02 + 0.96 * rng_uniform(&r), 0.5 + 2.0 * rng_uniform(&r)};
    assert_int_equal(ad_arena_init(&A, g_buf, sizeof g_buf / sizeof g_buf[0], 2), 0);
    ad ut = ad_var(&A, x[0], 0), tm = ad_var(&A, x[1], 1);
    medium_flight_ad f;
    assert_true(medium_sample_flight_ad(&A, &m, tm, ad_const(&A, u_ch), ut, &f));
    ad outs[5] = {f.t, f.pdf, f.weight.r, f.weight.g, f.weight.b};
    double plain[5];
    flight_plain(&m, u_ch, x, plain);
    for (int o = 0; o < 5; o++) assert_near(outs[o].v, plain[o], 1e-12 * (1.0 + fabs(plain[o])));
    /* Away from the switch between scattering and reaching t_max. */
    double t_s = -log1p(-x[0]) / (u_ch < 1.0 / 3.0 ? 0.5 : 2.0);
    if (fabs(t_s - x[1]) < 1e-3) continue;
    scattered += f.scattered;
    for (int j = 0; j < 2; j++) {
      double h = 1e-7, xp[2] = {x[0], x[1]}, xm[2] = {x[0], x[1]}, op[5], om[5];
      xp[j] += h, xm[j] -= h;
      flight_plain(&m, u_ch, xp, op);
      flight_plain(&m, u_ch, xm, om);
      for (int o = 0; o < 5; o++) {
        double fd = (op[o] - om[o]) / (2.0 * h), d = ad_deriv(&A, outs[o], j);
        if (!(fabs(d - fd) <= 1e-5 * (1.0 + fabs(fd))))
          fail_msg("flight: d out%d / d x%d = %.10g, central difference %.10g", o, j, d, fd);
      }
    }
    checks++;
  }
  assert_true(checks >= 390);
  assert_true(scattered > 50 && scattered < checks - 50); /* both outcomes checked */
}

/* A scene with a sensor, a light and `body`. */
static scene *media_scene(const char *body, const char *tag) {
  char xml[4096];
  snprintf(xml, sizeof xml,
           "<scene version=\"0.6.0\">\n"
           "  <sensor type=\"perspective\">%s<film type=\"hdrfilm\">"
           "<integer name=\"width\" value=\"4\"/><integer name=\"height\" value=\"4\"/>"
           "</film></sensor>\n"
           "  <emitter type=\"constant\"/>\n%s</scene>\n",
           strstr(body, "<!--cam-->") ? "<ref id=\"fog\"/>" : "", body);
  lmc_warn_set_quiet(1);
  scene *s = try_load_scene_text(xml, tag);
  lmc_warn_set_quiet(0);
  return s;
}

static int near3(rgb a, rgb b, double tol) {
  return fabs(a.r - b.r) <= tol && fabs(a.g - b.g) <= tol && fabs(a.b - b.b) <= tol;
}

static void test_loader(void **state) {
  (void)state;
  int checks = 0;
  scene *s = media_scene(
      "  <medium type=\"homogeneous\" id=\"fog\">\n"
      "    <rgb name=\"sigmaA\" value=\"0.1, 0.2, 0.3\"/><rgb name=\"sigmaS\" value=\"1, 2, 3\"/>\n"
      "    <float name=\"scale\" value=\"2\"/>\n"
      "    <phase type=\"hg\"><float name=\"g\" value=\"0.5\"/></phase>\n"
      "  </medium>\n"
      "  <medium type=\"homogeneous\" id=\"skin\"/>\n"
      "  <medium type=\"homogeneous\" id=\"milk\"><string name=\"material\" value=\"regular "
      "milk\"/></medium>\n"
      "  <medium type=\"homogeneous\" id=\"ta\"><rgb name=\"sigmaT\" value=\"4\"/>"
      "<rgb name=\"albedo\" value=\"0.25, 0.5, 1\"/></medium>\n"
      "  <shape type=\"sphere\"><bsdf type=\"dielectric\"/><ref name=\"interior\" id=\"milk\"/>"
      "<ref name=\"exterior\" id=\"fog\"/></shape>\n"
      "<!--cam-->\n",
      "media");
  assert_non_null(s);
  assert_int_equal(s->n_media, 4);
  const medium *fog = &s->media[0], *skin = &s->media[1], *milk = &s->media[2], *ta = &s->media[3];
  assert_true(strcmp(fog->id, "fog") == 0 && strcmp(ta->id, "ta") == 0);
  assert_true(near3(fog->sigma_a, rgb_make(0.2, 0.4, 0.6), 1e-12));
  assert_true(near3(fog->sigma_s, rgb_make(2, 4, 6), 1e-12));
  assert_true(near3(fog->sigma_t, rgb_make(2.2, 4.4, 6.6), 1e-12));
  assert_true(strcmp(fog->ph.model->name, "hg") == 0 && fog->ph.g == 0.5);
  checks += 4;
  /* Mitsuba's default preset Skin1, per metre (its table times 100). */
  assert_true(near3(skin->sigma_s, rgb_make(74, 88, 101), 1e-4));
  assert_true(near3(skin->sigma_a, rgb_make(3.2, 17, 48), 1e-4));
  assert_true(strcmp(skin->ph.model->name, "isotropic") == 0);
  /* Regular Milk: sigma_s reduced by its g (0.75, 0.714, 0.681). */
  assert_true(
      near3(milk->sigma_s, rgb_make(1820.52 * 0.25, 2038.26 * 0.286, 2236.98 * 0.319), 2e-2));
  assert_true(near3(ta->sigma_s, rgb_make(1, 2, 4), 1e-12) &&
              near3(ta->sigma_a, rgb_make(3, 2, 0), 1e-12));
  checks += 5;
  /* The sphere's interior and exterior; the camera's medium. */
  assert_int_equal(s->n_meshes, 1);
  assert_int_equal(s->meshes[0].interior, 3);
  assert_int_equal(s->meshes[0].exterior, 1);
  assert_int_equal(s->cam.medium, 1);
  checks += 3;
  scene_destroy(s);
  /* Errors. */
  static const char *const bad[] = {
      "<medium type=\"homogeneous\"><rgb name=\"sigmaA\" value=\"1\"/><rgb name=\"sigmaT\" "
      "value=\"1\"/></medium>",
      "<medium type=\"homogeneous\"><string name=\"material\" value=\"Gravy\"/></medium>",
      "<medium type=\"homogeneous\"><phase type=\"hg\"><float name=\"g\" "
      "value=\"1\"/></phase></medium>",
      "<medium type=\"homogeneous\"><rgb name=\"sigmaS\" value=\"-1, 1, 1\"/></medium>",
      "<shape type=\"sphere\"><medium type=\"homogeneous\"/></shape>",
      "<medium type=\"homogeneous\"><string name=\"material\" value=\"Apple\"/>"
      "<rgb name=\"sigmaS\" value=\"1\"/></medium>",
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++, checks++) {
    char body[1024];
    snprintf(body, sizeof body, "  %s\n", bad[i]);
    assert_null(media_scene(body, "badmedia"));
  }
  assert_int_equal(checks, 12 + 6);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_phase_sampling), cmocka_unit_test(test_phase_invert),
      cmocka_unit_test(test_phase_duals),    cmocka_unit_test(test_flight_distribution),
      cmocka_unit_test(test_flight_invert),  cmocka_unit_test(test_flight_duals),
      cmocka_unit_test(test_track_pieces),
      cmocka_unit_test(test_loader),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
