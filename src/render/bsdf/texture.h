/*
 * texture.h: the textures a BSDF parameter can take: a constant, a bitmap
 * (PNG, JPEG or EXR; Mitsuba's filters nearest, bilinear, trilinear and EWA
 * over a MIP map, its wrap modes and uvscale/uoffset/voffset) or a
 * checkerboard (Mitsuba's: color0 where floor(u*uscale)+floor(v*vscale) is
 * even... see texture.c for the exact rule).
 *
 * Textures are small values stored inside the BSDF; a bitmap borrows its
 * image (and its MIP levels) from the scene, which owns them. Lookups are
 * pure and thread safe. A lookup is filtered over a footprint only when the
 * texture value carries one (tex_set_footprint: the path tracer's camera
 * hits, on a copy of the BSDF); otherwise it reads the full-resolution
 * level, as Mitsuba does at vertices without ray differentials.
 */
#ifndef LMC_RENDER_TEXTURE_H
#define LMC_RENDER_TEXTURE_H

#include "render/image.h"
#include "render/vec3.h"

typedef enum tex_type { TEX_CONSTANT = 0, TEX_BITMAP, TEX_CHECKERBOARD } tex_type;

/* A bitmap's filter (Mitsuba's filterType; its default is EWA). */
typedef enum tex_filter {
  TEX_FILTER_EWA = 0,   /* elliptically weighted average over the MIP map (Heckbert 1989) */
  TEX_FILTER_TRILINEAR, /* bilinear on the two MIP levels around the footprint, blended */
  TEX_FILTER_BILINEAR,  /* bilinear on the full-resolution image */
  TEX_FILTER_NEAREST    /* the texel containing the point */
} tex_filter;

/* What a bitmap reads outside [0, 1] (Mitsuba's wrapMode; default repeat). */
typedef enum tex_wrap {
  TEX_WRAP_REPEAT = 0, /* periodic */
  TEX_WRAP_MIRROR,     /* periodic, every other copy mirrored */
  TEX_WRAP_CLAMP,      /* the nearest edge texel */
  TEX_WRAP_ZERO,       /* black outside */
  TEX_WRAP_ONE         /* white outside */
} tex_wrap;

/* A lookup's footprint: the derivatives of the texture coordinates (u, v)
 * along the film's x and y, per step of the ray differential. */
typedef struct tex_footprint {
  double dudx, dvdx; /* along x */
  double dudy, dvdy; /* along y */
} tex_footprint;

typedef struct texture {
  tex_type type;
  rgb value;                   /* TEX_CONSTANT */
  const lmc_image *image;      /* TEX_BITMAP: borrowed from the scene, 3 channels; its MIP
                                  levels are image[1 .. levels - 1], each half the size */
  int levels;                  /* TEX_BITMAP: MIP levels (1: the image alone) */
  tex_filter filter;           /* TEX_BITMAP: the filter over a footprint */
  tex_wrap wrap_u, wrap_v;     /* TEX_BITMAP: the wrap modes */
  double max_aniso;            /* TEX_BITMAP, EWA: the most eccentric ellipse (Mitsuba: 20) */
  int has_footprint;           /* the lookups are filtered over `footprint` */
  tex_footprint footprint;     /* see has_footprint */
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

/* A bitmap texture with Mitsuba's defaults (scale 1, offset 0, repeat,
 * EWA, maximum anisotropy 20) without MIP levels, whose image mean is
 * cached (sampling weights of phong and plastic use it). */
texture tex_bitmap(const lmc_image *img);
/* The number of MIP levels of a width x height image, down to 1 x 1: each
 * level (w + 1) / 2 by (h + 1) / 2 texels (Mitsuba's sizes). */
int tex_mip_levels(int width, int height);
/* The MIP level below src: each texel the area average of the texels of
 * src it covers (exact for odd sizes: a level's texels partition the
 * image). OUT is allocated. */
lmc_status tex_mip_halve(const lmc_image *src, lmc_image *OUT, lmc_error *err);
/* Does the filter read MIP levels (trilinear, EWA)? */
static inline int tex_filter_uses_mip(tex_filter f) {
  return f == TEX_FILTER_EWA || f == TEX_FILTER_TRILINEAR;
}
/* Sets (fp != NULL) or clears the footprint of t's lookups. */
void tex_set_footprint(texture *t, const tex_footprint *fp);
/* Does a footprint change t's lookups (a bitmap with MIP levels)? */
int tex_is_filtered(const texture *t);
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
