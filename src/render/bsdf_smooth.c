/*
 * bsdf_smooth.c: the models without microfacets, as Mitsuba 0.6 defines
 * them. Conventions of bsdf.h: local frame, z-up, wo toward the viewer,
 * f without the cosine, weight = f |cos wi| / pdf, delta lobes only from
 * sampling (pdf = lobe probability).
 *
 * diffuse     f = R / pi; cosine-weighted sampling, pdf = cos(wi) / pi.
 *
 * phong       Mitsuba's energy-normalised modified Phong (Lafortune and
 *             Willems 1994):
 *               f = kd / pi + ks (n + 2) / (2 pi) cos^n(a),  cos(a) = wi . r,
 *             with r = (-wo.x, -wo.y, wo.z) the mirror direction (cos^n taken
 *             as 0 when cos(a) <= 0). The specular lobe is chosen with
 *             probability w = lum(mean ks) / (lum(mean ks) + lum(mean kd)),
 *             and sampled around r with density (n + 1) / (2 pi) cos^n(a)
 *             (cos(a) = u2^(1/(n+1)), azimuth 2 pi u1); directions below the
 *             surface are rejected, so the pdf, the mixture
 *               pdf = w (n + 1)/(2 pi) cos^n(a) + (1 - w) cos(wi) / pi,
 *             integrates to less than 1 over the upper hemisphere.
 *
 * conductor   delta reflection with weight specularReflectance F_cond(cos).
 *
 * dielectric  delta reflection (probability F) and refraction (1 - F),
 *             F = fresnel_dielectric(cos wo); weights specularReflectance,
 *             and specularTransmittance times (eta_o / eta_i)^2 in radiance
 *             mode (the 1/eta^2 radiance scaling) or 1 in importance mode.
 *             Total internal reflection: F = 1.
 *
 * plastic     Mitsuba's smooth plastic: a dielectric coating (eta) on a
 *             Lambertian base with reflectance kd. Specular: delta reflection
 *             with weight ks F_i. Diffuse, including the infinite series of
 *             internal reflections (F_dr: diffuse Fresnel reflectance seen
 *             from inside, at 1/eta):
 *               f = kd' (1 - F_i) (1 - F_o) / (pi eta^2),
 *               kd' = kd / (1 - F_dr)         (default, colour preserving),
 *               kd' = kd / (1 - kd F_dr)      (nonlinear = 1).
 *             F_i = F(cos wo), F_o = F(cos wi). The specular lobe is chosen
 *             with probability p = F_i w / (F_i w + (1 - F_i)(1 - w)), w the
 *             specular weight as for phong; pdf = (1 - p) cos(wi) / pi.
 */
#include <math.h>
#include <stddef.h>

#include "render/bsdf_internal.h"
#include "render/frame.h"
#include "render/warp.h"

/* ---- diffuse --------------------------------------------------------------- */

rgb bsdf__diffuse_eval(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, transport_mode mode) {
  (void)mode;
  if (wo.z <= 0.0 || wi.z <= 0.0) return rgb_zero();
  return rgb_scale(tex_eval(&b->diffuse, tu, tv), 1.0 / M_PI);
}

double bsdf__diffuse_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi) {
  (void)b, (void)tu, (void)tv;
  if (wo.z <= 0.0 || wi.z <= 0.0) return 0.0;
  return wi.z / M_PI;
}

int bsdf__diffuse_sample(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe, double u1,
                         double u2, transport_mode mode, bsdf_sample *out) {
  (void)u_lobe;
  if (wo.z <= 0.0) return 0;
  vec3 wi = warp_square_to_cosine_hemisphere(u1, u2);
  if (wi.z <= 0.0) return 0;
  return bsdf__finish(out, wi, bsdf__diffuse_eval(b, tu, tv, wo, wi, mode), wi.z / M_PI, 1.0,
                      BSDF_REFLECTION | BSDF_DIFFUSE_LOBE);
}

/* ---- phong ----------------------------------------------------------------- */

/* f and pdf of one (wo, wi) pair in one pass (eval, pdf and sample all
 * come here), sharing cos^n(a), the costly pow. want_f = 0 skips f;
 * OUT_pdf = NULL skips the pdf. */
