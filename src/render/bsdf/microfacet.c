/*
 * microfacet.c: Beckmann and GGX distributions, exact Smith shadowing, and
 * sampling of all normals or of the visible normals. See microfacet.h for
 * the papers and conventions.
 *
 * The formulas are written once (microfacet_generic.h) and compiled here
 * twice, in doubles and in duals (render/real.h); the value-only helpers
 * they share (erfinv, the Beckmann slope inversion) come first.
 *
 * Slopes. A normal m = (mx, my, mz) has slopes (x, y) = (-mx/mz, -my/mz);
 * both distributions are "stretch invariant": the slope density of
 * roughness alpha is the one of roughness 1 scaled by alpha. Visible-normal
 * sampling therefore stretches v to the alpha = 1 configuration, samples
 * slopes there, and unstretches.
 */
#include "render/bsdf/microfacet.h"
#include "render/bsdf/microfacet_ad.h"
#include "render/warp.h"

#include <math.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define MF_INV_SQRT_PI 0.56418958354775628695 /* 1/sqrt(pi) */

double mf_erfinv(double x) {
  if (x <= -1.0) return -INFINITY;
  if (x >= 1.0) return INFINITY;
  /* Initial guess: Winitzki's closed-form approximation (a = 0.147), then
   * Newton steps on erf(y) - x = 0 with erf'(y) = 2/sqrt(pi) exp(-y^2). */
  const double a = 0.147;
  double ln = log1p(-x * x);
  double t = 2.0 / (M_PI * a) + 0.5 * ln;
  double y = copysign(sqrt(sqrt(t * t - ln / a) - t), x);
  for (int i = 0; i < 4; i++) {
    double d = 2.0 * MF_INV_SQRT_PI * exp(-y * y);
    if (!(d > 0.0)) break;
    double step = (erf(y) - x) / d;
    y -= step;
    if (fabs(step) < 1e-15 * fmax(1.0, fabs(y))) break;
  }
  return y;
}

/* The x-slope of the alpha = 1 Beckmann visible-slope distribution at
 * incidence angle theta (cos_t, sin_t > 0), phi = 0, values only. The
 * x-slope density is
 *   p(x) ~ (cos_t - x sin_t) exp(-x^2) / sqrt(pi),  x < a = cot(theta),
 * with the unnormalised CDF
 *   C(x) = [cos_t erfc(-x) + sin_t exp(-x^2) / sqrt(pi)] / 2;
 * u1 is inverted with a Newton iteration safeguarded by bisection. (The
 * y-slope is independent, Gaussian with variance 1/2: erfinv(2 u2 - 1).) */
