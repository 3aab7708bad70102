/*
 * scene.c: the scene container, its finalisation and the ray queries that
 * turn an accelerator hit into a shading point.
 *
 * Normals, as Mitsuba 0.6 orients them (mesh.h's mesh_hit_normals): the
 * shading normal is the interpolated vertex normal (reversed by
 * flipNormals), and the geometric normal, the triangle's winding normal,
 * is turned to its side when the two disagree; without vertex normals (or
 * with faceNormals) both are the winding normal, reversed by flipNormals.
 * A one-sided BSDF and a one-sided area light so agree on which side is
 * front, and it is the side the vertex normals say.
 * Texture coordinates default to the barycentrics (b1, b2) when a mesh has
 * none.
 *
 * Self-intersection: rays leaving a surface start at t = scene_ray_eps(p),
 * an offset proportional to the magnitude of p (Embree traces in float).
 */
#include "render/scene.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

lmc_status scene_create(scene **out, lmc_error *err) {
  *out = calloc(1, sizeof(scene));
  if (!*out) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory creating the scene");
  (*out)->settings = render_settings_default();
  (*out)->settings.set = 0;
  filter_init(&(*out)->filter, FILTER_BOX);
  return LMC_OK;
}

void scene_destroy(scene *s) {
  if (!s) return;
  accel_destroy(s->accel);
  accel_destroy(s->accel_media);
  for (int i = 0; i < s->n_meshes; i++) mesh_free(&s->meshes[i]);
  for (int i = 0; i < s->n_lights; i++) light_free(&s->lights[i]);
  for (int i = 0; i < s->n_images; i++) image_free(&s->images[i]);
  distrib1d_free(&s->light_select);
  free(s->meshes);
  free(s->bsdfs);
  free(s->lights);
  free(s->media);
  free(s->images);
  free(s->infinite_lights);
  free(s->params);
  free(s);
}

/* Grows an array of `size`-byte elements to hold one more. */
static int scene__grow(void **arr, int *cap, int n, size_t size) {
  if (n < *cap) return 1;
  int ncap = *cap ? 2 * *cap : 8;
  void *p = realloc(*arr, (size_t)ncap * size);
  if (!p) return 0;
  *arr = p;
  *cap = ncap;
  return 1;
}

int scene_add_bsdf(scene *s, const bsdf *b, lmc_error *err) {
  if (!scene__grow((void **)&s->bsdfs, &s->cap_bsdfs, s->n_bsdfs, sizeof(bsdf)))
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory adding a BSDF");
  s->bsdfs[s->n_bsdfs] = *b;
  return s->n_bsdfs++;
}

int scene_add_mesh(scene *s, mesh *m, lmc_error *err) {
  if (!scene__grow((void **)&s->meshes, &s->cap_meshes, s->n_meshes, sizeof(mesh)))
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory adding a mesh");
  s->meshes[s->n_meshes] = *m;
  memset(m, 0, sizeof *m);
  return s->n_meshes++;
}

int scene_add_light(scene *s, const light *l, lmc_error *err) {
  if (!scene__grow((void **)&s->lights, &s->cap_lights, s->n_lights, sizeof(light)))
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory adding a light");
  s->lights[s->n_lights] = *l;
  return s->n_lights++;
}

int scene_add_medium(scene *s, const medium *m, lmc_error *err) {
  if (!scene__grow((void **)&s->media, &s->cap_media, s->n_media, sizeof(medium)))
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory adding a medium");
  s->media[s->n_media] = *m;
  return s->n_media++;
}

int scene_add_image(scene *s, lmc_image *img, lmc_error *err) {
  if (!scene__grow((void **)&s->images, &s->cap_images, s->n_images, sizeof(lmc_image)))
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory adding an image");
  s->images[s->n_images] = *img;
  memset(img, 0, sizeof *img);
  return s->n_images++;
}

