/*
 * test_bsdf.c: the BSDF models of src/render/bsdf*.c and the microfacet
 * distributions of src/render/microfacet.c.
 *
 * What is checked:
 *   - chi-square goodness of fit of every non-delta sampler against its pdf
 *     (diffuse, phong at three exponents, roughconductor and
 *     roughdielectric for both distributions, two roughnesses, visible
 *     normals on and off, normal / oblique / grazing wo, both sides for the
 *     dielectric, the diffuse part of plastic, roughdiffuse full and fast
 *     at two roughnesses, ward's three variants isotropic and anisotropic,
 *     roughplastic for both distributions at alpha 0.1 and 0.5, normal /
 *     oblique / grazing wo, linear and nonlinear, masks), each at the Sidak
 *     level of an overall 1% (fixed seeds), plus the visible-normal sampler
 *     alone;
 *   - the pdf integrates to the fraction of samples the sampler accepts
 *     (the total probability of its non-delta lobes), and to 1 - P(specular)
 *     for plastic; D(m) cos(theta_m) and the visible-normal density
 *     integrate to 1;
 *   - sample consistency: f and pdf of a sample equal bsdf_eval and
 *     bsdf_pdf at that direction, weight = f |cos| / pdf, and a reverse
 *     density the sampler computed equals bsdf_pdf(wi, wo);
 *   - energy: diffuse albedo = reflectance, plastic albedo in closed form
 *     (F_i + (1 - F_i) kd, linear mode), phong and rough models at most 1
 *     (roughplastic with white base and coating, both distributions, alpha
 *     0.05, 0.3, 1, four angles), a perfect mirror ("none") reflects
 *     exactly 1; roughplastic at alpha = 0.001 against smooth plastic: its
 *     rough F_dr against the smooth one, its diffuse value away from the
 *     mirror direction (relative 2e-3), its albedo against plastic's closed
 *     form (4 standard errors + 2e-3);
 *   - roughdiffuse: alpha = 0 is Lambertian bit for bit (both variants);
 *     f equals a transcription of Oren and Nayar's formulas in angles;
 *     albedo (R = 1) in closed form at the normal (A; C1 + C4) and, for the
 *     fast model, at grazing (A + B/2, above 1 for alpha < 0.46); albedo
 *     <= 1 for wo.z >= 0.8 and <= 1.05 at all angles;
 *   - ward: f at the mirror direction against the closed form; the
 *     anisotropy along the frame's x and y (swapping alphaU, alphaV = a
 *     90 degree turn), isotropy under any turn; albedo <= 1 (ks + kd <= 1)
 *     for balanced and ward at all angles and ward-duer away from grazing,
 *     and ward-duer above 1 at grazing (Mitsuba's documentation);
 *   - reciprocity of the reflection models (roughdiffuse, the three ward
 *     variants and roughplastic included: their f are symmetric), and for
 *     rough refraction the
 *     generalised reciprocity f_rad(a, b) eta_b^2 = f_rad(b, a) eta_a^2 and
 *     the adjoint f_imp(a, b) = f_rad(b, a);
 *   - delta lobes: dielectric reflect + refract probabilities sum to 1 and
 *     equal F, Snell's law, total internal reflection, radiance scaling;
 *     thindielectric's reflect probability equals the series of the slab's
 *     passes R + sum (1 - R)^2 R^(2k+1), reflect + transmit = 1, the
 *     transmitted direction is exactly -wo with weight 1 in both modes and
 *     eta 1, both sides alike, eta = 1 always transmits;
 *   - one-sidedness and the twosided flip; Fresnel identities; tables and
 *     defaults (the new models' defaults, flags, bsdf_is_rough, bsdf_prepare);
 *   - the mask: f, pdf and samples against the wrapped model's, its
 *     pass-through lobe, and energy conservation of a white diffuse mask.
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
#include "chi2.h"
#include "render/bsdf/bsdf.h"
#include "render/bsdf/microfacet.h"
#include "render/rng.h"
#include "render/warp.h"



static double rel_err(double a, double b) { return fabs(a - b) / fmax(1e-300, fmax(fabs(a), fabs(b))); }

static double rgb_rel_err(rgb a, rgb b) {
  return fmax(rel_err(a.r, b.r), fmax(rel_err(a.g, b.g), rel_err(a.b, b.b)));
}

/* ---- chi-square ------------------------------------------------------------ */


static int chi2_bsdf_sample(void *ctx, double u1, double u2, double u3, vec3 *w) {
  const config *c = ctx;
  bsdf_sample s;
  if (!bsdf_sample_f(&c->b, 0.5, 0.5, c->wo, u1, u2, u3, c->mode, &s)) return 0;
  if (s.flags & BSDF_DELTA) return 0;
  *w = s.wi;
  return 1;
}

/* The chi-square helper integrates the pdf over each cell by a midpoint
 * rule and fails outright when a cell with zero expectation receives a
 * sample. Where the pdf falls continuously to zero at a curved boundary
 * (the edge of the refraction cone, where 1 - F -> 0, or v.m -> 0 for
 * visible normals) a cell can straddle the boundary with all its midpoints
 * outside. A floor of 1e-9 per steradian (total mass 1.3e-8, i.e. 0.003 of
 * a sample at N = 2e5) gives such cells a tiny expectation so they are
 * pooled; a sampler that really puts mass where the pdf is zero still
 * fails through the pooled cell, and test_sample_consistency checks that
 * every sample has pdf > 0. */
#define PDF_FLOOR 1e-9

static double chi2_bsdf_pdf(void *ctx, vec3 w) {
  const config *c = ctx;
  return fmax(PDF_FLOOR, bsdf_pdf(&c->b, 0.5, 0.5, c->wo, w));
}

/* Samples per chi-square test; with 60 x 120 cells the expected counts of
 * the lobes are in the hundreds to thousands (cells expecting fewer than 5
 * are pooled by chi2_pvalue). */
#define CHI2_SAMPLES 200000

static void test_chi2_sampling(void **state) {
  (void)state;
  static config cfg[MAX_CONFIGS];
  int n = make_configs(cfg);
  assert_true(n <= MAX_CONFIGS);
  double level = chi2_sidak(0.01, n);
  int passed = 0, integral_ok = 0;
  for (int i = 0; i < n; i++) {
    chi2_result r = chi2_sphere(chi2_bsdf_sample, chi2_bsdf_pdf, &cfg[i], cfg[i].n_theta, cfg[i].n_phi, 6, CHI2_SAMPLES,
                                1000 + (uint64_t)i);
    if (r.pvalue > level)
      passed++;
    else
      print_error("chi2 FAILED %s: p = %g (level %g), stat %g, dof %d\n", cfg[i].name, r.pvalue,
                  level, r.stat, r.dof);
    /* The pdf integrates to the accepted fraction: binomial standard error
     * sqrt(p (1 - p) / N) <= 1.2e-3 at N = 2e5; allow 5 of them plus 3e-3
     * for the midpoint integration of the sharpest lobes. */
    double acc = (double)r.accepted / CHI2_SAMPLES;
    double tol = 5.0 * sqrt(fmax(acc * (1.0 - acc), 1e-6) / CHI2_SAMPLES) + 3e-3;
    if (fabs(r.pdf_integral - acc) <= tol && r.pdf_integral <= 1.0 + 3e-3)
      integral_ok++;
    else
      print_error("pdf integral %s: %g, accepted fraction %g\n", cfg[i].name, r.pdf_integral, acc);
  }
  assert_int_equal(passed, n);
  assert_int_equal(integral_ok, n);
}

/* The visible-normal and D cos samplers of microfacet.c on their own. */
typedef struct mf_ctx {
  mf_dist dist;
  double alpha;
  vec3 v;
  int visible;
} mf_ctx;

static int chi2_mf_sample(void *ctx, double u1, double u2, double u3, vec3 *w) {
  const mf_ctx *c = ctx;
  (void)u3;
  *w = mf_sample(c->dist, c->alpha, c->v, c->visible, u1, u2);
  return 1;
}

static double chi2_mf_pdf(void *ctx, vec3 w) {
  const mf_ctx *c = ctx;
  return fmax(PDF_FLOOR, mf_pdf(c->dist, c->alpha, c->v, w, c->visible));
}

static void test_chi2_microfacet(void **state) {
  (void)state;
  const double alphas[] = {0.3, 0.8};
  const double vz[] = {0.99, 0.5, 0.05};
  int k = 0, passed = 0;
  double level = chi2_sidak(0.01, 2 * 2 * 2 * 3);
  for (int d = 0; d < 2; d++)
    for (int a = 0; a < 2; a++)
      for (int vis = 0; vis < 2; vis++)
        for (int i = 0; i < 3; i++) {
          mf_ctx c = {d ? MF_GGX : MF_BECKMANN, alphas[a], dir(vz[i], 2.0), vis};
          chi2_result r = chi2_sphere(chi2_mf_sample, chi2_mf_pdf, &c, 100, 100, 8, 100000,
                                      77 + (uint64_t)k);
          k++;
          /* Normalisation: these densities integrate to exactly 1. */
          if (r.pvalue > level && fabs(r.pdf_integral - 1.0) < 5e-3)
            passed++;
          else
            print_error("mf chi2 %d a=%g vis=%d vz=%g: p=%g integral=%g\n", d, alphas[a], vis, vz[i],
                        r.pvalue, r.pdf_integral);
        }
  assert_int_equal(k, 24);
  assert_int_equal(passed, k);
}

/* ---- pdf / eval / sample consistency --------------------------------------- */

