/*
 * texture_generic.h: the texture lookups, written once in render/real.h's
 * vocabulary and compiled twice by texture.c: tex_eval in doubles and
 * tex_eval_ad in duals (bsdf_ad.h), whose derivatives are those of the
 * texture coordinates. Not a header: no include guard.
 *
 * Filters. nearest reads one texel (derivative 0) everywhere; the others
 * read the bilinear interpolation below, and with a footprint (plain
 * lookups only: texture.c's tex__filtered) trilinear or EWA over the MIP map.
 *
 * Derivatives. constant: 0. bitmap: the bilinear interpolation
 *   c = (1 - dy) ((1 - dx) c00 + dx c10) + dy ((1 - dx) c01 + dx c11),
 *   x = frac(u') width - 1/2,  dx = x - floor(x),
 * so dc/du' = width ((1 - dy)(c10 - c00) + dy (c11 - c01)): continuous inside
 * a texel, a kink on texel boundaries (the derivative is the one of the
 * texel containing the point); frac(u') = u' - floor(u') has derivative 1.
 * checkerboard: piecewise constant, derivative 0 (its jumps are left to the
 * MCMC acceptance step, as every discontinuity).
 */

/* (1 - t) c0 + t c1 for one channel, with s = 1 - t given (in duals: one
 * allocation). */
static REAL R_FN(tex__lerp)(R_CTX REAL s, REAL t, double c0, double c1) {
#if R_DUAL
  return ad_lincomb(A, c0, s, c1, t);
#else
  return c0 * s + c1 * t;
#endif
}

/* Coordinate u' brought near [0, 1) by wrap mode w without changing the
 * lookup, so the integer conversion cannot overflow: repeat shifts by
 * whole periods (u' - floor(u') keeps u's derivative), mirror by periods of
 * 2; clamp, zero and one read the same texels for every u' below -1 (or
 * above 2) as at -1 (2), where the texture is constant. */
static REAL R_FN(tex__prewrap)(R_CTX REAL u, tex_wrap w) {
  switch (w) {
  case TEX_WRAP_REPEAT:
    return R_SUB_S(u, floor(R_V(u)));
  case TEX_WRAP_MIRROR:
    return R_SUB_S(u, 2.0 * floor(0.5 * R_V(u)));
  default:
    return R_V(u) < -1.0 ? R_C(-1.0) : R_V(u) > 2.0 ? R_C(2.0) : u;
  }
}

/* The texel cell of (u', v') on img (a level of t), pixel centres at
 * half-integers: its corner (x0, y0) and the fractions (dx, dy) inside it;
 * 0 for non-finite coordinates. */
static int R_FN(tex__cell)(R_CTX const texture *t, const lmc_image *img, REAL u, REAL v,
                           int *OUT_x0, int *OUT_y0, REAL *OUT_dx, REAL *OUT_dy) {
  if (!isfinite(R_V(u)) || !isfinite(R_V(v))) return 0;
  u = R_FN(tex__prewrap)(R_ARG u, t->wrap_u);
  v = R_FN(tex__prewrap)(R_ARG v, t->wrap_v);
  REAL x = R_SUB_S(R_MUL_S(u, (double)img->width), 0.5);
  REAL y = R_SUB_S(R_MUL_S(v, (double)img->height), 0.5);
  double fx = floor(R_V(x)), fy = floor(R_V(y));
  *OUT_x0 = (int)fx, *OUT_y0 = (int)fy;
  *OUT_dx = R_SUB_S(x, fx), *OUT_dy = R_SUB_S(y, fy);
  return 1;
}

/* Bilinear lookup at (u', v') on img (a level of t) under t's wrap modes;
 * pixel centres at half-integers. */
