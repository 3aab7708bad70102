/*
 * medium.c: the homogeneous medium (medium.h): its free flight and
 * transmittance written once (medium_generic.h) and compiled here in
 * doubles and in duals, and the flight's inverse (values only).
 */
#include "render/media/medium.h"

#include <ctype.h>
#include <math.h>
#include <string.h>

#include "ad/dual_math.h"
#include "render/warp.h"

void medium_set(medium *m, rgb sigma_a, rgb sigma_s) {
  memset(m, 0, sizeof *m);
  m->sigma_a = sigma_a;
  m->sigma_s = sigma_s;
  m->sigma_t = rgb_add(sigma_a, sigma_s);
  phase_init(&m->ph, "isotropic");
}

/* Mitsuba 0.6's presets (src/medium/materials.h): sigma_s and sigma_a per
 * millimetre as measured (times 100 when read, as Mitsuba does) and g.
 * The first twelve from Jensen et al. 2001, "A Practical Model for
 * Subsurface Light Transport" (no anisotropy data); the rest from
 * Narasimhan et al. 2006, "Acquiring Scattering Properties of
 * Participating Media by Dilution". */
typedef struct medium__preset {
  const char *name;
  float sigma_s[3], sigma_a[3], g[3];
} medium__preset;

static const medium__preset medium__presets[] = {
    {"Apple", {2.29f, 2.39f, 1.97f}, {0.0030f, 0.0034f, 0.046f}, {0, 0, 0}},
    {"Chicken1", {0.15f, 0.21f, 0.38f}, {0.0015f, 0.077f, 0.19f}, {0, 0, 0}},
    {"Chicken2", {0.19f, 0.25f, 0.32f}, {0.0018f, 0.088f, 0.20f}, {0, 0, 0}},
    {"Cream", {7.38f, 5.47f, 3.15f}, {0.0002f, 0.0028f, 0.0163f}, {0, 0, 0}},
    {"Ketchup", {0.18f, 0.07f, 0.03f}, {0.061f, 0.97f, 1.45f}, {0, 0, 0}},
    {"Marble", {2.19f, 2.62f, 3.00f}, {0.0021f, 0.0041f, 0.0071f}, {0, 0, 0}},
    {"Potato", {0.68f, 0.70f, 0.55f}, {0.0024f, 0.0090f, 0.12f}, {0, 0, 0}},
    {"Skimmilk", {0.70f, 1.22f, 1.90f}, {0.0014f, 0.0025f, 0.0142f}, {0, 0, 0}},
    {"Skin1", {0.74f, 0.88f, 1.01f}, {0.032f, 0.17f, 0.48f}, {0, 0, 0}},
    {"Skin2", {1.09f, 1.59f, 1.79f}, {0.013f, 0.070f, 0.145f}, {0, 0, 0}},
    {"Spectralon", {11.6f, 20.4f, 14.9f}, {0.00f, 0.00f, 0.00f}, {0, 0, 0}},
    {"Wholemilk", {2.55f, 3.21f, 3.77f}, {0.0011f, 0.0024f, 0.014f}, {0, 0, 0}},
    {"Lowfat Milk", {13.1157f, 15.4445f, 17.9572f}, {0.00287f, 0.00575f, 0.01150f}, {0.93200f, 0.90200f, 0.85900f}},
    {"Reduced Milk", {13.7335f, 15.6003f, 17.8007f}, {0.00256f, 0.00511f, 0.01278f}, {0.81900f, 0.79700f, 0.74600f}},
    {"Regular Milk", {18.2052f, 20.3826f, 22.3698f}, {0.00153f, 0.00460f, 0.01993f}, {0.75000f, 0.71400f, 0.68100f}},
    {"Espresso", {7.78262f, 8.13050f, 8.53875f}, {4.79838f, 6.57512f, 8.84925f}, {0.90700f, 0.89600f, 0.88000f}},
    {"Mint Mocha Coffee", {3.51133f, 4.14383f, 5.59667f}, {3.77200f, 5.82283f, 7.82000f}, {0.91000f, 0.90700f, 0.91400f}},
    {"Lowfat Soy Milk", {2.03838f, 2.32875f, 3.90281f}, {0.00144f, 0.00719f, 0.03594f}, {0.85000f, 0.85300f, 0.84200f}},
    {"Regular Soy Milk", {4.66325f, 5.20183f, 8.74575f}, {0.00192f, 0.00958f, 0.06517f}, {0.87300f, 0.85800f, 0.83200f}},
    {"Lowfat Chocolate Milk", {9.83710f, 11.4954f, 13.1629f}, {0.01150f, 0.03680f, 0.15640f}, {0.93400f, 0.92700f, 0.91600f}},
    {"Regular Chocolate Milk", {10.5685f, 13.1416f, 15.2202f}, {0.01006f, 0.04313f, 0.14375f}, {0.86200f, 0.83800f, 0.80600f}},
    {"Coke", {0.00254f, 0.00299f, 0.00000f}, {0.10014f, 0.16503f, 0.24680f}, {0.96500f, 0.97200f, 0.00000f}},
    {"Pepsi", {0.00083f, 0.00203f, 0.00000f}, {0.09164f, 0.14158f, 0.20729f}, {0.92600f, 0.97900f, 0.00000f}},
    {"Sprite", {0.00011f, 0.00014f, 0.00014f}, {0.00189f, 0.00183f, 0.00200f}, {0.94300f, 0.95300f, 0.95200f}},
    {"Gatorade", {0.03668f, 0.04488f, 0.05742f}, {0.02479f, 0.01929f, 0.00888f}, {0.93300f, 0.93300f, 0.93500f}},
    {"Chardonnay", {0.00021f, 0.00033f, 0.00048f}, {0.01078f, 0.01186f, 0.02400f}, {0.91400f, 0.95800f, 0.97500f}},
    {"White Zinfandel", {0.00022f, 0.00033f, 0.00046f}, {0.01207f, 0.01618f, 0.01984f}, {0.91900f, 0.94300f, 0.97200f}},
    {"Merlot", {0.00081f, 0.00000f, 0.00000f}, {0.11632f, 0.25191f, 0.29434f}, {0.97400f, 0.00000f, 0.00000f}},
    {"Budweiser Beder", {0.00029f, 0.00055f, 0.00059f}, {0.01149f, 0.02491f, 0.05779f}, {0.91700f, 0.95600f, 0.98200f}},
    {"Coors Light Beer", {0.00062f, 0.00127f, 0.00000f}, {0.00616f, 0.01398f, 0.03498f}, {0.91800f, 0.96600f, 0.00000f}},
    {"Clorox", {0.02731f, 0.03302f, 0.03695f}, {0.00335f, 0.01489f, 0.02630f}, {0.91200f, 0.90500f, 0.89200f}},
    {"Apple Juice", {0.00257f, 0.00311f, 0.00413f}, {0.01296f, 0.02374f, 0.05218f}, {0.94700f, 0.94900f, 0.94500f}},
    {"Cranberry Juice", {0.00196f, 0.00238f, 0.00301f}, {0.03944f, 0.09422f, 0.12426f}, {0.94700f, 0.95100f, 0.97400f}},
    {"Grape Juice", {0.00138f, 0.00000f, 0.00000f}, {0.10404f, 0.23958f, 0.29325f}, {0.96100f, 0.00000f, 0.00000f}},
    {"Ruby Grapefruit Juice", {0.15496f, 0.15391f, 0.15995f}, {0.08587f, 0.18314f, 0.25262f}, {0.92900f, 0.92900f, 0.93100f}},
    {"White Grapefruit Juice", {0.50499f, 0.52742f, 0.75282f}, {0.01380f, 0.01883f, 0.05678f}, {0.54800f, 0.54500f, 0.56500f}},
    {"Shampoo", {0.00797f, 0.00874f, 0.01127f}, {0.01411f, 0.04569f, 0.06172f}, {0.91000f, 0.90500f, 0.92000f}},
    {"Strawberry Shampoo", {0.00215f, 0.00245f, 0.00253f}, {0.01449f, 0.05796f, 0.07582f}, {0.92700f, 0.93500f, 0.99400f}},
    {"Head & Shoulders Shampoo", {0.26747f, 0.27696f, 0.29574f}, {0.08462f, 0.15688f, 0.20365f}, {0.91100f, 0.89600f, 0.88400f}},
    {"Lemon Tea Powder", {0.74489f, 0.83823f, 1.00158f}, {2.42881f, 4.57573f, 7.21270f}, {0.94600f, 0.94600f, 0.94900f}},
    {"Orange Juice Powder", {0.00193f, 0.00213f, 0.00226f}, {0.00145f, 0.00344f, 0.00786f}, {0.91900f, 0.91800f, 0.92200f}},
    {"Pink Lemonade Powder", {0.00123f, 0.00133f, 0.00131f}, {0.00116f, 0.00237f, 0.00320f}, {0.90200f, 0.90200f, 0.90400f}},
};

