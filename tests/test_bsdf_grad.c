/*
 * test_bsdf_grad.c: the dual BSDFs, Fresnel terms and textures of
 * src/render/bsdf_ad.h against their plain counterparts (bsdf.h,
 * texture.h).
 *
 * What is checked:
 *   (a) values: with an arena of tangent length 0 (and again with length
 *       9), bsdf_eval_ad, bsdf_pdf_ad, bsdf_sample_f_ad and tex_eval_ad
 *       give the values of bsdf_eval, bsdf_pdf, bsdf_sample_f and tex_eval
 *       (relative 1e-12) with the same success, lobe flags and eta, at
 *       thousands of random inputs per model (both hemispheres, every lobe;
 *       thindielectric and roughplastic among the models, roughplastic's
 *       rough transmittance spline included);
 *   (b) derivatives: with the 9 independent variables
 *         theta_o, phi_o (wo), u_lobe, u1, u2, tu, tv, theta_i, phi_i (wi,
 *         for eval and pdf),
 *       every AD derivative of the sample's wi, f, pdf and weight and of
 *       bsdf_eval / bsdf_pdf is compared with central differences of the
 *       plain functions. A component is checked where the branch (success,
 *       lobe, sides of wo and wi) is the same at x +- h and x +- h/2 and
 *       the two central differences agree (|D_h - D_h/2| within the
 *       tolerance below): a kink within h (a texel edge, the phong cut-off,
 *       a clamp) makes them disagree, and the point is skipped. The AD
 *       derivative then has to match the Richardson value (4 D_h/2 - D_h)/3
 *       to relative 1e-5, or absolute 1e-8 of the magnitude (max(|f|, 1)).
 *       Per model, at least 99.9% of the checked components must pass and
 *       the count must exceed a stated minimum. Masks (a textured opacity
 *       on diffuse, constant ones on a twosided rough conductor and the
 *       smooth dielectric) are a model of their own here;
 *   (c) roughdiffuse at normal incidence (wo, wi or both at the pole, where
 *       the azimuth is undefined): finite dual values equal to the plain
 *       ones, finite tangents, and every derivative as in (b) with none
 *       skipped, but for the fast model's kink in the theta of the direction
 *       at the normal, where the derivative must be one of the one-sided
 *       ones.
 * Fixed seeds; the sampled points are a deterministic function of them.
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

#include "render/bsdf/bsdf.h"
#include "render/bsdf/bsdf_ad.h"
#include "render/rng.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define NVAR 9
enum { V_THO, V_PHO, V_ULOBE, V_U1, V_U2, V_TU, V_TV, V_THI, V_PHI };

/* ---- A small bitmap texture (5 x 4, RGB) with a uv transform. ------------ */

static float g_pixels[5 * 4 * 3];
static lmc_image g_image = {5, 4, 3, g_pixels};

static texture make_bitmap(double uscale, double uoffset) {
  texture t = tex_bitmap(&g_image);
  t.uscale = uscale;
  t.vscale = 0.5 * uscale + 0.25;
  t.uoffset = uoffset;
  t.voffset = -0.37;
  return t;
}

static void init_image(void) {
  rng r;
  rng_seed(&r, 77, 1);
  for (int i = 0; i < 5 * 4 * 3; i++) g_pixels[i] = (float)(0.05 + 0.9 * rng_uniform(&r));
}

/* ---- The models under test. ------------------------------------------------- */

enum {
  M_DIFFUSE,
  M_PHONG,
  M_CONDUCTOR,
  M_ROUGHCOND,
  M_DIELECTRIC,
  M_ROUGHDIEL,
  M_THINDIEL,
  M_PLASTIC,
  M_ROUGHPLASTIC,
  M_TWOSIDED,
  M_MASK,
  M_ROUGHDIFFUSE,
  M_WARD,
  M_DIFFTRANS,
  M_BLEND,
  M_COUNT
};
static const char *const g_model_names[M_COUNT] = {
    "diffuse",        "phong",          "conductor", "roughconductor", "dielectric",
    "roughdielectric", "thindielectric", "plastic",   "roughplastic",   "twosided",
    "mask",           "roughdiffuse",   "ward",      "difftrans", "blendbsdf"};

typedef struct config {
  char name[64];
  int model;
  bsdf b;
} config;

#define MAX_CONFIGS 64