static RRGB R_FN(tex__bilinear)(R_CTX const texture *t, const lmc_image *img, REAL u, REAL v) {
  if (!img || !img->data || img->width <= 0 || img->height <= 0 || img->channels <= 0)
    return RRGB_ZERO();
  int x0, y0;
  REAL dx, dy;
  if (!R_FN(tex__cell)(R_ARG t, img, u, v, &x0, &y0, &dx, &dy)) return RRGB_ZERO();
  REAL sx = R_S_SUB(1.0, dx), sy = R_S_SUB(1.0, dy);
  rgb c00 = tex__texel(t, img, x0, y0), c10 = tex__texel(t, img, x0 + 1, y0);
  rgb c01 = tex__texel(t, img, x0, y0 + 1), c11 = tex__texel(t, img, x0 + 1, y0 + 1);
  /* Interpolate along x in both rows, then along y. */
  RRGB top = RRGB_MAKE(R_FN(tex__lerp)(R_ARG sx, dx, c00.r, c10.r),
                       R_FN(tex__lerp)(R_ARG sx, dx, c00.g, c10.g),
                       R_FN(tex__lerp)(R_ARG sx, dx, c00.b, c10.b));
  RRGB bottom = RRGB_MAKE(R_FN(tex__lerp)(R_ARG sx, dx, c01.r, c11.r),
                          R_FN(tex__lerp)(R_ARG sx, dx, c01.g, c11.g),
                          R_FN(tex__lerp)(R_ARG sx, dx, c01.b, c11.b));
  return RRGB_ADD(RRGB_SCALE(top, sy), RRGB_SCALE(bottom, dy));
}

RRGB R_FN(tex_eval)(R_CTX const texture *t, REAL u, REAL v) {
  switch (t->type) {
  case TEX_CONSTANT:
    return RRGB_CONST(t->value);
  case TEX_BITMAP: {
    REAL tu = R_ADD_S(R_MUL_S(u, t->uscale), t->uoffset);
    REAL tv = R_ADD_S(R_MUL_S(v, t->vscale), t->voffset);
    /* nearest: the texel containing the point, piecewise constant. */
    if (t->filter == TEX_FILTER_NEAREST)
      return RRGB_CONST(tex__nearest(t, t->image, R_V(tu), R_V(tv)));
#if !R_DUAL
    if (t->has_footprint && tex_is_filtered(t)) return tex__filtered(t, tu, tv);
#endif
    return R_FN(tex__bilinear)(R_ARG t, t->image, tu, tv);
  }
  case TEX_CHECKERBOARD:
    return RRGB_CONST(tex__checkerboard(t, R_V(u), R_V(v)));
  }
  return RRGB_ZERO();
}

/* The gradient (d/du, d/dv) of the luminance of the texture at (u, v), as
 * Mitsuba's bump map reads its displacement: for a bitmap the derivative of
 * the bilinear interpolation above (Mitsuba's evalGradientBilinear at level
 * 0, times uscale and vscale); constant and checkerboard: 0 (Mitsuba's
 * finite difference of a piecewise constant). */
void R_FN(tex_lum_gradient)(R_CTX const texture *t, REAL u, REAL v, REAL *OUT_du, REAL *OUT_dv) {
  *OUT_du = *OUT_dv = R_C(0.0);
  const lmc_image *img = t->image;
  if (t->type != TEX_BITMAP || t->filter == TEX_FILTER_NEAREST || !img || !img->data ||
      img->width <= 0 || img->height <= 0)
    return;
  /* The texel cell and fractions of tex__bilinear. */
  int x0, y0;
  REAL dx, dy;
  if (!R_FN(tex__cell)(R_ARG t, img, R_ADD_S(R_MUL_S(u, t->uscale), t->uoffset),
                       R_ADD_S(R_MUL_S(v, t->vscale), t->voffset), &x0, &y0, &dx, &dy))
    return;
  double l00 = rgb_luminance(tex__texel(t, img, x0, y0));
  double l10 = rgb_luminance(tex__texel(t, img, x0 + 1, y0));
  double l01 = rgb_luminance(tex__texel(t, img, x0, y0 + 1));
  double l11 = rgb_luminance(tex__texel(t, img, x0 + 1, y0 + 1));
  /* dl/dx = (1 - dy)(l10 - l00) + dy (l11 - l01), dl/dy likewise; then
   * dx/du = width uscale, dy/dv = height vscale. */
  REAL gx = R_ADD_S(R_MUL_S(dy, (l11 - l01) - (l10 - l00)), l10 - l00);
  REAL gy = R_ADD_S(R_MUL_S(dx, (l11 - l10) - (l01 - l00)), l01 - l00);
  *OUT_du = R_MUL_S(gx, img->width * t->uscale);
  *OUT_dv = R_MUL_S(gy, img->height * t->vscale);
}

