/*
 * microfacet_ad.c: Beckmann and GGX distributions, exact Smith shadowing and
 * normal sampling in dual arithmetic (microfacet_ad.h). Formulas and
 * branches are those of microfacet.c; the comments there and in
 * microfacet.h name the papers.
 *
 * Derivative of the visible Beckmann slope. Heitz and d'Eon sample the
 * x-slope of the alpha = 1 configuration by solving
 *   C(x; c, s) = u1 C(a; c, s),  C(x) = [c erfc(-x) + s exp(-x^2)/sqrt(pi)] / 2,
 * with c = cos(theta), s = sin(theta) of the stretched direction and
 * a = c / s. The solution x(u1, c, s) is found by a safeguarded Newton
 * iteration on values. By the implicit function theorem,
 *   dx = (d[u1 C(a)] - C_c dc - C_s ds) / C_x,
 *   C_c = erfc(-x)/2,  C_s = exp(-x^2)/(2 sqrt(pi)),
 *   C_x = (c - x s) exp(-x^2)/sqrt(pi)  (the slope density, > 0 for x < a),
 * and d[u1 C(a)] is carried by dual arithmetic through C(a) (its
 * a-derivative vanishes at a = c / s, so no special care is needed). The
 * y-slope is erfinv(2 u2 - 1): its value comes from mf_erfinv (the plain
 * code's) and its tangent from ad_erfinv's rule sqrt(pi)/2 exp(y^2).
 */
#include "render/microfacet_ad.h"

#include <math.h>

#include "render/bsdf_ad_internal.h"

#define MF_AD_INV_SQRT_PI 0.56418958354775628695 /* 1/sqrt(pi) */

/* tan^2(theta) of a direction (|v.z| used); +inf at grazing. */
static ad mf__ad_tan2(ad_arena *A, adv3 v) {
  ad c2 = ad_sqr(A, v.z);
  if (!(c2.v > 0.0)) return ad_const(A, INFINITY);
  ad s2 = ad_s_sub(A, 1.0, c2);
  if (s2.v < 0.0) s2 = ad_const(A, 0.0);
  return ad_div(A, s2, c2);
}

ad mf_D_ad(ad_arena *A, mf_dist dist, ad alpha, adv3 m) {
  if (m.z.v <= 0.0) return ad_const(A, 0.0);
  ad a2 = ad_sqr(A, alpha), c2 = ad_sqr(A, m.z);
  if (dist == MF_BECKMANN) {
    /* D = exp(-tan^2 / alpha^2) / (pi alpha^2 cos^4) */
    ad t2 = mf__ad_tan2(A, m);
    ad num = ad_exp(A, ad_neg(A, ad_div(A, t2, a2)));
    ad den = ad_mul(A, ad_mul(A, ad_mul_s(A, a2, M_PI), c2), c2);
    ad d = ad_div(A, num, den);
    return isfinite(d.v) ? d : ad_const(A, 0.0);
  }
  /* GGX: D = alpha^2 / (pi ((alpha^2 - 1) cos^2 + 1)^2) */
  ad k = ad_add_s(A, ad_mul(A, ad_sub_s(A, a2, 1.0), c2), 1.0);
  return ad_div(A, a2, ad_mul_s(A, ad_sqr(A, k), M_PI));
}

ad mf_lambda_ad(ad_arena *A, mf_dist dist, ad alpha, adv3 v) {
  ad t2 = mf__ad_tan2(A, v);
  if (t2.v == 0.0) return ad_const(A, 0.0);
  if (!isfinite(t2.v)) return ad_const(A, INFINITY);
  if (dist == MF_BECKMANN) {
    /* a = 1 / (alpha tan); Lambda = (erf(a) - 1)/2 + exp(-a^2) / (2 a sqrt(pi)) */
    ad a = ad_inv(A, ad_mul(A, alpha, ad_sqrt(A, t2)));
    if (a.v > 26.0) return ad_const(A, 0.0);
    ad e1 = ad_erfc(A, a);
    ad e2 = ad_div(A, ad_mul_s(A, ad_exp(A, ad_neg(A, ad_sqr(A, a))), MF_AD_INV_SQRT_PI), a);
    return ad_mul_s(A, ad_sub(A, e2, e1), 0.5);
  }
  /* GGX: Lambda = (-1 + sqrt(1 + alpha^2 tan^2)) / 2 */
  ad r = ad_sqrt(A, ad_add_s(A, ad_mul(A, ad_sqr(A, alpha), t2), 1.0));
  return ad_mul_s(A, ad_sub_s(A, r, 1.0), 0.5);
}

ad mf_G1_ad(ad_arena *A, mf_dist dist, ad alpha, adv3 v, adv3 m) {
  ad vm = adv3_dot(A, v, m);
  if (vm.v * v.z.v <= 0.0) return ad_const(A, 0.0);
  ad l = mf_lambda_ad(A, dist, alpha, v);
  /* G1 = 1 / (1 + Lambda) */
  return isfinite(l.v) ? ad_s_div(A, 1.0, ad_add_s(A, l, 1.0)) : ad_const(A, 0.0);
}

