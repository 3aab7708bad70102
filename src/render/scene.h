/*
 * scene.h: the scene, immutable after loading and shared read-only by all
 * threads.
 *
 * The loader (io/scene_xml.c) fills the arrays through the scene_add_*
 * functions, then scene_finalize computes bounds, builds the accelerator and
 * the light distributions. Everything the scene points to it owns.
 */
#ifndef LMC_RENDER_SCENE_H
#define LMC_RENDER_SCENE_H

#include "render/accel.h"
#include "render/bsdf/bsdf.h"
#include "render/camera.h"
#include "render/distribution.h"
#include "render/film.h"
#include "render/frame.h"
#include "render/lights/light.h"
#include "render/media/medium.h"
#include "render/mesh.h"
#include "render/settings.h"

/* A parameter of the scene's <integrator> or <dpt> block that the loader
 * passes on as it stands (its value as text): the integrators' own
 * settings, applied with their option tables (render/options.h). */
typedef struct scene_param {
  char name[64];
  char value[256];
  char file[512];
  int line;
  int is_bool; /* the value came from a <boolean> ("true" / "false") */
} scene_param;

typedef struct scene {
  char path[512];          /* the scene file, for messages */
  mesh *meshes;
  int n_meshes, cap_meshes;
  bsdf *bsdfs;
  int n_bsdfs, cap_bsdfs;
  light *lights;
  int n_lights, cap_lights;
  medium *media;           /* participating media (rendered by pt; scene_media_note) */
  int n_media, cap_media;
  lmc_image *images;       /* texture images (pointers into it are stable after finalize) */
  int n_images, cap_images;
  int tex_filtered;        /* some BSDF has a MIP-filtered texture (tex_is_filtered) */
  int *infinite_lights;    /* indices of constant/envmap lights */
  int n_infinite;
  camera cam;
  film_filter filter;
  render_settings settings; /* from the scene's <integrator>/<dpt> */
  scene_param *params;      /* the rest of those blocks' parameters (owned) */
  int n_params;
  vec3 bounds_min, bounds_max;
  vec3 center;
  double radius;           /* bounding sphere radius (> 0) */
  distrib1d light_select;  /* light choice, in proportion to power */
  accel *accel;            /* every surface with a BSDF */
  accel *accel_media;      /* the same and the index-matched medium boundaries; NULL when
                              there are none (scene_intersect_media uses accel) */
  int ambient_medium;      /* the medium (1-based; 0: none) outside every shape that bounds
                              media: the camera's, when the camera lies outside them all */
  int finalized;
} scene;

/* Surface point found by a ray, with everything shading needs. */
typedef struct surface_hit {
  double t;
  int mesh;
  int64_t prim;
  double b1, b2;   /* barycentrics */
  vec3 p;          /* position */
  vec3 ng;         /* unit geometric normal, on the shading normal's side (mesh.h's
                      mesh_hit_normals; the emitting side for area lights) */
  frame sh;        /* shading frame (sh.n: the interpolated vertex normal, or ng) */
  double tu, tv;   /* texture coordinates */
  const bsdf *bsdf;
  int light;       /* area light index, or -1 */
} surface_hit;

lmc_status scene_create(scene **out, lmc_error *err);
void scene_destroy(scene *s);
/* Each returns the index of the added element, or a negative status.
 * scene_add_mesh takes ownership of the mesh's arrays. */
int scene_add_bsdf(scene *s, const bsdf *b, lmc_error *err);
int scene_add_mesh(scene *s, mesh *m, lmc_error *err);
int scene_add_light(scene *s, const light *l, lmc_error *err);
/* Copies a medium into the scene; returns its index or a negative status. */
int scene_add_medium(scene *s, const medium *m, lmc_error *err);
/* Takes ownership of img's pixels; returns the index. Pointers to scene
 * images are only valid after scene_finalize (the array may grow before). */
int scene_add_image(scene *s, lmc_image *img, lmc_error *err);
lmc_status scene_finalize(scene *s, lmc_error *err);

/* Closest surface along the ray (dir unit), with t in (tmin, tmax). */
int scene_intersect(const scene *s, vec3 org, vec3 dir, double tmin, double tmax,
                    surface_hit *OUT_hit);
/* The same among the surfaces and the index-matched boundaries between
 * media (mesh.h: bsdf -1), whose hits have bsdf NULL: what the
 * integrators that render media trace. */
int scene_intersect_media(const scene *s, vec3 org, vec3 dir, double tmin, double tmax,
                          surface_hit *OUT_hit);
/* The medium (1 + index into s->media; 0: none) a ray along dir enters
 * crossing mesh mesh_index where its geometric normal is ng, having come
 * in medium cur: the shape's exterior when dir leaves on the side of ng,
 * else its interior, for a shape that bounds media (Mitsuba's
 * getTargetMedium); cur for one that does not. scene_medium_after: the
 * same at a hit h (the dual path's hits give their mesh and ng). */
static inline int scene_medium_across(const scene *s, int mesh_index, vec3 ng, int cur,
                                      vec3 dir) {
  const mesh *m = &s->meshes[mesh_index];
  if (!m->interior && !m->exterior) return cur;
  return v3_dot(dir, ng) > 0.0 ? m->exterior : m->interior;
}
static inline int scene_medium_after(const scene *s, const surface_hit *h, int cur, vec3 dir) {
  return scene_medium_across(s, h->mesh, h->ng, cur, dir);
}
/* The medium (1-based; 0: none) around point p, from the side a probe ray
 * arrives at the first shape that bounds media (skipping the mesh `skip`,
 * -1: none); -1 when the probe meets none. */
int scene_locate_medium(const scene *s, vec3 p, int skip);
/* The medium by its 1-based index (0: NULL, none). */
static inline const medium *scene_medium(const scene *s, int index) {
  return index > 0 ? &s->media[index - 1] : NULL;
}
/* The footprint on the texture coordinates of the camera ray's hit h: the
 * rays from org along dx and dy (the ray differentials, unit or not) meet
 * h's tangent plane at p + dpdx and p + dpdy, and (du, dv) solve
 * dpdx = dpdu du + dpdv dv on the two coordinate axes the normal is least
 * along (Mitsuba's Intersection::computePartials, after pbrt); a mesh
 * without texture coordinates has u = b1, v = b2. Returns 0 (and no
 * footprint) when a differential is parallel to the plane. */
int scene_tex_footprint(const scene *s, const surface_hit *h, vec3 org, vec3 dx, vec3 dy,
                        tex_footprint *OUT);
/* 1 when the segment from p0 to p1 is blocked (endpoints excluded). */
int scene_occluded_segment(const scene *s, vec3 p0, vec3 p1);
/* 1 when the ray from p along dir hits anything (towards an infinite light). */
int scene_occluded_ray(const scene *s, vec3 p, vec3 dir);
/* Offset for rays leaving point p, relative to the scene's scale. */
double scene_ray_eps(const scene *s, vec3 p);

/* Light choice: index of the light for u, with its probability. */
int scene_sample_light(const scene *s, double u, double *OUT_pmf, double *OUT_u_remap);
double scene_light_pmf(const scene *s, int index);

#endif
