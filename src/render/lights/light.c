/*
 * light.c: Mitsuba 0.6's emitters (area, point, spot, directional,
 * constant, envmap) with the sampling routines that path tracing and BDPT
 * need: direct sampling from a receiver (sample_li / pdf_li), emission
 * (sample_le / pdf_le) and evaluation (le_area / le_infinite).
 *
 * Conventions (light.h): wi points from the receiver towards the light;
 * densities of sample_li are per unit solid angle at the receiver; those of
 * sample_le are per unit area (pdf_pos) times per unit solid angle
 * (pdf_dir). For sample_le, u1 and u2 always drive the position and u3 and
 * u4 the direction, whatever the light, so primary-sample-space mutations
 * keep the same meaning for every light type.
 *
 * The models.
 *  area        Radiance L, one-sided on the side of the geometric normal
 *              a hit on the point has (mesh_hit_normals: the side of the
 *              mesh's vertex normals where it has them, else its winding's,
 *              flip_normals honoured), so that a sampled point and a hit
 *              on it agree. A triangle is chosen with probability
 *              area_i / A (tri_dist), then a uniform point on it, so the
 *              area density is 1/A. Seen from ref at distance d with
 *              cos_l = <n, -wi>, the solid-angle density is
 *                  pdf_li = (1/A) d^2 / cos_l,
 *              and the sample fails (returns 0) when cos_l <= 0: the
 *              receiver is behind the emitting side. Emission: position by
 *              area, direction cosine-weighted around n (pdf cos/pi).
 *              Power pi A lum(L).
 *  point       Intensity I at pos: li = I / d^2, delta; emission uniform on
 *              the sphere (pdf 1/(4 pi)).
 *  spot        Intensity I along the local +z axis frm.n with Mitsuba 0.6's
 *              falloff, linear in the angle theta from the axis:
 *                  1                                  theta <= beam_width
 *                  (cutoff - theta)/(cutoff - beam)   beam < theta < cutoff
 *                  0                                  theta >= cutoff.
 *              Emission uniform in the cone of half angle cutoff.
 *  directional Irradiance E travelling along frm.n: wi = -frm.n, li = E,
 *              dist = INFINITY. Emission: parallel rays along frm.n from a
 *              disk of radius r (the scene's bounding radius) centred at
 *              center - frm.n r, perpendicular to frm.n; pdf_pos = 1/(pi r^2).
 *  constant    Radiance L from every direction; sample_li uniform on the
 *              sphere (pdf 1/(4 pi)). Emission: travel direction uniform on
 *              the sphere, origin uniform on the disk of radius r facing it
 *              just outside the bounding sphere.
 *  envmap      A latitude-longitude image in Mitsuba's orientation. With
 *              d = to_world^-1(w) the direction towards the environment in
 *              the map's local frame (+y up),
 *                  u = atan2(d.x, -d.z) / (2 pi)  (wrapped into [0,1)),
 *                  v = acos(d.y) / pi,
 *              so row 0 (the image's top) is +y, column 0 looks along -z
 *              and u = 1/4 looks along +x; inversely, with phi = 2 pi u and
 *              theta = pi v,
 *                  d = (sin phi sin theta, cos theta, -cos phi sin theta).
 *              Radiance is the pixel containing (u, v) times `scale`
 *              (piecewise constant, no filtering), and pixels are importance
 *              sampled by a distrib2d over luminance * sin(theta at the row
 *              centre). Since domega = 2 pi^2 sin(theta) du dv, the density
 *              in solid angle is p(u, v) / (2 pi^2 sin theta); it is exactly
 *              the density of the samples, and radiance and density use the
 *              same pixel, so light_sample_li is unbiased.
 *
 * Which lights are "infinite": constant and envmap, the lights a ray that
 * escapes the scene sees (scene->infinite_lights). Directional lights are
 * delta lights with dist = INFINITY, but no ray can hit them.
 */
#include "render/lights/light.h"
#include "render/lights/light_ad.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "render/mesh.h"
#include "render/scene.h"
#include "render/warp.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ---------------------------------------------------------------------------
 * Helpers.
 */

