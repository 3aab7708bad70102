/*
 * vec3.h: 3-vectors of doubles for points, directions and normals, and the
 * RGB colour type.
 *
 * Conventions (used throughout src/render): directions are unit vectors
 * pointing away from the surface; the shading frame is z-up; radiometric
 * quantities are linear RGB in the scene's units.
 */
#ifndef LMC_RENDER_VEC3_H
#define LMC_RENDER_VEC3_H

#include <math.h>

typedef struct vec3 {
  double x, y, z;
} vec3;

/* fmax and fmin, inline: at -O2 on x86-64 GCC calls libm for them (to
 * honour NaN). Same results as glibc's (maxsd/minsd): the larger (smaller)
 * value, the argument that is not NaN, and b when a and b compare equal
 * (signed zeros included). */
static inline double lmc_fmax(double a, double b) { return a > b || isnan(b) ? a : b; }
static inline double lmc_fmin(double a, double b) { return a < b || isnan(b) ? a : b; }

static inline vec3 v3(double x, double y, double z) { return (vec3){x, y, z}; }
static inline vec3 v3_add(vec3 a, vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline vec3 v3_sub(vec3 a, vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline vec3 v3_mul(vec3 a, vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline vec3 v3_scale(vec3 a, double s) { return v3(a.x * s, a.y * s, a.z * s); }
static inline vec3 v3_neg(vec3 a) { return v3(-a.x, -a.y, -a.z); }
/* a + b * s */
static inline vec3 v3_fma(vec3 a, vec3 b, double s) {
  return v3(a.x + b.x * s, a.y + b.y * s, a.z + b.z * s);
}
static inline double v3_dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline vec3 v3_cross(vec3 a, vec3 b) {
  return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double v3_len2(vec3 a) { return v3_dot(a, a); }
static inline double v3_len(vec3 a) { return sqrt(v3_dot(a, a)); }
/* Unit vector along a; returns a unchanged when it has zero length. */
static inline vec3 v3_normalize(vec3 a) {
  double l = v3_len(a);
  return l > 0.0 ? v3_scale(a, 1.0 / l) : a;
}
static inline double v3_max_comp(vec3 a) { return fmax(a.x, fmax(a.y, a.z)); }
static inline vec3 v3_min(vec3 a, vec3 b) { return v3(fmin(a.x, b.x), fmin(a.y, b.y), fmin(a.z, b.z)); }
static inline vec3 v3_max(vec3 a, vec3 b) { return v3(fmax(a.x, b.x), fmax(a.y, b.y), fmax(a.z, b.z)); }
static inline double v3_comp(vec3 a, int i) { return i == 0 ? a.x : (i == 1 ? a.y : a.z); }
static inline int v3_isfinite(vec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }
/* Mirror reflection of w about n (both pointing away from the surface). */
static inline vec3 v3_reflect(vec3 w, vec3 n) { return v3_sub(v3_scale(n, 2.0 * v3_dot(w, n)), w); }

/* Linear RGB radiometric value. */
typedef struct rgb {
  double r, g, b;
} rgb;

static inline rgb rgb_make(double r, double g, double b) { return (rgb){r, g, b}; }
static inline rgb rgb_gray(double v) { return (rgb){v, v, v}; }
static inline rgb rgb_zero(void) { return (rgb){0.0, 0.0, 0.0}; }
static inline rgb rgb_add(rgb a, rgb b) { return rgb_make(a.r + b.r, a.g + b.g, a.b + b.b); }
static inline rgb rgb_sub(rgb a, rgb b) { return rgb_make(a.r - b.r, a.g - b.g, a.b - b.b); }
static inline rgb rgb_mul(rgb a, rgb b) { return rgb_make(a.r * b.r, a.g * b.g, a.b * b.b); }
static inline rgb rgb_scale(rgb a, double s) { return rgb_make(a.r * s, a.g * s, a.b * s); }
static inline rgb rgb_div(rgb a, rgb b) {
  return rgb_make(b.r != 0.0 ? a.r / b.r : 0.0, b.g != 0.0 ? a.g / b.g : 0.0,
                  b.b != 0.0 ? a.b / b.b : 0.0);
}
/* a + b * c, component-wise. */
static inline rgb rgb_fma(rgb a, rgb b, rgb c) {
  return rgb_make(a.r + b.r * c.r, a.g + b.g * c.g, a.b + b.b * c.b);
}
static inline double rgb_max(rgb a) { return fmax(a.r, fmax(a.g, a.b)); }
static inline double rgb_avg(rgb a) { return (a.r + a.g + a.b) / 3.0; }
static inline int rgb_is_black(rgb a) { return a.r == 0.0 && a.g == 0.0 && a.b == 0.0; }
static inline int rgb_isfinite(rgb a) { return isfinite(a.r) && isfinite(a.g) && isfinite(a.b); }
/* Luminance of linear sRGB/Rec.709 primaries (the MCMC target function). */
static inline double rgb_luminance(rgb a) { return 0.212671 * a.r + 0.715160 * a.g + 0.072169 * a.b; }

#endif
