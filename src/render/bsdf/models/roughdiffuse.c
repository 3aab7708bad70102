/*
 * roughdiffuse.c: Oren-Nayar reflection (Mitsuba's roughdiffuse), one BSDF model (bsdf_model.h).
 * Parameters (Mitsuba's names and defaults): reflectance (or diffuseReflectance, 0.5), alpha
 *   (0.2), useFastApprox.
 *
 * Oren and Nayar 1994, "Generalization of Lambert's
 *             Reflectance Model", as Mitsuba 0.6's roughdiffuse: sigma =
 *             alpha / sqrt(2) (Mitsuba's RMS slope alpha to Oren-Nayar's
 *             slope deviation), theta_a = max, theta_b = min of the two
 *             polar angles, dphi their azimuth difference:
 * full  f = rho / pi (C1 + cos(dphi) C2 tan(b)
 *           + (1 - |cos dphi|) C3 tan((a + b) / 2))
 *         + rho^2 / pi C4 (1 - cos(dphi) (2b / pi)^2),
 *       C1 = 1 - 0.5 s2 / (s2 + 0.33), t = s2 / (s2 + 0.09),
 *       C2 = 0.45 t sin(a) (cos dphi > 0) or
 *            0.45 t (sin(a) - (2b / pi)^3),
 *       C3 = 0.125 t (4 a b / pi^2)^2, C4 = 0.17 s2 / (s2 + 0.13);
 * fast  f = rho / pi (A + B max(0, cos dphi) sin(a) tan(b)),
 *       A = C1, B = 0.45 t  (useFastApprox).
 *             Written with p = sin(a) sin(b) cos(dphi) = wa.x wb.x + wa.y wb.y,
 *             so that cos(dphi) sin(a) tan(b) = p / cos(b) and
 *             cos(dphi) b^2 = (p / sin a) b (b / sin b) never divide by
 *             sin(b), which vanishes at the normal: f and its dual are finite
 *             there and equal the limit (Mitsuba sets cos(dphi) = 0 when a
 *             sine is below its Epsilon, which differs from the limit by
 *             O(Epsilon)). alpha = 0 is Lambertian exactly. Cosine-weighted
 *             sampling, pdf = cos(wi) / pi; a glossy lobe, as Mitsuba flags
 *             it.
 *
 * The body below the #else is written once in render/real.h's vocabulary
 * and compiled twice by model_twice.h, in doubles and in duals.
 */
#ifndef R_DUAL
#include <math.h>

#include "render/bsdf/bsdf_model_file.h"

#define MODEL_BODY "render/bsdf/models/roughdiffuse.c"
#include "render/model_twice.h"

/* ---- The inverse of the sampler (values only; bsdf_invert) ----------------- */

static int bsdf__roughdiffuse_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,
                                     int delta, const double r[4], double OUT_u[3],
                                     double *OUT_pmf) {
  (void)b, (void)tu, (void)tv, (void)OUT_pmf;
  if (delta || !(wo.z > 0.0)) return 0;
  return bsdf__invert_cosine(wi, 0.0, 1.0, r, OUT_u);
}

static void bsdf__roughdiffuse_defaults(bsdf *b) { b->alpha = 0.2; }

static double bsdf__roughdiffuse_roughness(const bsdf *b) {
  (void)b;
  return 1.0;
}

static lmc_status bsdf__roughdiffuse_read(bsdf *b, plugin_props *p) {
  /* Mitsuba reads `reflectance`, or `diffuseReflectance` when there is no
   * `reflectance`. */
  const char *rname = props_has(p, "reflectance") ? "reflectance" : "diffuseReflectance";
  lmc_status st = props_texture(p, rname, rgb_gray(0.5), &b->diffuse);
  if (st == LMC_OK) st = props_roughness(p, "alpha", b->alpha, &b->alpha, NULL);
  if (st != LMC_OK) return st;
  if (!(b->alpha >= 0.0)) return props_fail(p, NULL, "roughdiffuse alpha must be >= 0");
  return props_bool(p, "useFastApprox", 0, &b->fast_approx);
}

const bsdf_model bsdf_model_roughdiffuse = {
    .name = "roughdiffuse",
    .flags = BSDF_REFLECTION | BSDF_GLOSSY,
    .defaults = bsdf__roughdiffuse_defaults,
    .read = bsdf__roughdiffuse_read,
    .roughness = bsdf__roughdiffuse_roughness,
    BSDF_MODEL_OPS(roughdiffuse),
};

#else /* the body, in render/real.h's vocabulary */

/* ---- roughdiffuse (Oren-Nayar) ---------------------------------------------- */

/* sin(theta) = sqrt(x^2 + y^2): at the normal its dual has tangent 0 (the
 * one-sided choice of ad_safe_sqrt), never an infinite one. */
static REAL R_FN(bsdf__sin_theta)(R_CTX REAL3 w) {
  return R_SAFE_SQRT(R_ADD(R_SQR(w.x), R_SQR(w.y)));
}

