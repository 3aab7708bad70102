/*
 * microfacet.c: Beckmann and GGX distributions, exact Smith shadowing, and
 * sampling of all normals or of the visible normals. See microfacet.h for
 * the papers and conventions.
 *
 * Slopes. A normal m = (mx, my, mz) has slopes (x, y) = (-mx/mz, -my/mz);
 * both distributions are "stretch invariant": the slope density of
 * roughness alpha is the one of roughness 1 scaled by alpha. Visible-normal
 * sampling therefore stretches v to the alpha = 1 configuration, samples
 * slopes there, and unstretches.
 */
#include "render/microfacet.h"

#include <math.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define MF_INV_SQRT_PI 0.56418958354775628695 /* 1/sqrt(pi) */

/* tan^2(theta) of a direction (|v.z| used); +inf at grazing. */
static double mf__tan2(vec3 v) {
  double c2 = v.z * v.z;
  double s2 = lmc_fmax(0.0, 1.0 - c2);
  return c2 > 0.0 ? s2 / c2 : INFINITY;
}

double mf_D(mf_dist dist, double alpha, vec3 m) {
  if (m.z <= 0.0) return 0.0;
  double a2 = alpha * alpha, c2 = m.z * m.z;
  if (dist == MF_BECKMANN) {
    /* D = exp(-tan^2 / alpha^2) / (pi alpha^2 cos^4) */
    double t2 = mf__tan2(m);
    double d = exp(-t2 / a2) / (M_PI * a2 * c2 * c2);
    return isfinite(d) ? d : 0.0;
  }
  /* GGX: D = alpha^2 / (pi ((alpha^2 - 1) cos^2 + 1)^2) */
  double k = (a2 - 1.0) * c2 + 1.0;
  return a2 / (M_PI * k * k);
}

double mf_lambda(mf_dist dist, double alpha, vec3 v) {
  double t2 = mf__tan2(v);
  if (t2 == 0.0) return 0.0;
  if (!isfinite(t2)) return INFINITY;
  if (dist == MF_BECKMANN) {
    /* a = 1 / (alpha tan); Lambda = (erf(a) - 1)/2 + exp(-a^2) / (2 a sqrt(pi)) */
    double a = 1.0 / (alpha * sqrt(t2));
    if (a > 26.0) return 0.0; /* both terms below double precision */
    return 0.5 * (-erfc(a) + exp(-a * a) * MF_INV_SQRT_PI / a);
  }
  /* GGX: Lambda = (-1 + sqrt(1 + alpha^2 tan^2)) / 2 */
  return 0.5 * (-1.0 + sqrt(1.0 + alpha * alpha * t2));
}

double mf_G1(mf_dist dist, double alpha, vec3 v, vec3 m) {
  if (v3_dot(v, m) * v.z <= 0.0) return 0.0;
  double l = mf_lambda(dist, alpha, v);
  return isfinite(l) ? 1.0 / (1.0 + l) : 0.0;
}

double mf_G(mf_dist dist, double alpha, vec3 wi, vec3 wo, vec3 m) {
  return mf_G1(dist, alpha, wi, m) * mf_G1(dist, alpha, wo, m);
}

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

/* Slope of the alpha = 1 Beckmann visible-slope distribution, incidence
 * angle theta (cos_t, sin_t), phi = 0. The x-slope density is
 *   p(x) ~ (cos_t - x sin_t) exp(-x^2) / sqrt(pi),  x < a = cot(theta),
 * with the unnormalised CDF
 *   C(x) = [cos_t erfc(-x) + sin_t exp(-x^2) / sqrt(pi)] / 2;
 * u1 is inverted with a Newton iteration safeguarded by bisection. The
 * y-slope is independent, Gaussian with variance 1/2: y = erfinv(2 u2 - 1). */
static void mf__beckmann_visible_slopes(double cos_t, double sin_t, double u1, double u2, double *x,
                                        double *y) {
  *y = mf_erfinv(2.0 * u2 - 1.0);
  if (sin_t < 1e-9) {
    *x = mf_erfinv(2.0 * u1 - 1.0);
    return;
  }
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
  *x = xx;
}