static int make_configs(config *c) {
  int n = 0;
  bsdf b;

  /* Diffuse: textured, and the constant default. */
  bsdf_init_defaults(&b, "diffuse");
  b.diffuse = make_bitmap(1.0, 0.0);
  c[n++] = (config){"diffuse bitmap", M_DIFFUSE, b};
  bsdf_init_defaults(&b, "diffuse");
  c[n++] = (config){"diffuse constant", M_DIFFUSE, b};

  /* Phong at two exponents, textured diffuse and specular. */
  const double exps[] = {8.0, 150.0};
  for (int i = 0; i < 2; i++) {
    bsdf_init_defaults(&b, "phong");
    b.exponent = exps[i];
    b.diffuse = make_bitmap(2.0, 0.3);
    b.specular = make_bitmap(1.0, 0.1);
    c[n] = (config){"", M_PHONG, b};
    snprintf(c[n].name, sizeof c[n].name, "phong n=%g", exps[i]);
    n++;
  }

  /* Smooth conductor: Cu (textured) and a perfect mirror. */
  bsdf_init_defaults(&b, "conductor");
  b.specular = make_bitmap(1.5, 0.2);
  c[n++] = (config){"conductor Cu", M_CONDUCTOR, b};
  bsdf_init_defaults(&b, "conductor");
  conductor_lookup("Au", &b.cond_eta, &b.cond_k);
  c[n++] = (config){"conductor Au", M_CONDUCTOR, b};

  /* Rough conductor: both distributions, visible normals on and off, two roughnesses. */
  const double alphas[] = {0.15, 0.5};
  for (int d = 0; d < 2; d++)
    for (int vis = 0; vis < 2; vis++)
      for (int a = 0; a < 2; a++) {
        bsdf_init_defaults(&b, "roughconductor");
        b.dist = d ? MF_GGX : MF_BECKMANN;
        b.sample_visible = vis;
        b.alpha = alphas[a];
        b.specular = make_bitmap(1.0, 0.6);
        c[n] = (config){"", M_ROUGHCOND, b};
        snprintf(c[n].name, sizeof c[n].name, "roughconductor %s vis=%d a=%g", d ? "ggx" : "beckmann",
                 vis, alphas[a]);
        n++;
      }

  /* Smooth dielectric (textured transmittance). */
  bsdf_init_defaults(&b, "dielectric");
  b.transmittance = make_bitmap(1.0, 0.0);
  b.specular = make_bitmap(2.0, 0.5);
  c[n++] = (config){"dielectric", M_DIELECTRIC, b};

  /* Rough dielectric: both distributions, visible normals on and off, two roughnesses. */
  for (int d = 0; d < 2; d++)
    for (int vis = 0; vis < 2; vis++)
      for (int a = 0; a < 2; a++) {
        bsdf_init_defaults(&b, "roughdielectric");
        b.dist = d ? MF_GGX : MF_BECKMANN;
        b.sample_visible = vis;
        b.alpha = alphas[a];
        b.transmittance = make_bitmap(1.0, 0.2);
        c[n] = (config){"", M_ROUGHDIEL, b};
        snprintf(c[n].name, sizeof c[n].name, "roughdielectric %s vis=%d a=%g",
                 d ? "ggx" : "beckmann", vis, alphas[a]);
        n++;
      }

  /* Thin dielectric (textured reflectance and transmittance). */
  bsdf_init_defaults(&b, "thindielectric");
  b.transmittance = make_bitmap(1.0, 0.3);
  b.specular = make_bitmap(2.0, 0.1);
  c[n++] = (config){"thindielectric", M_THINDIEL, b};

  /* Rough plastic: both distributions, two roughnesses, visible normals
   * with the smaller, nonlinear with GGX, textured base. */
  for (int d = 0; d < 2; d++)
    for (int a = 0; a < 2; a++) {
      bsdf_init_defaults(&b, "roughplastic");
      b.dist = d ? MF_GGX : MF_BECKMANN;
      b.sample_visible = !a;
      b.alpha = alphas[a];
      b.nonlinear = d;
      b.diffuse = make_bitmap(1.0, 0.4);
      bsdf_prepare(&b);
      c[n] = (config){"", M_ROUGHPLASTIC, b};
      snprintf(c[n].name, sizeof c[n].name, "roughplastic %s vis=%d a=%g nonlinear=%d",
               d ? "ggx" : "beckmann", !a, alphas[a], d);
      n++;
    }

  /* Plastic, linear and nonlinear. */
  for (int nl = 0; nl < 2; nl++) {
    bsdf_init_defaults(&b, "plastic");
    b.nonlinear = nl;
    b.diffuse = make_bitmap(1.0, 0.4);
    c[n] = (config){"", M_PLASTIC, b};
    snprintf(c[n].name, sizeof c[n].name, "plastic nonlinear=%d", nl);
    n++;
  }

  /* Twosided: diffuse, rough conductor, plastic. */
  bsdf_init_defaults(&b, "diffuse");
  b.twosided = 1;
  b.diffuse = make_bitmap(1.0, 0.0);
  c[n++] = (config){"twosided diffuse", M_TWOSIDED, b};
  bsdf_init_defaults(&b, "roughconductor");
  b.twosided = 1;
  b.dist = MF_GGX;
  b.alpha = 0.3;
  c[n++] = (config){"twosided roughconductor", M_TWOSIDED, b};
  bsdf_init_defaults(&b, "plastic");
  b.twosided = 1;
  c[n++] = (config){"twosided plastic", M_TWOSIDED, b};

  /* Mask: a textured opacity on diffuse (derivatives in tu, tv through
   * the lobe probability), a constant one on a twosided rough conductor
   * and on the smooth dielectric. */
  bsdf_init_defaults(&b, "diffuse");
  b.masked = 1;
  b.opacity = make_bitmap(1.0, 0.3);
  c[n++] = (config){"mask diffuse", M_MASK, b};
  bsdf_init_defaults(&b, "roughconductor");
  b.twosided = 1;
  b.dist = MF_GGX;
  b.alpha = 0.3;
  b.masked = 1;
  b.opacity = tex_constant(rgb_make(0.2, 0.5, 0.9));
  c[n++] = (config){"mask twosided roughconductor", M_MASK, b};
  bsdf_init_defaults(&b, "dielectric");
  b.masked = 1;
  b.opacity = tex_constant(rgb_make(0.7, 0.6, 0.5));
  c[n++] = (config){"mask dielectric", M_MASK, b};
  /* Rough diffuse: the full model and the fast approximation, two
   * roughnesses, textured reflectance. */
  const double rd_alphas[] = {0.3, 0.8};
  for (int fa = 0; fa < 2; fa++)
    for (int a = 0; a < 2; a++) {
      bsdf_init_defaults(&b, "roughdiffuse");
      b.fast_approx = fa;
      b.alpha = rd_alphas[a];
      b.diffuse = make_bitmap(1.0, 0.3);
      c[n] = (config){"", M_ROUGHDIFFUSE, b};
      snprintf(c[n].name, sizeof c[n].name, "roughdiffuse fast=%d a=%g", fa, rd_alphas[a]);
      n++;
    }

  /* Ward: the three variants anisotropic, balanced isotropic; textured. */
  for (int v = 0; v < 4; v++) {
    bsdf_init_defaults(&b, "ward");
    b.variant = v < 3 ? (ward_variant)v : WARD_BALANCED;
    b.alpha_u = v < 3 ? 0.15 : 0.3;
    b.alpha_v = v < 3 ? 0.4 : 0.3;
    b.diffuse = make_bitmap(1.0, 0.1);
    b.specular = make_bitmap(2.0, 0.7);
    c[n] = (config){"", M_WARD, b};
    snprintf(c[n].name, sizeof c[n].name, "ward variant=%d au=%g av=%g", (int)b.variant, b.alpha_u,
             b.alpha_v);
    n++;
  }

  /* Diffuse transmission: textured, and the constant default. */
  bsdf_init_defaults(&b, "difftrans");
  b.transmittance = make_bitmap(1.0, 0.2);
  c[n++] = (config){"difftrans bitmap", M_DIFFTRANS, b};
  bsdf_init_defaults(&b, "difftrans");
  c[n++] = (config){"difftrans constant", M_DIFFTRANS, b};

  /* Blends (their BSDFs in static storage): a textured weight over
   * textured diffuse and rough gold; smooth glass with a phong lobe. */
  static bsdf parts[4];
  bsdf_init_defaults(&parts[0], "diffuse");
  parts[0].diffuse = make_bitmap(1.0, 0.4);
  bsdf_init_defaults(&parts[1], "roughconductor");
  parts[1].alpha = 0.25;
  bsdf_init_defaults(&parts[2], "dielectric");
  bsdf_init_defaults(&parts[3], "phong");
  for (int i = 0; i < 2; i++) {
    bsdf_init_defaults(&b, "blendbsdf");
    b.diffuse = i ? tex_constant(rgb_gray(0.4)) : make_bitmap(0.5, 0.2);
    b.nested_bsdf[0] = &parts[2 * i];
    b.nested_bsdf[1] = &parts[2 * i + 1];
    c[n++] = (config){"", M_BLEND, b};
    snprintf(c[n - 1].name, sizeof c[n - 1].name, "blendbsdf %s",
             i ? "dielectric+phong" : "diffuse+roughconductor (textured weight)");
  }
  assert_true(n <= MAX_CONFIGS);
  return n;
}

