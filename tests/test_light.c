/*
 * test_light.c: the emitters of src/render/light.c in scenes built here.
 *
 * For every light that samples a continuous direction (area, point and
 * spot emission, constant, envmap) the sampled directions are compared
 * with the claimed density by a chi-square test on the sphere (tests/chi2.h)
 * and the density is checked to integrate to 1. Estimators built from the
 * samples are compared with independent values:
 *
 *  - area: irradiance at a point below a square light, E = L * integral of
 *    cos, against the closed-form point-to-rectangle form factor (and a
 *    quadrature of light_le_area over the hemisphere);
 *  - spot: the intensity integrated over the sphere, which for Mitsuba's
 *    linear falloff is 2 pi I (1 + (sin beam - sin cutoff)/(cutoff - beam));
 *  - constant: irradiance pi L on a plane;
 *  - envmap: irradiance on a tilted plane against a quadrature of
 *    light_le_infinite over the sphere.
 *
 * Monte Carlo means pass when within 4 standard errors, where the standard
 * error is the sample standard deviation over sqrt(N), plus the known
 * quadrature error bound where a quadrature is involved. Seeds are fixed;
 * the chi-square tests share an overall level of 1% (Sidak). The envmap's
 * orientation is checked against Mitsuba's convention pixel by pixel.
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

#include "chi2.h"
#include "light_scene.h"
#include "render/lights/light.h"
#include "render/rng.h"
#include "render/scene.h"
#include "render/warp.h"


/* Added to every seed (-DSEED_OFFSET=k reruns the suite with other seeds). */
#ifndef SEED_OFFSET
#define SEED_OFFSET 0
#endif

/* Number of chi-square tests in this file, for the Sidak level. */
#define N_CHI2_TESTS 11
static double alpha_per_test(void) { return chi2_sidak(0.01, N_CHI2_TESTS); }

static void check_chi2(const char *what, chi2_result r) {
  print_message("%-24s chi2 %9.2f dof %5d p %.4f pdf integral %.6f accepted %lld\n", what, r.stat,
                r.dof, r.pvalue, r.pdf_integral, (long long)r.accepted);
  assert_true(r.pvalue > alpha_per_test());
}

/* Running mean and standard error. */
typedef struct stats {
  double n, mean, m2;
} stats;
static void stats_add(stats *s, double x) {
  s->n += 1.0;
  double d = x - s->mean;
  s->mean += d / s->n;
  s->m2 += d * (x - s->mean);
}
static double stats_se(const stats *s) { return sqrt(s->m2 / (s->n - 1.0) / s->n); }

/* Sampling contexts for chi2_sphere. */
typedef struct ctx {
  const light *l;
  vec3 ref;
  vec3 n; /* the area light's emitting normal */
} ctx;

static int sample_li_fn(void *c_, double u1, double u2, double u3, vec3 *w) {
  (void)u3;
  ctx *c = c_;
  light_li_sample ls;
  if (!light_sample_li(c->l, g_scene, c->ref, u1, u2, &ls)) return 0;
  *w = ls.wi;
  return 1;
}

/* Density of area-light directions: the plane z = H hit inside the square. */
static double pdf_li_area_fn(void *c_, vec3 w) {
  ctx *c = c_;
  if (!(w.z > 0.0)) return 0.0;
  double t = (H - c->ref.z) / w.z;
  vec3 p = v3_fma(c->ref, w, t);
  if (fabs(p.x) > 0.5 || fabs(p.y) > 0.5) return 0.0;
  return light_pdf_li(c->l, g_scene, c->ref, w, p, c->n);
}

static double pdf_li_inf_fn(void *c_, vec3 w) {
  ctx *c = c_;
  return light_pdf_li(c->l, g_scene, c->ref, w, v3(0, 0, 0), v3(0, 0, 0));
}

static int sample_le_dir_fn(void *c_, double u1, double u2, double u3, vec3 *w) {
  ctx *c = c_;
  light_le_sample es;
  /* The position numbers are fixed-ish: u3 drives both position numbers. */
  if (!light_sample_le(c->l, g_scene, u3, 1.0 - u3, u1, u2, &es)) return 0;
  *w = es.dir;
  return 1;
}

static double pdf_le_dir_fn(void *c_, vec3 w) {
  ctx *c = c_;
  double pp, pd;
  light_pdf_le(c->l, g_scene, v3(0, 0, 0), c->n, w, &pp, &pd);
  return pd;
}

/* ---------------------------------------------------------------------------
 * Properties of every light.
 */