static rgb bsdf__ph_eval_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int want_f,
                             double *OUT_pdf) {
  if (OUT_pdf) *OUT_pdf = 0.0;
  if (wo.z <= 0.0 || wi.z <= 0.0) return rgb_zero();
  /* cos(a) = wi . r with r the mirror of wo about the normal. */
  double ca = -wi.x * wo.x - wi.y * wo.y + wi.z * wo.z;
  double n = b->exponent;
  double can = ca > 0.0 ? pow(ca, n) : 0.0;
  if (OUT_pdf) {
    double w = bsdf__specular_weight(&b->specular, &b->diffuse);
    double spec = ca > 0.0 ? (n + 1.0) / (2.0 * M_PI) * can : 0.0;
    *OUT_pdf = w * spec + (1.0 - w) * wi.z / M_PI;
  }
  if (!want_f) return rgb_zero();
  rgb f = rgb_scale(tex_eval(&b->diffuse, tu, tv), 1.0 / M_PI);
  if (ca > 0.0)
    f = rgb_add(f, rgb_scale(tex_eval(&b->specular, tu, tv), (n + 2.0) / (2.0 * M_PI) * can));
  return f;
}

rgb bsdf__phong_eval(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, transport_mode mode) {
  (void)mode;
  return bsdf__ph_eval_pdf(b, tu, tv, wo, wi, 1, NULL);
}

double bsdf__phong_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi) {
  double pdf;
  bsdf__ph_eval_pdf(b, tu, tv, wo, wi, 0, &pdf);
  return pdf;
}

rgb bsdf__phong_eval_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,
                         transport_mode mode, double *OUT_pdf) {
  (void)mode;
  return bsdf__ph_eval_pdf(b, tu, tv, wo, wi, 1, OUT_pdf);
}

int bsdf__phong_sample(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe, double u1,
                       double u2, transport_mode mode, bsdf_sample *out) {
  (void)mode;
  if (wo.z <= 0.0) return 0;
  double w = bsdf__specular_weight(&b->specular, &b->diffuse);
  vec3 wi;
  int flags;
  if (u_lobe < w) {
    /* Specular lobe: cos(a) = u2^(1/(n+1)) around the mirror direction. */
    double n = b->exponent;
    double ca = pow(u2, 1.0 / (n + 1.0));
    double sa = sqrt(lmc_fmax(0.0, 1.0 - ca * ca));
    double phi = 2.0 * M_PI * u1;
    frame fr = frame_from_z(v3(-wo.x, -wo.y, wo.z));
    wi = v3_normalize(frame_to_world(&fr, v3(sa * cos(phi), sa * sin(phi), ca)));
    flags = BSDF_REFLECTION | BSDF_GLOSSY;
  } else {
    wi = warp_square_to_cosine_hemisphere(u1, u2);
    flags = BSDF_REFLECTION | BSDF_DIFFUSE_LOBE;
  }
  if (wi.z <= 0.0) return 0;
  double pdf;
  rgb f = bsdf__ph_eval_pdf(b, tu, tv, wo, wi, 1, &pdf);
  return bsdf__finish(out, wi, f, pdf, 1.0, flags);
}

/* ---- conductor (smooth) ------------------------------------------------- */

rgb bsdf__conductor_eval(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, transport_mode mode) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi, (void)mode;
  return rgb_zero();
}

double bsdf__conductor_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi;
  return 0.0;
}

int bsdf__conductor_sample(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe, double u1,
                           double u2, transport_mode mode, bsdf_sample *out) {
  (void)u_lobe, (void)u1, (void)u2, (void)mode;
  if (wo.z <= 0.0) return 0;
  vec3 wi = v3(-wo.x, -wo.y, wo.z);
  rgb weight = rgb_mul(tex_eval(&b->specular, tu, tv), fresnel_conductor(wo.z, b->cond_eta, b->cond_k));
  /* Delta convention: pdf 1, f = weight / |cos wi|. */
  return bsdf__finish(out, wi, rgb_scale(weight, 1.0 / wi.z), 1.0, 1.0, BSDF_REFLECTION | BSDF_DELTA);
}

/* ---- dielectric (smooth) ------------------------------------------------ */

rgb bsdf__dielectric_eval(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, transport_mode mode) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi, (void)mode;
  return rgb_zero();
}

double bsdf__dielectric_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi;
  return 0.0;
}