ad mf_G_ad(ad_arena *A, mf_dist dist, ad alpha, adv3 wi, adv3 wo, adv3 m) {
  return ad_mul(A, mf_G1_ad(A, dist, alpha, wi, m), mf_G1_ad(A, dist, alpha, wo, m));
}

/* erfinv(x) with mf_erfinv's value and the tangent of ad_erfinv. */
static ad mf__ad_erfinv(ad_arena *A, ad x) {
  return bsdf__ad_with_value(A, ad_erfinv(A, x), mf_erfinv(x.v));
}

/* The x-slope of the alpha = 1 visible Beckmann slopes (values only): the
 * same safeguarded Newton inversion as microfacet.c. */
static double mf__ad_beckmann_slope_x(double cos_t, double sin_t, double u1) {
  double a = cos_t / sin_t;
  double hi = fmin(a, 9.0), lo = -9.0;
  double c_hi = 0.5 * (cos_t * erfc(-a) + sin_t * exp(-a * a) * MF_AD_INV_SQRT_PI);
  double target = u1 * c_hi;
  double xx = 0.5 * (lo + hi);
  for (int i = 0; i < 100; i++) {
    double c = 0.5 * (cos_t * erfc(-xx) + sin_t * exp(-xx * xx) * MF_AD_INV_SQRT_PI) - target;
    if (c > 0.0)
      hi = xx;
    else
      lo = xx;
    double dc = (cos_t - xx * sin_t) * exp(-xx * xx) * MF_AD_INV_SQRT_PI;
    double next = dc > 0.0 ? xx - c / dc : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (fabs(next - xx) < 1e-13 || hi - lo < 1e-13) {
      xx = next;
      break;
    }
    xx = next;
  }
  return xx;
}

/* Visible-normal slopes of the alpha = 1 Beckmann distribution seen at
 * (cos_t, sin_t), in duals (see the opening comment). */
static void mf__ad_beckmann_visible_slopes(ad_arena *A, ad cos_t, ad sin_t, ad u1, ad u2,
                                           ad *OUT_x, ad *OUT_y) {
  *OUT_y = mf__ad_erfinv(A, ad_sub_s(A, ad_mul_s(A, u2, 2.0), 1.0));
  if (sin_t.v < 1e-9) {
    *OUT_x = mf__ad_erfinv(A, ad_sub_s(A, ad_mul_s(A, u1, 2.0), 1.0));
    return;
  }
  double x = mf__ad_beckmann_slope_x(cos_t.v, sin_t.v, u1.v);

  /* The right-hand side u1 C(a) with a = cos_t / sin_t, in duals. */
  ad a = ad_div(A, cos_t, sin_t);
  ad c_hi = ad_mul_s(A,
                     ad_add(A, ad_mul(A, cos_t, ad_erfc(A, ad_neg(A, a))),
                            ad_mul(A, sin_t, ad_mul_s(A, ad_exp(A, ad_neg(A, ad_sqr(A, a))),
                                                       MF_AD_INV_SQRT_PI))),
                     0.5);
  ad target = ad_mul(A, u1, c_hi);

  /* dx = (d target - C_c d cos_t - C_s d sin_t) / C_x */
  double ex = exp(-x * x) * MF_AD_INV_SQRT_PI;
  double c_c = 0.5 * erfc(-x), c_s = 0.5 * ex;
  double c_x = (cos_t.v - x * sin_t.v) * ex;
  ad rhs = ad_sub(A, target, ad_lincomb(A, c_c, cos_t, c_s, sin_t));
  ad dx = c_x > 0.0 ? ad_mul_s(A, rhs, 1.0 / c_x) : ad_const(A, 0.0);
  *OUT_x = bsdf__ad_with_value(A, dx, x);
}