static void test_sample_consistency(void **state) {
  (void)state;
  static config cfg[MAX_CONFIGS];
  int n = make_configs(cfg);
  rng r;
  rng_seed(&r, 4242, 1);
  long checked = 0, checked_rev = 0, bad = 0;
  for (int i = 0; i < n; i++) {
    const config *c = &cfg[i];
    for (int j = 0; j < 2000; j++) {
      bsdf_sample s;
      double ul = rng_uniform(&r), u1 = rng_uniform(&r), u2 = rng_uniform(&r);
      if (!bsdf_sample_f(&c->b, 0.5, 0.5, c->wo, ul, u1, u2, c->mode, &s)) continue;
      if (s.flags & BSDF_DELTA) continue;
      rgb f = bsdf_eval(&c->b, 0.5, 0.5, c->wo, s.wi, c->mode);
      double pdf = bsdf_pdf(&c->b, 0.5, 0.5, c->wo, s.wi);
      rgb w = rgb_scale(f, fabs(s.wi.z) / pdf);
      int ok = fabs(v3_len(s.wi) - 1.0) < 1e-12 && rgb_rel_err(f, s.f) < 1e-9 &&
               rel_err(pdf, s.pdf) < 1e-9 && rgb_rel_err(w, s.weight) < 1e-9 && pdf > 0.0;
      /* A reverse density computed in the same pass is bsdf_pdf(wi, wo). */
      if (s.has_pdf_rev) {
        double rev = bsdf_pdf(&c->b, 0.5, 0.5, s.wi, c->wo);
        ok = ok && (rev == 0.0 ? s.pdf_rev == 0.0 : rel_err(rev, s.pdf_rev) < 1e-9);
        checked_rev++;
      }
      /* The flags say which side wi is on. */
      int side_ok = (s.flags & BSDF_TRANSMISSION) ? (s.wi.z * c->wo.z < 0.0) : 1;
      if (!(s.flags & BSDF_TRANSMISSION) && !c->b.twosided) side_ok = s.wi.z * c->wo.z > 0.0;
      if (c->b.twosided) side_ok = s.wi.z < 0.0;
      if (!ok || !side_ok) {
        if (bad < 5)
          print_error("%s: wi (%g %g %g) f %g/%g pdf %g/%g w %g/%g\n", c->name, s.wi.x, s.wi.y,
                      s.wi.z, f.r, s.f.r, pdf, s.pdf, w.r, s.weight.r);
        bad++;
      }
      checked++;
    }
  }
  assert_true(checked > 100000);
  assert_true(checked_rev > 20000); /* the rough models compute it */
  assert_int_equal(bad, 0);
}

/* ---- mask ------------------------------------------------------------------ */

/* Mitsuba's mask around a model, from both sides and in both modes: f and
 * the density are the model's times the opacity and its luminance P; u_lobe
 * at or above P passes straight through (wi = -wo, delta transmission,
 * eta 1, density 1 - P, weight (1 - opacity) / (1 - P)); below P the
 * model's own sample at u_lobe / P, f times the opacity, density times P.
 * A white diffuse mask conserves energy: opacity reflected plus
 * 1 - opacity passed is 1 in every channel (Monte Carlo, 5 sigma). */
static void test_mask(void **state) {
  (void)state;
  int checks = 0;
  const rgb alpha = rgb_make(0.2, 0.5, 0.9);
  const double prob = rgb_luminance(alpha);
  bsdf models[3];
  bsdf_init_defaults(&models[0], "diffuse");
  bsdf_init_defaults(&models[1], "roughconductor");
  models[1].twosided = 1;
  models[1].alpha = 0.3;
  bsdf_init_defaults(&models[2], "dielectric");
  rng r;
  rng_seed(&r, 99, 5);
  for (int m = 0; m < 3; m++) {
    bsdf masked = models[m];
    masked.masked = 1;
    masked.opacity = tex_constant(alpha);
    for (int k = 0; k < 200; k++) {
      vec3 wo = dir(2.0 * rng_uniform(&r) - 1.0, 2.0 * M_PI * rng_uniform(&r));
      vec3 wi = dir(2.0 * rng_uniform(&r) - 1.0, 2.0 * M_PI * rng_uniform(&r));
      transport_mode mode = (transport_mode)(k & 1);
      /* eval and pdf. */
      rgb f0 = bsdf_eval(&models[m], 0.5, 0.5, wo, wi, mode);
      rgb f1 = bsdf_eval(&masked, 0.5, 0.5, wo, wi, mode);
      double p0 = bsdf_pdf(&models[m], 0.5, 0.5, wo, wi), p1 = bsdf_pdf(&masked, 0.5, 0.5, wo, wi);
      double pe;
      rgb fe = bsdf_eval_pdf(&masked, 0.5, 0.5, wo, wi, mode, &pe);
      assert_true(rgb_rel_err(f1, rgb_mul(f0, alpha)) <= 1e-15 || rgb_is_black(f0));
      assert_true(rel_err(p1, p0 * prob) <= 1e-15 || p0 == 0.0);
      assert_true(memcmp(&fe, &f1, sizeof fe) == 0 && pe == p1);
      /* The pass-through. */
      bsdf_sample s;
      double ul = prob + (1.0 - prob) * rng_uniform(&r);
      assert_true(bsdf_sample_f(&masked, 0.5, 0.5, wo, ul, 0.3, 0.6, mode, &s));
      assert_int_equal(s.flags, BSDF_TRANSMISSION | BSDF_DELTA);
      assert_true(s.wi.x == -wo.x && s.wi.y == -wo.y && s.wi.z == -wo.z && s.eta == 1.0);
      assert_true(rel_err(s.pdf, 1.0 - prob) < 1e-15 && s.has_pdf_rev && s.pdf_rev == s.pdf);
      rgb w = rgb_scale(rgb_sub(rgb_gray(1.0), alpha), 1.0 / (1.0 - prob));
      assert_true(rgb_rel_err(s.weight, w) < 1e-14);
      /* The model's lobes. */
      double ul2 = prob * rng_uniform(&r), u1 = rng_uniform(&r), u2 = rng_uniform(&r);
      bsdf_sample s0, s1;
      int ok0 = bsdf_sample_f(&models[m], 0.5, 0.5, wo, ul2 / prob, u1, u2, mode, &s0);
      int ok1 = bsdf_sample_f(&masked, 0.5, 0.5, wo, ul2, u1, u2, mode, &s1);
      assert_int_equal(ok0, ok1);
      if (ok0) {
        assert_true(s1.wi.x == s0.wi.x && s1.wi.y == s0.wi.y && s1.wi.z == s0.wi.z);
        assert_int_equal(s1.flags, s0.flags);
        assert_true(rgb_rel_err(s1.f, rgb_mul(s0.f, alpha)) < 1e-14);
        assert_true(rel_err(s1.pdf, s0.pdf * prob) < 1e-14);
        assert_true(rgb_rel_err(s1.weight, rgb_scale(rgb_mul(s0.weight, alpha), 1.0 / prob)) <
                    1e-14);
        if (s0.has_pdf_rev) assert_true(rel_err(s1.pdf_rev, s0.pdf_rev * prob) < 1e-14);
      }
      checks++;
    }
  }
  /* Energy of a white diffuse mask, per channel. */
  bsdf white;
  bsdf_init_defaults(&white, "diffuse");
  white.diffuse = tex_constant(rgb_gray(1.0));
  white.masked = 1;
  white.opacity = tex_constant(alpha);
  const int n = 200000;
  double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
  for (int i = 0; i < n; i++) {
    bsdf_sample s;
    double ul = rng_uniform(&r), u1 = rng_uniform(&r), u2 = rng_uniform(&r);
    double w[3] = {0, 0, 0};
    if (bsdf_sample_f(&white, 0.5, 0.5, dir(0.6, 0.4), ul, u1, u2, TRANSPORT_RADIANCE, &s))
      w[0] = s.weight.r, w[1] = s.weight.g, w[2] = s.weight.b;
    for (int c = 0; c < 3; c++) sum[c] += w[c], sum2[c] += w[c] * w[c];
  }
  for (int c = 0; c < 3; c++) {
    double mean = sum[c] / n, se = sqrt((sum2[c] / n - mean * mean) / n);
    if (fabs(mean - 1.0) > 5.0 * se + 1e-12)
      fail_msg("white mask channel %d: energy %.6f +- %.6f, expected 1", c, mean, se);
    checks++;
  }
  assert_int_equal(checks, 3 * 200 + 3);
}

/* ---- energy ---------------------------------------------------------------- */

/* Integral of f |cos wi| over the sphere by the midpoint rule in (cos theta, phi). */
static rgb integrate_f_cos(const bsdf *b, vec3 wo, transport_mode mode, int nt, int np) {
  rgb acc = rgb_zero();
  double dz = 2.0 / nt, dp = 2.0 * M_PI / np;
  for (int i = 0; i < nt; i++)
    for (int j = 0; j < np; j++) {
      vec3 wi = dir(1.0 - (i + 0.5) * dz, (j + 0.5) * dp);
      acc = rgb_add(acc, rgb_scale(bsdf_eval(b, 0.5, 0.5, wo, wi, mode), fabs(wi.z)));
    }
  return rgb_scale(acc, dz * dp);
}

/* Monte Carlo albedo: mean sample weight (delta lobes included), and its
 * standard error. */
