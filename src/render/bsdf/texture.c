/*
 * texture.c: the textures of Mitsuba 0.6 that BSDF parameters take:
 * constant, bitmap and checkerboard.
 *
 * Texture coordinates. Every 2D texture first maps the surface's (u, v) to
 *   (u', v') = (u * uscale + uoffset, v * vscale + voffset)
 * as Mitsuba's Texture2D does, then looks up (u', v').
 *
 * Bitmap. Bilinear interpolation on the full-resolution image, as Mitsuba's
 * MIPMap::evalBilinear at level 0 (the lookup Mitsuba performs when a path
 * vertex has no ray differentials). Pixel centres sit at half-integers:
 *   x = u' * width - 1/2,  y = v' * height - 1/2,
 * and the four texels floor(x), floor(x) + 1 (and the same in y) are
 * brought into the image by the wrap modes (Mitsuba's boundary conditions:
 * repeat, mirror, clamp, or zero and one outside). The filter `nearest`
 * reads the texel floor(u' width), floor(v' height) instead (Mitsuba's box
 * lookup).
 *
 * MIP map (filters trilinear and ewa). Level k + 1 has (w + 1) / 2 by
 * (h + 1) / 2 texels of level k (Mitsuba's sizes), each the exact area
 * average of the texels of level k it covers (Mitsuba resamples with a
 * Lanczos filter; the box keeps every level's mean that of the image). A
 * lookup with a footprint (tex_set_footprint: the derivatives of (u, v)
 * along the film) follows Mitsuba's MIPMap::eval: the footprint's two
 * steps span an ellipse in texels; trilinear blends the bilinear lookups of
 * the levels floor(l) and floor(l) + 1, l = log2(major radius); EWA
 * (Heckbert 1989; Greene and Heckbert 1986) bounds the ellipse's
 * eccentricity by max_aniso and averages the texels inside it with
 * Gaussian weights exp(-2 q) - exp(-2), on the two levels around
 * log2(minor radius), blended. Footprints come only with the path tracer's
 * camera rays (render/integrators/render.c), as Mitsuba's ray
 * differentials; every other lookup, and every dual one, reads level 0. Mitsuba's bitmap texture does NOT flip v:
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

/* Pixel (x, y) of img, in range, as RGB (1 channel: grey; 2: grey + alpha;
 * 3 or 4: RGB(A)). */
static rgb tex__pixel(const lmc_image *img, int x, int y) {
  const float *p = img->data + ((size_t)y * (size_t)img->width + (size_t)x) * (size_t)img->channels;
  if (img->channels >= 3) return rgb_make(p[0], p[1], p[2]);
  return rgb_gray(p[0]);
}

/* Brings texel index x into [0, n) by wrap mode w; 0 when w gives a
 * constant there (*OUT_const: 0 or 1 for zero and one). */
static int tex__wrap_index(int *x, int n, tex_wrap w, double *OUT_const) {
  if (*x >= 0 && *x < n) return 1;
  switch (w) {
  case TEX_WRAP_CLAMP:
    *x = *x < 0 ? 0 : n - 1;
    return 1;
  case TEX_WRAP_MIRROR:
    *x = tex__mod(*x, 2 * n);
    if (*x >= n) *x = 2 * n - *x - 1;
    return 1;
  case TEX_WRAP_ZERO:
    *OUT_const = 0.0;
    return 0;
  case TEX_WRAP_ONE:
    *OUT_const = 1.0;
    return 0;
  case TEX_WRAP_REPEAT:
    break;
  }
  *x = tex__mod(*x, n);
  return 1;
}

/* Texel (x, y) of img (a level of t) under t's wrap modes (Mitsuba's
 * boundary conditions: the u rule first, then the v rule). */
static rgb tex__texel(const texture *t, const lmc_image *img, int x, int y) {
  double c = 0.0;
  if (!tex__wrap_index(&x, img->width, t->wrap_u, &c)) return rgb_gray(c);
  if (!tex__wrap_index(&y, img->height, t->wrap_v, &c)) return rgb_gray(c);
  return tex__pixel(img, x, y);
}