static void test_flags_and_power(void **state) {
  (void)state;
  int checks = 0;
  const int delta[N_LIGHTS] = {0, 1, 1, 1, 0, 0, 0, 0};
  const int inf[N_LIGHTS] = {0, 0, 0, 0, 1, 1, 1, 1};
  for (int i = 0; i < N_LIGHTS; i++) {
    assert_int_equal(light_is_delta(L(i)), delta[i]);
    assert_int_equal(light_is_infinite(L(i)), inf[i]);
    double p = light_power(L(i), g_scene);
    assert_true(isfinite(p) && p > 0.0);
    checks += 3;
  }
  assert_int_equal(g_scene->n_infinite, 4);
  assert_near(L(L_AREA)->area, 1.0, 1e-6);
  assert_near(light_power(L(L_AREA), g_scene), M_PI * 1.0 * rgb_luminance(area_L), 1e-5);
  assert_near(light_power(L(L_POINT), g_scene), 4.0 * M_PI * rgb_luminance(point_I), 1e-12);
  /* Triangle choice in proportion to area. */
  const double areas[4] = {0.1, 0.15, 0.4, 0.35};
  for (int t = 0; t < 4; t++) assert_near(distrib1d_pmf(&L(L_AREA)->tri_dist, t), areas[t], 1e-6);
  /* The spot's prepared cosines. */
  assert_near(L(L_SPOT)->cos_cutoff, cos(SPOT_CUTOFF), 1e-15);
  assert_near(L(L_SPOT)->cos_beam, cos(SPOT_BEAM), 1e-15);
  checks += 10;
  assert_int_equal(checks, 3 * N_LIGHTS + 10);
}

/* A light_prepare failure is an error, not a crash. */
static void test_prepare_errors(void **state) {
  (void)state;
  lmc_error err;
  int checks = 0;
  light l;
  memset(&l, 0, sizeof l);
  l.type = LIGHT_AREA;
  l.mesh = 7; /* no such mesh */
  lmc_error_clear(&err);
  assert_int_equal(light_prepare(&l, g_scene, &err), LMC_EINVAL);
  assert_true(err.msg[0] != '\0');
  memset(&l, 0, sizeof l);
  l.type = LIGHT_SPOT; /* no direction */
  l.cutoff = 0.3;
  assert_int_equal(light_prepare(&l, g_scene, &err), LMC_EINVAL);
  memset(&l, 0, sizeof l);
  l.type = LIGHT_ENVMAP; /* no image */
  assert_int_equal(light_prepare(&l, g_scene, &err), LMC_EINVAL);
  light_free(&l);
  light_free(NULL);
  checks += 4;
  assert_int_equal(checks, 4);
}

/* ---------------------------------------------------------------------------
 * Area light.
 */

/* Integral over [0,a] x [0,b] at height h of cos * cos_l / d^2 =
 * h^2 / (x^2 + y^2 + h^2)^2; odd in a and in b. */
static double rect_corner(double a, double b, double h) {
  double ra = sqrt(a * a + h * h), rb = sqrt(b * b + h * h);
  return 0.5 * (a / ra * atan(b / ra) + b / rb * atan(a / rb));
}