/* Vertices of triangle `tri` of mesh m. */
static void light__triangle(const mesh *m, int64_t tri, vec3 *a, vec3 *b, vec3 *c) {
  const uint32_t *idx = m->idx + 3 * tri;
  *a = mesh_position(m, idx[0]);
  *b = mesh_position(m, idx[1]);
  *c = mesh_position(m, idx[2]);
}

/* Barycentrics (b1, b2) of p on the triangle (a, b, c): least squares in
 * the triangle's plane. Returns 0 for a degenerate triangle. */
static int light__barycentrics(vec3 a, vec3 b, vec3 c, vec3 p, double *OUT_b1, double *OUT_b2) {
  vec3 e1 = v3_sub(b, a), e2 = v3_sub(c, a), d = v3_sub(p, a);
  double d11 = v3_dot(e1, e1), d12 = v3_dot(e1, e2), d22 = v3_dot(e2, e2);
  double d1 = v3_dot(d, e1), d2 = v3_dot(d, e2);
  double den = d11 * d22 - d12 * d12;
  if (!(den > 0.0)) return 0;
  *OUT_b1 = (d22 * d1 - d12 * d2) / den;
  *OUT_b2 = (d11 * d2 - d12 * d1) / den;
  return 1;
}

/* The emitting side's normal at point p of triangle tri of an area light
 * (the normal light__area_point gave it). Returns 0 for a
 * degenerate triangle. */
static int light__area_normal(const light *l, const struct scene *s, int64_t tri, vec3 p,
                              vec3 *OUT_n) {
  const mesh *m = &s->meshes[l->mesh];
  vec3 a, b, c;
  double b1, b2;
  light__triangle(m, tri, &a, &b, &c);
  if (!light__barycentrics(a, b, c, p, &b1, &b2)) return 0;
  *OUT_n = mesh_hit_normals(m, tri, a, b, c, b1, b2, NULL);
  return 1;
}

/* Pixel (x, y) of the environment map as RGB (grey and RGBA accepted). */
static rgb light__env_pixel(const lmc_image *img, int x, int y) {
  const float *p = img->data + ((size_t)y * (size_t)img->width + (size_t)x) * (size_t)img->channels;
  if (img->channels >= 3) return rgb_make(p[0], p[1], p[2]);
  return rgb_gray(p[0]);
}

/* Pixel containing (u, v) in [0,1]^2 (u wraps, v clamps). */
static void light__env_cell(const lmc_image *img, double u, double v, int *x, int *y) {
  double fx = floor(u * img->width), fy = floor(v * img->height);
  /* fmod only when u is outside [0, 1) (it is a slow call, and the
   * identity inside). */
  int ix = fx >= 0.0 && fx < img->width ? (int)fx
                                         : (isfinite(fx) ? (int)fmod(fx, (double)img->width) : 0);
  if (ix < 0) ix += img->width;
  int iy = fy < 0.0 || !isfinite(fy) ? 0 : (fy > img->height - 1 ? img->height - 1 : (int)fy);
  *x = ix;
  *y = iy;
}

/* World direction (towards the environment) -> lat-long (u, v) and
 * sin(theta) in the map's frame. Returns 0 for a degenerate direction. */
static int light__env_dir_to_uv(const light *l, vec3 dir, double *u, double *v, double *sin_theta) {
  vec3 d = v3_normalize(xform_inv_vector(&l->to_world, dir));
  if (!v3_isfinite(d) || !(v3_len2(d) > 0.0)) return 0;
  double uu = atan2(d.x, -d.z) * (0.5 / M_PI);
  if (uu < 0.0) uu += 1.0;
  if (uu >= 1.0) uu = 0.0;
  double y = lmc_fmin(1.0, lmc_fmax(-1.0, d.y));
  *u = uu;
  *v = acos(y) / M_PI;
  *sin_theta = sqrt(lmc_fmax(0.0, 1.0 - y * y));
  return 1;
}

/* Radiance of the envmap for lat-long (u, v). */
static rgb light__env_eval_uv(const light *l, double u, double v) {
  int x, y;
  light__env_cell(&l->image, u, v, &x, &y);
  return rgb_scale(light__env_pixel(&l->image, x, y), l->scale);
}