/* Mean of all pixels (in double precision). */
static rgb tex__image_mean(const lmc_image *img) {
  if (!img || !img->data || img->width <= 0 || img->height <= 0 || img->channels <= 0)
    return rgb_zero();
  double r = 0.0, g = 0.0, b = 0.0;
  for (int y = 0; y < img->height; y++)
    for (int x = 0; x < img->width; x++) {
      rgb c = tex__pixel(img, x, y);
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

/* The box and the filtered lookups at (u', v') (defined after the generic
 * bodies, whose plain tex__prewrap and tex__bilinear they use). */
static rgb tex__nearest(const texture *t, const lmc_image *img, double u, double v);
static rgb tex__filtered(const texture *t, double u, double v);

/* The lookups in doubles (tex_eval), then in duals (tex_eval_ad, bsdf_ad.h),
 * from one source. */
#define R_DUAL 0
#include "render/real.h"
#include "render/bsdf/texture_generic.h"
#undef R_DUAL
#define R_DUAL 1
#include "render/real.h"
#include "render/bsdf/texture_generic.h"

/* The texel of img (a level of t) containing (u', v'): Mitsuba's box
 * lookup; black for non-finite coordinates. */
static rgb tex__nearest(const texture *t, const lmc_image *img, double u, double v) {
  if (!isfinite(u) || !isfinite(v) || !img || !img->data) return rgb_zero();
  u = tex__prewrap(u, t->wrap_u);
  v = tex__prewrap(v, t->wrap_v);
  return tex__texel(t, img, (int)floor(u * img->width), (int)floor(v * img->height));
}

/* Bilinear lookup on MIP level `level` of t; past the last level, the
 * last level's (1 x 1) texel. */
static rgb tex__level(const texture *t, int level, double u, double v) {
  if (level >= t->levels) return tex__nearest(t, &t->image[t->levels - 1], u, v);
  return tex__bilinear(t, &t->image[level], u, v);
}

/* The elliptically weighted average on MIP level `level` of the ellipse
 * A x^2 + B x y + C y^2 < 1 around (u', v') (coefficients in level-0
 * texels, normalised): each texel weighted by the truncated Gaussian
 * exp(-2 q) - exp(-2) of its q (Mitsuba's weights, without its table);
 * bilinear when no texel centre falls inside. */
static rgb tex__ewa(const texture *t, int level, double u, double v, double A, double B,
                    double C) {
  if (level >= t->levels) return tex__nearest(t, &t->image[t->levels - 1], u, v);
  const lmc_image *img = &t->image[level];
  if (!isfinite(u) || !isfinite(v)) return rgb_zero();
  u = tex__prewrap(u, t->wrap_u);
  v = tex__prewrap(v, t->wrap_v);
  /* To this level's texels: the ellipse shrinks with the level's size. */
  double rx = (double)img->width / t->image[0].width, ry = (double)img->height / t->image[0].height;
  A /= rx * rx, B /= rx * ry, C /= ry * ry;
  double x = u * img->width - 0.5, y = v * img->height - 0.5;
  /* The ellipse's bounding box. */
  double inv_det = 1.0 / (4.0 * A * C - B * B);
  double ex = 2.0 * sqrt(C * inv_det), ey = 2.0 * sqrt(A * inv_det);
  int x0 = (int)ceil(x - ex), x1 = (int)floor(x + ex);
  int y0 = (int)ceil(y - ey), y1 = (int)floor(y + ey);
  double sr = 0.0, sg = 0.0, sb = 0.0, wsum = 0.0, tail = exp(-2.0);
  for (int ty = y0; ty <= y1; ty++) {
    double dy = ty - y;
    for (int tx = x0; tx <= x1; tx++) {
      double dx = tx - x, q = A * dx * dx + B * dx * dy + C * dy * dy;
      if (!(q < 1.0)) continue;
      double w = exp(-2.0 * q) - tail;
      rgb c = tex__texel(t, img, tx, ty);
      sr += w * c.r, sg += w * c.g, sb += w * c.b, wsum += w;
    }
  }
  if (!(wsum > 0.0)) return tex__bilinear(t, img, u, v);
  return rgb_make(sr / wsum, sg / wsum, sb / wsum);
}

/* Mitsuba's MIPMap::eval with the footprint's Jacobian: the footprint in
 * level-0 texels is the ellipse of the two image-space steps; trilinear
 * (or EWA on a degenerate ellipse) blends the bilinear lookups of the two
 * levels around log2 of its major radius, bilinear on level 0 below one
 * texel; EWA widens an ellipse more eccentric than max_aniso, then blends
 * the weighted averages of the two levels around log2 of its minor radius. */
static rgb tex__filtered(const texture *t, double u, double v) {
  const tex_footprint *fp = &t->footprint;
  double w = t->image[0].width, h = t->image[0].height;
  double du0 = fp->dudx * t->uscale * w, dv0 = fp->dvdx * t->vscale * h;
  double du1 = fp->dudy * t->uscale * w, dv1 = fp->dvdy * t->vscale * h;
  /* The ellipse A x^2 + B x y + C y^2 = F, and its radii. */
  double A = dv0 * dv0 + dv1 * dv1, B = -2.0 * (du0 * dv0 + du1 * dv1);
  double C = du0 * du0 + du1 * du1, F = A * C - 0.25 * B * B;
  double root = hypot(A - C, B), a1 = 0.5 * (A + C - root), c1 = 0.5 * (A + C + root);
  double major = a1 != 0.0 ? sqrt(F / a1) : 0.0, minor = c1 != 0.0 ? sqrt(F / c1) : 0.0;
  if (t->filter == TEX_FILTER_TRILINEAR || !(minor > 0.0) || !(major > 0.0) || F < 0.0) {
    double level = log2(fmax(major, 1e-7));
    if (!(level >= 0.0)) return tex__bilinear(t, &t->image[0], u, v);
    int il = (int)floor(level);
    double a = level - il;
    return rgb_add(rgb_scale(tex__level(t, il, u, v), 1.0 - a),
                   rgb_scale(tex__level(t, il + 1, u, v), a));
  }
  if (minor * t->max_aniso < major) {
    /* Widen the minor radius; the ellipse keeps its orientation. */
    minor = major / t->max_aniso;
    double theta = 0.5 * atan(B / (A - C)), st = sin(theta), ct = cos(theta);
    double a2 = major * major, b2 = minor * minor;
    A = a2 * ct * ct + b2 * st * st;
    B = (a2 - b2) * 2.0 * st * ct;
    C = a2 * st * st + b2 * ct * ct;
    F = a2 * b2;
  }
  A /= F, B /= F, C /= F;
  double level = fmax(0.0, log2(minor));
  int il = (int)level;
  double a = level - il;
  if (major < 1.0 || !(A > 0.0 && C > 0.0)) return tex__level(t, il, u, v);
  return rgb_add(rgb_scale(tex__ewa(t, il, u, v, A, B, C), 1.0 - a),
                 rgb_scale(tex__ewa(t, il + 1, u, v, A, B, C), a));
}

texture tex_bitmap(const lmc_image *img) {
  texture t = {0};
  t.type = TEX_BITMAP;
  t.image = img;
  t.levels = 1;
  t.filter = TEX_FILTER_EWA;
  t.max_aniso = 20.0;
  t.uscale = t.vscale = 1.0;
  tex_update_mean(&t);
  return t;
}

int tex_mip_levels(int width, int height) {
  int n = 1;
  while (width > 1 || height > 1) {
    width = width > 1 ? (width + 1) / 2 : 1;
    height = height > 1 ? (height + 1) / 2 : 1;
    n++;
  }
  return n;
}

/* One row of n source values into m (m = (n + 1) / 2, or 1): output i is
 * the mean of the source over [i r, (i + 1) r), r = n / m, each source
 * value weighted by its overlap. */
static void tex__halve_line(const float *src, size_t src_stride, int n, float *dst,
                            size_t dst_stride, int m) {
  double r = (double)n / m;
  for (int i = 0; i < m; i++) {
    double a = i * r, b = (i + 1) * r, sum = 0.0;
    for (int j = (int)floor(a); j < n && j < b; j++) {
      double w = fmin(b, j + 1.0) - fmax(a, (double)j);
      if (w > 0.0) sum += w * src[(size_t)j * src_stride];
    }
    dst[(size_t)i * dst_stride] = (float)(sum / r);
  }
}

lmc_status tex_mip_halve(const lmc_image *src, lmc_image *OUT, lmc_error *err) {
  int w = src->width > 1 ? (src->width + 1) / 2 : 1;
  int h = src->height > 1 ? (src->height + 1) / 2 : 1;
  int c = src->channels;
  lmc_image tmp = {0};
  lmc_status st = image_init(&tmp, w, src->height, c, err);
  if (st == LMC_OK) st = image_init(OUT, w, h, c, err);
  if (st != LMC_OK) {
    image_free(&tmp);
    return st;
  }
  /* Along x, then along y: the box is separable. */
  for (int y = 0; y < src->height; y++)
    for (int k = 0; k < c; k++)
      tex__halve_line(src->data + (size_t)y * src->width * c + k, (size_t)c, src->width,
                      tmp.data + (size_t)y * w * c + k, (size_t)c, w);
  for (int x = 0; x < w; x++)
    for (int k = 0; k < c; k++)
      tex__halve_line(tmp.data + (size_t)x * c + k, (size_t)w * c, src->height,
                      OUT->data + (size_t)x * c + k, (size_t)w * c, h);
  image_free(&tmp);
  return LMC_OK;
}

void tex_set_footprint(texture *t, const tex_footprint *fp) {
  t->has_footprint = fp != NULL;
  if (fp) t->footprint = *fp;
}

int tex_is_filtered(const texture *t) {
  return t->type == TEX_BITMAP && t->levels > 1 && tex_filter_uses_mip(t->filter);
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