static void test_area_li(void **state) {
  (void)state;
  int checks = 0;
  ctx c = {L(L_AREA), v3(0.1, 0.2, 0.0), v3(0, 0, -1)};
  /* The emitting normal is the flipped winding normal. */
  vec3 n = mesh_face_normal(&g_scene->meshes[0], 0);
  assert_near(n.z, -1.0, 1e-12);
  checks++;

  /* Chi-square of the directions. chi2_sphere's cells would cut the
   * light's sharp outline into slivers that its midpoint rule misses, so
   * the directions are binned in gnomonic coordinates instead,
   * (x, y) = (w.x, w.y) / w.z * (H - ref.z), on a 10 x 10 grid aligned with
   * the square, plus one cell for everything outside it. The expected count
   * of a cell is N times the integral of pdf_li over its solid angle,
   * domega = h dx dy / (h^2 + x^2 + y^2)^(3/2) (midpoint rule on a 16 x 16
   * sub-grid: the integrand is smooth inside a cell). */
  enum { NB = 10, SUBB = 16, NS = 400000 };
  double obs[NB * NB + 1] = {0}, expct[NB * NB + 1] = {0};
  {
    rng g0;
    rng_seed(&g0, SEED_OFFSET + 11, 1);
    double h = H - c.ref.z;
    for (int k = 0; k < NS; k++) {
      vec3 w;
      if (!sample_li_fn(&c, rng_uniform(&g0), rng_uniform(&g0), 0.0, &w) || !(w.z > 0.0)) {
        obs[NB * NB] += 1.0;
        continue;
      }
      double sx = c.ref.x + w.x / w.z * h, sy = c.ref.y + w.y / w.z * h;
      int bx = (int)floor((sx + 0.5) * NB), by = (int)floor((sy + 0.5) * NB);
      if (bx < 0 || bx >= NB || by < 0 || by >= NB) {
        obs[NB * NB] += 1.0;
        continue;
      }
      obs[by * NB + bx] += 1.0;
    }
    double total = 0.0, dxy = 1.0 / (NB * SUBB);
    for (int by = 0; by < NB; by++)
      for (int bx = 0; bx < NB; bx++) {
        double acc = 0.0;
        for (int a = 0; a < SUBB; a++)
          for (int b = 0; b < SUBB; b++) {
            double x = -0.5 + (bx * SUBB + b + 0.5) * dxy - c.ref.x;
            double y = -0.5 + (by * SUBB + a + 0.5) * dxy - c.ref.y;
            double r2 = h * h + x * x + y * y;
            vec3 w = v3_scale(v3(x, y, h), 1.0 / sqrt(r2));
            acc += pdf_li_area_fn(&c, w) * h / (r2 * sqrt(r2)) * dxy * dxy;
          }
        expct[by * NB + bx] = acc * NS;
        total += acc;
      }
    expct[NB * NB] = fmax(0.0, 1.0 - total) * NS;
    chi2_result r = {0};
    r.pvalue = chi2_pvalue(obs, expct, NB * NB + 1, 5.0, &r.dof, &r.stat);
    r.pdf_integral = total;
    r.accepted = (int64_t)(NS - obs[NB * NB]);
    check_chi2("area sample_li", r);
    assert_true(obs[NB * NB] == 0.0);
    assert_near(total, 1.0, 1e-3);
    checks += 3;
  }

  /* Fine quadrature of pdf_li over the upper hemisphere. */
  int nz = 2000, nphi = 2000;
  double integral = 0.0, e_quad = 0.0;
  for (int i = 0; i < nz; i++) {
    double z = (i + 0.5) / nz, st = sqrt(1.0 - z * z);
    for (int j = 0; j < nphi; j++) {
      double phi = 2.0 * M_PI * (j + 0.5) / nphi;
      vec3 w = v3(st * cos(phi), st * sin(phi), z);
      double pdf = pdf_li_area_fn(&c, w);
      integral += pdf;
      if (pdf > 0.0) {
        /* Independent irradiance quadrature: L_e towards the receiver. */
        e_quad += light_le_area(c.l, n, v3_neg(w)).r * z;
      }
    }
  }
  double dw = (1.0 / nz) * (2.0 * M_PI / nphi);
  integral *= dw;
  e_quad *= dw;
  assert_near(integral, 1.0, 5e-3);
  checks++;

  /* Closed form: the rectangle relative to the receiver. */
  double x0 = -0.5 - c.ref.x, x1 = 0.5 - c.ref.x, y0 = -0.5 - c.ref.y, y1 = 0.5 - c.ref.y;
  double e_exact = area_L.r * (rect_corner(x1, y1, H) - rect_corner(x0, y1, H) -
                               rect_corner(x1, y0, H) + rect_corner(x0, y0, H));
  assert_near(e_quad, e_exact, 3e-3 * e_exact);
  checks++;

  /* Monte Carlo: mean of L cos / pdf; every sample's pdf agrees with
   * light_pdf_li and its point lies on the square. */
  stats st = {0};
  rng g;
  rng_seed(&g, SEED_OFFSET + 5, 1);
  int bad = 0;
  for (int k = 0; k < 200000; k++) {
    light_li_sample ls;
    if (!light_sample_li(c.l, g_scene, c.ref, rng_uniform(&g), rng_uniform(&g), &ls)) {
      bad++;
      continue;
    }
    if (ls.delta || fabs(ls.p.z - H) > 1e-6 || fabs(ls.p.x) > 0.5 + 1e-6 || fabs(ls.p.y) > 0.5 + 1e-6)
      bad++;
    double pdf2 = light_pdf_li(c.l, g_scene, c.ref, ls.wi, ls.p, ls.n);
    if (fabs(pdf2 - ls.pdf) > 1e-9 * ls.pdf) bad++;
    if (fabs(ls.dist - v3_len(v3_sub(ls.p, c.ref))) > 1e-9) bad++;
    stats_add(&st, ls.li.r * ls.wi.z / ls.pdf);
  }
  assert_int_equal(bad, 0);
  print_message("area irradiance: MC %.6f +- %.6f, exact %.6f, quadrature %.6f\n", st.mean,
                stats_se(&st), e_exact, e_quad);
  assert_near(st.mean, e_exact, 4.0 * stats_se(&st));
  checks += 2;

  /* One-sided: from above, nothing is sampled and le / pdf vanish. */
  vec3 above = v3(0.0, 0.1, 2.0);
  int got = 0;
  for (int k = 0; k < 1000; k++) {
    light_li_sample ls;
    got += light_sample_li(c.l, g_scene, above, rng_uniform(&g), rng_uniform(&g), &ls);
  }
  assert_int_equal(got, 0);
  vec3 down = v3(0.0, -0.1, -1.0);
  assert_true(light_pdf_li(c.l, g_scene, above, v3_normalize(down), v3(0.0, 0.0, H), n) == 0.0);
  assert_true(rgb_is_black(light_le_area(c.l, n, v3(0, 0, 1))));
  assert_true(light_le_area(c.l, n, v3_normalize(v3(0.2, 0.0, -1.0))).g == area_L.g);
  checks += 4;
  assert_int_equal(checks, 12);
}

