/*
 * mesh.h: triangle meshes, in world space.
 *
 * Every shape (obj, ply, serialized files and the built-in rectangle, cube,
 * sphere, disk, cylinder) becomes a triangle mesh with its toWorld transform
 * applied at load time. Positions are float (what Embree traces; the
 * buffer has one float of padding at the end, as rtcSetSharedGeometryBuffer
 * requires); normals and uvs are optional. `face_normals` ignores vertex
 * normals. The geometric normal of triangle (a, b, c) is normalize((b-a) x
 * (c-a)), flipped when `flip_normals` is set; area lights emit on its side.
 */
#ifndef LMC_RENDER_MESH_H
#define LMC_RENDER_MESH_H

#include <stdint.h>

#include "render/error.h"
#include "render/transform.h"
#include "render/vec3.h"

typedef struct mesh {
  int64_t n_vertices, n_triangles;
  float *p;       /* owned: 3 * n_vertices (+1 padding) */
  float *n;       /* owned or NULL: 3 * n_vertices, unit */
  float *uv;      /* owned or NULL: 2 * n_vertices */
  uint32_t *idx;  /* owned: 3 * n_triangles */
  int face_normals;
  int flip_normals;
  int bsdf;       /* index into scene->bsdfs */
  int light;      /* index into scene->lights, or -1 */
  char name[128]; /* for messages: "file.obj" or the XML id */
} mesh;

/* Allocates the arrays (normals/uvs only when asked). */
lmc_status mesh_alloc(mesh *m, int64_t n_vertices, int64_t n_triangles, int with_normals,
                      int with_uvs, lmc_error *err);
/* Frees the arrays; accepts NULL. */
void mesh_free(mesh *m);
/* Applies a transform to positions and normals (normals renormalised);
 * reverses the winding when the transform mirrors, so geometric normals
 * keep pointing outwards. */
void mesh_transform(mesh *m, const xform *t);
/* Drops degenerate triangles and checks indices and values; errors name
 * `file` and `line` (the XML element). Warns (with file and line) about
 * what it drops. */
lmc_status mesh_validate(mesh *m, const char *file, int line, lmc_error *err);

static inline vec3 mesh_position(const mesh *m, uint32_t i) {
  return v3(m->p[3 * i], m->p[3 * i + 1], m->p[3 * i + 2]);
}
/* Unit geometric normal of triangle `tri` (with flip_normals applied). */
vec3 mesh_face_normal(const mesh *m, int64_t tri);
/* The same normal from the triangle's corners p0, p1, p2 (mesh_position of
 * its three indices), for callers that have loaded them already. */
static inline vec3 mesh_corners_normal(const mesh *m, vec3 p0, vec3 p1, vec3 p2) {
  vec3 n = v3_normalize(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
  return m->flip_normals ? v3_neg(n) : n;
}
double mesh_triangle_area(const mesh *m, int64_t tri);
/* Mitsuba's maxSmoothAngle (TriMesh::rebuildTopology): corners that share a
 * position (and texture coordinates) share a vertex only where their
 * faces' normals are within max_angle_deg of the first face's of the
 * group (greedy, in triangle order); then smooth normals are made anew,
 * each vertex's the sum of its faces' normals weighted by the corner
 * angles (Thuermer and Wuethrich 1998), normalised. Normals the mesh had
 * are replaced. */
lmc_status mesh_rebuild_topology(mesh *m, double max_angle_deg, lmc_error *err);
/* The uv tangents of triangle `tri` (corners p0, p1, p2): dpdu and dpdv
 * with p - p0 = dpdu (u - u0) + dpdv (v - v0) over the triangle (Mitsuba's
 * TriMesh::computeUVTangents); where the uv triangle is degenerate, two
 * unit tangents orthogonal to the face. Returns 0 when the mesh has no
 * texture coordinates (bump maps need them, as Mitsuba's). */
int mesh_uv_tangents(const mesh *m, int64_t tri, vec3 p0, vec3 p1, vec3 p2, vec3 *OUT_dpdu,
                     vec3 *OUT_dpdv);
/* Ray-triangle intersection in double (Moller and Trumbore 1997) with
 * triangle `tri`, no bounds on t or the barycentrics: the hit Embree found
 * in float, recomputed to double precision. With e1 = p1 - p0,
 * e2 = p2 - p0, pv = dir x e2, det = e1 . pv, tv = org - p0, qv = tv x e1:
 *   b1 = (tv . pv) / det,  b2 = (dir . qv) / det,  t = (e2 . qv) / det,
 * each division a product with 1 / det. The differentiable path sampler
 * (path.c) evaluates this same formula in dual numbers. Returns 0 when the
 * ray is parallel to the triangle (det = 0). */
int mesh_intersect_triangle(const mesh *m, int64_t tri, vec3 org, vec3 dir, double *OUT_t,
                            double *OUT_b1, double *OUT_b2);
/* mesh_intersect_triangle on the triangle's corners p0, p1, p2. */
static inline int mesh_intersect_corners(vec3 p0, vec3 p1, vec3 p2, vec3 org, vec3 dir,
                                         double *OUT_t, double *OUT_b1, double *OUT_b2) {
  vec3 e1 = v3_sub(p1, p0), e2 = v3_sub(p2, p0);
  vec3 pv = v3_cross(dir, e2);
  double det = v3_dot(e1, pv);
  if (!(det != 0.0) || !isfinite(det)) return 0;
  double inv = 1.0 / det;
  vec3 tv = v3_sub(org, p0);
  vec3 qv = v3_cross(tv, e1);
  *OUT_b1 = v3_dot(tv, pv) * inv;
  *OUT_b2 = v3_dot(dir, qv) * inv;
  *OUT_t = v3_dot(e2, qv) * inv;
  return 1;
}

#endif