lmc_status scene_finalize(scene *s, lmc_error *err) {
  lmc_status st;
  if (s->finalized) return LMC_OK;
  /* Bounds of all geometry (and the camera, so infinite lights' disks
   * enclose it too). */
  vec3 lo = v3(DBL_MAX, DBL_MAX, DBL_MAX), hi = v3(-DBL_MAX, -DBL_MAX, -DBL_MAX);
  int64_t n_tris = 0;
  for (int i = 0; i < s->n_meshes; i++) {
    const mesh *m = &s->meshes[i];
    for (int64_t v = 0; v < m->n_vertices; v++) {
      vec3 p = mesh_position(m, (uint32_t)v);
      lo = v3_min(lo, p);
      hi = v3_max(hi, p);
    }
    n_tris += m->n_triangles;
  }
  lo = v3_min(lo, s->cam.pos);
  hi = v3_max(hi, s->cam.pos);
  s->bounds_min = lo;
  s->bounds_max = hi;
  s->center = v3_scale(v3_add(lo, hi), 0.5);
  s->radius = fmax(1e-3, 0.5 * v3_len(v3_sub(hi, lo)) * 1.001);
  if (n_tris == 0 && s->n_lights == 0)
    return lmc_error_set(err, LMC_EINVAL, s->path, 0, "the scene has neither geometry nor lights");

  for (int i = 0; i < s->n_bsdfs; i++) {
    bsdf_link(&s->bsdfs[i], s->bsdfs);
    s->tex_filtered |= bsdf_is_tex_filtered(&s->bsdfs[i]);
  }

  /* The accelerator. */
  st = accel_create(&s->accel, s->meshes, s->n_meshes, 0, err);
  if (st) return st;
  int n_null = 0;
  for (int i = 0; i < s->n_meshes; i++) n_null += s->meshes[i].bsdf < 0;
  if (n_null > 0 && (st = accel_create(&s->accel_media, s->meshes, s->n_meshes, 1, err)))
    return st;
  /* The medium outside every boundary: the camera's, if the camera is there. */
  if (s->n_media > 0 && scene_locate_medium(s, s->cam.pos, -1) < 0)
    s->ambient_medium = s->cam.medium;

  /* Lights: sampling distributions, the list of infinite ones, and the
   * light choice in proportion to power. */
  s->infinite_lights = calloc((size_t)s->n_lights + 1, sizeof(int));
  if (!s->infinite_lights) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory");
  s->n_infinite = 0;
  double *power = calloc((size_t)s->n_lights + 1, sizeof(double));
  if (!power) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory");
  for (int i = 0; i < s->n_lights; i++) {
    st = light_prepare(&s->lights[i], s, err);
    if (st) {
      free(power);
      return st;
    }
    if (light_is_infinite(&s->lights[i])) s->infinite_lights[s->n_infinite++] = i;
    double p = light_power(&s->lights[i], s);
    power[i] = (isfinite(p) && p > 0.0) ? p : 0.0;
  }
  if (s->n_lights > 0) {
    st = distrib1d_init(&s->light_select, power, s->n_lights, err);
    free(power);
    if (st) return st;
  } else {
    free(power);
  }
  s->finalized = 1;
  return LMC_OK;
}

double scene_ray_eps(const scene *s, vec3 p) {
  (void)s;
  double m = lmc_fmax(fabs(p.x), lmc_fmax(fabs(p.y), fabs(p.z)));
  return 2e-5 * (1.0 + m);
}

/* The hit ah of the ray (org, dir) as a surface_hit. */
static int scene__hit(const scene *s, accel_hit ah, vec3 org, vec3 dir, surface_hit *OUT_hit) {
  const mesh *m = &s->meshes[ah.mesh];
  /* The triangle's corners, loaded once for the refinement, the hit point
   * and the geometric normal. */
  const uint32_t *tri = m->idx + 3 * ah.prim;
  vec3 p0 = mesh_position(m, tri[0]), p1 = mesh_position(m, tri[1]), p2 = mesh_position(m, tri[2]);
  /* Refine Embree's float hit to double on the same triangle (the formula
   * the differentiable path sampler re-evaluates, see path.h). */
  double rt, rb1, rb2;
  if (mesh_intersect_corners(p0, p1, p2, org, dir, &rt, &rb1, &rb2) && isfinite(rb1) &&
      isfinite(rb2) && isfinite(rt)) {
    ah.t = rt;
    ah.b1 = rb1;
    ah.b2 = rb2;
  }
  surface_hit *h = OUT_hit;
  h->t = ah.t;
  h->mesh = ah.mesh;
  h->prim = ah.prim;
  h->b1 = ah.b1;
  h->b2 = ah.b2;
  /* Re-evaluate the hit point on the triangle from its barycentrics. */
  double b0 = 1.0 - ah.b1 - ah.b2;
  h->p = v3_add(v3_add(v3_scale(p0, b0), v3_scale(p1, ah.b1)), v3_scale(p2, ah.b2));
  /* Normals as Mitsuba orients them (mesh.h): the shading normal
   * interpolated, the geometric normal turned to its side. */
  vec3 ns;
  h->ng = mesh_hit_normals(m, ah.prim, p0, p1, p2, ah.b1, ah.b2, &ns);
  h->sh = frame_from_z(ns);
  if (m->uv) {
    const float *uv = m->uv;
    h->tu = b0 * uv[2 * tri[0]] + ah.b1 * uv[2 * tri[1]] + ah.b2 * uv[2 * tri[2]];
    h->tv = b0 * uv[2 * tri[0] + 1] + ah.b1 * uv[2 * tri[1] + 1] + ah.b2 * uv[2 * tri[2] + 1];
  } else {
    h->tu = ah.b1;
    h->tv = ah.b2;
  }
  h->bsdf = m->bsdf >= 0 ? &s->bsdfs[m->bsdf] : NULL;
  h->light = m->light;
  /* A bump map tilts the shading frame by its displacement's slope; an
   * anisotropic lobe turns it to follow dpdu. */
  vec3 dpdu, dpdv;
  if (h->bsdf && bsdf_needs_tangents(h->bsdf) &&
      mesh_uv_tangents(m, ah.prim, p0, p1, p2, &dpdu, &dpdv))
    h->sh = bsdf_shading_frame(h->bsdf, h->tu, h->tv, dpdu, dpdv, h->sh.n, h->ng);
  return 1;
}