static void test_area_le(void **state) {
  (void)state;
  int checks = 0;
  ctx c = {L(L_AREA), v3(0, 0, 0), v3(0, 0, -1)};
  /* Directions: cosine-weighted around the emitting normal. */
  chi2_result r = chi2_sphere(sample_le_dir_fn, pdf_le_dir_fn, &c, 32, 64, 8, 300000, SEED_OFFSET + 12);
  check_chi2("area sample_le dir", r);
  assert_near(r.pdf_integral, 1.0, 2e-3);
  checks += 2;

  /* Positions: uniform on the square (8 x 8 bins), on the emitting side. */
  enum { NB = 8, N = 200000 };
  double obs[NB * NB] = {0}, expct[NB * NB];
  rng g;
  rng_seed(&g, SEED_OFFSET + 13, 1);
  int bad = 0;
  for (int k = 0; k < N; k++) {
    light_le_sample es;
    if (!light_sample_le(c.l, g_scene, rng_uniform(&g), rng_uniform(&g), rng_uniform(&g),
                         rng_uniform(&g), &es)) {
      bad++;
      continue;
    }
    if (es.delta_pos || es.delta_dir || fabs(es.p.z - H) > 1e-6 || !(es.dir.z < 0.0)) bad++;
    if (fabs(es.pdf_pos - 1.0 / L(L_AREA)->area) > 1e-12) bad++;
    if (fabs(es.pdf_dir - (-es.dir.z) / M_PI) > 1e-9) bad++;
    double pp, pd;
    light_pdf_le(c.l, g_scene, es.p, es.n, es.dir, &pp, &pd);
    if (fabs(pp - es.pdf_pos) > 1e-12 || fabs(pd - es.pdf_dir) > 1e-9) bad++;
    if (es.le.r != area_L.r) bad++;
    int bx = (int)((es.p.x + 0.5) * NB), by = (int)((es.p.y + 0.5) * NB);
    bx = bx < 0 ? 0 : (bx >= NB ? NB - 1 : bx);
    by = by < 0 ? 0 : (by >= NB ? NB - 1 : by);
    obs[by * NB + bx] += 1.0;
  }
  assert_int_equal(bad, 0);
  for (int i = 0; i < NB * NB; i++) expct[i] = (double)N / (NB * NB);
  int dof;
  double stat;
  double p = chi2_pvalue(obs, expct, NB * NB, 5.0, &dof, &stat);
  print_message("area sample_le position: chi2 %.2f dof %d p %.4f\n", stat, dof, p);
  assert_true(p > alpha_per_test());
  checks += 2;
  assert_int_equal(checks, 4);
}

/* ---------------------------------------------------------------------------
 * Point and spot lights.
 */
static void test_point(void **state) {
  (void)state;
  int checks = 0;
  const light *l = L(L_POINT);
  vec3 ref = v3(1.3, 0.8, -1.6);
  light_li_sample ls;
  assert_true(light_sample_li(l, g_scene, ref, 0.3, 0.7, &ls));
  double d2 = v3_len2(v3_sub(l->pos, ref));
  assert_near(ls.li.g, point_I.g / d2, 1e-12);
  assert_near(ls.dist, sqrt(d2), 1e-12);
  assert_near(v3_dot(ls.wi, v3_normalize(v3_sub(l->pos, ref))), 1.0, 1e-12);
  assert_true(ls.delta && ls.pdf == 1.0);
  assert_true(light_pdf_li(l, g_scene, ref, ls.wi, l->pos, v3(0, 0, 0)) == 0.0);
  checks += 6;

  ctx c = {l, v3(0, 0, 0), v3(0, 0, 1)};
  chi2_result r = chi2_sphere(sample_le_dir_fn, pdf_le_dir_fn, &c, 16, 32, 4, 100000, SEED_OFFSET + 21);
  check_chi2("point sample_le dir", r);
  assert_near(r.pdf_integral, 1.0, 1e-9);
  light_le_sample es;
  assert_true(light_sample_le(l, g_scene, 0.1, 0.2, 0.3, 0.4, &es));
  assert_true(es.delta_pos && !es.delta_dir && es.le.r == point_I.r);
  assert_near(v3_len(v3_sub(es.p, l->pos)), 0.0, 1e-15);
  checks += 5;
  assert_int_equal(checks, 11);
}