static double mc_albedo(const bsdf *b, vec3 wo, transport_mode mode, int n, uint64_t seed,
                        double *stderr_out) {
  rng r;
  rng_seed(&r, seed, 3);
  double s = 0.0, s2 = 0.0;
  for (int i = 0; i < n; i++) {
    bsdf_sample smp;
    double ul = rng_uniform(&r), u1 = rng_uniform(&r), u2 = rng_uniform(&r);
    double w = 0.0;
    if (bsdf_sample_f(b, 0.5, 0.5, wo, ul, u1, u2, mode, &smp)) w = rgb_max(smp.weight);
    s += w;
    s2 += w * w;
  }
  double mean = s / n;
  *stderr_out = sqrt(fmax(0.0, s2 / n - mean * mean) / n);
  return mean;
}

static void test_energy(void **state) {
  (void)state;
  int checks = 0;
  /* Diffuse: the albedo is the reflectance at every angle (the midpoint
   * rule in cos theta integrates the linear cosine exactly). */
  bsdf b;
  bsdf_init_defaults(&b, "diffuse");
  b.diffuse = tex_constant(rgb_make(0.2, 0.5, 0.9));
  for (int i = 0; i < 3; i++) {
    rgb a = integrate_f_cos(&b, dir(0.2 + 0.35 * i, 0.3), TRANSPORT_RADIANCE, 200, 64);
    assert_near(a.r, 0.2, 1e-12);
    assert_near(a.g, 0.5, 1e-12);
    assert_near(a.b, 0.9, 1e-12);
    checks += 3;
  }
  /* Diffuse sample weights are the reflectance exactly. */
  bsdf_sample s;
  assert_true(bsdf_sample_f(&b, 0, 0, dir(0.7, 0), 0.3, 0.4, 0.6, TRANSPORT_RADIANCE, &s));
  assert_near(s.weight.g, 0.5, 1e-14);
  checks += 2;

  /* Plastic: albedo = F_i ks + (1 - F_i) kd in linear mode, because
   * 1 - F_dr(eta) = eta^2 (1 - F_dr(1/eta)); nonlinear mode:
   * F_i + (1 - F_i) kd (1 - F_dr_int) / (1 - kd F_dr_int). */
  for (int nl = 0; nl < 2; nl++)
    for (int i = 0; i < 3; i++) {
      bsdf_init_defaults(&b, "plastic");
      b.nonlinear = nl;
      b.diffuse = tex_constant(rgb_gray(0.8));
      vec3 wo = dir(0.15 + 0.4 * i, 1.1);
      double fi = fresnel_dielectric(wo.z, b.eta, NULL);
      rgb diff = integrate_f_cos(&b, wo, TRANSPORT_RADIANCE, 2000, 8);
      double expect;
      if (!nl) {
        expect = (1.0 - fi) * 0.8;
      } else {
        /* F_dr(1/eta) from the identity with the exterior one, integrated here. */
        double fdr_int = 0.0;
        const int m = 200000;
        for (int k = 0; k < m; k++) {
          double c = (k + 0.5) / m;
          fdr_int += fresnel_dielectric(c, 1.0 / b.eta, NULL) * 2.0 * c / m;
        }
        expect = (1.0 - fi) * 0.8 * (1.0 - fdr_int) / (1.0 - 0.8 * fdr_int);
      }
      assert_near(diff.r, expect, 2e-4);
      checks++;
      /* The specular lobe: weight F_i / P(spec) with probability P(spec). */
      assert_true(bsdf_sample_f(&b, 0, 0, wo, 0.0, 0.5, 0.5, TRANSPORT_RADIANCE, &s));
      assert_true(s.flags & BSDF_DELTA);
      assert_near(s.weight.r * s.pdf, fi, 1e-12);
      /* P(spec) + the integral of the diffuse pdf = 1. */
      double pint = 0.0;
      for (int k = 0; k < 2000; k++) {
        vec3 wi = dir(1.0 - (k + 0.5) / 2000.0, 0.0);
        pint += bsdf_pdf(&b, 0, 0, wo, wi) * 2.0 * M_PI / 2000.0;
      }
      assert_near(pint + s.pdf, 1.0, 1e-6);
      checks += 4;
    }

  /* Phong, kd + ks <= 1: albedo <= 1 (grid integration). */
  const double exps[] = {1.0, 10.0, 100.0};
  for (int e = 0; e < 3; e++)
    for (int i = 0; i < 3; i++) {
      bsdf_init_defaults(&b, "phong");
      b.exponent = exps[e];
      b.diffuse = tex_constant(rgb_gray(0.3));
      b.specular = tex_constant(rgb_gray(0.7));
      rgb a = integrate_f_cos(&b, dir(0.05 + 0.45 * i, 0.0), TRANSPORT_RADIANCE, 800, 800);
      assert_le(a.r, 1.0 + 1e-3);
      assert_true(a.r > 0.29);
      checks += 2;
    }

  /* Rough conductor with a perfect mirror ("none"): albedo <= 1, close to
   * 1 for a smooth surface at normal incidence (Smith's masking takes a
   * little); rough dielectric in importance mode: R + T <= 1. Tolerance:
   * 4 standard errors of the Monte Carlo mean. */
  const mf_dist dists[] = {MF_BECKMANN, MF_GGX};
  for (int d = 0; d < 2; d++)
    for (int a = 0; a < 2; a++) {
      double se;
      bsdf_init_defaults(&b, "roughconductor");
      conductor_lookup("none", &b.cond_eta, &b.cond_k);
      b.dist = dists[d];
      b.alpha = a ? 0.6 : 0.05;
      double alb = mc_albedo(&b, dir(0.95, 0.2), TRANSPORT_RADIANCE, 50000, 9 + d, &se);
      assert_le(alb, 1.0 + 4.0 * se + 1e-9);
      if (!a) assert_true(alb > 0.98);
      checks += 2;
      bsdf_init_defaults(&b, "roughdielectric");
      b.dist = dists[d];
      b.alpha = a ? 0.6 : 0.05;
      for (int side = 0; side < 2; side++) {
        alb = mc_albedo(&b, dir(side ? -0.8 : 0.8, 0.2), TRANSPORT_IMPORTANCE, 50000, 19 + d, &se);
        assert_le(alb, 1.0 + 4.0 * se + 1e-9);
        if (!a) assert_true(alb > 0.97);
        checks += 2;
      }
    }

  /* Rough plastic, white base and coating (ks = kd = 1): albedo at most 1
   * at every angle, both distributions, three roughnesses, linear and
   * nonlinear (the same at kd = 1). Tolerance: 4 standard errors. */
  const double rp_alpha[] = {0.05, 0.3, 1.0};
  const double rp_z[] = {0.98, 0.6, 0.25, 0.05};
  for (int d = 0; d < 2; d++)
    for (int a = 0; a < 3; a++) {
      bsdf_init_defaults(&b, "roughplastic");
      b.dist = dists[d];
      b.alpha = rp_alpha[a];
      b.nonlinear = a == 1;
      b.diffuse = tex_constant(rgb_gray(1.0));
      bsdf_prepare(&b);
      for (int i = 0; i < 4; i++) {
        double se;
        double alb = mc_albedo(&b, dir(rp_z[i], 0.4), TRANSPORT_RADIANCE, 40000, 31 + 4 * a + d, &se);
        if (!(alb <= 1.0 + 4.0 * se + 1e-9))
          print_error("roughplastic %d a=%g wo.z=%g: albedo %g +- %g\n", d, rp_alpha[a], rp_z[i],
                      alb, se);
        assert_le(alb, 1.0 + 4.0 * se + 1e-9);
        /* Only Smith's masking at the coating loses energy (single
         * scattering): near 1 unless grazing or rough (GGX at alpha = 1
         * loses 11% at normal incidence, 27% at wo.z = 0.6). */
        double low = a < 2 ? 0.9 : 0.6;
        if (i < 2 && !(alb > low))
          print_error("low albedo %d a=%g wo.z=%g: %g\n", d, rp_alpha[a], rp_z[i], alb);
        if (i < 2) assert_true(alb > low);
        checks += 2;
      }
    }
  /* Rough plastic as alpha -> 0 is smooth plastic: the diffuse term equals
   * plastic's (T -> 1 - F, the rough F_dr -> F_dr) away from the mirror
   * direction, and the albedo is plastic's closed form
   * F_i ks + (1 - F_i) kd (linear mode), up to the coating's masking. */
  for (int d = 0; d < 2; d++) {
    bsdf rp, pl;
    bsdf_init_defaults(&rp, "roughplastic");
    rp.dist = dists[d];
    rp.alpha = 0.001;
    rp.diffuse = tex_constant(rgb_gray(0.8));
    bsdf_prepare(&rp);
    bsdf_init_defaults(&pl, "plastic");
    pl.diffuse = rp.diffuse;
    double fdr_int = 0.0; /* the smooth F_dr(1 / eta), midpoint rule */
    for (int k = 0; k < 200000; k++) {
      double c = (k + 0.5) / 200000;
      fdr_int += fresnel_dielectric(c, 1.0 / pl.eta, NULL) * 2.0 * c / 200000;
    }
    assert_near(rp.rtrans.fdr_int, fdr_int, 2e-4);
    checks++;
    for (int k = 0; k < 20; k++) {
      /* (Not at grazing angles, where GGX's long tails still show at this
       * alpha: 4e-3 at cos 0.03.) */
      vec3 wo = dir(0.1 + 0.04 * k, 0.3), wi = dir(0.9 - 0.04 * k, 2.0 + 0.1 * k);
      rgb f1 = bsdf_eval(&rp, 0, 0, wo, wi, TRANSPORT_RADIANCE);
      rgb f2 = bsdf_eval(&pl, 0, 0, wo, wi, TRANSPORT_RADIANCE);
      if (!(rel_err(f1.r, f2.r) < 2e-3))
        print_error("roughplastic %d a=0.001 vs plastic, wo.z %g wi.z %g: %g vs %g\n", d, wo.z,
                    wi.z, f1.r, f2.r);
      assert_true(rel_err(f1.r, f2.r) < 2e-3);
      checks++;
    }
    for (int i = 0; i < 3; i++) {
      vec3 wo = dir(0.9 - 0.35 * i, 1.0);
      double fi = fresnel_dielectric(wo.z, rp.eta, NULL), se;
      double alb = mc_albedo(&rp, wo, TRANSPORT_RADIANCE, 40000, 61 + 3 * d + i, &se);
      double expect = fi + (1.0 - fi) * 0.8;
      if (!(fabs(alb - expect) <= 4.0 * se + 2e-3))
        print_error("roughplastic a=0.001 albedo at wo.z %g: %g +- %g, smooth %g\n", wo.z, alb, se,
                    expect);
      assert_true(fabs(alb - expect) <= 4.0 * se + 2e-3);
      checks++;
    }
  }
  assert_int_equal(checks, 3 * 3 + 2 + 6 * 5 + 9 * 2 + 4 * 6 + 6 * 4 * 2 + 2 * (1 + 20 + 3));
}