/* 1 when the model answers queries from below the surface. */
static int both_sides(const bsdf *b) {
  return b->twosided || b->masked || (bsdf_flags(b) & BSDF_TRANSMISSION);
}

/* ---- Evaluation of everything at one point x[NVAR]. ----------------------- */

/* Outputs: the sample's wi (3), f (3), pdf, weight (3); then eval f (3), pdf. */
#define NOUT 14
#define NSAMPLE_OUT 10

typedef struct outputs {
  int ok, flags, eval_key;
  double eta;
  double v[NOUT];
  double d[NOUT][NVAR]; /* AD derivatives (dual evaluation only) */
} outputs;

static vec3 sph(double theta, double phi) {
  return v3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
}

/* The side pattern of (wo, wi): the branch eval and pdf take. */
static int side_key(vec3 wo, vec3 wi) { return (wo.z > 0.0) * 2 + (wi.z > 0.0); }

static void eval_plain(const bsdf *b, transport_mode mode, const double *x, outputs *o) {
  memset(o, 0, sizeof *o);
  vec3 wo = sph(x[V_THO], x[V_PHO]), wi = sph(x[V_THI], x[V_PHI]);
  bsdf_sample s;
  o->ok = bsdf_sample_f(b, x[V_TU], x[V_TV], wo, x[V_ULOBE], x[V_U1], x[V_U2], mode, &s);
  o->flags = s.flags;
  o->eta = s.eta;
  double sv[NSAMPLE_OUT] = {s.wi.x, s.wi.y, s.wi.z, s.f.r, s.f.g, s.f.b, s.pdf, s.weight.r, s.weight.g, s.weight.b};
  memcpy(o->v, sv, sizeof sv);
  rgb f = bsdf_eval(b, x[V_TU], x[V_TV], wo, wi, mode);
  o->v[10] = f.r;
  o->v[11] = f.g;
  o->v[12] = f.b;
  o->v[13] = bsdf_pdf(b, x[V_TU], x[V_TV], wo, wi);
  o->eval_key = side_key(wo, wi);
}