/* Solid-angle density of the envmap's importance sampling for (u, v). */
static double light__env_pdf_uv(const light *l, double u, double v, double sin_theta) {
  if (!(sin_theta > 0.0)) return 0.0;
  /* pdf_omega = p(u, v) / (2 pi^2 sin theta) */
  return distrib2d_pdf(&l->env_dist, u, v) / (2.0 * M_PI * M_PI * sin_theta);
}

void light_disk_invert(const struct scene *s, vec3 dir, vec3 p, double *OUT_u1, double *OUT_u2) {
  /* p = center + r (x s + y t - dir) */
  frame f = frame_from_z(dir);
  vec3 offset = v3_add(v3_scale(v3_sub(p, s->center), 1.0 / s->radius), dir);
  warp_disk_concentric_to_square(v3_dot(offset, f.s), v3_dot(offset, f.t), OUT_u1, OUT_u2);
}

double light_disk_pdf(const struct scene *s) {
  return 1.0 / (M_PI * s->radius * s->radius);
}

/* ---------------------------------------------------------------------------
 * Direct sampling from a receiver and emission, in doubles (light.h) and in
 * duals (light_ad.h), from one source.
 */

#define R_DUAL 0
#include "render/real.h"
#include "render/lights/light_generic.h"
#undef R_DUAL
#define R_DUAL 1
#include "render/real.h"
#include "render/lights/light_generic.h"
#undef R_DUAL

vec3 light_disk_point(const struct scene *s, vec3 dir, double u1, double u2) {
  return light__disk_point(s, dir, u1, u2);
}

/* ---------------------------------------------------------------------------
 * Preparation and properties.
 */

static lmc_status light__prepare_area(light *l, const struct scene *s, lmc_error *err) {
  if (l->mesh < 0 || l->mesh >= s->n_meshes)
    return lmc_error_set(err, LMC_EINVAL, s->path, 0, "area light attached to missing mesh %d",
                         l->mesh);
  const mesh *m = &s->meshes[l->mesh];
  if (m->n_triangles < 1 || m->n_triangles > INT32_MAX)
    return lmc_error_set(err, LMC_EINVAL, s->path, 0,
                         "area light on mesh \"%s\" with %lld triangles", m->name,
                         (long long)m->n_triangles);
  int n = (int)m->n_triangles;
  double *areas = malloc((size_t)n * sizeof(double));
  if (!areas) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for an area light");
  double total = 0.0;
  for (int i = 0; i < n; i++) {
    double a = mesh_triangle_area(m, i);
    areas[i] = isfinite(a) && a > 0.0 ? a : 0.0;
    total += areas[i];
  }
  if (!(total > 0.0)) {
    free(areas);
    return lmc_error_set(err, LMC_EINVAL, s->path, 0, "area light on mesh \"%s\" has zero area",
                         m->name);
  }
  distrib1d_free(&l->tri_dist);
  lmc_status st = distrib1d_init(&l->tri_dist, areas, n, err);
  free(areas);
  if (st) return st;
  l->area = total;
  return LMC_OK;
}

static lmc_status light__prepare_envmap(light *l, const struct scene *s, lmc_error *err) {
  const lmc_image *img = &l->image;
  if (!img->data || img->width < 1 || img->height < 1 || img->channels < 1)
    return lmc_error_set(err, LMC_EINVAL, s->path, 0, "environment map without an image");
  int w = img->width, h = img->height;
  double *f = malloc((size_t)w * (size_t)h * sizeof(double));
  if (!f) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for an environment map");
  /* Weight of pixel (x, y): luminance * sin(theta at the row centre);
   * negative or invalid pixels get no samples. */
  for (int y = 0; y < h; y++) {
    double sin_theta = sin(M_PI * (y + 0.5) / h);
    for (int x = 0; x < w; x++) {
      double lum = rgb_luminance(light__env_pixel(img, x, y));
      f[(size_t)y * (size_t)w + (size_t)x] = isfinite(lum) && lum > 0.0 ? lum * sin_theta : 0.0;
    }
  }
  distrib2d_free(&l->env_dist);
  lmc_status st = distrib2d_init(&l->env_dist, f, w, h, err);
  free(f);
  return st;
}

