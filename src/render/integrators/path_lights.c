/*
 * path_lights.c: the emitters in duals for the path evaluators
 * (path_internal.h): light.c's direct-sampling routines and densities,
 * the area lights' sampled points, the spot falloff and the environment
 * map's parametrisation, with their derivatives. The formulas are
 * light.c's (lights/light.h says which paper each follows).
 */
#include <math.h>
#include <string.h>

#include "render/integrators/path_internal.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ---------------------------------------------------------------------------
 * Lights in duals (light.c's formulas).
 */


/* Pixel of the envmap containing (u, v) (light.c's rule: u wraps, v clamps). */
rgb path__env_eval_uv(const light *l, double u, double v) {
  const lmc_image *img = &l->image;
  double fx = floor(u * img->width), fy = floor(v * img->height);
  int ix = isfinite(fx) ? (int)fmod(fx, (double)img->width) : 0;
  if (ix < 0) ix += img->width;
  int iy = fy < 0.0 || !isfinite(fy) ? 0 : (fy > img->height - 1 ? img->height - 1 : (int)fy);
  const float *p =
      img->data + ((size_t)iy * (size_t)img->width + (size_t)ix) * (size_t)img->channels;
  rgb c = img->channels >= 3 ? rgb_make(p[0], p[1], p[2]) : rgb_gray(p[0]);
  return rgb_scale(c, l->scale);
}

/* sin(theta) of world direction w in the envmap's frame, as a dual. */
ad path__env_sin_theta(ad_arena *A, const light *l, adv3 w) {
  adv3 d = adv3_normalize(A, path__mat_vec(A, (const double (*)[4])l->to_world.inv, w));
  ad y = ad_clamp(A, d.y, -1.0, 1.0);
  return ad_safe_sqrt(A, ad_s_sub(A, 1.0, ad_sqr(A, y)));
}

/* light_pdf_li for direction w leaving ref towards an infinite light or an
 * area light point p with normal n (value from light.c, tangent here). */
ad path__pdf_li(path__ctx *c, const light *l, adv3 ref, adv3 w, adv3 p, vec3 n) {
  ad_arena *A = c->A;
  switch (l->type) {
  case LIGHT_AREA: {
    adv3 d = adv3_sub(A, p, ref);
    ad dist2 = adv3_len2(A, d);
    ad cos_l = ad_neg(A, path__dot_c(A, n, w));
    if (!(cos_l.v > 0.0) || !(dist2.v > 0.0) || !(l->area > 0.0)) return ad_const(A, 0.0);
    ad r = ad_div(A, dist2, ad_mul_s(A, cos_l, l->area));
    r.v = dist2.v / (cos_l.v * l->area);
    return r;
  }
  case LIGHT_CONSTANT:
    return ad_const(A, 1.0 / (4.0 * M_PI));
  case LIGHT_ENVMAP: {
    vec3 rv = path__val(ref);
    double pdf = light_pdf_li(l, c->sc, rv, path__val(w), rv, rv);
    if (!(pdf > 0.0)) return ad_const(A, pdf);
    /* Inside one pixel pdf = C / sin(theta). */
    ad st = path__env_sin_theta(A, l, w);
    ad r = ad_mul_s(A, ad_s_div(A, st.v, st), pdf);
    r.v = pdf;
    return r;
  }
  default:
    return ad_const(A, 0.0);
  }
}

/* Mitsuba's spot falloff (light.c) of the dual cosine to the axis. */
ad path__spot_falloff(ad_arena *A, const light *l, ad cos_theta) {
  if (cos_theta.v <= l->cos_cutoff) return ad_const(A, 0.0);
  if (cos_theta.v >= l->cos_beam) return ad_const(A, 1.0);
  double width = l->cutoff - l->beam_width;
  if (!(width > 0.0)) return ad_const(A, 1.0);
  ad theta = ad_acos(A, ad_clamp(A, cos_theta, -1.0, 1.0));
  ad f = ad_div_s(A, ad_s_sub(A, l->cutoff, theta), width);
  f.v = (l->cutoff - theta.v) / width;
  return ad_clamp(A, f, 0.0, 1.0);
}

/* A uniform point on an area light from (u1, u2) (light.c's
 * light__sample_area_point): position and the emitting side's normal. */
void path__area_point(path__ctx *c, const light *l, ad u1, ad u2, adv3 *p, vec3 *n) {
  ad_arena *A = c->A;
  const mesh *m = &c->sc->meshes[l->mesh];
  double pmf, u1r;
  int tri = distrib1d_sample_discrete(&l->tri_dist, u1.v, &pmf, &u1r);
  path__topo(c, tri);
  double width = l->tri_dist.cdf[tri + 1] - l->tri_dist.cdf[tri];
  ad ur = path__chain(A, u1r, width > 0.0 ? 1.0 / width : 0.0, u1);
  /* warp_square_to_triangle: b1 = 1 - sqrt(u1'), b2 = u2 sqrt(u1'). */
  ad s = ad_safe_sqrt(A, ur);
  ad b1 = ad_s_sub(A, 1.0, s);
  ad b2 = ad_mul(A, u2, s);
  ad b0 = ad_sub(A, ad_s_sub(A, 1.0, b1), b2);
  const uint32_t *idx = m->idx + 3 * tri;
  *p = path__bary(A, mesh_position(m, idx[0]), mesh_position(m, idx[1]), mesh_position(m, idx[2]),
                  b0, b1, b2);
  /* The emitting side: a hit's geometric normal at the point's values. */
  *n = mesh_hit_normals(m, tri, mesh_position(m, idx[0]), mesh_position(m, idx[1]),
                        mesh_position(m, idx[2]), b1.v, b2.v, NULL);
}

/* Envmap importance sampling (light.c): the pixel is chosen by the discrete
 * part of (u1, u2), the point inside it moves with them. Writes the lat-long
 * coordinates and the sampling density with respect to them. */
int path__env_sample_uv(path__ctx *c, const light *l, ad u1, ad u2, ad *uu, ad *vv,
                               double *pdf_uv, double uv[2]) {
  ad_arena *A = c->A;
  const distrib2d *d2 = &l->env_dist;
  distrib2d_sample(d2, u1.v, u2.v, uv, pdf_uv);
  /* distrib2d_sample: the row (v) from u2 on the marginal, u from u1 in that row. */
  double pdf_v;
  int row, col;
  distrib1d_sample_cont(&d2->marginal, u2.v, &pdf_v, &row);
  distrib1d_sample_cont(&d2->conditional[row], u1.v, NULL, &col);
  path__topo(c, row);
  path__topo(c, col);
  const distrib1d *mv = &d2->marginal, *cu = &d2->conditional[row];
  double wv = mv->cdf[row + 1] - mv->cdf[row], wu = cu->cdf[col + 1] - cu->cdf[col];
  *vv = path__chain(A, uv[1], wv > 0.0 ? 1.0 / (wv * mv->n) : 0.0, u2);
  *uu = path__chain(A, uv[0], wu > 0.0 ? 1.0 / (wu * cu->n) : 0.0, u1);
  return 1;
}

/* Lat-long (u, v) to a world direction and sin(theta) (light.c). */
adv3 path__env_uv_to_dir(ad_arena *A, const light *l, ad uu, ad vv, ad *sin_theta) {
  ad phi = ad_mul_s(A, uu, 2.0 * M_PI);
  phi.v = 2.0 * M_PI * uu.v;
  ad theta = ad_mul_s(A, vv, M_PI);
  theta.v = M_PI * vv.v;
  ad st = ad_sin(A, theta), ct = ad_cos(A, theta);
  *sin_theta = st;
  adv3 d = {ad_mul(A, ad_sin(A, phi), st), ct, ad_neg(A, ad_mul(A, ad_cos(A, phi), st))};
  return adv3_normalize(A, path__mat_vec(A, (const double (*)[4])l->to_world.m, d));
}

/* light_sample_li in duals, per light type (path__sample_li completes pd). */
static int path__sample_li_any(path__ctx *c, const light *l, adv3 ref, ad u1, ad u2,
                               path__li *out) {
  ad_arena *A = c->A;
  const scene *sc = c->sc;
  switch (l->type) {
  case LIGHT_AREA: {
    adv3 p;
    vec3 n;
    path__area_point(c, l, u1, u2, &p, &n);
    adv3 d = adv3_sub(A, p, ref);
    ad dist2 = adv3_len2(A, d);
    if (!(dist2.v > 0.0)) return 0;
    ad dist = ad_sqrt(A, dist2);
    ad inv = ad_inv(A, dist);
    adv3 wi = adv3_scale(A, d, inv);
    ad cos_l = ad_neg(A, path__dot_c(A, n, wi));
    if (!(cos_l.v > 0.0)) return 0;
    out->wi = wi;
    out->dist = dist.v;
    out->p = path__val(p);
    out->pd = p;
    out->n = n;
    out->li = adrgb_const(A, l->value);
    out->pdf = ad_div(A, dist2, ad_mul_s(A, cos_l, l->area));
    out->pdf.v = dist2.v / (cos_l.v * l->area);
    return isfinite(out->pdf.v) && out->pdf.v > 0.0;
  }
  case LIGHT_POINT:
  case LIGHT_SPOT: {
    adv3 d = {ad_s_sub(A, l->pos.x, ref.x), ad_s_sub(A, l->pos.y, ref.y),
              ad_s_sub(A, l->pos.z, ref.z)};
    ad dist2 = adv3_len2(A, d);
    if (!(dist2.v > 0.0)) return 0;
    ad dist = ad_sqrt(A, dist2);
    adv3 wi = adv3_scale(A, d, ad_inv(A, dist));
    ad falloff = ad_const(A, 1.0);
    if (l->type == LIGHT_SPOT) {
      falloff = path__spot_falloff(A, l, ad_neg(A, path__dot_c(A, l->frm.n, wi)));
      if (!(falloff.v > 0.0)) return 0;
    }
    ad s = ad_div(A, falloff, dist2);
    s.v = falloff.v / dist2.v;
    out->wi = wi;
    out->dist = dist.v;
    out->p = l->pos;
    out->li = path__rgb_scale_c(A, l->value, s);
    out->pdf = ad_const(A, 1.0);
    out->delta = 1;
    return 1;
  }
  case LIGHT_DIRECTIONAL:
    out->wi = path__cv(A, v3_neg(l->frm.n));
    out->dist = INFINITY;
    out->p = v3_fma(path__val(ref), v3_neg(l->frm.n), 2.0 * sc->radius);
    out->li = adrgb_const(A, l->value);
    out->pdf = ad_const(A, 1.0);
    out->delta = 1;
    return 1;
  case LIGHT_CONSTANT: {
    /* warp_square_to_uniform_sphere: z = 1 - 2 u1, phi = 2 pi u2. */
    ad z = ad_s_sub(A, 1.0, ad_mul_s(A, u1, 2.0));
    ad r = ad_safe_sqrt(A, ad_s_sub(A, 1.0, ad_sqr(A, z)));
    ad phi = ad_mul_s(A, u2, 2.0 * M_PI);
    phi.v = 2.0 * M_PI * u2.v;
    out->wi = (adv3){ad_mul(A, r, ad_cos(A, phi)), ad_mul(A, r, ad_sin(A, phi)), z};
    out->dist = INFINITY;
    out->p = v3_fma(path__val(ref), path__val(out->wi), 2.0 * sc->radius);
    out->li = adrgb_const(A, l->value);
    out->pdf = ad_const(A, 1.0 / (4.0 * M_PI));
    return 1;
  }
  case LIGHT_ENVMAP: {
    ad uu, vv, st;
    double pdf_uv, uv[2];
    path__env_sample_uv(c, l, u1, u2, &uu, &vv, &pdf_uv, uv);
    adv3 wi = path__env_uv_to_dir(A, l, uu, vv, &st);
    if (!(st.v > 0.0) || !(pdf_uv > 0.0)) return 0;
    out->wi = wi;
    out->dist = INFINITY;
    out->p = v3_fma(path__val(ref), path__val(wi), 2.0 * sc->radius);
    out->li = adrgb_const(A, path__env_eval_uv(l, uv[0], uv[1]));
    out->pdf = ad_s_div(A, pdf_uv, ad_mul_s(A, st, 2.0 * M_PI * M_PI));
    out->pdf.v = pdf_uv / (2.0 * M_PI * M_PI * st.v);
    return isfinite(out->pdf.v);
  }
  }
  return 0;
}

/* light_sample_li in duals. */
int path__sample_li(path__ctx *c, const light *l, adv3 ref, ad u1, ad u2, path__li *out) {
  out->delta = 0;
  out->n = v3(0.0, 0.0, 0.0);
  int ok = path__sample_li_any(c, l, ref, u1, u2, out);
  if (ok && l->type != LIGHT_AREA) out->pd = path__cv(c->A, out->p);
  return ok;
}

unsigned path__emit_flag(const light *l) {
  switch (l->type) {
  case LIGHT_AREA:
    return PATH_EMIT_AREA;
  case LIGHT_CONSTANT:
    return PATH_EMIT_INFINITE;
  case LIGHT_ENVMAP:
    return PATH_EMIT_INFINITE | PATH_EMIT_ENVMAP;
  default:
    return PATH_EMIT_DELTA;
  }
}

unsigned path__lobe_flag(int bsdf_flags) {
  unsigned f = 0;
  if (bsdf_flags & BSDF_DIFFUSE_LOBE) f |= PATH_LOBE_DIFFUSE;
  if (bsdf_flags & BSDF_GLOSSY) f |= PATH_LOBE_GLOSSY;
  if (bsdf_flags & BSDF_DELTA) f |= PATH_LOBE_DELTA;
  if (bsdf_flags & BSDF_TRANSMISSION) f |= PATH_LOBE_TRANSMISSION;
  return f;
}

