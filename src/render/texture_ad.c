/*
 * texture_ad.c: tex_eval in dual arithmetic (bsdf_ad.h), for the gradient
 * of the path contribution with respect to the texture coordinates.
 *
 * The lookups are those of texture.c (read its opening comment): the uv
 * transform (u', v') = (u uscale + uoffset, v vscale + voffset), then
 *   constant      the value, derivative 0;
 *   bitmap        bilinear interpolation on the full-resolution image with
 *                 repeat wrapping and pixel centres at half-integers,
 *                   x = frac(u') width - 1/2,  dx = x - floor(x),
 *                   c = (1 - dy) ((1 - dx) c00 + dx c10) + dy ((1 - dx) c01 + dx c11),
 *                 so dc/du' = width ((1 - dy)(c10 - c00) + dy (c11 - c01)):
 *                 continuous inside a texel, a kink on texel boundaries
 *                 (the derivative is the one of the texel containing the point);
 *   checkerboard  piecewise constant: derivative 0 (its jumps are left to
 *                 the MCMC acceptance step, as every discontinuity).
 * frac(u') = u' - floor(u') has derivative 1 (floor is piecewise constant).
 */
#include <math.h>
#include <stddef.h>

#include "render/bsdf_ad.h"

/* One texel as RGB, wrapped (as tex__texel in texture.c). */
static rgb tex__ad_texel(const lmc_image *img, int x, int y) {
  x %= img->width;
  if (x < 0) x += img->width;
  y %= img->height;
  if (y < 0) y += img->height;
  const float *p = img->data + ((size_t)y * (size_t)img->width + (size_t)x) * (size_t)img->channels;
  if (img->channels >= 3) return rgb_make(p[0], p[1], p[2]);
  return rgb_gray(p[0]);
}

/* (1 - t) c0 + t c1 for one channel, with s = 1 - t given: one allocation. */
static ad tex__ad_lerp_s(ad_arena *A, ad s, ad t, double c0, double c1) {
  return ad_lincomb(A, c0, s, c1, t);
}

/* Bilinear lookup at (u', v'), the dual of tex__bilinear. */
static adrgb tex__ad_bilinear(ad_arena *A, const lmc_image *img, ad u, ad v) {
  if (!img || !img->data || img->width <= 0 || img->height <= 0 || img->channels <= 0)
    return adrgb_const(A, rgb_zero());
  if (!isfinite(u.v) || !isfinite(v.v)) return adrgb_const(A, rgb_zero());
  /* Bring the coordinates near [0, 1): u - floor(u) keeps the tangent of u. */
  u = ad_sub_s(A, u, floor(u.v));
  v = ad_sub_s(A, v, floor(v.v));
  /* Texel coordinates with centres at half-integers. */
  ad x = ad_sub_s(A, ad_mul_s(A, u, (double)img->width), 0.5);
  ad y = ad_sub_s(A, ad_mul_s(A, v, (double)img->height), 0.5);
  double fx = floor(x.v), fy = floor(y.v);
  int x0 = (int)fx, y0 = (int)fy;
  ad dx = ad_sub_s(A, x, fx), dy = ad_sub_s(A, y, fy);
  ad sx = ad_s_sub(A, 1.0, dx), sy = ad_s_sub(A, 1.0, dy);
  rgb c00 = tex__ad_texel(img, x0, y0), c10 = tex__ad_texel(img, x0 + 1, y0);
  rgb c01 = tex__ad_texel(img, x0, y0 + 1), c11 = tex__ad_texel(img, x0 + 1, y0 + 1);
  /* Interpolate along x in both rows, then along y. */
  adrgb top = {tex__ad_lerp_s(A, sx, dx, c00.r, c10.r), tex__ad_lerp_s(A, sx, dx, c00.g, c10.g),
               tex__ad_lerp_s(A, sx, dx, c00.b, c10.b)};
  adrgb bot = {tex__ad_lerp_s(A, sx, dx, c01.r, c11.r), tex__ad_lerp_s(A, sx, dx, c01.g, c11.g),
               tex__ad_lerp_s(A, sx, dx, c01.b, c11.b)};
  return adrgb_add(A, adrgb_scale(A, top, sy), adrgb_scale(A, bot, dy));
}

adrgb tex_eval_ad(ad_arena *A, const texture *t, ad u, ad v) {
  switch (t->type) {
  case TEX_CONSTANT:
    return adrgb_const(A, t->value);
  case TEX_BITMAP: {
    ad su = ad_add_s(A, ad_mul_s(A, u, t->uscale), t->uoffset);
    ad sv = ad_add_s(A, ad_mul_s(A, v, t->vscale), t->voffset);
    return tex__ad_bilinear(A, t->image, su, sv);
  }
  case TEX_CHECKERBOARD:
    /* Piecewise constant: the plain lookup, with zero derivative. */
    return adrgb_const(A, tex_eval(t, u.v, v.v));
  }
  return adrgb_const(A, rgb_zero());
}