static void test_spot(void **state) {
  (void)state;
  int checks = 0;
  const light *l = L(L_SPOT);
  frame f = l->frm;
  /* Falloff seen from receivers at known angles from the axis, distance 2:
   * 1 inside the beam, linear in the angle across the transition, 0 out. */
  const double deg[6] = {0.0, 10.0, 19.9, 25.0, 29.0, 35.0};
  for (int k = 0; k < 6; k++) {
    double th = deg[k] * M_PI / 180.0;
    vec3 dir = frame_to_world(&f, v3(sin(th) * 0.6, sin(th) * 0.8, cos(th)));
    vec3 ref = v3_fma(l->pos, dir, 2.0);
    double expect = th <= SPOT_BEAM ? 1.0
                    : th >= SPOT_CUTOFF ? 0.0
                                        : (SPOT_CUTOFF - th) / (SPOT_CUTOFF - SPOT_BEAM);
    light_li_sample ls;
    int ok = light_sample_li(l, g_scene, ref, 0.5, 0.5, &ls);
    assert_int_equal(ok, expect > 0.0);
    if (ok) assert_near(ls.li.b, spot_I.b * expect / 4.0, 1e-12);
    else assert_true(rgb_is_black(ls.li));
    checks += 2;
  }

  /* Emitted directions against pdf_le. chi2_sphere's cells would cut the
   * cone's sharp rim into slivers its midpoint rule misses, so the
   * directions are binned in the spot's frame, in NZ bands equal in
   * cos(theta) between cos_cutoff and 1 times NP sectors, plus one cell for
   * everything outside the cone; expected counts are N times pdf_le
   * integrated over each cell (midpoint rule, 4 x 4 sub-grid). */
  ctx c = {l, v3(0, 0, 0), v3(0, 0, 1)};
  {
    enum { NZ = 16, NP = 32, SUBC = 4, NS = 200000 };
    double obs[NZ * NP + 1] = {0}, expct[NZ * NP + 1] = {0};
    double cc = l->cos_cutoff, dz = (1.0 - cc) / NZ, dphi = 2.0 * M_PI / NP;
    rng g0;
    rng_seed(&g0, SEED_OFFSET + 31, 1);
    for (int k = 0; k < NS; k++) {
      vec3 w;
      if (!sample_le_dir_fn(&c, rng_uniform(&g0), rng_uniform(&g0), rng_uniform(&g0), &w)) {
        obs[NZ * NP] += 1.0;
        continue;
      }
      vec3 q = frame_to_local(&f, w);
      if (q.z < cc) {
        obs[NZ * NP] += 1.0;
        continue;
      }
      int iz = (int)((1.0 - q.z) / dz), ip = (int)((atan2(q.y, q.x) + M_PI) / dphi);
      iz = iz >= NZ ? NZ - 1 : (iz < 0 ? 0 : iz);
      ip = ip >= NP ? NP - 1 : (ip < 0 ? 0 : ip);
      obs[iz * NP + ip] += 1.0;
    }
    double total = 0.0;
    for (int iz = 0; iz < NZ; iz++)
      for (int ip = 0; ip < NP; ip++) {
        double acc = 0.0;
        for (int a = 0; a < SUBC; a++)
          for (int b = 0; b < SUBC; b++) {
            double z = 1.0 - (iz + (a + 0.5) / SUBC) * dz, sz = sqrt(fmax(0.0, 1.0 - z * z));
            double phi = -M_PI + (ip + (b + 0.5) / SUBC) * dphi;
            acc += pdf_le_dir_fn(&c, frame_to_world(&f, v3(sz * cos(phi), sz * sin(phi), z)));
          }
        acc *= dz * dphi / (SUBC * SUBC);
        expct[iz * NP + ip] = acc * NS;
        total += acc;
      }
    expct[NZ * NP] = fmax(0.0, 1.0 - total) * NS;
    chi2_result r = {0};
    r.pvalue = chi2_pvalue(obs, expct, NZ * NP + 1, 5.0, &r.dof, &r.stat);
    r.pdf_integral = total;
    r.accepted = (int64_t)(NS - obs[NZ * NP]);
    check_chi2("spot sample_le dir", r);
    assert_near(total, 1.0, 1e-12);
    checks += 2;
  }
  /* pdf_le integrates to 1 over the whole sphere (world-frame quadrature;
   * the rim's cells bound the error by about 2e-3). */
  {
    int nz = 2000, nphi = 2000;
    double integral = 0.0;
    for (int i = 0; i < nz; i++) {
      double z = 1.0 - 2.0 * (i + 0.5) / nz, sz = sqrt(fmax(0.0, 1.0 - z * z));
      for (int j = 0; j < nphi; j++) {
        double phi = 2.0 * M_PI * (j + 0.5) / nphi;
        integral += pdf_le_dir_fn(&c, v3(sz * cos(phi), sz * sin(phi), z));
      }
    }
    integral *= (2.0 / nz) * (2.0 * M_PI / nphi);
    assert_near(integral, 1.0, 2e-3);
    checks++;
  }

  /* Integral of the intensity over the sphere:
   * 2 pi I (1 + (sin beam - sin cutoff) / (cutoff - beam)). */
  double exact = 2.0 * M_PI * spot_I.r *
                 (1.0 + (sin(SPOT_BEAM) - sin(SPOT_CUTOFF)) / (SPOT_CUTOFF - SPOT_BEAM));
  stats st = {0};
  rng g;
  rng_seed(&g, SEED_OFFSET + 33, 1);
  int bad = 0;
  for (int k = 0; k < 200000; k++) {
    light_le_sample es;
    double u[4] = {rng_uniform(&g), rng_uniform(&g), rng_uniform(&g), rng_uniform(&g)};
    if (light_sample_le(l, g_scene, u[0], u[1], u[2], u[3], &es)) {
      if (!es.delta_pos || v3_dot(es.dir, f.n) < l->cos_cutoff - 1e-12) bad++;
      stats_add(&st, es.le.r / es.pdf_dir);
    } else {
      stats_add(&st, 0.0);
    }
  }
  assert_int_equal(bad, 0);
  print_message("spot intensity integral: MC %.6f +- %.6f, exact %.6f\n", st.mean, stats_se(&st),
                exact);
  assert_near(st.mean, exact, 4.0 * stats_se(&st));
  checks += 2;
  assert_int_equal(checks, 17);
}