lmc_status light_prepare(light *l, const struct scene *s, lmc_error *err) {
  switch (l->type) {
  case LIGHT_AREA:
    return light__prepare_area(l, s, err);
  case LIGHT_POINT:
    return LMC_OK;
  case LIGHT_SPOT: {
    vec3 n = v3_normalize(l->frm.n);
    if (!(v3_len2(n) > 0.5) || !v3_isfinite(n))
      return lmc_error_set(err, LMC_EINVAL, s->path, 0, "spot light without a direction");
    l->frm = frame_from_z(n);
    if (!(l->cutoff > 0.0) || l->cutoff > M_PI)
      return lmc_error_set(err, LMC_EINVAL, s->path, 0, "spot light cutoffAngle %g degrees",
                           l->cutoff * 180.0 / M_PI);
    if (!(l->beam_width >= 0.0) || l->beam_width > l->cutoff) l->beam_width = l->cutoff;
    l->cos_cutoff = cos(l->cutoff);
    l->cos_beam = cos(l->beam_width);
    return LMC_OK;
  }
  case LIGHT_DIRECTIONAL: {
    vec3 n = v3_normalize(l->frm.n);
    if (!(v3_len2(n) > 0.5) || !v3_isfinite(n))
      return lmc_error_set(err, LMC_EINVAL, s->path, 0, "directional light without a direction");
    l->frm = frame_from_z(n);
    return LMC_OK;
  }
  case LIGHT_CONSTANT:
    return LMC_OK;
  case LIGHT_ENVMAP:
    return light__prepare_envmap(l, s, err);
  }
  return lmc_error_set(err, LMC_EUNSUPPORTED, s->path, 0, "unknown light type %d", (int)l->type);
}

void light_free(light *l) {
  if (!l) return;
  distrib1d_free(&l->tri_dist);
  distrib2d_free(&l->env_dist);
  image_free(&l->image);
}

int light_is_delta(const light *l) {
  return l->type == LIGHT_POINT || l->type == LIGHT_SPOT || l->type == LIGHT_DIRECTIONAL;
}

int light_is_infinite(const light *l) {
  return l->type == LIGHT_CONSTANT || l->type == LIGHT_ENVMAP;
}

double light_power(const light *l, const struct scene *s) {
  double r2 = s->radius * s->radius;
  switch (l->type) {
  case LIGHT_AREA:
    return M_PI * l->area * rgb_luminance(l->value);
  case LIGHT_POINT:
    return 4.0 * M_PI * rgb_luminance(l->value);
  case LIGHT_SPOT:
    /* Intensity over the cone, the transition counted at half weight. */
    return 2.0 * M_PI * (1.0 - 0.5 * (l->cos_cutoff + l->cos_beam)) * rgb_luminance(l->value);
  case LIGHT_DIRECTIONAL:
    return M_PI * r2 * rgb_luminance(l->value);
  case LIGHT_CONSTANT:
    return M_PI * r2 * 4.0 * M_PI * rgb_luminance(l->value);
  case LIGHT_ENVMAP: {
    /* pi r^2 times the integral of luminance over the sphere,
     * sum over pixels of lum * (2 pi / w) (pi / h) sin(theta). */
    const lmc_image *img = &l->image;
    if (!img->data) return 0.0;
    double sum = 0.0;
    for (int y = 0; y < img->height; y++) {
      double sin_theta = sin(M_PI * (y + 0.5) / img->height);
      for (int x = 0; x < img->width; x++) {
        double lum = rgb_luminance(light__env_pixel(img, x, y));
        if (isfinite(lum) && lum > 0.0) sum += lum * sin_theta;
      }
    }
    double integral = sum * (2.0 * M_PI / img->width) * (M_PI / img->height) * l->scale;
    return M_PI * r2 * integral;
  }
  }
  return 0.0;
}

/* ---------------------------------------------------------------------------
 * Emission seen by a ray and the emission densities (the sampling routines
 * are light_generic.h's, above).
 */

