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