adv3 mf_sample_ad(ad_arena *A, mf_dist dist, ad alpha, adv3 v, int visible, ad u1, ad u2) {
  if (!visible) {
    /* Sample D(m) cos(theta_m): tan^2(theta_m) by inversion of its CDF,
     * Beckmann: 1 - exp(-tan^2 / alpha^2); GGX: tan^2 / (alpha^2 + tan^2). */
    ad a2 = ad_sqr(A, alpha);
    ad t2 = dist == MF_BECKMANN ? ad_mul(A, ad_neg(A, a2), ad_log1p(A, ad_neg(A, u1)))
                                : ad_div(A, ad_mul(A, a2, u1), ad_s_sub(A, 1.0, u1));
    ad cos_m = ad_inv(A, ad_sqrt(A, ad_add_s(A, t2, 1.0)));
    ad sin_m = ad_safe_sqrt(A, ad_s_sub(A, 1.0, ad_sqr(A, cos_m)));
    ad phi = ad_mul_s(A, u2, 2.0 * M_PI);
    return adv3_make(ad_mul(A, sin_m, ad_cos(A, phi)), ad_mul(A, sin_m, ad_sin(A, phi)), cos_m);
  }
  /* Stretch v to the alpha = 1 configuration. */
  adv3 vh = adv3_normalize(A, adv3_make(ad_mul(A, alpha, v.x), ad_mul(A, alpha, v.y), v.z));
  if (dist == MF_GGX) {
    /* Heitz 2018: sample the projected disk with its lower half squeezed by
     * s = (1 + vh.z)/2, lift to the hemisphere, unstretch. */
    ad lensq = ad_add(A, ad_sqr(A, vh.x), ad_sqr(A, vh.y));
    adv3 t1;
    if (lensq.v > 0.0) {
      ad il = ad_inv(A, ad_sqrt(A, lensq));
      t1 = adv3_make(ad_mul(A, ad_neg(A, vh.y), il), ad_mul(A, vh.x, il), ad_const(A, 0.0));
    } else {
      t1 = adv3_const(A, 1.0, 0.0, 0.0);
    }
    adv3 t2 = adv3_cross(A, vh, t1);
    ad r = ad_sqrt(A, u1), phi = ad_mul_s(A, u2, 2.0 * M_PI);
    ad p1 = ad_mul(A, r, ad_cos(A, phi)), p2 = ad_mul(A, r, ad_sin(A, phi));
    ad s = ad_mul_s(A, ad_add_s(A, vh.z, 1.0), 0.5);
    /* p2 = (1 - s) sqrt(max(0, 1 - p1^2)) + s p2 */
    ad p1sq = ad_sqr(A, p1);
    p2 = ad_add(A, ad_mul(A, ad_s_sub(A, 1.0, s), ad_safe_sqrt(A, ad_s_sub(A, 1.0, p1sq))),
                ad_mul(A, s, p2));
    /* nh = t1 p1 + t2 p2 + vh sqrt(max(0, 1 - p1^2 - p2^2)) */
    ad lift = ad_safe_sqrt(A, ad_sub(A, ad_s_sub(A, 1.0, p1sq), ad_sqr(A, p2)));
    adv3 nh = adv3_make(
        ad_add(A, ad_add(A, ad_mul(A, t1.x, p1), ad_mul(A, t2.x, p2)), ad_mul(A, vh.x, lift)),
        ad_add(A, ad_add(A, ad_mul(A, t1.y, p1), ad_mul(A, t2.y, p2)), ad_mul(A, vh.y, lift)),
        ad_add(A, ad_add(A, ad_mul(A, t1.z, p1), ad_mul(A, t2.z, p2)), ad_mul(A, vh.z, lift)));
    ad nz = nh.z.v < 1e-12 ? ad_const(A, 1e-12) : nh.z;
    return adv3_normalize(A, adv3_make(ad_mul(A, alpha, nh.x), ad_mul(A, alpha, nh.y), nz));
  }
  /* Beckmann (Heitz and d'Eon 2014): slopes in the standard configuration,
   * rotated to the azimuth of vh, scaled by alpha. */
  ad cos_t = vh.z;
  ad sin_t = ad_safe_sqrt(A, ad_s_sub(A, 1.0, ad_sqr(A, cos_t)));
  ad sx, sy;
  mf__ad_beckmann_visible_slopes(A, cos_t, sin_t, u1, u2, &sx, &sy);
  ad cos_p = ad_const(A, 1.0), sin_p = ad_const(A, 0.0);
  if (sin_t.v > 0.0) {
    ad l = ad_sqrt(A, ad_add(A, ad_sqr(A, vh.x), ad_sqr(A, vh.y)));
    if (l.v > 0.0) {
      cos_p = ad_div(A, vh.x, l);
      sin_p = ad_div(A, vh.y, l);
    }
  }
  ad rx = ad_sub(A, ad_mul(A, cos_p, sx), ad_mul(A, sin_p, sy));
  ad ry = ad_add(A, ad_mul(A, sin_p, sx), ad_mul(A, cos_p, sy));
  rx = ad_mul(A, rx, alpha);
  ry = ad_mul(A, ry, alpha);
  return adv3_normalize(A, adv3_make(ad_neg(A, rx), ad_neg(A, ry), ad_const(A, 1.0)));
}

ad mf_pdf_ad(ad_arena *A, mf_dist dist, ad alpha, adv3 v, adv3 m, int visible) {
  if (!visible) {
    /* D(m) max(0, m.z) */
    if (!(m.z.v > 0.0)) return ad_const(A, 0.0);
    return ad_mul(A, mf_D_ad(A, dist, alpha, m), m.z);
  }
  if (v.z.v <= 0.0) return ad_const(A, 0.0);
  /* D_v(m) = G1(v, m) max(0, v.m) D(m) / v.z */
  ad vm = adv3_dot(A, v, m);
  if (vm.v <= 0.0) return ad_const(A, 0.0);
  ad g1 = mf_G1_ad(A, dist, alpha, v, m);
  return ad_div(A, ad_mul(A, ad_mul(A, g1, vm), mf_D_ad(A, dist, alpha, m)), v.z);
}
