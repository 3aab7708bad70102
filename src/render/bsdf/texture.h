/*
 * texture.h: the textures a BSDF parameter can take: a constant, a bitmap
 * (PNG, JPEG or EXR, bilinear, repeating, Mitsuba's uvscale/uoffset/voffset)
 * or a checkerboard (Mitsuba's: color0 where floor(u*uscale)+floor(v*vscale)
 * is even... see texture.c for the exact rule).
 *
 * Textures are small values stored inside the BSDF; a bitmap borrows its
 * image from the scene, which owns it. Lookups are pure and thread safe.
 */
#ifndef LMC_RENDER_TEXTURE_H
#define LMC_RENDER_TEXTURE_H

#include "render/image.h"
#include "render/vec3.h"

typedef enum tex_type { TEX_CONSTANT = 0, TEX_BITMAP, TEX_CHECKERBOARD } tex_type;

typedef struct texture {
  tex_type type;
  rgb value;                   /* TEX_CONSTANT */
  const lmc_image *image;      /* TEX_BITMAP: borrowed from the scene, 3 channels */
  double uscale, vscale;       /* uv scale (bitmap and checkerboard), default 1 */
  double uoffset, voffset;     /* uv offset, default 0 */
  rgb color0, color1;          /* TEX_CHECKERBOARD */
  rgb mean;                    /* TEX_BITMAP: cached image mean, valid when mean_valid */
  int mean_valid;              /* set by tex_bitmap / tex_update_mean; else tex_mean computes it */
} texture;

static inline texture tex_constant(rgb v) {
  texture t = {0};
  t.type = TEX_CONSTANT;
  t.value = v;
  t.uscale = t.vscale = 1.0;
  return t;
}

/* A bitmap texture with Mitsuba's defaults (scale 1, offset 0) whose image
 * mean is cached (sampling weights of phong and plastic use it). */
texture tex_bitmap(const lmc_image *img);
/* A checkerboard with Mitsuba's defaults (color0 0.4, color1 0.2). */
texture tex_checkerboard(rgb color0, rgb color1);
/* Recomputes the cached mean of a bitmap texture (after t->image changed). */
void tex_update_mean(texture *t);

/* Value at texture coordinates (u, v). */
rgb tex_eval(const texture *t, double u, double v);
/* The gradient (d/du, d/dv) of the texture's luminance at (u, v): a bump
 * map's slope (texture.c); 0 for constant and checkerboard textures. */
void tex_lum_gradient(const texture *t, double u, double v, double *OUT_du, double *OUT_dv);
/* The mean value over the texture (used for sampling weights, e.g. plastic). */
rgb tex_mean(const texture *t);
int tex_is_constant(const texture *t);

#endif
