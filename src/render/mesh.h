/*
 * mesh.h: triangle meshes, in world space.
 *
 * Every shape (obj, ply, serialized files and the built-in rectangle, cube,
 * sphere, disk, cylinder) becomes a triangle mesh with its toWorld transform
 * applied at load time. Positions are float (what Embree traces; the
 * buffer has one float of padding at the end, as rtcSetSharedGeometryBuffer
 * requires); normals and uvs are optional. `face_normals` ignores vertex
 * normals.
 *
 * Which side a surface faces, as Mitsuba 0.6 decides it (TriMesh::
 * computeNormals, and ShapeKDTree::fillIntersectionRecord: "Ensure that
 * the geometric & shading normals face the same direction"). The winding
 * normal of triangle (a, b, c) is normalize((b-a) x (c-a)), reversed when
 * `flip_normals` is set (Mitsuba reverses the winding under faceNormals,
 * and negates the normals it generates for a mesh that has none). Where
 * vertex normals are used (present, `face_normals` off) they decide
 * instead: `flip_normals` reverses them (Mitsuba negates the stored
 * normals before any hit is made), the shading normal is their
 * interpolation, and the geometric normal is the winding normal turned to
 * agree with it (mesh_hit_normals). So a one-sided surface faces where its
 * vertex normals say, whatever its winding; BSDFs, area lights (which emit
 * on the side of this geometric normal), the path evaluators and the
 * emitters' sampled points all take their side from mesh_hit_normals.
 */
#ifndef LMC_RENDER_MESH_H
#define LMC_RENDER_MESH_H

#include <stddef.h>
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
  int bsdf;       /* index into scene->bsdfs; -1: an index-matched boundary between media
                     (no BSDF: light crosses it unchanged), which only the integrators that
                     render media see (scene_intersect_media) */
  int light;      /* index into scene->lights, or -1 */
  int interior;   /* 1 + index into scene->media of the medium inside it; 0: none */
  int exterior;   /* the same for the medium outside it */
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
/* Unit winding normal of triangle `tri` (with flip_normals applied): the
 * side the triangle faces when the mesh's vertex normals are not used; a
 * hit's geometric normal is mesh_hit_normals'. */
vec3 mesh_face_normal(const mesh *m, int64_t tri);
/* The same normal from the triangle's corners p0, p1, p2 (mesh_position of
 * its three indices), for callers that have loaded them already. */
static inline vec3 mesh_corners_normal(const mesh *m, vec3 p0, vec3 p1, vec3 p2) {
  vec3 n = v3_normalize(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
  return m->flip_normals ? v3_neg(n) : n;
}
/* 1 when hits on the mesh interpolate its vertex normals. */
static inline int mesh_uses_vertex_normals(const mesh *m) {
  return m->n != NULL && !m->face_normals;
}
/* Vertex normal i as shading uses it: reversed when flip_normals is set
 * (Mitsuba's computeNormals negates the stored normals). */
static inline vec3 mesh_vertex_normal(const mesh *m, uint32_t i) {
  vec3 n = v3(m->n[3 * i], m->n[3 * i + 1], m->n[3 * i + 2]);
  return m->flip_normals ? v3_neg(n) : n;
}
/* The normals of the point with barycentrics (b1, b2) on triangle `tri`
 * (corners p0, p1, p2), oriented as Mitsuba orients them (see the top of
 * this file): returns the unit geometric normal, and *OUT_ns (may be NULL)
 * gets the unit shading normal, the interpolated vertex normal. Without
 * used vertex normals, or where they interpolate to zero, both are the
 * winding normal. The turn is a choice of sign on values only: the dual
 * hit (path.c) makes the same choice and its derivatives follow it. */
static inline vec3 mesh_hit_normals(const mesh *m, int64_t tri, vec3 p0, vec3 p1, vec3 p2,
                                    double b1, double b2, vec3 *OUT_ns) {
  vec3 ng = mesh_corners_normal(m, p0, p1, p2);
  vec3 ns = ng;
  if (mesh_uses_vertex_normals(m)) {
    const uint32_t *idx = m->idx + 3 * tri;
    double b0 = 1.0 - b1 - b2;
    vec3 ni = v3_add(v3_add(v3_scale(mesh_vertex_normal(m, idx[0]), b0),
                            v3_scale(mesh_vertex_normal(m, idx[1]), b1)),
                     v3_scale(mesh_vertex_normal(m, idx[2]), b2));
    double l = v3_len(ni);
    if (l > 1e-12) {
      /* The geometric normal turns to the shading normal's side. */
      ns = v3_scale(ni, 1.0 / l);
      if (v3_dot(ng, ns) < 0.0) ng = v3_neg(ng);
    }
  }
  if (OUT_ns) *OUT_ns = ns;
  return ng;
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
