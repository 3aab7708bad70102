/*
 * warp.c: sample / pdf / invert triples for the standard warps.
 *
 * Each `invert` is the exact inverse of its `sample` on the interior of the
 * domain, so a point x maps back to the u with sample(u) = x (up to
 * rounding). Angles use atan2 so inverses land in [0,1).
 */
#include "render/warp.h"

#include <math.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Wraps an angle in (-pi, pi] into [0, 1) as a fraction of a turn. */
double warp_uniform_in(double lo, double hi, double r) {
  double x = lo + r * (hi - lo);
  return x < hi ? x : nextafter(hi, lo);
}

double warp_turn(double phi) {
  double t = phi / (2.0 * M_PI);
  if (t < 0.0) t += 1.0;
  if (t >= 1.0) t -= 1.0;
  return t;
}

static double warp__clamp01(double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); }

/* Concentric map (Shirley and Chiu 1997): squares of [-1,1]^2 to rings. */
void warp_square_to_disk_concentric(double u1, double u2, double *x, double *y) {
  double a = 2.0 * u1 - 1.0, b = 2.0 * u2 - 1.0;
  if (a == 0.0 && b == 0.0) {
    *x = *y = 0.0;
    return;
  }
  double r, phi;
  if (fabs(a) > fabs(b)) {
    r = a;
    phi = (M_PI / 4.0) * (b / a);
  } else {
    r = b;
    phi = (M_PI / 2.0) - (M_PI / 4.0) * (a / b);
  }
  *x = r * cos(phi);
  *y = r * sin(phi);
}

double warp_square_to_disk_concentric_pdf(double x, double y) {
  return (x * x + y * y <= 1.0) ? 1.0 / M_PI : 0.0;
}

void warp_disk_concentric_to_square(double x, double y, double *u1, double *u2) {
  double r = sqrt(x * x + y * y);
  double phi = atan2(y, x);
  if (phi < -M_PI / 4.0) phi += 2.0 * M_PI; /* phi in [-pi/4, 7pi/4) */
  double a, b;
  if (phi < M_PI / 4.0) { /* region 1: a = r, b/a = phi / (pi/4) */
    a = r;
    b = phi * a / (M_PI / 4.0);
  } else if (phi < 3.0 * M_PI / 4.0) { /* region 2: b = r */
    b = r;
    a = -(phi - M_PI / 2.0) * b / (M_PI / 4.0);
  } else if (phi < 5.0 * M_PI / 4.0) { /* region 3: a = -r */
    a = -r;
    b = (phi - M_PI) * a / (M_PI / 4.0);
  } else { /* region 4: b = -r */
    b = -r;
    a = -(phi - 3.0 * M_PI / 2.0) * b / (M_PI / 4.0);
  }
  *u1 = warp__clamp01(0.5 * (a + 1.0));
  *u2 = warp__clamp01(0.5 * (b + 1.0));
}

/* Malley's method: a concentric disk sample lifted to the hemisphere. */
vec3 warp_square_to_cosine_hemisphere(double u1, double u2) {
  double x, y;
  warp_square_to_disk_concentric(u1, u2, &x, &y);
  double z = sqrt(lmc_fmax(0.0, 1.0 - x * x - y * y));
  return v3(x, y, z);
}

double warp_square_to_cosine_hemisphere_pdf(vec3 w) { return w.z > 0.0 ? w.z / M_PI : 0.0; }

void warp_cosine_hemisphere_to_square(vec3 w, double *u1, double *u2) {
  warp_disk_concentric_to_square(w.x, w.y, u1, u2);
}

/* z = 1 - 2 u1, phi = 2 pi u2. */
vec3 warp_square_to_uniform_sphere(double u1, double u2) {
  double z = 1.0 - 2.0 * u1;
  double r = sqrt(lmc_fmax(0.0, 1.0 - z * z));
  double phi = 2.0 * M_PI * u2;
  return v3(r * cos(phi), r * sin(phi), z);
}

double warp_square_to_uniform_sphere_pdf(vec3 w) {
  (void)w;
  return 1.0 / (4.0 * M_PI);
}

void warp_uniform_sphere_to_square(vec3 w, double *u1, double *u2) {
  *u1 = warp__clamp01(0.5 * (1.0 - w.z));
  *u2 = warp_turn(atan2(w.y, w.x));
}

/* z = u1, phi = 2 pi u2. */
vec3 warp_square_to_uniform_hemisphere(double u1, double u2) {
  double z = u1;
  double r = sqrt(fmax(0.0, 1.0 - z * z));
  double phi = 2.0 * M_PI * u2;
  return v3(r * cos(phi), r * sin(phi), z);
}

double warp_square_to_uniform_hemisphere_pdf(vec3 w) { return w.z > 0.0 ? 1.0 / (2.0 * M_PI) : 0.0; }

void warp_uniform_hemisphere_to_square(vec3 w, double *u1, double *u2) {
  *u1 = warp__clamp01(w.z);
  *u2 = warp_turn(atan2(w.y, w.x));
}

/* cos(theta) = 1 - u1 (1 - cos_max), phi = 2 pi u2. */
vec3 warp_square_to_uniform_cone(double u1, double u2, double cos_max) {
  double z = 1.0 - u1 * (1.0 - cos_max);
  double r = sqrt(fmax(0.0, 1.0 - z * z));
  double phi = 2.0 * M_PI * u2;
  return v3(r * cos(phi), r * sin(phi), z);
}

double warp_square_to_uniform_cone_pdf(vec3 w, double cos_max) {
  if (w.z < cos_max) return 0.0;
  return 1.0 / (2.0 * M_PI * (1.0 - cos_max));
}

void warp_uniform_cone_to_square(vec3 w, double cos_max, double *u1, double *u2) {
  *u1 = warp__clamp01((1.0 - w.z) / (1.0 - cos_max));
  *u2 = warp_turn(atan2(w.y, w.x));
}

/* Uniform triangle by the square-root parameterisation:
 * b1 = 1 - sqrt(u1), b2 = u2 sqrt(u1). */
void warp_square_to_triangle(double u1, double u2, double *b1, double *b2) {
  double s = sqrt(u1);
  *b1 = 1.0 - s;
  *b2 = u2 * s;
}

void warp_triangle_to_square(double b1, double b2, double *u1, double *u2) {
  double s = 1.0 - b1;
  *u1 = warp__clamp01(s * s);
  *u2 = s > 0.0 ? warp__clamp01(b2 / s) : 0.0;
}

/* Tent: invert the cdf of 1 - |x| on each half. */
double warp_interval_to_tent(double u) {
  if (u < 0.5) return sqrt(2.0 * u) - 1.0;
  return 1.0 - sqrt(2.0 - 2.0 * u);
}

double warp_interval_to_tent_pdf(double x) { return fabs(x) < 1.0 ? 1.0 - fabs(x) : 0.0; }

double warp_tent_to_interval(double x) {
  if (x < 0.0) return 0.5 * (x + 1.0) * (x + 1.0);
  return 1.0 - 0.5 * (1.0 - x) * (1.0 - x);
}