/* The dual evaluation; the arena's tangent length says whether derivatives
 * are recorded (9) or not (0). */
static void eval_dual(ad_arena *A, const bsdf *b, transport_mode mode, const double *x, outputs *o) {
  memset(o, 0, sizeof *o);
  ad_arena_reset(A);
  ad var[NVAR];
  for (int i = 0; i < NVAR; i++) var[i] = ad_var(A, x[i], i);
  adv3 wo = adv3_make(ad_mul(A, ad_sin(A, var[V_THO]), ad_cos(A, var[V_PHO])),
                      ad_mul(A, ad_sin(A, var[V_THO]), ad_sin(A, var[V_PHO])), ad_cos(A, var[V_THO]));
  adv3 wi = adv3_make(ad_mul(A, ad_sin(A, var[V_THI]), ad_cos(A, var[V_PHI])),
                      ad_mul(A, ad_sin(A, var[V_THI]), ad_sin(A, var[V_PHI])), ad_cos(A, var[V_THI]));
  bsdf_sample_ad s;
  o->ok = bsdf_sample_f_ad(A, b, var[V_TU], var[V_TV], wo, var[V_ULOBE], var[V_U1], var[V_U2], mode, &s);
  o->flags = s.flags;
  o->eta = s.eta;
  adrgb f = bsdf_eval_ad(A, b, var[V_TU], var[V_TV], wo, wi, mode);
  ad pdf = bsdf_pdf_ad(A, b, var[V_TU], var[V_TV], wo, wi);
  ad all[NOUT] = {s.wi.x, s.wi.y, s.wi.z, s.f.r, s.f.g, s.f.b, s.pdf, s.weight.r, s.weight.g, s.weight.b,
                  f.r, f.g, f.b, pdf};
  for (int k = 0; k < NOUT; k++) {
    o->v[k] = all[k].v;
    for (int j = 0; j < NVAR; j++) o->d[k][j] = ad_deriv(A, all[k], j);
  }
  o->eval_key = side_key(v3(wo.x.v, wo.y.v, wo.z.v), v3(wi.x.v, wi.y.v, wi.z.v));
}