/* ---- roughdiffuse and ward: independent expectations ------------------------ */

/* Oren and Nayar 1994 (their eqs. for L1 and L2, E0 = 1, divided by
 * cos(theta_i)), transcribed in angles: theta from acos, phi from atan2, as
 * Mitsuba's roughdiffuse.cpp states it with sigma = alpha / sqrt(2); `fast`:
 * the qualitative A + B model. An independent form of the model. */
static rgb oren_nayar_ref(rgb rho, double alpha_rms, int fast, vec3 wo, vec3 wi) {
  double sigma = alpha_rms / sqrt(2.0), s2 = sigma * sigma;
  double th_o = acos(wo.z), th_i = acos(wi.z);
  double cdphi = cos(atan2(wo.y, wo.x) - atan2(wi.y, wi.x));
  double al = fmax(th_o, th_i), be = fmin(th_o, th_i);
  double g[3] = {rho.r, rho.g, rho.b}, out[3];
  for (int k = 0; k < 3; k++) {
    double r = g[k];
    if (fast) {
      double A = 1.0 - 0.5 * s2 / (s2 + 0.33), B = 0.45 * s2 / (s2 + 0.09);
      out[k] = r / M_PI * (A + B * fmax(0.0, cdphi) * sin(al) * tan(be));
      continue;
    }
    double c1 = 1.0 - 0.5 * s2 / (s2 + 0.33);
    double c2 = cdphi >= 0.0 ? 0.45 * s2 / (s2 + 0.09) * sin(al)
                             : 0.45 * s2 / (s2 + 0.09) * (sin(al) - pow(2.0 * be / M_PI, 3.0));
    double c3 = 0.125 * s2 / (s2 + 0.09) * pow(4.0 * al * be / (M_PI * M_PI), 2.0);
    double l1 = r / M_PI * (c1 + cdphi * c2 * tan(be) + (1.0 - fabs(cdphi)) * c3 * tan(0.5 * (al + be)));
    double l2 = 0.17 * r * r / M_PI * s2 / (s2 + 0.13) * (1.0 - cdphi * pow(2.0 * be / M_PI, 2.0));
    out[k] = l1 + l2;
  }
  return rgb_make(out[0], out[1], out[2]);
}

static void test_roughdiffuse(void **state) {
  (void)state;
  int checks = 0;
  rng r;
  rng_seed(&r, 314, 9);
  bsdf b;
  const rgb rho = rgb_make(0.2, 0.5, 0.9);
  /* alpha = 0 is Lambertian exactly (sigma = 0: A = C1 = 1, the other
   * coefficients 0), in both variants, at random pairs and at the normal. */
  bsdf lam;
  bsdf_init_defaults(&lam, "diffuse");
  lam.diffuse = tex_constant(rho);
  int exact = 0;
  for (int fa = 0; fa < 2; fa++) {
    bsdf_init_defaults(&b, "roughdiffuse");
    b.diffuse = tex_constant(rho);
    b.alpha = 0.0;
    b.fast_approx = fa;
    for (int k = 0; k < 500; k++) {
      vec3 wo = k == 0 ? v3(0, 0, 1) : warp_square_to_uniform_hemisphere(rng_uniform(&r), rng_uniform(&r));
      vec3 wi = warp_square_to_uniform_hemisphere(rng_uniform(&r), rng_uniform(&r));
      rgb f = bsdf_eval(&b, 0, 0, wo, wi, TRANSPORT_RADIANCE);
      rgb fl = bsdf_eval(&lam, 0, 0, wo, wi, TRANSPORT_RADIANCE);
      exact += f.r == fl.r && f.g == fl.g && f.b == fl.b;
      checks++;
    }
  }
  assert_int_equal(exact, 1000);

  /* Against the transcription in angles, at random pairs away from the
   * normal (where the angle form needs atan2 of two zeros), f >= 0. */
  int agree = 0, n_cmp = 0;
  const double alphas[] = {0.1, 0.4, 1.0};
  for (int fa = 0; fa < 2; fa++)
    for (int a = 0; a < 3; a++) {
      bsdf_init_defaults(&b, "roughdiffuse");
      b.diffuse = tex_constant(rho);
      b.alpha = alphas[a];
      b.fast_approx = fa;
      for (int k = 0; k < 400; k++) {
        vec3 wo = warp_square_to_uniform_hemisphere(rng_uniform(&r), rng_uniform(&r));
        vec3 wi = warp_square_to_uniform_hemisphere(rng_uniform(&r), rng_uniform(&r));
        if (wo.z > 1.0 - 1e-6 || wi.z > 1.0 - 1e-6) continue;
        rgb f = bsdf_eval(&b, 0, 0, wo, wi, TRANSPORT_RADIANCE);
        rgb e = oren_nayar_ref(rho, alphas[a], fa, wo, wi);
        n_cmp++;
        if (rgb_rel_err(f, e) < 1e-9 && f.r >= 0.0)
          agree++;
        else if (n_cmp - agree < 5)
          print_error("roughdiffuse a=%g fast=%d: f %.17g ref %.17g\n", alphas[a], fa, f.r, e.r);
      }
    }
  assert_int_equal(agree, n_cmp);
  assert_true(n_cmp > 2000);
  checks += 2;

  /* Albedo with R = 1. At the normal f is constant in wi, so the midpoint
   * rule in cos is exact: A (fast), C1 + C4 (full). The fast model's albedo
   * tends at grazing wo to A + B/2 (sin(alpha) -> 1, tan(beta) cos(theta_i)
   * = sin(theta_i), int sin max(0, cos dphi) dw = pi / 2), which exceeds 1
   * for alpha < 0.46: the model loses energy at the normal and gains a
   * little at grazing angles. */
  for (int a = 0; a < 3; a++) {
    double s2 = 0.5 * alphas[a] * alphas[a];
    double A = 1.0 - 0.5 * s2 / (s2 + 0.33), B = 0.45 * s2 / (s2 + 0.09), c4 = 0.17 * s2 / (s2 + 0.13);
    for (int fa = 0; fa < 2; fa++) {
      bsdf_init_defaults(&b, "roughdiffuse");
      b.diffuse = tex_constant(rgb_gray(1.0));
      b.alpha = alphas[a];
      b.fast_approx = fa;
      rgb n0 = integrate_f_cos(&b, v3(0, 0, 1), TRANSPORT_RADIANCE, 200, 16);
      assert_near(n0.g, fa ? A : A + c4, 1e-12);
      assert_true(n0.g < 1.0);
      checks += 2;
    }
    b.fast_approx = 1;
    rgb gz = integrate_f_cos(&b, dir(1e-7, 0.3), TRANSPORT_RADIANCE, 4000, 512);
    assert_near(gz.g, A + 0.5 * B, 1e-4);
    checks++;
    if (alphas[a] < 0.46) {
      assert_true(gz.g > 1.0);
      checks++;
    }
  }
  /* Albedo <= 1 for wo within 37 degrees of the normal (wo.z >= 0.8), every
   * roughness and both variants; at grazing angles the model (Mitsuba's
   * too) exceeds 1 by up to 4.7% (full, alpha 0.4, wo.z = 0.01), bounded
   * here by 1.05. Grid error of these smooth integrands: below 1e-4. */
  int le1 = 0, le105 = 0, n_alb = 0;
  for (int fa = 0; fa < 2; fa++)
    for (int a = 1; a <= 10; a++) {
      bsdf_init_defaults(&b, "roughdiffuse");
      b.diffuse = tex_constant(rgb_gray(1.0));
      b.alpha = 0.1 * a;
      b.fast_approx = fa;
      const double zs[] = {0.95, 0.8, 0.5, 0.2, 0.05, 0.01};
      for (int i = 0; i < 6; i++) {
        double al = integrate_f_cos(&b, dir(zs[i], 0.3), TRANSPORT_RADIANCE, 400, 200).g;
        n_alb++;
        le105 += al <= 1.05;
        if (zs[i] >= 0.8) le1 += al <= 1.0 + 1e-4;
      }
    }
  assert_int_equal(n_alb, 120);
  assert_int_equal(le105, 120);
  assert_int_equal(le1, 40);
  checks += 3;
  assert_int_equal(checks, 1000 + 2 + 3 * 5 + 2 + 3);
}