rgb light_le_area(const light *l, vec3 n, vec3 w) {
  if (l->type != LIGHT_AREA) return rgb_zero();
  return v3_dot(n, w) > 0.0 ? l->value : rgb_zero();
}

rgb light_le_infinite(const light *l, vec3 dir) {
  if (l->type == LIGHT_CONSTANT) return l->value;
  if (l->type != LIGHT_ENVMAP) return rgb_zero();
  double u, v, sin_theta;
  if (!light__env_dir_to_uv(l, dir, &u, &v, &sin_theta)) return rgb_zero();
  return light__env_eval_uv(l, u, v);
}

rgb light_le_pdf_infinite(const light *l, const struct scene *s, vec3 dir, double *OUT_pdf) {
  *OUT_pdf = 0.0;
  if (l->type == LIGHT_CONSTANT) {
    *OUT_pdf = light_pdf_li(l, s, dir, dir, dir, dir);
    return l->value;
  }
  if (l->type != LIGHT_ENVMAP) return rgb_zero();
  double u, v, sin_theta;
  if (!light__env_dir_to_uv(l, dir, &u, &v, &sin_theta)) return rgb_zero();
  *OUT_pdf = light__env_pdf_uv(l, u, v, sin_theta);
  return light__env_eval_uv(l, u, v);
}

void light_pdf_le(const light *l, const struct scene *s, vec3 p, vec3 n, vec3 dir,
                  double *OUT_pdf_pos, double *OUT_pdf_dir) {
  double pdf_pos = 0.0;
  switch (l->type) {
  case LIGHT_AREA:
    pdf_pos = l->area > 0.0 ? 1.0 / l->area : 0.0;
    break;
  case LIGHT_POINT:
  case LIGHT_SPOT:
    pdf_pos = 1.0;
    break;
  case LIGHT_DIRECTIONAL:
  case LIGHT_CONSTANT:
  case LIGHT_ENVMAP:
    pdf_pos = light_disk_pdf(s);
    break;
  }
  if (OUT_pdf_pos) *OUT_pdf_pos = pdf_pos;
  if (OUT_pdf_dir) *OUT_pdf_dir = light_pdf_le_dir(l, s, p, n, dir);
}

int light_sample_dir(const light *l, vec3 n, double u3, double u4, vec3 *OUT_dir,
                     double *OUT_pdf_dir) {
  switch (l->type) {
  case LIGHT_AREA: {
    vec3 local = warp_square_to_cosine_hemisphere(u3, u4);
    frame f = frame_from_z(n);
    *OUT_dir = v3_normalize(frame_to_world(&f, local));
    *OUT_pdf_dir = warp_square_to_cosine_hemisphere_pdf(local);
    return *OUT_pdf_dir > 0.0;
  }
  case LIGHT_POINT:
    *OUT_dir = warp_square_to_uniform_sphere(u3, u4);
    *OUT_pdf_dir = 1.0 / (4.0 * M_PI);
    return 1;
  case LIGHT_SPOT: {
    vec3 local = warp_square_to_uniform_cone(u3, u4, l->cos_cutoff);
    *OUT_dir = v3_normalize(frame_to_world(&l->frm, local));
    *OUT_pdf_dir = 1.0 / (2.0 * M_PI * (1.0 - l->cos_cutoff));
    return light__spot_falloff(l, local.z) > 0.0;
  }
  default:
    return 0;
  }
}

/* ---------------------------------------------------------------------------
 * The inverses of the samplers.
 */

/* The (u1, u2) of light__area_point giving p on triangle tri: its
 * barycentrics (least squares in the triangle's plane) through
 * warp_triangle_to_square, u1 moved into the triangle's cell. */
static int light__invert_area_point(const light *l, const struct scene *s, int64_t tri, vec3 p,
                                    double *OUT_u1, double *OUT_u2) {
  if (tri < 0 || tri >= l->tri_dist.n) return 0;
  vec3 a, b, c;
  light__triangle(&s->meshes[l->mesh], tri, &a, &b, &c);
  double b1, b2;
  if (!light__barycentrics(a, b, c, p, &b1, &b2)) return 0;
  double ur;
  warp_triangle_to_square(b1, b2, &ur, OUT_u2);
  *OUT_u1 = distrib1d_invert_discrete(&l->tri_dist, (int)tri, fmin(ur, nextafter(1.0, 0.0)));
  return *OUT_u1 >= 0.0;
}