/* Case-insensitive equality (Mitsuba lower-cases both names). */
static int medium__same_name(const char *a, const char *b) {
  for (; *a && *b; a++, b++)
    if (tolower((unsigned char)*a) != tolower((unsigned char)*b)) return 0;
  return *a == *b;
}

int medium_material(const char *name, rgb *OUT_sigma_s, rgb *OUT_sigma_a, rgb *OUT_g) {
  for (size_t i = 0; name && i < sizeof medium__presets / sizeof medium__presets[0]; i++) {
    const medium__preset *e = &medium__presets[i];
    if (!medium__same_name(name, e->name)) continue;
    *OUT_sigma_s = rgb_scale(rgb_make(e->sigma_s[0], e->sigma_s[1], e->sigma_s[2]), 100.0);
    *OUT_sigma_a = rgb_scale(rgb_make(e->sigma_a[0], e->sigma_a[1], e->sigma_a[2]), 100.0);
    *OUT_g = rgb_make(e->g[0], e->g[1], e->g[2]);
    return 1;
  }
  return 0;
}

/* A coefficient that must be finite and at least 0 in every channel. */
static lmc_status medium__check(plugin_props *p, const char *name, rgb c) {
  if (c.r >= 0.0 && c.g >= 0.0 && c.b >= 0.0 && isfinite(c.r) && isfinite(c.g) && isfinite(c.b))
    return LMC_OK;
  return props_fail(p, name, "medium %s must be finite and at least 0 (it is %g, %g, %g)", name,
                    c.r, c.g, c.b);
}