/* ---------------------------------------------------------------------------
 * Directional light.
 */
static void test_directional(void **state) {
  (void)state;
  int checks = 0;
  const light *l = L(L_DIR);
  vec3 n = v3_normalize(v3(0.3, -1.0, 0.2));
  assert_near(v3_dot(l->frm.n, n), 1.0, 1e-12);
  light_li_sample ls;
  assert_true(light_sample_li(l, g_scene, v3(0.2, 0.1, 0.3), 0.4, 0.6, &ls));
  assert_near(v3_dot(ls.wi, n), -1.0, 1e-12);
  assert_true(isinf(ls.dist) && ls.delta && ls.li.r == dir_E.r);
  assert_true(light_pdf_li(l, g_scene, v3(0, 0, 0), ls.wi, ls.p, ls.n) == 0.0);
  checks += 5;

  /* Emission: the disk of radius r centred at center - n r, perpendicular
   * to n; uniform (equal-area bins in (rho^2, phi)). */
  enum { NR = 8, NP = 16, N = 200000 };
  double obs[NR * NP] = {0}, expct[NR * NP];
  frame f = frame_from_z(n);
  double rad = g_scene->radius;
  vec3 c0 = v3_fma(g_scene->center, n, -rad);
  rng g;
  rng_seed(&g, SEED_OFFSET + 41, 1);
  int bad = 0;
  for (int k = 0; k < N; k++) {
    light_le_sample es;
    if (!light_sample_le(l, g_scene, rng_uniform(&g), rng_uniform(&g), rng_uniform(&g),
                         rng_uniform(&g), &es)) {
      bad++;
      continue;
    }
    vec3 q = frame_to_local(&f, v3_sub(es.p, c0));
    double rho2 = (q.x * q.x + q.y * q.y) / (rad * rad);
    if (fabs(q.z) > 1e-9 * rad || rho2 > 1.0 + 1e-12) bad++;
    if (!es.delta_dir || es.delta_pos || v3_dot(es.dir, n) < 1.0 - 1e-12) bad++;
    if (fabs(es.pdf_pos * M_PI * rad * rad - 1.0) > 1e-12 || es.le.g != dir_E.g) bad++;
    double phi = atan2(q.y, q.x) + M_PI;
    int ir = (int)(rho2 * NR), ip = (int)(phi / (2.0 * M_PI) * NP);
    ir = ir >= NR ? NR - 1 : ir;
    ip = ip >= NP ? NP - 1 : (ip < 0 ? 0 : ip);
    obs[ir * NP + ip] += 1.0;
  }
  assert_int_equal(bad, 0);
  for (int i = 0; i < NR * NP; i++) expct[i] = (double)N / (NR * NP);
  int dof;
  double stat;
  double p = chi2_pvalue(obs, expct, NR * NP, 5.0, &dof, &stat);
  print_message("directional disk: chi2 %.2f dof %d p %.4f\n", stat, dof, p);
  assert_true(p > alpha_per_test());
  checks += 2;
  assert_int_equal(checks, 7);
}

/* ---------------------------------------------------------------------------
 * Constant light.
 */