/* The (u, v) of the envmap's importance sampling towards world direction w. */
static int light__invert_env(const light *l, vec3 w, double *OUT_u1, double *OUT_u2) {
  double uv[2], sin_theta, out[2];
  if (!light__env_dir_to_uv(l, w, &uv[0], &uv[1], &sin_theta) || !(sin_theta > 0.0)) return 0;
  if (!(distrib2d_pdf(&l->env_dist, uv[0], uv[1]) > 0.0)) return 0;
  distrib2d_invert(&l->env_dist, uv[0], uv[1], out);
  *OUT_u1 = out[0];
  *OUT_u2 = out[1];
  return 1;
}

int light_invert_li(const light *l, const struct scene *s, vec3 ref, vec3 wi, vec3 p,
                    int64_t tri, const double r[2], double OUT_u[2]) {
  OUT_u[0] = r[0];
  OUT_u[1] = r[1];
  switch (l->type) {
  case LIGHT_AREA: {
    vec3 n;
    if (tri < 0 || tri >= l->tri_dist.n || !light__area_normal(l, s, tri, p, &n)) return 0;
    /* The sampler refuses points whose emitting side faces away from ref. */
    if (!(v3_dot(n, v3_sub(ref, p)) > 0.0)) return 0;
    return light__invert_area_point(l, s, tri, p, &OUT_u[0], &OUT_u[1]);
  }
  case LIGHT_CONSTANT:
    warp_uniform_sphere_to_square(wi, &OUT_u[0], &OUT_u[1]);
    return 1;
  case LIGHT_ENVMAP:
    return light__invert_env(l, wi, &OUT_u[0], &OUT_u[1]);
  default:
    return 1; /* delta lights read no numbers */
  }
}

int light_invert_le(const light *l, const struct scene *s, vec3 p, vec3 dir, int64_t tri,
                    const double r[4], double OUT_u[4]) {
  for (int i = 0; i < 4; i++) OUT_u[i] = r[i];
  switch (l->type) {
  case LIGHT_AREA: {
    vec3 n;
    if (!light__invert_area_point(l, s, tri, p, &OUT_u[0], &OUT_u[1]) ||
        !light__area_normal(l, s, tri, p, &n))
      return 0;
    frame f = frame_from_z(n);
    vec3 local = frame_to_local(&f, dir);
    if (!(local.z > 0.0)) return 0;
    warp_cosine_hemisphere_to_square(local, &OUT_u[2], &OUT_u[3]);
    return 1;
  }
  case LIGHT_POINT:
    warp_uniform_sphere_to_square(dir, &OUT_u[2], &OUT_u[3]);
    return 1;
  case LIGHT_SPOT: {
    vec3 local = frame_to_local(&l->frm, dir);
    if (!(light__spot_falloff(l, local.z) > 0.0)) return 0;
    warp_uniform_cone_to_square(local, l->cos_cutoff, &OUT_u[2], &OUT_u[3]);
    return 1;
  }
  case LIGHT_DIRECTIONAL:
    if (!(v3_len2(v3_sub(dir, l->frm.n)) < 1e-10)) return 0;
    light_disk_invert(s, dir, p, &OUT_u[0], &OUT_u[1]);
    return 1;
  case LIGHT_CONSTANT:
    warp_uniform_sphere_to_square(dir, &OUT_u[2], &OUT_u[3]);
    light_disk_invert(s, dir, p, &OUT_u[0], &OUT_u[1]);
    return 1;
  case LIGHT_ENVMAP:
    if (!light__invert_env(l, v3_neg(dir), &OUT_u[2], &OUT_u[3])) return 0;
    light_disk_invert(s, dir, p, &OUT_u[0], &OUT_u[1]);
    return 1;
  }
  return 0;
}