int scene_intersect(const scene *s, vec3 org, vec3 dir, double tmin, double tmax,
                    surface_hit *OUT_hit) {
  accel_hit ah;
  if (!accel_intersect(s->accel, org, dir, tmin, tmax, &ah)) return 0;
  return scene__hit(s, ah, org, dir, OUT_hit);
}

int scene_intersect_media(const scene *s, vec3 org, vec3 dir, double tmin, double tmax,
                          surface_hit *OUT_hit) {
  accel_hit ah;
  if (!accel_intersect(s->accel_media ? s->accel_media : s->accel, org, dir, tmin, tmax, &ah))
    return 0;
  return scene__hit(s, ah, org, dir, OUT_hit);
}

int scene_locate_medium(const scene *s, vec3 p, int skip) {
  /* A probe along a fixed direction (no axis: it meets no box face edge
   * on) to the first shape that bounds media. */
  const vec3 probe = v3_normalize(v3(0.2718, 0.9129, 0.3046));
  vec3 o = p;
  double tmin = scene_ray_eps(s, p);
  surface_hit h;
  for (int k = 0; k < 1000; k++) {
    if (!scene_intersect_media(s, o, probe, tmin, INFINITY, &h)) return -1;
    const mesh *m = &s->meshes[h.mesh];
    if ((m->interior || m->exterior) && h.mesh != skip)
      return scene_medium_after(s, &h, 0, v3_neg(probe));
    o = h.p;
    tmin = scene_ray_eps(s, h.p);
  }
  return -1;
}

int scene_tex_footprint(const scene *s, const surface_hit *h, vec3 org, vec3 dx, vec3 dy,
                        tex_footprint *OUT) {
  const mesh *m = &s->meshes[h->mesh];
  const uint32_t *tri = m->idx + 3 * h->prim;
  vec3 p0 = mesh_position(m, tri[0]), p1 = mesh_position(m, tri[1]), p2 = mesh_position(m, tri[2]);
  vec3 dpdu = v3_sub(p1, p0), dpdv = v3_sub(p2, p0);
  if (m->uv) mesh_uv_tangents(m, h->prim, p0, p1, p2, &dpdu, &dpdv);
  /* Where the offset rays meet the tangent plane. */
  vec3 n = h->ng;
  double pn = v3_dot(n, v3_sub(h->p, org)), nx = v3_dot(n, dx), ny = v3_dot(n, dy);
  if (nx == 0.0 || ny == 0.0) return 0;
  vec3 dpdx = v3_sub(v3_add(org, v3_scale(dx, pn / nx)), h->p);
  vec3 dpdy = v3_sub(v3_add(org, v3_scale(dy, pn / ny)), h->p);
  /* Two of the three equations: drop the axis the normal is most along. */
  double ax = fabs(n.x), ay = fabs(n.y), az = fabs(n.z);
  int i0 = 0, i1 = 1;
  if (ax > ay && ax > az) i0 = 1, i1 = 2;
  else if (ay > az) i0 = 0, i1 = 2;
  double a00 = v3_comp(dpdu, i0), a01 = v3_comp(dpdv, i0);
  double a10 = v3_comp(dpdu, i1), a11 = v3_comp(dpdv, i1);
  double det = a00 * a11 - a01 * a10;
  if (!(fabs(det) > 1e-30)) {
    *OUT = (tex_footprint){0.0, 0.0, 0.0, 0.0};
    return 1;
  }
  double inv = 1.0 / det;
  double bx0 = v3_comp(dpdx, i0), bx1 = v3_comp(dpdx, i1);
  double by0 = v3_comp(dpdy, i0), by1 = v3_comp(dpdy, i1);
  OUT->dudx = (a11 * bx0 - a01 * bx1) * inv;
  OUT->dvdx = (a00 * bx1 - a10 * bx0) * inv;
  OUT->dudy = (a11 * by0 - a01 * by1) * inv;
  OUT->dvdy = (a00 * by1 - a10 * by0) * inv;
  return 1;
}

int scene_occluded_segment(const scene *s, vec3 p0, vec3 p1) {
  vec3 d = v3_sub(p1, p0);
  double len = v3_len(d);
  if (!(len > 0.0)) return 0;
  d = v3_scale(d, 1.0 / len);
  double e0 = scene_ray_eps(s, p0), e1 = scene_ray_eps(s, p1);
  if (len <= e0 + e1) return 0;
  return accel_occluded(s->accel, p0, d, e0, len - e1);
}

int scene_occluded_ray(const scene *s, vec3 p, vec3 dir) {
  return accel_occluded(s->accel, p, dir, scene_ray_eps(s, p), INFINITY);
}

int scene_sample_light(const scene *s, double u, double *OUT_pmf, double *OUT_u_remap) {
  if (s->n_lights == 0) {
    *OUT_pmf = 0.0;
    return -1;
  }
  return distrib1d_sample_discrete(&s->light_select, u, OUT_pmf, OUT_u_remap);
}

double scene_light_pmf(const scene *s, int index) {
  if (index < 0 || index >= s->n_lights) return 0.0;
  return distrib1d_pmf(&s->light_select, index);
}