/* The Ward lobe's normalisation by variant, by hand, at the mirror
 * direction of wo (h = (0, 0, 2 cos), exponent 0):
 *   ward       1 / (4 pi au av cos),
 *   ward-duer  1 / (4 pi au av cos^2),
 *   balanced   (4 cos^2) / (pi au av 16 cos^4) = 1 / (4 pi au av cos^2). */
static double ward_mirror_expect(int variant, double au, double av, double c, double ks,
                                 double kd) {
  double lobe = variant == 0 ? 1.0 / (4.0 * M_PI * au * av * c)
                             : 1.0 / (4.0 * M_PI * au * av * c * c);
  return kd / M_PI + ks * lobe;
}

static void test_ward(void **state) {
  (void)state;
  int checks = 0;
  bsdf b;
  rng r;
  rng_seed(&r, 2718, 11);
  /* The mirror direction: isotropic and anisotropic, three variants. */
  const double au_[] = {0.2, 0.1}, av_[] = {0.2, 0.3};
  for (int v = 0; v < 3; v++)
    for (int an = 0; an < 2; an++) {
      bsdf_init_defaults(&b, "ward");
      b.variant = (ward_variant)v;
      b.alpha_u = au_[an];
      b.alpha_v = av_[an];
      vec3 wo = dir(0.6, 0.4), wi = v3(-wo.x, -wo.y, wo.z);
      rgb f = bsdf_eval(&b, 0, 0, wo, wi, TRANSPORT_RADIANCE);
      assert_near(f.g, ward_mirror_expect(v, au_[an], av_[an], wo.z, 0.2, 0.5), 1e-12 * f.g);
      checks++;
    }
  /* Anisotropy lies along the frame's axes: swapping alphaU and alphaV is
   * the same as turning both directions by 90 degrees about the normal;
   * an isotropic lobe is invariant under any turn. */
  int rot_ok = 0;
  for (int v = 0; v < 3; v++)
    for (int k = 0; k < 200; k++) {
      vec3 wo = warp_square_to_uniform_hemisphere(rng_uniform(&r), rng_uniform(&r));
      vec3 wi = warp_square_to_uniform_hemisphere(rng_uniform(&r), rng_uniform(&r));
      if (k & 1) wi = v3_normalize(v3(-wo.x + 0.1 * wi.x, -wo.y + 0.1 * wi.y, wo.z)); /* near the peak */
      vec3 wo90 = v3(-wo.y, wo.x, wo.z), wi90 = v3(-wi.y, wi.x, wi.z);
      bsdf_init_defaults(&b, "ward");
      b.variant = (ward_variant)v;
      b.alpha_u = 0.1;
      b.alpha_v = 0.35;
      rgb f1 = bsdf_eval(&b, 0, 0, wo, wi, TRANSPORT_RADIANCE);
      double p1 = bsdf_pdf(&b, 0, 0, wo, wi);
      b.alpha_u = 0.35;
      b.alpha_v = 0.1;
      rgb f2 = bsdf_eval(&b, 0, 0, wo90, wi90, TRANSPORT_RADIANCE);
      double p2 = bsdf_pdf(&b, 0, 0, wo90, wi90);
      double t = 6.28 * rng_uniform(&r), ct = cos(t), st = sin(t);
      b.alpha_u = b.alpha_v = 0.25;
      rgb f3 = bsdf_eval(&b, 0, 0, wo, wi, TRANSPORT_RADIANCE);
      rgb f4 = bsdf_eval(&b, 0, 0, v3(ct * wo.x - st * wo.y, st * wo.x + ct * wo.y, wo.z),
                         v3(ct * wi.x - st * wi.y, st * wi.x + ct * wi.y, wi.z), TRANSPORT_RADIANCE);
      rot_ok += rgb_rel_err(f1, f2) < 1e-9 && rel_err(p1, p2) < 1e-9 && rgb_rel_err(f3, f4) < 1e-9;
      checks++;
    }
  assert_int_equal(rot_ok, 600);

  /* Energy (Mitsuba's ward.cpp documentation: "ward" loses energy at
   * grazing angles, "ward-duer" does not always conserve energy,
   * "balanced" keeps it at all angles). With ks + kd <= 1: balanced and
   * ward at most 1 at every angle, ward-duer away from grazing; ward-duer
   * exceeds 1 at grazing (3.5 for alphas 0.3, 0.6 at wo.z = 0.02). Monte
   * Carlo with importance sampling; tolerance 4 standard errors. */
  const double alb_au[] = {0.1, 0.3, 0.7}, alb_av[] = {0.1, 0.6, 0.7};
  const double kss[] = {1.0, 0.3}, kds[] = {0.0, 0.7};
  const double zs[] = {0.95, 0.5, 0.1, 0.02};
  int bounded = 0, n_alb = 0;
  for (int v = 0; v < 3; v++)
    for (int a = 0; a < 3; a++)
      for (int m = 0; m < 2; m++)
        for (int i = 0; i < 4; i++) {
          if (v == WARD_DUER && zs[i] < 0.4) continue;
          bsdf_init_defaults(&b, "ward");
          b.variant = (ward_variant)v;
          b.alpha_u = alb_au[a];
          b.alpha_v = alb_av[a];
          b.specular = tex_constant(rgb_gray(kss[m]));
          b.diffuse = tex_constant(rgb_gray(kds[m]));
          double se;
          double alb = mc_albedo(&b, dir(zs[i], 0.2), TRANSPORT_RADIANCE, 20000,
                                 700 + (uint64_t)n_alb, &se);
          n_alb++;
          if (alb <= 1.0 + 4.0 * se + 1e-9)
            bounded++;
          else
            print_error("ward variant %d a=(%g %g) ks %g wo.z %g: albedo %g +- %g\n", v, alb_au[a],
                        alb_av[a], kss[m], zs[i], alb, se);
        }
  assert_int_equal(n_alb, 2 * 3 * 2 * 4 + 3 * 2 * 2);
  assert_int_equal(bounded, n_alb);
  bsdf_init_defaults(&b, "ward");
  b.variant = WARD_DUER;
  b.alpha_u = 0.3;
  b.alpha_v = 0.6;
  b.specular = tex_constant(rgb_gray(1.0));
  b.diffuse = tex_constant(rgb_gray(0.0));
  assert_true(integrate_f_cos(&b, dir(0.02, 0.3), TRANSPORT_RADIANCE, 800, 400).g > 1.5);
  checks += 2;
  assert_int_equal(checks, 6 + 600 + 2);
}

/* ---- reciprocity --------------------------------------------------------- */

static void test_reciprocity(void **state) {
  (void)state;
  rng r;
  rng_seed(&r, 99, 5);
  int checks = 0, bad = 0;
  /* Reflection models: f(a, b) = f(b, a). */
  /* 6-10: roughdiffuse full and fast, ward's three variants (anisotropic);
   * 11-12: roughplastic (Beckmann linear, GGX nonlinear); all reciprocal
   * formulas. */
  const int n_types = 13;
  for (int t = 0; t < n_types; t++) {
    bsdf b;
    const char *const types[] = {"diffuse",      "phong",        "roughconductor",
                               "roughconductor", "plastic",    "roughdielectric",
                               "roughdiffuse", "roughdiffuse", "ward",
                               "ward",         "ward",         "roughplastic",
                               "roughplastic"};
    bsdf_init_defaults(&b, types[t]);
    if (t == 3 || t == 12) b.dist = MF_GGX;
    b.nonlinear = t == 12;
    b.alpha = 0.4;
    b.exponent = 12.0;
    b.fast_approx = t == 7;
    if (t >= 8 && t <= 10) {
      b.variant = (ward_variant)(t - 8);
      b.alpha_u = 0.15;
      b.alpha_v = 0.4;
    }
    for (int k = 0; k < 300; k++) {
      vec3 a = warp_square_to_uniform_hemisphere(rng_uniform(&r), rng_uniform(&r));
      vec3 c = warp_square_to_uniform_hemisphere(rng_uniform(&r), rng_uniform(&r));
      if (t == 5 && (k & 1)) {
        a.z = -a.z; /* reflection inside the dielectric */
        c.z = -c.z;
      }
      rgb f1 = bsdf_eval(&b, 0, 0, a, c, TRANSPORT_RADIANCE);
      rgb f2 = bsdf_eval(&b, 0, 0, c, a, TRANSPORT_RADIANCE);
      if (!(rgb_rel_err(f1, f2) < 1e-9) && !(rgb_is_black(f1) && rgb_is_black(f2))) bad++;
      if (rgb_is_black(f1) && (t == 0 || t == 4 || t >= 6)) bad++; /* nonzero everywhere above */
      checks++;
    }
  }
  /* Rough refraction: f_rad(a, b) eta_b^2 = f_rad(b, a) eta_a^2 and
   * f_imp(a, b) = f_rad(b, a), a outside and b inside. */
  for (int d = 0; d < 2; d++) {
    bsdf b;
    bsdf_init_defaults(&b, "roughdielectric");
    b.dist = d ? MF_GGX : MF_BECKMANN;
    b.alpha = 0.5;
    int nonzero = 0;
    for (int k = 0; k < 300; k++) {
      /* a outside; c inside, drawn by refracting a through the model (a
       * random pair would mostly be an impossible refraction). */
      vec3 a = warp_square_to_uniform_hemisphere(rng_uniform(&r), rng_uniform(&r));
      bsdf_sample smp;
      vec3 c = v3(0.0, 0.0, -1.0);
      if (bsdf_sample_f(&b, 0, 0, a, 1.0 - 1e-12, rng_uniform(&r), rng_uniform(&r),
                        TRANSPORT_RADIANCE, &smp) &&
          smp.wi.z < 0.0)
        c = smp.wi;
      double eta_a = 1.0, eta_c = b.eta;
      rgb fac = bsdf_eval(&b, 0, 0, a, c, TRANSPORT_RADIANCE);
      rgb fca = bsdf_eval(&b, 0, 0, c, a, TRANSPORT_RADIANCE);
      rgb iac = bsdf_eval(&b, 0, 0, a, c, TRANSPORT_IMPORTANCE);
      rgb ica = bsdf_eval(&b, 0, 0, c, a, TRANSPORT_IMPORTANCE);
      if (!rgb_is_black(fac)) nonzero++;
      if (!(rel_err(fac.r * eta_c * eta_c, fca.r * eta_a * eta_a) < 1e-9) && !(fac.r == 0 && fca.r == 0)) {
        print_error("a (%g %g %g) c (%g %g %g): f(a,c) %g f(c,a) %g\n", a.x, a.y, a.z, c.x, c.y, c.z, fac.r, fca.r);
        bad++;
      }
      if (!(rel_err(iac.r, fca.r) < 1e-9) && !(iac.r == 0 && fca.r == 0)) bad++;
      if (!(rel_err(ica.r, fac.r) < 1e-9) && !(ica.r == 0 && fac.r == 0)) bad++;
      checks++;
    }
    assert_true(nonzero > 250);
    checks++;
  }
  assert_int_equal(bad, 0);
  assert_int_equal(checks, n_types * 300 + 2 * 301);
}

