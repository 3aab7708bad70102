/*
 * texture.c: the textures of Mitsuba 0.6 that BSDF parameters take:
 * constant, bitmap and checkerboard.
 *
 * Texture coordinates. Every 2D texture first maps the surface's (u, v) to
 *   (u', v') = (u * uscale + uoffset, v * vscale + voffset)
 * as Mitsuba's Texture2D does, then looks up (u', v').
 *
 * Bitmap. Bilinear interpolation on the full-resolution image with the
 * "repeat" boundary condition, as Mitsuba's MIPMap::evalBilinear at level 0
 * (the lookup Mitsuba performs when a path vertex has no ray
 * differentials). Pixel centres sit at half-integers:
 *   x = u' * width - 1/2,  y = v' * height - 1/2,
 * and the four texels floor(x), floor(x) + 1 (and the same in y) are
 * wrapped modulo the image size. Mitsuba's bitmap texture does NOT flip v:
 * v' = 0 is the top row of the image file (row 0 of lmc_image, which is
 * stored top row first). Any v flip of a mesh format (e.g. OBJ's bottom-left
 * texture origin) is the mesh reader's business, not the texture's.
 *
 * Checkerboard (Mitsuba 0.6 textures/checkerboard.cpp): with
 *   x = trunc(2 u') mod 2,  y = trunc(2 v') mod 2
 * (truncation toward zero, then the non-negative remainder), the result is
 * color0 when x == y and color1 otherwise. Squares are therefore 1/2 wide
 * in (u', v'), and the square around zero is twice as wide because of the
 * truncation; both are Mitsuba's behaviour. Defaults: color0 = 0.4,
 * color1 = 0.2. Its mean is the average of the two colours (Mitsuba's
 * getAverage).
 *
 * The lookups are written once (texture_generic.h) and compiled here twice,
 * in doubles and in duals (render/real.h).
 *
 * Lookups are pure and thread safe; the bitmap mean is cached in the texture
 * value by tex_bitmap / tex_update_mean (the scene is immutable afterwards).
 */
#include "render/bsdf/texture.h"
#include "render/bsdf/bsdf_ad.h"

#include <math.h>
#include <stddef.h>

/* Non-negative remainder of a modulo b (b > 0). */
static int tex__mod(int a, int b) {
  if (a >= 0 && a < b) return a; /* the usual case, without a division */
  int r = a % b;
  return r < 0 ? r + b : r;
}

/* One texel of the image as RGB (1 channel: grey; 2: grey + alpha; 3 or 4: RGB(A)). */
static rgb tex__texel(const lmc_image *img, int x, int y) {
  x = tex__mod(x, img->width);
  y = tex__mod(y, img->height);
  const float *p = img->data + ((size_t)y * (size_t)img->width + (size_t)x) * (size_t)img->channels;
  if (img->channels >= 3) return rgb_make(p[0], p[1], p[2]);
  return rgb_gray(p[0]);
}

/* Mean of all pixels (in double precision). */
static rgb tex__image_mean(const lmc_image *img) {
  if (!img || !img->data || img->width <= 0 || img->height <= 0 || img->channels <= 0)
    return rgb_zero();
  double r = 0.0, g = 0.0, b = 0.0;
  for (int y = 0; y < img->height; y++)
    for (int x = 0; x < img->width; x++) {
      rgb c = tex__texel(img, x, y);
      r += c.r;
      g += c.g;
      b += c.b;
    }
  double n = (double)img->width * (double)img->height;
  return rgb_make(r / n, g / n, b / n);
}

/* Checkerboard parity with truncation toward zero (Mitsuba's (int) cast). */
static int tex__check_parity(double s) {
  double t = trunc(2.0 * s);
  /* Keep the conversion in range; parity of huge values is meaningless anyway. */
  t = fmod(t, 2.0);
  int i = (int)t;
  return tex__mod(i, 2);
}

/* The checkerboard's colour at (u, v) (before the uv transform). */
static rgb tex__checkerboard(const texture *t, double u, double v) {
  double su = u * t->uscale + t->uoffset, sv = v * t->vscale + t->voffset;
  if (!isfinite(su) || !isfinite(sv)) return t->color1;
  return tex__check_parity(su) == tex__check_parity(sv) ? t->color0 : t->color1;
}

/* The lookups in doubles (tex_eval), then in duals (tex_eval_ad, bsdf_ad.h),
 * from one source. */
#define R_DUAL 0
#include "render/real.h"
#include "render/bsdf/texture_generic.h"
#undef R_DUAL
#define R_DUAL 1
#include "render/real.h"
#include "render/bsdf/texture_generic.h"

texture tex_bitmap(const lmc_image *img) {
  texture t = {0};
  t.type = TEX_BITMAP;
  t.image = img;
  t.uscale = t.vscale = 1.0;
  tex_update_mean(&t);
  return t;
}

texture tex_checkerboard(rgb color0, rgb color1) {
  texture t = {0};
  t.type = TEX_CHECKERBOARD;
  t.color0 = color0;
  t.color1 = color1;
  t.uscale = t.vscale = 1.0;
  return t;
}

void tex_update_mean(texture *t) {
  if (!t || t->type != TEX_BITMAP) return;
  t->mean = tex__image_mean(t->image);
  t->mean_valid = 1;
}

rgb tex_mean(const texture *t) {
  switch (t->type) {
  case TEX_CONSTANT:
    return t->value;
  case TEX_BITMAP:
    return t->mean_valid ? t->mean : tex__image_mean(t->image);
  case TEX_CHECKERBOARD:
    return rgb_scale(rgb_add(t->color0, t->color1), 0.5);
  }
  return rgb_zero();
}

int tex_is_constant(const texture *t) { return t->type == TEX_CONSTANT; }