static void test_constant(void **state) {
  (void)state;
  int checks = 0;
  const light *l = L(L_CONST);
  ctx c = {l, v3(0.1, 0.2, 0.3), v3(0, 0, 1)};
  chi2_result r = chi2_sphere(sample_li_fn, pdf_li_inf_fn, &c, 16, 32, 4, 100000, SEED_OFFSET + 51);
  check_chi2("constant sample_li", r);
  assert_near(r.pdf_integral, 1.0, 1e-9);
  r = chi2_sphere(sample_le_dir_fn, pdf_le_dir_fn, &c, 16, 32, 4, 100000, SEED_OFFSET + 52);
  check_chi2("constant sample_le dir", r);
  checks += 3;

  /* Irradiance on a plane with normal m: pi L. */
  vec3 m = v3_normalize(v3(0.4, -0.3, 0.8));
  stats st = {0};
  rng g;
  rng_seed(&g, SEED_OFFSET + 53, 1);
  int bad = 0;
  for (int k = 0; k < 200000; k++) {
    light_li_sample ls;
    if (!light_sample_li(l, g_scene, c.ref, rng_uniform(&g), rng_uniform(&g), &ls)) bad++;
    if (!isinf(ls.dist) || ls.delta) bad++;
    if (light_le_infinite(l, ls.wi).b != const_L.b) bad++;
    stats_add(&st, ls.li.b * fmax(0.0, v3_dot(ls.wi, m)) / ls.pdf);
  }
  print_message("constant irradiance: MC %.6f +- %.6f, exact %.6f\n", st.mean, stats_se(&st),
                M_PI * const_L.b);
  assert_int_equal(bad, 0);
  assert_near(st.mean, M_PI * const_L.b, 4.0 * stats_se(&st));
  checks += 2;

  /* Emission: origin on the disk of radius r facing dir, outside the
   * bounding sphere. */
  bad = 0;
  double rad = g_scene->radius;
  for (int k = 0; k < 10000; k++) {
    light_le_sample es;
    if (!light_sample_le(l, g_scene, rng_uniform(&g), rng_uniform(&g), rng_uniform(&g),
                         rng_uniform(&g), &es)) {
      bad++;
      continue;
    }
    vec3 q = v3_sub(es.p, g_scene->center);
    double along = v3_dot(q, es.dir);
    double perp2 = v3_len2(q) - along * along;
    if (fabs(along + rad) > 1e-9 * rad || perp2 > rad * rad * (1.0 + 1e-9)) bad++;
    if (fabs(es.pdf_pos * M_PI * rad * rad - 1.0) > 1e-12 || es.delta_pos || es.delta_dir) bad++;
  }
  assert_int_equal(bad, 0);
  checks++;
  assert_int_equal(checks, 6);
}

/* ---------------------------------------------------------------------------
 * Environment map.
 */

/* Mitsuba's lat-long map: pixel centre (x, y) -> local direction. */
static vec3 mitsuba_dir(double x, double y) {
  double phi = 2.0 * M_PI * (x + 0.5) / ENV_W, theta = M_PI * (y + 0.5) / ENV_H;
  return v3(sin(phi) * sin(theta), cos(theta), -cos(phi) * sin(theta));
}

static void test_envmap_orientation(void **state) {
  (void)state;
  int checks = 0;
  const light *l = L(L_ENV_ID);
  /* Every pixel centre maps to its own pixel (r = x + 100 y). */
  int bad = 0;
  for (int y = 0; y < ENV_H; y++)
    for (int x = 0; x < ENV_W; x++)
      if (light_le_infinite(l, mitsuba_dir(x, y)).r != x + 100 * y) bad++;
  assert_int_equal(bad, 0);
  checks++;
  /* The axes, spelled out: top row is +y, column 0 looks along -z, a
   * quarter turn is +x, half a turn +z. Directions slightly above the
   * equator land in row ENV_H / 2 - 1. */
  double e = 0.01;
  assert_near(light_le_infinite(l, v3_normalize(v3(0, e, -1))).r, 0 + 100 * (ENV_H / 2 - 1), 0);
  assert_near(light_le_infinite(l, v3_normalize(v3(1, e, -e))).r, 7 + 100 * (ENV_H / 2 - 1), 0);
  assert_near(light_le_infinite(l, v3_normalize(v3(1, e, e))).r, 8 + 100 * (ENV_H / 2 - 1), 0);
  assert_near(light_le_infinite(l, v3_normalize(v3(e, -e, 1))).r, 15 + 100 * (ENV_H / 2), 0);
  assert_near(light_le_infinite(l, v3_normalize(v3(-1, -e, -e))).r, 24 + 100 * (ENV_H / 2), 0);
  assert_true(light_le_infinite(l, v3_normalize(v3(e, 1, e))).r < ENV_W);         /* row 0 */
  assert_true(light_le_infinite(l, v3_normalize(v3(e, -1, e))).r >= 100 * (ENV_H - 1));
  checks += 7;

  /* Sampling a single bright pixel (11, 3) lands inside it. */
  const light *one = L(L_ENV_ONE);
  rng g;
  rng_seed(&g, SEED_OFFSET + 61, 1);
  bad = 0;
  for (int k = 0; k < 2000; k++) {
    light_li_sample ls;
    if (!light_sample_li(one, g_scene, v3(0, 0, 0), rng_uniform(&g), rng_uniform(&g), &ls)) {
      bad++;
      continue;
    }
    if (light_le_infinite(l, ls.wi).r != 11 + 100 * 3) bad++;
    if (ls.li.g != 1.0) bad++;
  }
  assert_int_equal(bad, 0);
  checks++;

  /* to_world rotates the map: L_rot(R d) = scale * L_test(d), checked on a
   * map with the same pixels but identity transform (through the test map
   * evaluated in its own frame). */
  const light *rot = L(L_ENV);
  bad = 0;
  for (int k = 0; k < 2000; k++) {
    vec3 d = warp_square_to_uniform_sphere(rng_uniform(&g), rng_uniform(&g));
    vec3 w = v3_normalize(xform_vector(&rot->to_world, d));
    /* Local pixel of d by Mitsuba's formula. */
    double u = atan2(d.x, -d.z) / (2.0 * M_PI);
    u = u < 0.0 ? u + 1.0 : u;
    double v = acos(d.y) / M_PI;
    int x = (int)(u * ENV_W), y = (int)(v * ENV_H);
    x = x >= ENV_W ? ENV_W - 1 : x;
    y = y >= ENV_H ? ENV_H - 1 : y;
    const float *p = rot->image.data + 3 * (y * ENV_W + x);
    if (fabs(light_le_infinite(rot, w).g - 1.5 * p[1]) > 1e-6) bad++;
  }
  assert_true(bad <= 2); /* directions within roundoff of a pixel edge */
  checks++;
  assert_int_equal(checks, 10);
}