/* A random point: wo anywhere (lower hemisphere only for models that see
 * both sides, unless `any_side`), random numbers away from 0 and 1, texture
 * coordinates anywhere in [-2, 3), and wi either random or the direction the
 * plain sampler picks (so that glossy peaks are evaluated too). */
static void random_point(rng *r, const bsdf *b, transport_mode mode, int any_side, double *x) {
  double top = (both_sides(b) || any_side) ? M_PI - 0.02 : 0.5 * M_PI - 0.02;
  x[V_THO] = 0.02 + (top - 0.02) * rng_uniform(r);
  x[V_PHO] = 2.0 * M_PI * rng_uniform(r);
  x[V_ULOBE] = 0.001 + 0.998 * rng_uniform(r);
  x[V_U1] = 0.001 + 0.998 * rng_uniform(r);
  x[V_U2] = 0.001 + 0.998 * rng_uniform(r);
  x[V_TU] = -2.0 + 5.0 * rng_uniform(r);
  x[V_TV] = -2.0 + 5.0 * rng_uniform(r);
  x[V_THI] = 0.02 + (M_PI - 0.04) * rng_uniform(r);
  x[V_PHI] = 2.0 * M_PI * rng_uniform(r);
  if (rng_uniform(r) < 0.5) {
    bsdf_sample s;
    vec3 wo = sph(x[V_THO], x[V_PHO]);
    double ul = rng_uniform(r), v1 = rng_uniform(r), v2 = rng_uniform(r);
    if (bsdf_sample_f(b, x[V_TU], x[V_TV], wo, ul, v1, v2, mode, &s) && !(s.flags & BSDF_DELTA)) {
      x[V_THI] = acos(fmax(-1.0, fmin(1.0, s.wi.z)));
      x[V_PHI] = atan2(s.wi.y, s.wi.x);
    }
  }
}

/* Relative difference; values both below 1e-30 count as equal. Such values
 * only occur far in the tails of the Beckmann exp(-tan^2 / alpha^2), where
 * one ulp of the direction moves the exponent by hundreds of ulps. */
static double rel_err(double a, double b) {
  if (a == b || (fabs(a) < 1e-30 && fabs(b) < 1e-30)) return 0.0;
  return fabs(a - b) / fmax(fabs(a), fabs(b));
}

/* ---- (a) value agreement ----------------------------------------------------- */

static double g_buf0[64];
static double g_buf9[1 << 16];

static void test_values(void **state) {
  (void)state;
  init_image();
  config cfg[MAX_CONFIGS];
  int nc = make_configs(cfg);
  ad_arena A0, A9;
  assert_int_equal(ad_arena_init(&A0, g_buf0, 64, 0), 0);
  assert_int_equal(ad_arena_init(&A9, g_buf9, sizeof g_buf9 / sizeof g_buf9[0], NVAR), 0);
  long per_model[M_COUNT] = {0};
  long ok_per_model[M_COUNT] = {0};
  const int points = 1500;
  long mismatches = 0;
  for (int c = 0; c < nc; c++) {
    rng r;
    rng_seed(&r, 1000 + (uint64_t)c, 3);
    for (int mode = 0; mode < 2; mode++)
      for (int i = 0; i < points; i++) {
        double x[NVAR];
        random_point(&r, &cfg[c].b, (transport_mode)mode, 1, x);
        outputs p, d0, d9;
        eval_plain(&cfg[c].b, (transport_mode)mode, x, &p);
        eval_dual(&A0, &cfg[c].b, (transport_mode)mode, x, &d0);
        eval_dual(&A9, &cfg[c].b, (transport_mode)mode, x, &d9);
        assert_true(ad_arena_ok(&A9));
        const outputs *ds[2] = {&d0, &d9};
        for (int k = 0; k < 2; k++) {
          const outputs *d = ds[k];
          int bad = d->ok != p.ok || (p.ok && (d->flags != p.flags || d->eta != p.eta));
          /* The sample's values count when it succeeded; eval and pdf always. */
          for (int o = p.ok ? 0 : NSAMPLE_OUT; o < NOUT; o++) {
            per_model[cfg[c].model]++;
            if (rel_err(p.v[o], d->v[o]) > 1e-12) {
              bad = 1;
            } else {
              ok_per_model[cfg[c].model]++;
            }
          }
          if (bad) {
            if (mismatches < 10)
              print_error("%s (n=%d): ok %d/%d flags %d/%d; f %.17g/%.17g pdf %.17g/%.17g "
                          "eval %.17g/%.17g pdf %.17g/%.17g\n",
                          cfg[c].name, k ? NVAR : 0, p.ok, d->ok, p.flags, d->flags, p.v[3], d->v[3],
                          p.v[6], d->v[6], p.v[10], d->v[10], p.v[13], d->v[13]);
            mismatches++;
          }
        }
      }
  }
  for (int m = 0; m < M_COUNT; m++) {
    print_message("values %-16s %8ld compared, %8ld equal\n", g_model_names[m], per_model[m],
                  ok_per_model[m]);
    /* Each model has at least 1500 points x 2 modes x 2 arenas x 4 outputs. */
    assert_true(per_model[m] >= 24000);
  }
  assert_int_equal(mismatches, 0);
}