static RRGB R_FN(bsdf__roughdiffuse_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                          transport_mode mode) {
  (void)mode;
  if (R_V(wo.z) <= 0.0 || R_V(wi.z) <= 0.0) return RRGB_ZERO();
  RRGB rho = R_FN(tex_eval)(R_ARG &b->diffuse, tu, tv);
  /* Oren and Nayar's sigma from Mitsuba's RMS slope: sigma = alpha / sqrt(2). */
  double sigma = b->alpha / sqrt(2.0), s2 = sigma * sigma;
  /* wa: the direction farther from the normal (Oren-Nayar's angle alpha),
   * wb: the nearer one (beta). p = sin(a) sin(b) cos(phi_a - phi_b). */
  int wo_near = R_V(wo.z) > R_V(wi.z);
  REAL3 wa = wo_near ? wi : wo, wb = wo_near ? wo : wi;
  REAL p = R_ADD(R_MUL(wa.x, wb.x), R_MUL(wa.y, wb.y));
  REAL cb = wb.z;

  if (b->fast_approx) {
    /* f = rho / pi (A + B max(0, cos dphi) sin(alpha) tan(beta)), where
     * cos(dphi) sin(alpha) tan(beta) = p / cos(beta). */
    double ka = 1.0 - 0.5 * s2 / (s2 + 0.33), kb = 0.45 * s2 / (s2 + 0.09);
    REAL s = R_V(p) > 0.0 ? R_ADD_S(R_MUL_S(R_DIV(p, cb), kb), ka) : R_C(ka);
    return RRGB_SCALE(rho, R_MUL_S(s, 1.0 / M_PI));
  }

  /* The full model: the angles, and the products with cos(dphi) written so
   * that no factor divides by sin(beta), which vanishes at the normal. */
  REAL sa = R_FN(bsdf__sin_theta)(R_ARG wa), sb = R_FN(bsdf__sin_theta)(R_ARG wb), ca = wa.z;
  REAL alpha = R_ATAN2(sa, ca), beta = R_ATAN2(sb, cb);
  /* ps = p / sin(alpha) = sin(beta) cos(dphi) (0 when both are at the normal) */
  REAL ps = R_V(sa) > 1e-12 ? R_DIV(p, sa) : R_C(0.0);
  /* q = beta / sin(beta), 1 + beta^2 / 6 near the normal; then
   * cos(dphi) beta^2 = ps beta q. */
  REAL q = R_V(beta) > 1e-4 ? R_DIV(beta, sb) : R_ADD_S(R_MUL_S(R_SQR(beta), 1.0 / 6.0), 1.0);
  REAL psbq = R_MUL(R_MUL(ps, beta), q);
  double tmp = s2 / (s2 + 0.09);
  double c1 = 1.0 - 0.5 * s2 / (s2 + 0.33), c4 = 0.17 * s2 / (s2 + 0.13);
  /* cos(dphi) C2 tan(beta), C2 = 0.45 tmp sin(alpha) (cos dphi > 0) or
   * 0.45 tmp (sin(alpha) - (2 beta / pi)^3):
   *   = 0.45 tmp (p - [cos dphi <= 0] (2 beta / pi)^3 ps) / cos(beta). */
  REAL t2 = p;
  if (!(R_V(p) > 0.0)) {
    REAL g = R_MUL_S(beta, 2.0 / M_PI);
    t2 = R_SUB(t2, R_MUL(R_MUL(R_SQR(g), g), ps));
  }
  t2 = R_MUL_S(R_DIV(t2, cb), 0.45 * tmp);
  /* (1 - |cos dphi|) C3 tan((alpha + beta) / 2), C3 = 0.125 tmp (4 alpha beta / pi^2)^2:
   *   = 0.125 tmp (4 alpha / pi^2)^2 (beta^2 - |ps| beta q) tan((alpha + beta) / 2),
   * tan((alpha + beta) / 2) = (sin a + sin b) / (cos a + cos b). */
  REAL tan_half = R_DIV(R_ADD(sa, sb), R_ADD(ca, cb));
  REAL k3 = R_MUL_S(R_SQR(R_MUL_S(alpha, 4.0 / (M_PI * M_PI))), 0.125 * tmp);
  REAL t3 = R_MUL(R_MUL(k3, R_SUB(R_SQR(beta), R_MUL(R_MUL(R_FABS(ps), beta), q))), tan_half);
  /* Single scattering C1 + t2 + t3; the interreflection term
   * C4 (1 - cos(dphi) (2 beta / pi)^2) = C4 (1 - (4 / pi^2) ps beta q). */
  REAL single = R_ADD(R_ADD_S(t2, c1), t3);
  REAL dbl = R_MUL_S(R_S_SUB(1.0, R_MUL_S(psbq, 4.0 / (M_PI * M_PI))), c4);
  /* f = (rho single + rho^2 dbl) / pi */
  RRGB f = RRGB_ADD(RRGB_SCALE(rho, single), RRGB_SCALE(RRGB_MUL(rho, rho), dbl));
  return RRGB_SCALE_S(f, 1.0 / M_PI);
}

static REAL R_FN(bsdf__roughdiffuse_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                         REAL3 wi) {
  (void)b, (void)tu, (void)tv;
  /* cosine-weighted, as diffuse */
  if (R_V(wo.z) <= 0.0 || R_V(wi.z) <= 0.0) return R_C(0.0);
  return R_DIV_S(wi.z, M_PI);
}

static int R_FN(bsdf__roughdiffuse_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                           REAL u_lobe, REAL u1, REAL u2, transport_mode mode,
                                           R_FN(bsdf_sample) *out) {
  (void)u_lobe;
  if (R_V(wo.z) <= 0.0) return 0;
  REAL3 wi = R_FN(bsdf__cosine_hemisphere)(R_ARG u1, u2);
  if (R_V(wi.z) <= 0.0) return 0;
  return R_FN(bsdf__finish)(R_ARG out, wi,
                            R_FN(bsdf__roughdiffuse_eval)(R_ARG b, tu, tv, wo, wi, mode),
                            R_DIV_S(wi.z, M_PI), 1.0, BSDF_REFLECTION | BSDF_GLOSSY);
}

#endif