/* ---- delta lobes ----------------------------------------------------------- */

static void test_dielectric_delta(void **state) {
  (void)state;
  int checks = 0;
  bsdf b;
  bsdf_init_defaults(&b, "dielectric");
  assert_true(bsdf_is_delta(&b));
  checks++;
  const double zs[] = {1.0, 0.7, 0.2, 0.01, -1.0, -0.8, -0.75, -0.5, -0.1};
  for (int i = 0; i < 9; i++) {
    vec3 wo = dir(zs[i], 0.4);
    bsdf_sample sr, st;
    double cos_t;
    double fr = fresnel_dielectric(wo.z, b.eta, &cos_t);
    int okr = bsdf_sample_f(&b, 0, 0, wo, 0.0, 0.5, 0.5, TRANSPORT_RADIANCE, &sr);
    int okt = bsdf_sample_f(&b, 0, 0, wo, 1.0 - 1e-12, 0.5, 0.5, TRANSPORT_RADIANCE, &st);
    /* Reflection: mirror direction, probability F, weight 1. */
    assert_true(okr);
    assert_true((sr.flags & (BSDF_REFLECTION | BSDF_DELTA)) == (BSDF_REFLECTION | BSDF_DELTA));
    assert_near(sr.pdf, fr, 1e-15);
    assert_near(sr.weight.r, 1.0, 1e-12);
    assert_near(sr.wi.z, wo.z, 0);
    checks += 5;
    if (cos_t == 0.0) {
      /* Total internal reflection: always reflect. */
      assert_near(fr, 1.0, 0);
      assert_true(okt && (st.flags & BSDF_REFLECTION));
      checks += 2;
      continue;
    }
    /* Refraction: probabilities sum to 1, Snell's law, unit direction,
     * other side; weight (eta_o/eta_i)^2 in radiance mode, 1 in importance. */
    assert_true(okt);
    assert_true(st.flags & BSDF_TRANSMISSION);
    assert_near(sr.pdf + st.pdf, 1.0, 1e-14);
    double e = wo.z > 0 ? b.eta : 1.0 / b.eta; /* eta_i / eta_o */
    double sin_o = sqrt(1.0 - wo.z * wo.z), sin_i = sqrt(fmax(0.0, 1.0 - st.wi.z * st.wi.z));
    assert_near(sin_i * e, sin_o, 1e-12);
    assert_near(v3_len(st.wi), 1.0, 1e-12);
    assert_true(st.wi.z * wo.z < 0.0);
    assert_near(st.weight.r, 1.0 / (e * e), 1e-12);
    assert_near(st.eta, e, 1e-15);
    assert_near(st.f.r * fabs(st.wi.z) / st.pdf, st.weight.r, 1e-12);
    bsdf_sample si;
    assert_true(bsdf_sample_f(&b, 0, 0, wo, 1.0 - 1e-12, 0.5, 0.5, TRANSPORT_IMPORTANCE, &si));
    assert_near(si.weight.r, 1.0, 1e-12);
    /* Energy in importance mode: F * 1 + (1 - F) * 1 = 1. */
    assert_near(sr.pdf * sr.weight.r + st.pdf * si.weight.r, 1.0, 1e-12);
    /* Fresnel is the same from both sides of a refraction pair. */
    assert_near(fresnel_dielectric(st.wi.z, b.eta, NULL), fr, 1e-12);
    checks += 12;
  }
  /* The lobe choice follows u_lobe: the fraction of reflections is F. */
  vec3 wo = dir(0.3, 0.0);
  double fr = fresnel_dielectric(wo.z, b.eta, NULL);
  int refl = 0;
  for (int k = 0; k < 10000; k++) {
    bsdf_sample s;
    bsdf_sample_f(&b, 0, 0, wo, (k + 0.5) / 10000.0, 0.5, 0.5, TRANSPORT_RADIANCE, &s);
    refl += (s.flags & BSDF_REFLECTION) != 0;
  }
  assert_near(refl / 10000.0, fr, 1.5e-4);
  /* eval and pdf are zero for delta models. */
  assert_true(rgb_is_black(bsdf_eval(&b, 0, 0, wo, v3(-wo.x, -wo.y, wo.z), TRANSPORT_RADIANCE)));
  assert_true(bsdf_pdf(&b, 0, 0, wo, v3(-wo.x, -wo.y, wo.z)) == 0.0);
  checks += 3;
  /* Smooth conductor: weight = F_cond * specularReflectance; "none" = 1. */
  bsdf_init_defaults(&b, "conductor");
  bsdf_sample s;
  assert_true(bsdf_sample_f(&b, 0, 0, wo, 0.5, 0.5, 0.5, TRANSPORT_RADIANCE, &s));
  rgb fc = fresnel_conductor(wo.z, b.cond_eta, b.cond_k);
  assert_near(s.weight.r, fc.r, 1e-14);
  assert_near(s.pdf, 1.0, 0);
  assert_true(s.flags & BSDF_DELTA);
  conductor_lookup("none", &b.cond_eta, &b.cond_k);
  for (int i = 0; i < 5; i++) {
    assert_true(bsdf_sample_f(&b, 0, 0, dir(0.01 + 0.24 * i, 1.0), 0.5, 0.5, 0.5, TRANSPORT_RADIANCE, &s));
    assert_near(s.weight.r, 1.0, 1e-14);
    assert_near(s.weight.b, 1.0, 1e-14);
    checks += 3;
  }
  checks += 4;
  assert_int_equal(checks, 1 + 9 * 5 + 2 * 2 + 7 * 12 + 3 + 4 + 15);
}

/* The thin slab: R' = R + (1 - R)^2 R / (1 - R^2) against the series of
 * its passes, R + sum_k (1 - R)^2 R^(2k+1); lobe probabilities and
 * weights; straight-through transmission; both sides alike. */