/* Textures alone: constant, bitmap (all wrap cases), checkerboard. */
static void test_texture_values(void **state) {
  (void)state;
  init_image();
  ad_arena A0, A9;
  assert_int_equal(ad_arena_init(&A0, g_buf0, 64, 0), 0);
  assert_int_equal(ad_arena_init(&A9, g_buf9, sizeof g_buf9 / sizeof g_buf9[0], 2), 0);
  texture tex[4] = {tex_constant(rgb_make(0.1, 0.2, 0.3)), make_bitmap(1.0, 0.0), make_bitmap(3.7, -1.3),
                    tex_checkerboard(rgb_gray(0.4), rgb_gray(0.2))};
  tex[3].uscale = 3.0;
  tex[3].voffset = 0.1;
  rng r;
  rng_seed(&r, 5, 5);
  long compared = 0, checked_d = 0;
  for (int t = 0; t < 4; t++)
    for (int i = 0; i < 4000; i++) {
      double u = -5.0 + 10.0 * rng_uniform(&r), v = -5.0 + 10.0 * rng_uniform(&r);
      rgb p = tex_eval(&tex[t], u, v);
      ad_arena_reset(&A0);
      adrgb q0 = tex_eval_ad(&A0, &tex[t], ad_var(&A0, u, 0), ad_var(&A0, v, 1));
      ad_arena_reset(&A9);
      adrgb q9 = tex_eval_ad(&A9, &tex[t], ad_var(&A9, u, 0), ad_var(&A9, v, 1));
      const adrgb *qs[2] = {&q0, &q9};
      for (int k = 0; k < 2; k++) {
        assert_le(rel_err(p.r, qs[k]->r.v), 1e-12);
        assert_le(rel_err(p.g, qs[k]->g.v), 1e-12);
        assert_le(rel_err(p.b, qs[k]->b.v), 1e-12);
        compared += 3;
      }
      /* Derivative in u of the red channel vs central differences away
       * from texel edges (bilinear: exact up to rounding inside a texel). */
      const double h = 1e-7;
      double fd = (tex_eval(&tex[t], u + h, v).r - tex_eval(&tex[t], u - h, v).r) / (2.0 * h);
      double fd2 = (tex_eval(&tex[t], u + 2 * h, v).r - tex_eval(&tex[t], u - 2 * h, v).r) / (4.0 * h);
      if (fabs(fd - fd2) < 1e-6) {
        assert_near(ad_deriv(&A9, q9.r, 0), fd, 1e-6 * fmax(1.0, fabs(fd)));
        checked_d++;
      }
    }
  print_message("texture values compared %ld, derivatives checked %ld\n", compared, checked_d);
  assert_true(compared == 4 * 4000 * 6);
  assert_true(checked_d >= 15000);
}

/* ---- (b) derivatives ----------------------------------------------------------- */

typedef struct grad_stats {
  long checked, passed, skipped_branch, skipped_kink;
  double worst;
} grad_stats;

/* Compares every AD derivative of the outputs at x with central
 * differences of the plain functions (the rules of the opening comment),
 * adding to *s; prints the first mismatches. The variable skip_var (-1:
 * none) is left out. */
