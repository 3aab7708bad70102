/*
 * rgb_ad.h: RGB of duals (adrgb), the dual form of vec3.h's rgb, with the
 * operations the textures and BSDFs use. Each computes its values as the
 * rgb operation of the same name does.
 */
#ifndef LMC_RENDER_RGB_AD_H
#define LMC_RENDER_RGB_AD_H

#include "ad/dual.h"
#include "render/vec3.h"

typedef struct adrgb {
  ad r, g, b;
} adrgb;

static inline adrgb adrgb_const(const ad_arena *A, rgb c) {
  return (adrgb){ad_const(A, c.r), ad_const(A, c.g), ad_const(A, c.b)};
}
static inline adrgb adrgb_zero(const ad_arena *A) { return adrgb_const(A, rgb_zero()); }
static inline rgb adrgb_value(adrgb c) { return rgb_make(c.r.v, c.g.v, c.b.v); }
static inline adrgb adrgb_mul(ad_arena *A, adrgb a, adrgb b) {
  return (adrgb){ad_mul(A, a.r, b.r), ad_mul(A, a.g, b.g), ad_mul(A, a.b, b.b)};
}
static inline adrgb adrgb_scale(ad_arena *A, adrgb a, ad s) {
  return (adrgb){ad_mul(A, a.r, s), ad_mul(A, a.g, s), ad_mul(A, a.b, s)};
}
static inline adrgb adrgb_scale_s(ad_arena *A, adrgb a, double s) {
  return (adrgb){ad_mul_s(A, a.r, s), ad_mul_s(A, a.g, s), ad_mul_s(A, a.b, s)};
}
static inline adrgb adrgb_add(ad_arena *A, adrgb a, adrgb b) {
  return (adrgb){ad_add(A, a.r, b.r), ad_add(A, a.g, b.g), ad_add(A, a.b, b.b)};
}
/* Luminance with the weights of rgb_luminance, in its order:
 * 0.212671 r + 0.715160 g + 0.072169 b. */
static inline ad adrgb_luminance(ad_arena *A, adrgb c) {
  ad rg = ad_lincomb(A, 0.212671, c.r, 0.715160, c.g);
  return ad_add(A, rg, ad_mul_s(A, c.b, 0.072169));
}

#endif