static void test_thindielectric(void **state) {
  (void)state;
  int checks = 0;
  bsdf b;
  bsdf_init_defaults(&b, "thindielectric");
  const double zs[] = {1.0, 0.7, 0.2, 0.01, -1.0, -0.5, -0.05};
  for (int i = 0; i < 7; i++) {
    vec3 wo = dir(zs[i], 0.4 + i);
    double r = fresnel_dielectric(fabs(wo.z), b.eta, NULL), t = 1.0 - r;
    double series = r, r_odd = r; /* r_odd = R^(2k+1) */
    for (int k = 0; k < 4000; k++, r_odd *= r * r) series += t * t * r_odd;
    for (int tm = 0; tm < 2; tm++) {
      transport_mode mode = tm ? TRANSPORT_IMPORTANCE : TRANSPORT_RADIANCE;
      bsdf_sample sr, st;
      assert_true(bsdf_sample_f(&b, 0, 0, wo, 0.0, 0.5, 0.5, mode, &sr));
      assert_true(bsdf_sample_f(&b, 0, 0, wo, 1.0 - 1e-12, 0.5, 0.5, mode, &st));
      /* Reflection: mirror direction on wo's side, probability R', weight 1. */
      assert_int_equal(sr.flags, BSDF_REFLECTION | BSDF_DELTA);
      assert_near(sr.pdf, series, 1e-12);
      assert_true(sr.wi.x == -wo.x && sr.wi.y == -wo.y && sr.wi.z == wo.z);
      assert_near(sr.weight.r, 1.0, 1e-12);
      /* Transmission: exactly -wo, probability 1 - R' = (1 - R) / (1 + R),
       * weight 1 in both modes, eta 1. */
      assert_int_equal(st.flags, BSDF_TRANSMISSION | BSDF_DELTA);
      assert_true(st.wi.x == -wo.x && st.wi.y == -wo.y && st.wi.z == -wo.z);
      assert_near(st.pdf, (1.0 - r) / (1.0 + r), 1e-12);
      assert_near(sr.pdf + st.pdf, 1.0, 1e-15);
      assert_near(st.weight.r, 1.0, 1e-12);
      assert_true(sr.eta == 1.0 && st.eta == 1.0);
      /* Energy with white reflectances: R' + T' = 1; weight = f |cos| / pdf. */
      assert_near(sr.pdf * sr.weight.g + st.pdf * st.weight.g, 1.0, 1e-12);
      assert_near(st.f.b * fabs(st.wi.z) / st.pdf, st.weight.b, 1e-12);
      checks += 13;
    }
  }
  /* The lobe choice follows u_lobe: the fraction of reflections is R'. */
  vec3 wo = dir(0.3, 0.0);
  bsdf_sample s;
  assert_true(bsdf_sample_f(&b, 0, 0, wo, 0.0, 0.5, 0.5, TRANSPORT_RADIANCE, &s));
  double rp = s.pdf;
  int refl = 0;
  for (int k = 0; k < 10000; k++) {
    assert_true(bsdf_sample_f(&b, 0, 0, wo, (k + 0.5) / 10000.0, 0.5, 0.5, TRANSPORT_RADIANCE, &s));
    refl += (s.flags & BSDF_REFLECTION) != 0;
  }
  assert_near(refl / 10000.0, rp, 1.5e-4);
  /* Coloured reflectances are the weights; eval and pdf are zero; the
   * twosided flag changes nothing. */
  b.specular = tex_constant(rgb_make(0.9, 0.5, 0.1));
  b.transmittance = tex_constant(rgb_make(0.2, 0.4, 0.6));
  bsdf_sample s2;
  assert_true(bsdf_sample_f(&b, 0, 0, wo, 0.0, 0.5, 0.5, TRANSPORT_RADIANCE, &s));
  assert_true(rgb_rel_err(s.weight, rgb_make(0.9, 0.5, 0.1)) < 1e-12);
  assert_true(bsdf_sample_f(&b, 0, 0, wo, 0.99, 0.5, 0.5, TRANSPORT_IMPORTANCE, &s));
  assert_true(rgb_rel_err(s.weight, rgb_make(0.2, 0.4, 0.6)) < 1e-12);
  assert_true(rgb_is_black(bsdf_eval(&b, 0, 0, wo, v3_neg(wo), TRANSPORT_RADIANCE)));
  assert_true(bsdf_pdf(&b, 0, 0, wo, v3_neg(wo)) == 0.0);
  vec3 down = dir(-0.3, 0.0);
  assert_true(bsdf_sample_f(&b, 0, 0, down, 0.99, 0.5, 0.5, TRANSPORT_RADIANCE, &s));
  b.twosided = 1;
  assert_true(bsdf_sample_f(&b, 0, 0, down, 0.99, 0.5, 0.5, TRANSPORT_RADIANCE, &s2));
  assert_true(s.wi.z == s2.wi.z && s.pdf == s2.pdf && s2.wi.z == 0.3);
  /* eta = 1: an invisible slab, always transmits. */
  b.eta = 1.0;
  assert_true(bsdf_sample_f(&b, 0, 0, wo, 1e-9, 0.5, 0.5, TRANSPORT_RADIANCE, &s));
  assert_true(s.flags & BSDF_TRANSMISSION);
  assert_near(s.pdf, 1.0, 0);
  checks += 2 + 10001 + 12;
  assert_int_equal(checks, 7 * 2 * 13 + 2 + 10001 + 12);
}

/* ---- Fresnel, tables, defaults -------------------------------------------- */

static void test_fresnel(void **state) {
  (void)state;
  int checks = 0;
  /* Normal incidence: ((eta - 1)/(eta + 1))^2 from both sides. */
  const double etas[] = {1.33, 1.5, 2.4};
  for (int i = 0; i < 3; i++) {
    double e = etas[i], r0 = (e - 1) * (e - 1) / ((e + 1) * (e + 1)), ct;
    assert_near(fresnel_dielectric(1.0, e, &ct), r0, 1e-14);
    assert_near(ct, -1.0, 1e-14);
    assert_near(fresnel_dielectric(-1.0, e, &ct), r0, 1e-14);
    assert_near(ct, 1.0, 1e-14);
    /* Grazing: 1. Past the critical angle from inside: 1, cos_t = 0. */
    assert_near(fresnel_dielectric(1e-9, e, NULL), 1.0, 1e-8);
    double cc = sqrt(1.0 - 1.0 / (e * e));
    assert_near(fresnel_dielectric(-0.99 * cc, e, &ct), 1.0, 0);
    assert_near(ct, 0.0, 0);
    /* A conductor with k = 0 is a dielectric (from outside). */
    for (int k = 0; k < 5; k++) {
      double c = 0.05 + 0.2 * k;
      rgb fc = fresnel_conductor(c, rgb_gray(e), rgb_gray(0.0));
      assert_near(fc.g, fresnel_dielectric(c, e, NULL), 1e-12);
      checks++;
    }
    checks += 7;
  }
  /* eta = 1: no reflection. */
  double ct;
  assert_near(fresnel_dielectric(0.3, 1.0, &ct), 0.0, 0);
  assert_near(ct, -0.3, 0);
  /* Conductor limits: grazing 1; "none" exactly 1 everywhere; Cu at normal
   * incidence ((n-1)^2 + k^2) / ((n+1)^2 + k^2). */
  rgb eta, k;
  assert_true(conductor_lookup("Cu", &eta, &k));
  assert_near(fresnel_conductor(0.0, eta, k).r, 1.0, 1e-12);
  rgb f0 = fresnel_conductor(1.0, eta, k);
  double n = eta.r, kk = k.r;
  assert_near(f0.r, ((n - 1) * (n - 1) + kk * kk) / ((n + 1) * (n + 1) + kk * kk), 1e-12);
  assert_true(conductor_lookup("none", &eta, &k));
  for (int i = 0; i <= 10; i++) assert_near(fresnel_conductor(i / 10.0, eta, k).g, 1.0, 1e-15);
  checks += 4 + 11;
  assert_int_equal(checks, 3 * 12 + 15);
}

static void test_tables_defaults(void **state) {
  (void)state;
  int checks = 0;
  static const struct {
    const char *name;
    double v;
  } iors[] = {{"vacuum", 1.0},          {"helium", 1.000036},    {"hydrogen", 1.000132},
              {"air", 1.000277},        {"carbon dioxide", 1.00045}, {"water", 1.3330},
              {"acetone", 1.36},        {"ethanol", 1.361},      {"carbon tetrachloride", 1.461},
              {"glycerol", 1.4729},     {"benzene", 1.501},      {"silicone oil", 1.52045},
              {"bromine", 1.661},       {"water ice", 1.31},     {"fused quartz", 1.458},
              {"pyrex", 1.470},         {"acrylic glass", 1.49}, {"polypropylene", 1.49},
              {"bk7", 1.5046},          {"sodium chloride", 1.544}, {"amber", 1.55},
              {"pet", 1.5750},          {"diamond", 2.419}};
  for (size_t i = 0; i < sizeof iors / sizeof iors[0]; i++) {
    double v = 0.0;
    assert_true(ior_lookup(iors[i].name, &v));
    assert_near(v, iors[i].v, 0);
    checks++;
  }
  double v;
  assert_true(ior_lookup("BK7", &v)); /* case insensitive, as Mitsuba */
  assert_false(ior_lookup("unobtainium", &v));
  assert_false(ior_lookup(NULL, &v));
  checks += 3;
  const char *metals[] = {"Cu", "Au", "Ag", "Al", "Cr", "none"};
  for (int i = 0; i < 6; i++) {
    rgb e, k;
    assert_true(conductor_lookup(metals[i], &e, &k));
    assert_true(k.r > 0.9 && e.r >= 0.0);
    checks++;
  }
  rgb e, k;
  assert_false(conductor_lookup("Kryptonite", &e, &k));
  assert_true(conductor_lookup("Cu", &e, &k));
  assert_near(e.r, 0.200438, 1e-6);
  assert_near(k.b, 2.14219, 1e-5);
  checks += 3;

  /* Mitsuba's defaults. */
  bsdf b;
  bsdf_init_defaults(&b, "diffuse");
  assert_near(b.diffuse.value.g, 0.5, 0);
  assert_int_equal(bsdf_flags(&b), BSDF_REFLECTION | BSDF_DIFFUSE_LOBE);
  bsdf_init_defaults(&b, "phong");
  assert_near(b.exponent, 30.0, 0);
  assert_near(b.specular.value.r, 0.2, 0);
  assert_near(b.diffuse.value.r, 0.5, 0);
  bsdf_init_defaults(&b, "dielectric");
  assert_near(b.eta, 1.5046 / 1.000277, 1e-15);
  assert_true(bsdf_is_delta(&b));
  bsdf_init_defaults(&b, "plastic");
  assert_near(b.eta, 1.49 / 1.000277, 1e-15);
  assert_near(b.diffuse.value.r, 0.5, 0);
  assert_near(b.specular.value.r, 1.0, 0);
  assert_false(bsdf_is_delta(&b));
  assert_int_equal(bsdf_flags(&b), BSDF_REFLECTION | BSDF_DELTA | BSDF_DIFFUSE_LOBE);
  bsdf_init_defaults(&b, "roughconductor");
  assert_near(b.alpha, 0.1, 0);
  assert_int_equal(b.dist, MF_BECKMANN);
  assert_int_equal(b.sample_visible, 1);
  assert_near(b.cond_eta.r, 0.2004376970 / 1.000277, 1e-12);
  bsdf_init_defaults(&b, "roughdielectric");
  assert_near(b.alpha, 0.1, 0);
  assert_int_equal(bsdf_flags(&b), BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_GLOSSY);
  bsdf_init_defaults(&b, "conductor");
  assert_true(bsdf_is_delta(&b));
  checks += 21;
  /* roughdiffuse.cpp: reflectance 0.5, alpha 0.2, useFastApprox false, a
   * glossy lobe; ward.cpp: variant balanced, alpha 0.1, specular 0.2,
   * diffuse 0.5. */
  bsdf_init_defaults(&b, "roughdiffuse");
  assert_near(b.diffuse.value.g, 0.5, 0);
  assert_near(b.alpha, 0.2, 0);
  assert_int_equal(b.fast_approx, 0);
  assert_int_equal(bsdf_flags(&b), BSDF_REFLECTION | BSDF_GLOSSY);
  assert_true(bsdf_is_rough(&b, 0.05));
  bsdf_init_defaults(&b, "ward");
  assert_int_equal(b.variant, WARD_BALANCED);
  assert_near(b.alpha_u, 0.1, 0);
  assert_near(b.alpha_v, 0.1, 0);
  assert_near(b.specular.value.r, 0.2, 0);
  assert_near(b.diffuse.value.r, 0.5, 0);
  assert_int_equal(bsdf_flags(&b), BSDF_REFLECTION | BSDF_DIFFUSE_LOBE | BSDF_GLOSSY);
  assert_false(bsdf_is_delta(&b));
  checks += 13;
  bsdf_init_defaults(&b, "roughplastic");
  assert_near(b.eta, 1.49 / 1.000277, 1e-15);
  assert_near(b.alpha, 0.1, 0);
  assert_int_equal(b.dist, MF_BECKMANN);
  assert_int_equal(b.sample_visible, 1);
  assert_int_equal(b.nonlinear, 0);
  assert_near(b.diffuse.value.r, 0.5, 0);
  assert_near(b.specular.value.r, 1.0, 0);
  assert_false(bsdf_is_delta(&b));
  assert_int_equal(bsdf_flags(&b), BSDF_REFLECTION | BSDF_DIFFUSE_LOBE | BSDF_GLOSSY);
  /* Rough by its coating's alpha (as roughconductor). */
  assert_true(bsdf_is_rough(&b, 0.05));
  assert_false(bsdf_is_rough(&b, 0.2));
  /* bsdf_prepare fills the table for the current parameters only. */
  assert_false(b.rtrans.ready);
  bsdf_prepare(&b);
  assert_true(b.rtrans.ready && b.rtrans.alpha == b.alpha && b.rtrans.eta == b.eta);
  bsdf_init_defaults(&b, "thindielectric");
  assert_near(b.eta, 1.5046 / 1.000277, 1e-15);
  assert_near(b.specular.value.r, 1.0, 0);
  assert_near(b.transmittance.value.r, 1.0, 0);
  assert_true(bsdf_is_delta(&b));
  assert_false(bsdf_is_rough(&b, 0.0));
  assert_int_equal(bsdf_flags(&b), BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_DELTA);
  checks += 19;
  assert_int_equal(checks, 23 + 3 + 6 + 3 + 21 + 13 + 19);
}