static double mf__beckmann_slope_x(double cos_t, double sin_t, double u1) {
  double a = cos_t / sin_t;
  double hi = fmin(a, 9.0), lo = -9.0;
  double c_hi = 0.5 * (cos_t * erfc(-a) + sin_t * exp(-a * a) * MF_INV_SQRT_PI);
  double target = u1 * c_hi;
  double xx = 0.5 * (lo + hi);
  for (int i = 0; i < 100; i++) {
    double c = 0.5 * (cos_t * erfc(-xx) + sin_t * exp(-xx * xx) * MF_INV_SQRT_PI) - target;
    if (c > 0.0)
      hi = xx;
    else
      lo = xx;
    double dc = (cos_t - xx * sin_t) * exp(-xx * xx) * MF_INV_SQRT_PI;
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

/* The distributions in doubles (microfacet.h), then in duals
 * (microfacet_ad.h), from one source. */
#define R_DUAL 0
#include "render/real.h"
#include "render/bsdf/microfacet_generic.h"
#undef R_DUAL
#define R_DUAL 1
#include "render/real.h"
#include "render/bsdf/microfacet_generic.h"

/* ---- The inverse of mf_sample (values only) ---------------------------- */

static double mf__clamp01(double x) { return x < 0.0 ? 0.0 : (x >= 1.0 ? nextafter(1.0, 0.0) : x); }

/* The standard-configuration Beckmann visible slopes (sx, sy) to (u1, u2):
 * u1 = C(sx) / C(a) with mf__beckmann_slope_x's CDF, u2 = (1 + erf(sy)) / 2. */
static int mf__beckmann_visible_invert(double cos_t, double sin_t, double sx, double sy,
                                       double *OUT_u1, double *OUT_u2) {
  *OUT_u2 = mf__clamp01(0.5 * erfc(-sy));
  if (sin_t < 1e-9) {
    *OUT_u1 = mf__clamp01(0.5 * erfc(-sx));
    return 1;
  }
  double a = cos_t / sin_t;
  if (!(sx < a)) return 0;
  double c_hi = 0.5 * (cos_t * erfc(-a) + sin_t * exp(-a * a) * MF_INV_SQRT_PI);
  double c = 0.5 * (cos_t * erfc(-sx) + sin_t * exp(-sx * sx) * MF_INV_SQRT_PI);
  if (!(c_hi > 0.0)) return 0;
  *OUT_u1 = mf__clamp01(c / c_hi);
  return 1;
}

int mf_invert(mf_dist dist, double alpha, vec3 v, int visible, vec3 m, double *OUT_u1,
              double *OUT_u2) {
  if (!(m.z > 0.0) || !(alpha > 0.0)) return 0;
  if (!visible) {
    /* tan^2 = (m.x^2 + m.y^2) / m.z^2 through the CDF the sampler inverts. */
    double a2 = alpha * alpha;
    double t2 = (m.x * m.x + m.y * m.y) / (m.z * m.z);
    *OUT_u1 = mf__clamp01(dist == MF_BECKMANN ? -expm1(-t2 / a2) : t2 / (a2 + t2));
    *OUT_u2 = warp_turn(atan2(m.y, m.x));
    return 1;
  }
  if (!(v.z > 0.0) || !(v3_dot(v, m) > 0.0)) return 0;
  vec3 vh = v3_normalize(v3(alpha * v.x, alpha * v.y, v.z));
  if (dist == MF_GGX) {
    /* Undo the unstretch, project on the disk's axes, undo the squeeze. */
    vec3 nh = v3_normalize(v3(m.x / alpha, m.y / alpha, m.z));
    double lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = lensq > 0.0 ? v3_scale(v3(-vh.y, vh.x, 0.0), 1.0 / sqrt(lensq)) : v3(1.0, 0.0, 0.0);
    vec3 t2 = v3_cross(vh, t1);
    double p1 = v3_dot(nh, t1), p2 = v3_dot(nh, t2);
    double s = 0.5 * (vh.z + 1.0);
    p2 = (p2 - (1.0 - s) * sqrt(fmax(0.0, 1.0 - p1 * p1))) / s;
    double r2 = p1 * p1 + p2 * p2;
    if (!(r2 <= 1.0 + 1e-12)) return 0;
    *OUT_u1 = mf__clamp01(r2);
    *OUT_u2 = warp_turn(atan2(p2, p1));
    return 1;
  }
  /* Beckmann: the slopes of m, unscaled and rotated back to phi = 0. */
  double cos_t = vh.z, sin_t = sqrt(fmax(0.0, 1.0 - cos_t * cos_t));
  double cos_p = 1.0, sin_p = 0.0;
  if (sin_t > 0.0) {
    double l = sqrt(vh.x * vh.x + vh.y * vh.y);
    if (l > 0.0) {
      cos_p = vh.x / l;
      sin_p = vh.y / l;
    }
  }
  double rx = -m.x / (m.z * alpha), ry = -m.y / (m.z * alpha);
  double sx = cos_p * rx + sin_p * ry, sy = -sin_p * rx + cos_p * ry;
  return mf__beckmann_visible_invert(cos_t, sin_t, sx, sy, OUT_u1, OUT_u2);
}