static void grad_check_point(ad_arena *A, const config *cf, transport_mode mode, const double *x,
                             int skip_var, grad_stats *s, int *printed) {
  const double h = 1e-6;
  outputs d;
  eval_dual(A, &cf->b, mode, x, &d);
  assert_true(ad_arena_ok(A));
  /* Central differences with steps h and h/2 in every variable. */
  double fd1[NVAR][NOUT], fd2[NVAR][NOUT];
  int same[NVAR][2];
  for (int j = 0; j < NVAR; j++) {
    outputs o[4];
    const double steps[4] = {h, -h, 0.5 * h, -0.5 * h};
    for (int k = 0; k < 4; k++) {
      double xp[NVAR];
      memcpy(xp, x, sizeof xp);
      xp[j] += steps[k];
      eval_plain(&cf->b, mode, xp, &o[k]);
    }
    same[j][0] = same[j][1] = 1;
    for (int k = 0; k < 4; k++) {
      same[j][0] &= o[k].ok == d.ok && o[k].flags == d.flags;
      same[j][1] &= o[k].eval_key == d.eval_key;
    }
    for (int out = 0; out < NOUT; out++) {
      fd1[j][out] = (o[0].v[out] - o[1].v[out]) / (2.0 * h);
      fd2[j][out] = (o[2].v[out] - o[3].v[out]) / h;
    }
  }
  for (int out = 0; out < NOUT; out++) {
    int is_sample = out < NSAMPLE_OUT;
    if (is_sample && !d.ok) continue;
    /* The magnitude: max(|f|, |grad f|) with the finite-difference
     * gradient over the variables where the branch holds. */
    double g2 = 0.0;
    for (int j = 0; j < NVAR; j++)
      if (same[j][is_sample ? 0 : 1]) g2 += fd1[j][out] * fd1[j][out];
    double mag = fmax(fabs(d.v[out]), sqrt(g2));
    double tol_abs = 1e-8 * mag;
    for (int j = 0; j < NVAR; j++) {
      double ad_d = d.d[out][j];
      if (j == skip_var) continue;
      if (d.v[out] == 0.0 && ad_d == 0.0 && fd1[j][out] == 0.0 && fd2[j][out] == 0.0)
        continue; /* identically zero here: nothing to check */
      if (!same[j][is_sample ? 0 : 1]) {
        s->skipped_branch++;
        continue;
      }
      double a1 = fd1[j][out], a2 = fd2[j][out];
      if (fabs(a1 - a2) > fmax(1e-5 * fmax(fabs(a1), fabs(a2)), tol_abs)) {
        s->skipped_kink++;
        continue;
      }
      double err = fabs(ad_d - a1);
      s->checked++;
      if (err <= 1e-5 * fmax(fabs(ad_d), fabs(a1)) || err <= tol_abs) {
        s->passed++;
      } else {
        s->worst = fmax(s->worst, err / fmax(fabs(a1), tol_abs));
        if (*printed < 12) {
          print_message("  mismatch %s mode %d out %d var %d: ad %.12g fd %.12g (fd_h/2 %.12g) "
                        "value %.6g mag %.3g\n",
                        cf->name, (int)mode, out, j, ad_d, a1, a2, d.v[out], mag);
          (*printed)++;
        }
      }
    }
  }
}

static void test_gradients(void **state) {
  (void)state;
  init_image();
  config cfg[MAX_CONFIGS];
  int nc = make_configs(cfg);
  ad_arena A;
  assert_int_equal(ad_arena_init(&A, g_buf9, sizeof g_buf9 / sizeof g_buf9[0], NVAR), 0);
  grad_stats st[M_COUNT];
  memset(st, 0, sizeof st);
  const int points = 300;
  int printed = 0;
  for (int c = 0; c < nc; c++) {
    rng r;
    rng_seed(&r, 5000 + (uint64_t)c, 7);
    for (int mode = 0; mode < 2; mode++)
      for (int i = 0; i < points; i++) {
        double x[NVAR];
        random_point(&r, &cfg[c].b, (transport_mode)mode, 0, x);
        grad_check_point(&A, &cfg[c], (transport_mode)mode, x, -1, &st[cfg[c].model], &printed);
      }
  }
  for (int m = 0; m < M_COUNT; m++) {
    grad_stats *s = &st[m];
    print_message("gradients %-16s checked %7ld passed %7ld (skipped: branch %6ld, kink %6ld) worst %.3g\n",
                  g_model_names[m], s->checked, s->passed, s->skipped_branch, s->skipped_kink,
                  s->worst);
    /* At least 2000 checked components per model (each model has at least
     * one configuration x 600 points x 9 variables x its nonzero outputs). */
    assert_true(s->checked >= 2000);
    assert_true((double)s->passed >= 0.999 * (double)s->checked);
  }
}

/* Rough diffuse at normal incidence, where sin(theta) = 0 and the azimuth
 * is undefined: wo at the normal, wi at the normal, and both. The dual
 * values equal the plain ones and every tangent is finite. The full model
 * is differentiable there: its derivatives in theta (a step of -h crosses
 * the pole to azimuth phi + pi, a smooth path through it) and phi match
 * central differences, with no point skipped as a kink. The fast model has
 * max(0, cos dphi) sin(alpha) tan(beta), a kink in the theta of the
 * direction at the normal when the other is oblique (the sampled wi is):
 * there the derivative of f must be one of the two one-sided ones
 * (second-order one-sided differences), the other variables are checked as
 * for the full model. */