lmc_status medium_read(medium *m, plugin_props *p) {
  lmc_status st;
  int has_as = props_has(p, "sigmaA") || props_has(p, "sigmaS");
  int has_ta = props_has(p, "sigmaT") || props_has(p, "albedo");
  int preset = props_has(p, "material");
  if (preset && (has_as || has_ta))
    return props_fail(p, "material", "a medium takes a preset material or coefficients, not both");
  if (has_as && has_ta)
    return props_fail(p, NULL, "a medium takes sigmaA and sigmaS, or sigmaT and albedo, not both");
  const char *name;
  if ((st = props_string(p, "material", "Skin1", &name)) != LMC_OK) return st;
  rgb ss, sa, g;
  if (!medium_material(name, &ss, &sa, &g))
    return props_fail(p, "material", "unknown medium material \"%s\" (Mitsuba's presets: Apple, "
                      "Ketchup, Skimmilk, Wholemilk, Regular Milk, Espresso, ...)", name);
  if (has_as) {
    if ((st = props_rgb(p, "sigmaS", ss, &ss)) != LMC_OK) return st;
    if ((st = props_rgb(p, "sigmaA", sa, &sa)) != LMC_OK) return st;
    if ((st = medium__check(p, "sigmaS", ss)) || (st = medium__check(p, "sigmaA", sa))) return st;
  } else if (has_ta) {
    rgb st_ = rgb_add(ss, sa), alb = rgb_make(ss.r / st_.r, ss.g / st_.g, ss.b / st_.b);
    if ((st = props_rgb(p, "sigmaT", st_, &st_)) != LMC_OK) return st;
    if ((st = props_rgb(p, "albedo", alb, &alb)) != LMC_OK) return st;
    if ((st = medium__check(p, "sigmaT", st_)) != LMC_OK) return st;
    if (!(alb.r >= 0.0 && alb.r <= 1.0 && alb.g >= 0.0 && alb.g <= 1.0 && alb.b >= 0.0 &&
          alb.b <= 1.0))
      return props_fail(p, "albedo", "medium albedo must lie in [0, 1] (it is %g, %g, %g)", alb.r,
                        alb.g, alb.b);
    ss = rgb_mul(alb, st_);
    sa = rgb_make(st_.r - ss.r, st_.g - ss.g, st_.b - ss.b);
  }
  if (props_has(p, "g")) {
    double gv;
    if ((st = props_float(p, "g", 0.0, &gv, NULL)) != LMC_OK) return st;
    g = rgb_gray(gv);
  }
  if (!(g.r > -1.0 && g.r < 1.0 && g.g > -1.0 && g.g < 1.0 && g.b > -1.0 && g.b < 1.0))
    return props_fail(p, "g", "a medium's g must lie in (-1, 1)");
  double scale;
  if ((st = props_float(p, "scale", 1.0, &scale, NULL)) != LMC_OK) return st;
  if (!(scale >= 0.0) || !isfinite(scale))
    return props_fail(p, "scale", "medium scale must be finite and at least 0 (it is %g)", scale);
  /* Mitsuba reduces the scattering by the anisotropy (1 - g), then scales. */
  ss = rgb_make(ss.r * (1.0 - g.r), ss.g * (1.0 - g.g), ss.b * (1.0 - g.b));
  medium_set(m, rgb_scale(sa, scale), rgb_scale(ss, scale));
  return LMC_OK;
}

