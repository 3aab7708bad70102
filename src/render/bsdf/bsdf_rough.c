/*
 * bsdf_rough.c: the microfacet models of Walter, Marschner, Li and Torrance
 * 2007, "Microfacet Models for Refraction through Rough Surfaces", with the
 * distributions of microfacet.h, as Mitsuba 0.6's roughconductor,
 * roughdielectric and roughplastic define them (roughplastic's base seen
 * through the coating by Mitsuba's "rough Fresnel transmittance").
 *
 * roughconductor (one-sided). With h = normalize(wo + wi):
 *   f = F_cond(wo . h) D(h) G(wo, wi, h) / (4 cos_o cos_i) * specularReflectance.
 * Sampling draws a normal m (visible normals of wo, or D(m) cos(theta_m))
 * and reflects wo about it; the density of wi is
 *   pdf = p_m(h) / (4 |wi . h|).
 *
 * roughdielectric (both sides; wo.z < 0 means wo is inside, where the IOR
 * is eta = intIOR / extIOR). Let e = eta_i / eta_o be the IOR of wi's side
 * over the IOR of wo's side (e = eta when wo is outside, 1/eta inside).
 *   reflection (cos_o cos_i > 0):  h = normalize(wo + wi),
 *     f_r = F D G / (4 |cos_o| |cos_i|) * specularReflectance;
 *   refraction (cos_o cos_i < 0):  h = normalize(wo + e wi) (the generalised
 *     half vector), flipped to the upper hemisphere,
 *     f_t = (1 - F) D G e^2 |wo.h| |wi.h| / (|cos_o| |cos_i| (wo.h + e wi.h)^2)
 *           * specularTransmittance,
 *     times 1/e^2 in radiance mode (radiance is compressed when it enters a
 *     denser medium), so that f_imp(wo, wi) = f_rad(wi, wo).
 * F = fresnel_dielectric(wo . h, eta). Sampling: a normal m is drawn as for
 * the conductor (from the side of wo, i.e. with wo mirrored to the upper
 * hemisphere), reflection is chosen with probability F(wo . m), refraction
 * otherwise. Densities of wi:
 *   reflection  F p_m(h) / (4 |wi.h|),
 *   refraction  (1 - F) p_m(h) e^2 |wi.h| / (wo.h + e wi.h)^2.
 * Without visible-normal sampling, Mitsuba samples a slightly wider
 * distribution, alpha (1.2 - 0.2 sqrt(|cos_o|)) (Walter et al.'s trick to
 * lower the weights at grazing angles); the pdf uses the same alpha.
 *
 * roughplastic (one-sided; Mitsuba 0.6's roughplastic.cpp). A rough
 * dielectric coating (eta, Beckmann or GGX alpha) over a Lambertian base kd,
 * the sum of a specular and a diffuse lobe, with h = normalize(wo + wi):
 *   f_s = ks F(wo.h) D(h) G(wo, wi, h) / (4 cos_o cos_i),
 *   f_d = kd' T(cos_o) T(cos_i) / (pi eta^2),
 *   kd' = kd / (1 - F_dr)  or, nonlinear,  kd / (1 - kd F_dr).
 * T(c) is the rough transmittance: the energy that light arriving at cosine
 * c from outside carries through the rough interface, the hemispherical
 * integral of roughdielectric's refraction lobe (importance transport);
 * F_dr = 1 - int_0^1 2 c T_int(c) dc is the interface's diffuse reflectance
 * seen from inside (T_int: the same at 1 / eta). As alpha -> 0, T -> 1 - F
 * and F_dr -> plastic's F_dr: smooth plastic's diffuse term. Mitsuba 0.6
 * reads T and F_dr from tables it ships (data/microfacet/beckmann.dat and
 * ggx.dat, tricubic in cos^(1/4), alpha^(1/4), eta^(1/4)); here they are
 * computed when the model
 * is prepared (bsdf_prepare) for its own (dist, alpha, eta): T at 65 nodes
 * uniform in cos^(1/4) (where the boundary layer of width ~alpha near
 * grazing is resolved), by a product Gauss-Legendre rule over the visible
 * normals of each direction, interpolated by a C1 cubic; F_dr by
 * Gauss-Legendre in the cosine. Against Mitsuba's GGX table the nodes agree
 * to 1e-4 (8e-4 at alpha = 1); against its Beckmann table to 0.6%, the
 * difference of our exact Smith G1 and Mitsuba's rational approximation.
 * Sampling (Mitsuba's rule): the specular lobe with probability
 *   p_s = (1 - T_o) w / ((1 - T_o) w + T_o (1 - w)),  T_o = T(cos_o),
 * w the specular sampling weight (as for plastic), drawing a normal as the
 * rough conductor does and reflecting wo about it; else cosine-weighted.
 *   pdf = p_s p_m(h) / (4 wi.h) + (1 - p_s) cos_i / pi.
 * f is symmetric in (wo, wi): the model is reciprocal (its pdf is not).
 *
 * Sample weights are computed as f |cos_i| / pdf from the one function
 * that evaluates both (bsdf__rc_eval_pdf, bsdf__rd_eval_pdf,
 * bsdf__rp_eval_pdf), which eval
 * and pdf call too, so the three can never disagree. The models are
 * written once (bsdf_rough_generic.h) and compiled here twice, in doubles
 * and in duals (render/real.h).
 */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "render/bsdf/bsdf_ad_internal.h"