static void test_envmap_sampling(void **state) {
  (void)state;
  int checks = 0;
  const light *l = L(L_ENV);
  ctx c = {l, v3(0.1, 0.2, 0.3), v3(0, 0, 1)};
  chi2_result r = chi2_sphere(sample_li_fn, pdf_li_inf_fn, &c, 32, 64, 24, 300000, SEED_OFFSET + 71);
  check_chi2("envmap sample_li", r);
  assert_near(r.pdf_integral, 1.0, 2e-3);
  r = chi2_sphere(sample_le_dir_fn, pdf_le_dir_fn, &c, 32, 64, 24, 300000, SEED_OFFSET + 72);
  check_chi2("envmap sample_le dir", r);
  checks += 3;

  /* Irradiance on a tilted plane: Monte Carlo against a quadrature of
   * light_le_infinite over the sphere. */
  vec3 m = v3_normalize(v3(0.2, 1.0, -0.3));
  int nz = 1500, nphi = 3000;
  double e_quad = 0.0;
  for (int i = 0; i < nz; i++) {
    double z = 1.0 - 2.0 * (i + 0.5) / nz, s = sqrt(fmax(0.0, 1.0 - z * z));
    for (int j = 0; j < nphi; j++) {
      double phi = 2.0 * M_PI * (j + 0.5) / nphi;
      vec3 w = v3(s * cos(phi), s * sin(phi), z);
      double cm = v3_dot(w, m);
      if (cm > 0.0) e_quad += light_le_infinite(l, w).r * cm;
    }
  }
  e_quad *= (2.0 / nz) * (2.0 * M_PI / nphi);

  stats st = {0};
  rng g;
  rng_seed(&g, SEED_OFFSET + 73, 1);
  int bad = 0, mismatch = 0;
  for (int k = 0; k < 400000; k++) {
    light_li_sample ls;
    if (!light_sample_li(l, g_scene, c.ref, rng_uniform(&g), rng_uniform(&g), &ls)) {
      stats_add(&st, 0.0);
      continue;
    }
    if (!isinf(ls.dist) || ls.delta || !(ls.pdf > 0.0)) bad++;
    double pdf2 = light_pdf_li(l, g_scene, c.ref, ls.wi, ls.p, ls.n);
    if (fabs(pdf2 - ls.pdf) > 1e-6 * ls.pdf) mismatch++;
    stats_add(&st, ls.li.r * fmax(0.0, v3_dot(ls.wi, m)) / ls.pdf);
  }
  assert_int_equal(bad, 0);
  /* Samples on a pixel edge may be attributed to the neighbour. */
  assert_true(mismatch < 40);
  /* Quadrature error: cells cut by pixel edges, bounded by about 1e-3 of
   * the value for this grid. */
  double tol = 4.0 * stats_se(&st) + 1e-3 * e_quad;
  print_message("envmap irradiance: MC %.6f +- %.6f, quadrature %.6f (pdf mismatches %d)\n",
                st.mean, stats_se(&st), e_quad, mismatch);
  assert_near(st.mean, e_quad, tol);
  checks += 3;

  /* Emission positions lie on the disk facing the travel direction. */
  bad = 0;
  double rad = g_scene->radius;
  for (int k = 0; k < 10000; k++) {
    light_le_sample es;
    if (!light_sample_le(l, g_scene, rng_uniform(&g), rng_uniform(&g), rng_uniform(&g),
                         rng_uniform(&g), &es))
      continue;
    vec3 q = v3_sub(es.p, g_scene->center);
    if (fabs(v3_dot(q, es.dir) + rad) > 1e-9 * rad) bad++;
    if (fabs(light_le_infinite(l, v3_neg(es.dir)).r - es.le.r) > 1e-9) bad++;
  }
  assert_true(bad < 10);
  checks++;
  assert_int_equal(checks, 7);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_flags_and_power),
      cmocka_unit_test(test_prepare_errors),
      cmocka_unit_test(test_area_li),
      cmocka_unit_test(test_area_le),
      cmocka_unit_test(test_point),
      cmocka_unit_test(test_spot),
      cmocka_unit_test(test_directional),
      cmocka_unit_test(test_constant),
      cmocka_unit_test(test_envmap_orientation),
      cmocka_unit_test(test_envmap_sampling),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