#define R_DUAL 0
#include "render/real.h"
#include "render/media/medium_generic.h"
#undef R_DUAL
#define R_DUAL 1
#include "render/real.h"
#include "render/media/medium_generic.h"
#undef R_DUAL

int medium_invert_flight(const medium *m, int scattered, double t, const double r[2],
                         double OUT_u[2]) {
  const double st[3] = {m->sigma_t.r, m->sigma_t.g, m->sigma_t.b};
  /* Each channel's share of the density of this outcome (the sampler's
   * choice of a channel is uniform). */
  double share[3], sum = 0.0;
  for (int c = 0; c < 3; c++) {
    double e = st[c] > 0.0 ? exp(-st[c] * t) : (scattered ? 0.0 : 1.0);
    share[c] = scattered ? st[c] * e : e;
    sum += share[c];
  }
  if (!(sum > 0.0) || !(t >= 0.0) || !isfinite(t)) return 0;
  double x = r[0] * sum;
  int c = 0;
  while (c < 2 && !(x < share[c])) x -= share[c++];
  if (!(share[c] > 0.0)) return 0;
  /* u_ch inside the channel's third, at r[0]'s place within its share. */
  double within = fmin(fmax(x / share[c], 0.0), nextafter(1.0, 0.0));
  OUT_u[0] = warp_uniform_in(c / 3.0, (c + 1) / 3.0, within);
  if (scattered) {
    /* u_t = 1 - exp(-sigma_t t) */
    OUT_u[1] = -expm1(-st[c] * t);
  } else {
    /* any u_t whose distance reaches t: [1 - exp(-sigma_t t), 1) */
    double lo = st[c] > 0.0 ? -expm1(-st[c] * t) : 0.0;
    OUT_u[1] = warp_uniform_in(lo, 1.0, r[1]);
  }
  /* Refused where the sampler does not make it back (a u_t at the edge of
   * its interval, rounded to the other side of t). */
  medium_flight f;
  return OUT_u[1] < 1.0 &&
         medium_sample_flight(m, scattered ? INFINITY : t, OUT_u[0], OUT_u[1], &f) &&
         f.scattered == scattered && (!scattered || fabs(f.t - t) <= 1e-9 * (1.0 + t));
}