#include "render/bsdf/bsdf_internal.h"
#include "render/bsdf/microfacet.h"
#include "render/bsdf/microfacet_ad.h"

/* ---- roughplastic's rough transmittance (values only) ------------------- */

/* Order of the Gauss-Legendre rules: over the visible normals of one
 * direction (per axis; even), and over the cosine in each of the two
 * pieces of the diffuse integral. Doubling both changes T by under 1e-5
 * and F_dr by under 1e-3 (7e-4 at GGX, alpha 1, eta 1.005). */
#define BSDF__RT_ORDER_M 40
#define BSDF__RT_ORDER_C 24

/* Gauss-Legendre nodes x and weights w of order n on [0, 1]: Newton's
 * method on the Legendre polynomial P_n (three-term recurrence) from the
 * usual guesses cos(pi (i + 3/4) / (n + 1/2)). */
static void bsdf__gauss_legendre(int n, double *x, double *w) {
  for (int i = 0; i < (n + 1) / 2; i++) {
    double z = cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
    for (int it = 0; it < 100; it++) {
      double p1 = 1.0, p0 = 0.0;
      for (int j = 1; j <= n; j++) {
        double pm = p0;
        p0 = p1;
        p1 = ((2.0 * j - 1.0) * z * p0 - (j - 1.0) * pm) / j;
      }
      /* P_n'(z) = n (z P_n - P_{n-1}) / (z^2 - 1) */
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      double step = p1 / dp;
      z -= step;
      if (fabs(step) < 1e-15) break;
    }
    /* On [-1, 1] the weight is 2 / ((1 - z^2) P_n'(z)^2); halved on [0, 1]. */
    x[i] = 0.5 * (1.0 - z);
    x[n - 1 - i] = 0.5 * (1.0 + z);
    w[i] = w[n - 1 - i] = 1.0 / ((1.0 - z * z) * dp * dp);
  }
}

/* T(c) = int f_t(wo, wi) |cos wi| dwi: the energy that light arriving at
 * cosine c on the side of relative IOR eta (eta < 1: from inside) carries
 * through the rough interface, importance transport (no 1/eta^2), as
 * bsdf_rough.c's roughdielectric refraction defines f_t. With wi refracted
 * through the normal m, the refraction Jacobian cancels f_t's and
 *   T = int D_wo(m) (1 - F(wo.m)) G1(wi, m) dm,
 * D_wo the visible normals of wo (microfacet.h). The integral is taken
 * over the sample space (u1, u2) of mf_sample's visible normals, which
 * maps the unit square onto D_wo, with a product rule (x, w of order n):
 * the integrand is bounded by 1 and the rule adapts to any alpha. */