/* ---- one-sidedness and twosided ------------------------------------------- */

static void test_sidedness(void **state) {
  (void)state;
  int checks = 0;
  const char *const one_sided[] = {"diffuse",      "phong", "conductor",
                                 "roughconductor", "plastic", "roughdiffuse",
                                 "ward",         "roughplastic"};
  vec3 up = dir(0.6, 0.5), up2 = dir(0.7, 2.5), down = dir(-0.6, 0.5), down2 = dir(-0.7, 2.5);
  for (int t = 0; t < 8; t++) {
    bsdf b;
    bsdf_init_defaults(&b, one_sided[t]);
    b.alpha = 0.5;
    bsdf_sample s;
    /* Black from below, and for directions through the surface. */
    assert_true(rgb_is_black(bsdf_eval(&b, 0, 0, down, down2, TRANSPORT_RADIANCE)));
    assert_true(rgb_is_black(bsdf_eval(&b, 0, 0, up, down2, TRANSPORT_RADIANCE)));
    assert_true(rgb_is_black(bsdf_eval(&b, 0, 0, down, up2, TRANSPORT_RADIANCE)));
    assert_true(bsdf_pdf(&b, 0, 0, down, down2) == 0.0);
    int absorbed = 0;
    for (int k = 0; k < 50; k++)
      absorbed += !bsdf_sample_f(&b, 0, 0, down, k / 50.0, 0.3, 0.6, TRANSPORT_RADIANCE, &s);
    assert_int_equal(absorbed, 50);
    checks += 5;
    /* Twosided: from below it is the mirror image of the upper side. */
    b.twosided = 1;
    rgb f_dn = bsdf_eval(&b, 0, 0, down, down2, TRANSPORT_RADIANCE);
    rgb f_up = bsdf_eval(&b, 0, 0, up, up2, TRANSPORT_RADIANCE);
    assert_true(rgb_rel_err(f_dn, f_up) < 1e-15 || (rgb_is_black(f_dn) && rgb_is_black(f_up)));
    assert_near(bsdf_pdf(&b, 0, 0, down, down2), bsdf_pdf(&b, 0, 0, up, up2), 1e-15);
    assert_true(rgb_is_black(bsdf_eval(&b, 0, 0, down, up2, TRANSPORT_RADIANCE)));
    bsdf_sample s_up, s_dn;
    int ok_up = bsdf_sample_f(&b, 0, 0, up, 0.9, 0.3, 0.6, TRANSPORT_RADIANCE, &s_up);
    int ok_dn = bsdf_sample_f(&b, 0, 0, down, 0.9, 0.3, 0.6, TRANSPORT_RADIANCE, &s_dn);
    assert_int_equal(ok_up, ok_dn);
    assert_true(ok_up);
    assert_near(s_dn.wi.z, -s_up.wi.z, 1e-15);
    assert_near(s_dn.wi.x, s_up.wi.x, 1e-15);
    assert_near(s_dn.weight.r, s_up.weight.r, 1e-15);
    checks += 8;
  }
  /* Dielectrics ignore the flag (they have two sides already). */
  bsdf b;
  bsdf_init_defaults(&b, "roughdielectric");
  rgb f0 = bsdf_eval(&b, 0, 0, down, dir(-0.65, 3.5), TRANSPORT_RADIANCE);
  b.twosided = 1;
  rgb f1 = bsdf_eval(&b, 0, 0, down, dir(-0.65, 3.5), TRANSPORT_RADIANCE);
  assert_true(rgb_rel_err(f0, f1) == 0.0);
  checks++;
  assert_int_equal(checks, 8 * 13 + 1);
}

/* ---- microfacet internals ---------------------------------------------------- */

static void test_microfacet(void **state) {
  (void)state;
  int checks = 0;
  /* D(m) cos(theta_m) integrates to 1 over the hemisphere; the visible
   * normal density to 1 for every v (exact Smith G1). Midpoint rule on a
   * fine grid in (cos theta, phi). */
  const double alphas[] = {0.05, 0.3, 1.0};
  for (int d = 0; d < 2; d++)
    for (int a = 0; a < 3; a++) {
      mf_dist dist = d ? MF_GGX : MF_BECKMANN;
      const int nt = 20000, np = 64;
      double s = 0.0, sv = 0.0;
      vec3 v = dir(0.3, 0.4);
      for (int i = 0; i < nt; i++) {
        /* Denser near the pole: cos theta = 1 - t^2 substitution. */
        double t = (i + 0.5) / nt, z = 1.0 - t * t, jac = 2.0 * t / nt;
        for (int j = 0; j < np; j++) {
          vec3 m = dir(z, (j + 0.5) * 2.0 * M_PI / np);
          s += mf_D(dist, alphas[a], m) * m.z * jac * 2.0 * M_PI / np;
          sv += mf_pdf(dist, alphas[a], v, m, 1) * jac * 2.0 * M_PI / np;
        }
      }
      assert_near(s, 1.0, 2e-4);
      assert_near(sv, 1.0, 2e-4);
      /* Lambda is even in v.z; G1 vanishes for backfacing microfacets. */
      assert_near(mf_lambda(dist, alphas[a], v), mf_lambda(dist, alphas[a], v3(v.x, v.y, -v.z)), 0);
      assert_true(mf_G1(dist, alphas[a], v, v3(0, 0, 1)) > 0.0);
      assert_true(mf_G1(dist, alphas[a], v, v3_normalize(v3(-v.x, -v.y, 0.05))) == 0.0);
      checks += 5;
    }
  /* Beckmann Smith G1 against Walter's rational approximation (within its 0.4%). */
  for (int i = 1; i < 20; i++) {
    vec3 v = dir(i / 20.0, 0.0);
    double alpha = 0.3, a = v.z / (alpha * sqrt(1.0 - v.z * v.z));
    double approx = a >= 1.6 ? 1.0 : (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
    assert_near(mf_G1(MF_BECKMANN, alpha, v, v3(0, 0, 1)), approx, 4e-3);
    checks++;
  }
  /* erfinv inverts erf. */
  for (int i = -9; i <= 9; i++) {
    double x = i / 10.0 * 0.999999;
    assert_near(erf(mf_erfinv(x)), x, 1e-14);
    checks++;
  }
  assert_int_equal(checks, 6 * 5 + 19 + 19);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_tables_defaults),   cmocka_unit_test(test_fresnel),
      cmocka_unit_test(test_microfacet),        cmocka_unit_test(test_sidedness),
      cmocka_unit_test(test_dielectric_delta),  cmocka_unit_test(test_thindielectric),
      cmocka_unit_test(test_reciprocity),
      cmocka_unit_test(test_sample_consistency), cmocka_unit_test(test_energy),
      cmocka_unit_test(test_chi2_microfacet),   cmocka_unit_test(test_chi2_sampling),
      cmocka_unit_test(test_mask),
      cmocka_unit_test(test_roughdiffuse),      cmocka_unit_test(test_ward),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