int bsdf__dielectric_sample(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe, double u1,
                            double u2, transport_mode mode, bsdf_sample *out) {
  (void)u1, (void)u2;
  if (wo.z == 0.0) return 0;
  double cos_t;
  double fr = fresnel_dielectric(wo.z, b->eta, &cos_t);
  if (u_lobe < fr) {
    /* Reflection, chosen with probability F: weight = specularReflectance. */
    vec3 wi = v3(-wo.x, -wo.y, wo.z);
    rgb weight = tex_eval(&b->specular, tu, tv);
    return bsdf__finish(out, wi, rgb_scale(weight, fr / fabs(wi.z)), fr, 1.0,
                        BSDF_REFLECTION | BSDF_DELTA);
  }
  /* Refraction, probability 1 - F. s = eta_o / eta_i of the two sides. */
  if (cos_t == 0.0) return 0;
  double s = wo.z > 0.0 ? 1.0 / b->eta : b->eta;
  vec3 wi = v3(-s * wo.x, -s * wo.y, cos_t);
  double scale = mode == TRANSPORT_RADIANCE ? s * s : 1.0;
  rgb weight = rgb_scale(tex_eval(&b->transmittance, tu, tv), scale);
  double pdf = 1.0 - fr;
  return bsdf__finish(out, wi, rgb_scale(weight, pdf / fabs(cos_t)), pdf,
                      cos_t < 0.0 ? b->eta : 1.0 / b->eta, BSDF_TRANSMISSION | BSDF_DELTA);
}

/* ---- plastic -------------------------------------------------------------- */

/* Probability of choosing the specular coating at cos(wo) = cos_o. */
static double bsdf__plastic_prob_specular(const bsdf *b, double fi) {
  double w = bsdf__specular_weight(&b->specular, &b->diffuse);
  double den = fi * w + (1.0 - fi) * (1.0 - w);
  return den > 0.0 ? fi * w / den : 0.0;
}

rgb bsdf__plastic_eval(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, transport_mode mode) {
  (void)mode;
  if (wo.z <= 0.0 || wi.z <= 0.0) return rgb_zero();
  double fi = fresnel_dielectric(wo.z, b->eta, NULL);
  double fo = fresnel_dielectric(wi.z, b->eta, NULL);
  double fdr = bsdf__fresnel_diffuse_reflectance(1.0 / b->eta);
  rgb kd = tex_eval(&b->diffuse, tu, tv);
  /* kd' = kd / (1 - kd F_dr) (nonlinear) or kd / (1 - F_dr). */
  rgb kdp = b->nonlinear ? rgb_div(kd, rgb_sub(rgb_gray(1.0), rgb_scale(kd, fdr)))
                         : rgb_scale(kd, 1.0 / (1.0 - fdr));
  return rgb_scale(kdp, (1.0 - fi) * (1.0 - fo) / (M_PI * b->eta * b->eta));
}

double bsdf__plastic_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi) {
  (void)tu, (void)tv;
  if (wo.z <= 0.0 || wi.z <= 0.0) return 0.0;
  double p = bsdf__plastic_prob_specular(b, fresnel_dielectric(wo.z, b->eta, NULL));
  return (1.0 - p) * wi.z / M_PI;
}

int bsdf__plastic_sample(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe, double u1,
                         double u2, transport_mode mode, bsdf_sample *out) {
  if (wo.z <= 0.0) return 0;
  double fi = fresnel_dielectric(wo.z, b->eta, NULL);
  double p = bsdf__plastic_prob_specular(b, fi);
  if (u_lobe < p) {
    /* Specular coating: weight = ks F_i / p, f = ks F_i / cos. */
    vec3 wi = v3(-wo.x, -wo.y, wo.z);
    rgb ks = tex_eval(&b->specular, tu, tv);
    return bsdf__finish(out, wi, rgb_scale(ks, fi / wi.z), p, 1.0, BSDF_REFLECTION | BSDF_DELTA);
  }
  vec3 wi = warp_square_to_cosine_hemisphere(u1, u2);
  if (wi.z <= 0.0) return 0;
  return bsdf__finish(out, wi, bsdf__plastic_eval(b, tu, tv, wo, wi, mode), (1.0 - p) * wi.z / M_PI,
                      1.0, BSDF_REFLECTION | BSDF_DIFFUSE_LOBE);
}