static double bsdf__rtrans_dir(mf_dist dist, double alpha, double eta, double c, int n,
                               const double *x, const double *w) {
  if (!(c > 0.0)) return 0.0;
  if (c > 1.0) c = 1.0;
  vec3 wo = v3(sqrt(fmax(0.0, 1.0 - c * c)), 0.0, c);
  /* Beckmann's sampler maps u2 and 1 - u2 to normals mirrored in y, which
   * see the same integrand (wo lies in the xz-plane), and the rule's nodes
   * are symmetric: half the columns, counted twice (n is even). */
  int nj = dist == MF_BECKMANN ? n / 2 : n;
  double wj_scale = dist == MF_BECKMANN ? 2.0 : 1.0;
  double acc = 0.0;
  for (int i = 0; i < n; i++)
    for (int j = 0; j < nj; j++) {
      vec3 m = mf_sample(dist, alpha, wo, 1, x[i], x[j]);
      double wom = v3_dot(wo, m), cos_t;
      if (!(wom > 0.0)) continue;
      double fr = fresnel_dielectric(wom, eta, &cos_t);
      if (cos_t == 0.0) continue; /* total internal reflection */
      /* wi = m (wo.m s + cos_t) - wo s, s = 1 / eta (roughdielectric's refraction) */
      double s = 1.0 / eta;
      vec3 wi = v3_normalize(v3_sub(v3_scale(m, wom * s + cos_t), v3_scale(wo, s)));
      acc += w[i] * w[j] * wj_scale * (1.0 - fr) * mf_G1(dist, alpha, wi, m);
    }
  return acc;
}

void bsdf__rtrans_fill(bsdf_rtrans *rt, mf_dist dist, double alpha, double eta) {
  double xm[BSDF__RT_ORDER_M], wm[BSDF__RT_ORDER_M], xc[BSDF__RT_ORDER_C], wc[BSDF__RT_ORDER_C];
  bsdf__gauss_legendre(BSDF__RT_ORDER_M, xm, wm);
  bsdf__gauss_legendre(BSDF__RT_ORDER_C, xc, wc);
  memset(rt, 0, sizeof *rt);
  rt->dist = dist;
  rt->alpha = alpha;
  rt->eta = eta;
  /* T from outside at the nodes c = (k / (N - 1))^4; at grazing, T's limit
   * (nonzero on a rough surface: the facets that face wo stay visible). */
  const int last = BSDF_RTRANS_NODES - 1;
  for (int k = 0; k <= last; k++) {
    double s = (double)k / last, c = k > 0 ? s * s * s * s : 1e-12;
    rt->t_ext[k] = bsdf__rtrans_dir(dist, alpha, eta, c, BSDF__RT_ORDER_M, xm, wm);
  }
  /* The diffuse transmittance from inside, int_0^1 2 c T_int(c) dc at
   * 1 / eta, in two pieces split at the smooth critical cosine c_c, where
   * T_int has a square-root kink when alpha is small: [0, c_c] plainly,
   * [c_c, 1] after c = c_c + (1 - c_c) t^2 (as bsdf__fdr_compute). */
  double ei = 1.0 / eta;
  double cc = ei < 1.0 ? sqrt(fmax(0.0, 1.0 - ei * ei)) : 0.0;
  double td = 0.0;
  for (int k = 0; k < BSDF__RT_ORDER_C; k++) {
    if (cc > 0.0) {
      double c = cc * xc[k];
      td += wc[k] * cc * 2.0 * c * bsdf__rtrans_dir(dist, alpha, ei, c, BSDF__RT_ORDER_M, xm, wm);
    }
    double t = xc[k], c = cc + (1.0 - cc) * t * t;
    double jac = 2.0 * (1.0 - cc) * t;
    td += wc[k] * jac * 2.0 * c * bsdf__rtrans_dir(dist, alpha, ei, c, BSDF__RT_ORDER_M, xm, wm);
  }
  rt->fdr_int = 1.0 - td;
  rt->ready = 1;
}

const bsdf_rtrans *bsdf__rtrans_get(const bsdf *b) {
  const bsdf_rtrans *own = &b->rtrans;
  if (own->ready && own->dist == b->dist && own->alpha == b->alpha && own->eta == b->eta)
    return own;
  /* Not prepared (or prepared for other parameters): a small per-thread
   * cache, filled on first use. */
  static _Thread_local bsdf_rtrans cache[4];
  static _Thread_local int cache_next;
  for (int i = 0; i < 4; i++)
    if (cache[i].ready && cache[i].dist == b->dist && cache[i].alpha == b->alpha &&
        cache[i].eta == b->eta)
      return &cache[i];
  bsdf_rtrans *rt = &cache[cache_next];
  cache_next = (cache_next + 1) & 3;
  bsdf__rtrans_fill(rt, b->dist, b->alpha, b->eta);
  return rt;
}

/* The models in doubles (bsdf_internal.h), then in duals
 * (bsdf_ad_internal.h), from one source. */
#define R_DUAL 0
#include "render/real.h"
#include "render/bsdf/bsdf_rough_generic.h"
#undef R_DUAL
#define R_DUAL 1
#include "render/real.h"
#include "render/bsdf/bsdf_rough_generic.h"