static void test_normal_incidence(void **state) {
  (void)state;
  init_image();
  ad_arena A;
  assert_int_equal(ad_arena_init(&A, g_buf9, sizeof g_buf9 / sizeof g_buf9[0], NVAR), 0);
  grad_stats st;
  memset(&st, 0, sizeof st);
  int printed = 0, points = 0, one_sided = 0, one_sided_ok = 0;
  long finite = 0, values = 0;
  for (int fa = 0; fa < 2; fa++) {
    config cf;
    bsdf_init_defaults(&cf.b, "roughdiffuse");
    cf.b.fast_approx = fa;
    cf.b.alpha = 0.5;
    cf.b.diffuse = tex_constant(rgb_make(0.3, 0.6, 0.9));
    cf.model = M_ROUGHDIFFUSE;
    snprintf(cf.name, sizeof cf.name, "roughdiffuse normal incidence fast=%d", fa);
    rng r;
    rng_seed(&r, 77 + (uint64_t)fa, 9);
    for (int which = 0; which < 3; which++)
      for (int i = 0; i < 40; i++) {
        double x[NVAR];
        random_point(&r, &cf.b, TRANSPORT_RADIANCE, 0, x);
        x[V_THI] = 0.1 + 1.3 * rng_uniform(&r); /* wi above the surface */
        if (which != 1) x[V_THO] = 0.0;
        if (which != 0) x[V_THI] = 0.0;
        outputs p, d;
        eval_plain(&cf.b, TRANSPORT_RADIANCE, x, &p);
        eval_dual(&A, &cf.b, TRANSPORT_RADIANCE, x, &d);
        for (int o = p.ok ? 0 : NSAMPLE_OUT; o < NOUT; o++) {
          values++;
          int fin = isfinite(d.v[o]) && rel_err(p.v[o], d.v[o]) <= 1e-12;
          for (int j = 0; j < NVAR; j++) fin = fin && isfinite(d.d[o][j]);
          finite += fin;
        }
        int kink_var = !fa ? -1 : which == 1 ? V_THI : V_THO;
        grad_check_point(&A, &cf, TRANSPORT_RADIANCE, x, kink_var, &st, &printed);
        points++;
        if (kink_var < 0) continue;
        /* f (outputs 10-12) at theta = 0, +-h, +-2h: D+ = (-3 f0 + 4 f1 - f2) / 2h. */
        const double h = 1e-5;
        outputs o[5];
        for (int k = 0; k < 5; k++) {
          double xp[NVAR];
          memcpy(xp, x, sizeof xp);
          xp[kink_var] += (k - 2) * h;
          eval_plain(&cf.b, TRANSPORT_RADIANCE, xp, &o[k]);
        }
        for (int out = 3; out < 13; out++) {
          /* The sample's f (its wi does not move with wo) and eval's f. */
          if (out >= 6 && out < 10) continue;
          if (out < 6 && (!p.ok || kink_var != V_THO)) continue;
          double dp = (-3.0 * o[2].v[out] + 4.0 * o[3].v[out] - o[4].v[out]) / (2.0 * h);
          double dm = (3.0 * o[2].v[out] - 4.0 * o[1].v[out] + o[0].v[out]) / (2.0 * h);
          double ad_d = d.d[out][kink_var], tol = 1e-6 * fmax(1.0, fabs(d.v[out]));
          one_sided++;
          one_sided_ok += fabs(ad_d - dp) <= tol || fabs(ad_d - dm) <= tol;
        }
      }
  }
  print_message("normal incidence: %ld values finite and equal of %ld; derivatives checked %ld "
                "passed %ld (skipped: branch %ld, kink %ld); one-sided %d of %d\n",
                finite, values, st.checked, st.passed, st.skipped_branch, st.skipped_kink,
                one_sided_ok, one_sided);
  assert_int_equal(points, 2 * 3 * 40);
  assert_int_equal(finite, values);
  assert_int_equal(st.skipped_kink, 0);
  assert_true(st.checked >= 2000);
  assert_int_equal(st.passed, st.checked);
  assert_true(one_sided >= 3 * 40 * 3);
  assert_int_equal(one_sided_ok, one_sided);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_texture_values),
      cmocka_unit_test(test_values),
      cmocka_unit_test(test_gradients),
      cmocka_unit_test(test_normal_incidence),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