vec3 mf_sample(mf_dist dist, double alpha, vec3 v, int visible, double u1, double u2) {
  if (!visible) {
    /* Sample D(m) cos(theta_m): tan^2(theta_m) by inversion of its CDF,
     * Beckmann: 1 - exp(-tan^2 / alpha^2); GGX: tan^2 / (alpha^2 + tan^2). */
    double t2 = dist == MF_BECKMANN ? -alpha * alpha * log1p(-u1) : alpha * alpha * u1 / (1.0 - u1);
    double cos_m = 1.0 / sqrt(1.0 + t2);
    double sin_m = sqrt(lmc_fmax(0.0, 1.0 - cos_m * cos_m));
    double phi = 2.0 * M_PI * u2;
    return v3(sin_m * cos(phi), sin_m * sin(phi), cos_m);
  }
  /* Stretch v to the alpha = 1 configuration. */
  vec3 vh = v3_normalize(v3(alpha * v.x, alpha * v.y, v.z));
  if (dist == MF_GGX) {
    /* Heitz 2018: the visible normals of the alpha = 1 GGX (a hemisphere)
     * project to a disk; sample the disk with its lower half squeezed by
     * s = (1 + vh.z)/2, lift to the hemisphere, unstretch. */
    double lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = lensq > 0.0 ? v3_scale(v3(-vh.y, vh.x, 0.0), 1.0 / sqrt(lensq)) : v3(1.0, 0.0, 0.0);
    vec3 t2 = v3_cross(vh, t1);
    double r = sqrt(u1), phi = 2.0 * M_PI * u2;
    double p1 = r * cos(phi), p2 = r * sin(phi);
    double s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(lmc_fmax(0.0, 1.0 - p1 * p1)) + s * p2;
    vec3 nh = v3_add(v3_add(v3_scale(t1, p1), v3_scale(t2, p2)),
                     v3_scale(vh, sqrt(lmc_fmax(0.0, 1.0 - p1 * p1 - p2 * p2))));
    return v3_normalize(v3(alpha * nh.x, alpha * nh.y, lmc_fmax(1e-12, nh.z)));
  }
  /* Beckmann (Heitz and d'Eon 2014): slopes in the standard configuration,
   * rotated to the azimuth of vh, scaled by alpha. */
  double cos_t = vh.z, sin_t = sqrt(lmc_fmax(0.0, 1.0 - cos_t * cos_t));
  double sx, sy;
  mf__beckmann_visible_slopes(cos_t, sin_t, u1, u2, &sx, &sy);
  double cos_p = 1.0, sin_p = 0.0;
  if (sin_t > 0.0) {
    double l = sqrt(vh.x * vh.x + vh.y * vh.y);
    if (l > 0.0) {
      cos_p = vh.x / l;
      sin_p = vh.y / l;
    }
  }
  double rx = cos_p * sx - sin_p * sy, ry = sin_p * sx + cos_p * sy;
  rx *= alpha;
  ry *= alpha;
  return v3_normalize(v3(-rx, -ry, 1.0));
}

double mf_pdf_known(double d, double g1, vec3 v, vec3 m, int visible) {
  if (!visible) return d * lmc_fmax(0.0, m.z);
  if (v.z <= 0.0) return 0.0;
  /* D_v(m) = G1(v, m) max(0, v.m) D(m) / v.z */
  double vm = v3_dot(v, m);
  if (vm <= 0.0) return 0.0;
  return g1 * vm * d / v.z;
}

double mf_pdf(mf_dist dist, double alpha, vec3 v, vec3 m, int visible) {
  if (!visible) return mf_pdf_known(mf_D(dist, alpha, m), 0.0, v, m, 0);
  if (v.z <= 0.0 || v3_dot(v, m) <= 0.0) return 0.0;
  return mf_pdf_known(mf_D(dist, alpha, m), mf_G1(dist, alpha, v, m), v, m, 1);
}
