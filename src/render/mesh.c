/*
 * mesh.c: triangle mesh storage, transformation and validation.
 *
 * A mesh is an indexed triangle list (see mesh.h). Positions are stored as
 * float because that is what Embree traces; every derived quantity here
 * (face normals, areas) is computed in double from those floats, so the
 * values the renderer uses match the geometry Embree intersects.
 *
 * Transformation. Points go through the affine map M; normals go through the
 * inverse transpose M^-T and are renormalised. The geometric normal of a
 * triangle (a, b, c) is (b - a) x (c - a); under a mirroring map
 * (det M < 0) the cross product of the mapped edges equals
 *   (M e1) x (M e2) = det(M) M^-T (e1 x e2),
 * i.e. it flips relative to the transformed normal. Swapping two indices of
 * every triangle undoes that flip, so geometric normals keep the side they
 * had in object space (the side an area light emits on).
 *
 * Validation. Loaders run mesh_validate on every mesh. Hard errors (an index
 * out of range, a NaN or infinite position, normal or uv) carry the file and
 * line given by the caller (the XML element). Soft problems are repaired
 * with a warning: zero-area triangles are dropped, zero-length vertex
 * normals are recomputed from the area-weighted normals of the adjacent
 * faces (and if that fails too, all vertex normals are dropped), an empty
 * mesh ends with zero triangles so the loader can skip it.
 */
#include "render/mesh.h"
#include "render/frame.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

lmc_status mesh_alloc(mesh *m, int64_t n_vertices, int64_t n_triangles, int with_normals,
                      int with_uvs, lmc_error *err) {
  /* Check the counts before any allocation: indices are uint32. */
  if (n_vertices < 0 || n_triangles < 0)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "mesh_alloc: negative count");
  if (n_vertices > (int64_t)UINT32_MAX || n_triangles > (int64_t)(SIZE_MAX / 12 / 4))
    return lmc_error_set(err, LMC_EUNSUPPORTED, NULL, 0,
                         "mesh too large (%lld vertices, %lld triangles)",
                         (long long)n_vertices, (long long)n_triangles);
  m->n_vertices = n_vertices;
  m->n_triangles = n_triangles;
  /* One float of padding after the positions, as Embree's shared buffers read 16 bytes. */
  m->p = calloc((size_t)(3 * n_vertices + 1), sizeof(float));
  m->n = with_normals ? calloc((size_t)(3 * n_vertices + 1), sizeof(float)) : NULL;
  m->uv = with_uvs ? calloc((size_t)(2 * n_vertices + 1), sizeof(float)) : NULL;
  m->idx = calloc((size_t)(3 * n_triangles + 1), sizeof(uint32_t));
  if (!m->p || !m->idx || (with_normals && !m->n) || (with_uvs && !m->uv)) {
    mesh_free(m);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory allocating a mesh of %lld vertices",
                         (long long)n_vertices);
  }
  return LMC_OK;
}

void mesh_free(mesh *m) {
  if (!m) return;
  free(m->p);
  free(m->n);
  free(m->uv);
  free(m->idx);
  m->p = NULL;
  m->n = NULL;
  m->uv = NULL;
  m->idx = NULL;
  m->n_vertices = 0;
  m->n_triangles = 0;
}

void mesh_transform(mesh *m, const xform *t) {
  for (int64_t i = 0; i < m->n_vertices; i++) {
    vec3 p = xform_point(t, v3(m->p[3 * i], m->p[3 * i + 1], m->p[3 * i + 2]));
    m->p[3 * i] = (float)p.x;
    m->p[3 * i + 1] = (float)p.y;
    m->p[3 * i + 2] = (float)p.z;
  }
  if (m->n) {
    /* Normals by the inverse transpose, renormalised (zero stays zero). */
    for (int64_t i = 0; i < m->n_vertices; i++) {
      vec3 n = xform_normal(t, v3(m->n[3 * i], m->n[3 * i + 1], m->n[3 * i + 2]));
      n = v3_normalize(n);
      m->n[3 * i] = (float)n.x;
      m->n[3 * i + 1] = (float)n.y;
      m->n[3 * i + 2] = (float)n.z;
    }
  }
  /* A mirroring map flips (b-a)x(c-a); swap b and c to restore the side. */
  if (xform_det3(t) < 0.0) {
    for (int64_t f = 0; f < m->n_triangles; f++) {
      uint32_t tmp = m->idx[3 * f + 1];
      m->idx[3 * f + 1] = m->idx[3 * f + 2];
      m->idx[3 * f + 2] = tmp;
    }
  }
}

/* Unnormalised (b - a) x (c - a) of triangle f, in double. */
static vec3 mesh__cross(const mesh *m, int64_t f) {
  vec3 a = mesh_position(m, m->idx[3 * f]);
  vec3 b = mesh_position(m, m->idx[3 * f + 1]);
  vec3 c = mesh_position(m, m->idx[3 * f + 2]);
  return v3_cross(v3_sub(b, a), v3_sub(c, a));
}

vec3 mesh_face_normal(const mesh *m, int64_t tri) {
  const uint32_t *idx = m->idx + 3 * tri;
  return mesh_corners_normal(m, mesh_position(m, idx[0]), mesh_position(m, idx[1]),
                             mesh_position(m, idx[2]));
}

double mesh_triangle_area(const mesh *m, int64_t tri) { return 0.5 * v3_len(mesh__cross(m, tri)); }

int mesh_uv_tangents(const mesh *m, int64_t tri, vec3 p0, vec3 p1, vec3 p2, vec3 *OUT_dpdu,
                     vec3 *OUT_dpdv) {
  if (!m->uv) return 0;
  const uint32_t *idx = m->idx + 3 * tri;
  const float *uv = m->uv;
  double u0 = uv[2 * idx[0]], v0 = uv[2 * idx[0] + 1];
  double du1 = uv[2 * idx[1]] - u0, dv1 = uv[2 * idx[1] + 1] - v0;
  double du2 = uv[2 * idx[2]] - u0, dv2 = uv[2 * idx[2] + 1] - v0;
  vec3 e1 = v3_sub(p1, p0), e2 = v3_sub(p2, p0);
  double det = du1 * dv2 - dv1 * du2;
  if (det == 0.0 || !isfinite(det)) {
    frame f = frame_from_z(v3_normalize(v3_cross(e1, e2)));
    *OUT_dpdu = f.s;
    *OUT_dpdv = f.t;
    return 1;
  }
  /* [e1 e2] = [dpdu dpdv] [du1 du2; dv1 dv2], inverted. */
  double inv = 1.0 / det;
  *OUT_dpdu = v3_scale(v3_sub(v3_scale(e1, dv2), v3_scale(e2, dv1)), inv);
  *OUT_dpdv = v3_scale(v3_sub(v3_scale(e2, du1), v3_scale(e1, du2)), inv);
  return 1;
}

int mesh_intersect_triangle(const mesh *m, int64_t tri, vec3 org, vec3 dir, double *OUT_t,
                            double *OUT_b1, double *OUT_b2) {
  const uint32_t *idx = m->idx + 3 * tri;
  return mesh_intersect_corners(mesh_position(m, idx[0]), mesh_position(m, idx[1]),
                                mesh_position(m, idx[2]), org, dir, OUT_t, OUT_b1, OUT_b2);
}

/* Recomputes every vertex normal whose length is zero from the area-weighted
 * normals of its faces (sum of (b-a)x(c-a), which weights by twice the area).
 * Returns the number of normals that could not be repaired. */
static int64_t mesh__repair_normals(mesh *m, int64_t *n_repaired) {
  int64_t bad = 0;
  *n_repaired = 0;
  unsigned char *zero = calloc((size_t)m->n_vertices + 1, 1);
  double *acc = calloc((size_t)(3 * m->n_vertices + 1), sizeof(double));
  if (!zero || !acc) {
    free(zero);
    free(acc);
    return m->n_vertices; /* cannot repair: caller drops the normals */
  }
  int64_t n_zero = 0;
  for (int64_t i = 0; i < m->n_vertices; i++) {
    double l2 = (double)m->n[3 * i] * m->n[3 * i] + (double)m->n[3 * i + 1] * m->n[3 * i + 1] +
                (double)m->n[3 * i + 2] * m->n[3 * i + 2];
    if (!(l2 > 0.0)) {
      zero[i] = 1;
      n_zero++;
    } else if (fabs(l2 - 1.0) > 1e-6) {
      double s = 1.0 / sqrt(l2);
      for (int k = 0; k < 3; k++) m->n[3 * i + k] = (float)(m->n[3 * i + k] * s);
    }
  }
  if (n_zero > 0) {
    for (int64_t f = 0; f < m->n_triangles; f++) {
      vec3 c = mesh__cross(m, f);
      for (int k = 0; k < 3; k++) {
        uint32_t v = m->idx[3 * f + k];
        if (!zero[v]) continue;
        zero[v] = 2; /* referenced */
        acc[3 * v] += c.x;
        acc[3 * v + 1] += c.y;
        acc[3 * v + 2] += c.z;
      }
    }
    for (int64_t i = 0; i < m->n_vertices; i++) {
      if (!zero[i]) continue;
      vec3 n = v3(acc[3 * i], acc[3 * i + 1], acc[3 * i + 2]);
      double l = v3_len(n);
      if (l > 0.0 && isfinite(l)) {
        m->n[3 * i] = (float)(n.x / l);
        m->n[3 * i + 1] = (float)(n.y / l);
        m->n[3 * i + 2] = (float)(n.z / l);
        (*n_repaired)++;
      } else if (zero[i] == 1) {
        /* No triangle uses this vertex: any unit vector will do. */
        m->n[3 * i] = 0.0f;
        m->n[3 * i + 1] = 0.0f;
        m->n[3 * i + 2] = 1.0f;
      } else {
        bad++;
      }
    }
  }
  free(zero);
  free(acc);
  return bad;
}

lmc_status mesh_validate(mesh *m, const char *file, int line, lmc_error *err) {
  const char *name = m->name[0] ? m->name : "mesh";

  /* Indices in range. */
  for (int64_t f = 0; f < m->n_triangles; f++) {
    for (int k = 0; k < 3; k++) {
      if ((int64_t)m->idx[3 * f + k] >= m->n_vertices)
        return lmc_error_set(err, LMC_EPARSE, file, line,
                             "%s: triangle %lld refers to vertex %lu, but there are %lld vertices",
                             name, (long long)f, (unsigned long)m->idx[3 * f + k],
                             (long long)m->n_vertices);
    }
  }

  /* Finite positions, normals and uvs. */
  for (int64_t i = 0; i < 3 * m->n_vertices; i++) {
    if (!isfinite(m->p[i]))
      return lmc_error_set(err, LMC_EPARSE, file, line, "%s: vertex %lld has a non-finite position",
                           name, (long long)(i / 3));
    if (m->n && !isfinite(m->n[i]))
      return lmc_error_set(err, LMC_EPARSE, file, line, "%s: vertex %lld has a non-finite normal",
                           name, (long long)(i / 3));
  }
  if (m->uv) {
    for (int64_t i = 0; i < 2 * m->n_vertices; i++)
      if (!isfinite(m->uv[i]))
        return lmc_error_set(err, LMC_EPARSE, file, line,
                             "%s: vertex %lld has a non-finite texture coordinate", name,
                             (long long)(i / 2));
  }

  /* Drop zero-area triangles, compacting the index array in place. */
  int64_t kept = 0;
  for (int64_t f = 0; f < m->n_triangles; f++) {
    vec3 c = mesh__cross(m, f);
    if (!(v3_len2(c) > 0.0)) continue;
    if (kept != f) memmove(&m->idx[3 * kept], &m->idx[3 * f], 3 * sizeof(uint32_t));
    kept++;
  }
  if (kept != m->n_triangles) {
    lmc_warn(file, line, "%s: dropped %lld zero-area triangle(s) of %lld", name,
             (long long)(m->n_triangles - kept), (long long)m->n_triangles);
    m->n_triangles = kept;
  }
  if (m->n_triangles == 0) {
    lmc_warn(file, line, "%s: the mesh has no triangles", name);
    return LMC_OK;
  }

  /* Unit vertex normals: recompute zero ones, or drop them all. */
  if (m->n) {
    int64_t repaired = 0;
    int64_t bad = mesh__repair_normals(m, &repaired);
    if (bad > 0) {
      lmc_warn(file, line, "%s: %lld vertex normal(s) of zero length; vertex normals dropped", name,
               (long long)bad);
      free(m->n);
      m->n = NULL;
    } else if (repaired > 0) {
      lmc_warn(file, line, "%s: recomputed %lld zero-length vertex normal(s)", name,
               (long long)repaired);
    }
  }
  return LMC_OK;
}

/* ---- maxSmoothAngle ------------------------------------------------------- */

/* A corner of a triangle, for sorting by its vertex's position and uv. */
typedef struct mesh__corner {
  float key[5]; /* x, y, z, u, v (u = v = 0 without uv) */
  int64_t tri;
  int j;        /* corner 0, 1, 2 */
} mesh__corner;

static int mesh__corner_cmp(const void *pa, const void *pb) {
  const mesh__corner *a = pa, *b = pb;
  for (int k = 0; k < 5; k++)
    if (a->key[k] != b->key[k]) return a->key[k] < b->key[k] ? -1 : 1;
  /* Equal keys keep triangle order (Mitsuba's multimap keeps insertion order). */
  int64_t ia = 3 * a->tri + a->j, ib = 3 * b->tri + b->j;
  return ia < ib ? -1 : ia > ib;
}

/* The angle between unit vectors a and b, accurate also near 0 and pi. */
static double mesh__unit_angle(vec3 a, vec3 b) {
  if (v3_dot(a, b) < 0.0) return M_PI - 2.0 * asin(0.5 * v3_len(v3_add(a, b)));
  return 2.0 * asin(0.5 * v3_len(v3_sub(b, a)));
}

lmc_status mesh_rebuild_topology(mesh *m, double max_angle_deg, lmc_error *err) {
  const int64_t nt = m->n_triangles, nc = 3 * nt;
  const double dp_thresh = cos(max_angle_deg * M_PI / 180.0);
  mesh__corner *c = malloc((size_t)(nc + 1) * sizeof *c);
  vec3 *fn = malloc((size_t)(nt + 1) * sizeof *fn);
  uint32_t *new_idx = malloc((size_t)(nc + 1) * sizeof *new_idx);
  if (!c || !fn || !new_idx) {
    free(c), free(fn), free(new_idx);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory rebuilding a mesh");
  }
  for (int64_t t = 0; t < nt; t++) {
    const uint32_t *tri = m->idx + 3 * t;
    vec3 p0 = mesh_position(m, tri[0]), p1 = mesh_position(m, tri[1]), p2 = mesh_position(m, tri[2]);
    vec3 n = v3_cross(v3_sub(p1, p0), v3_sub(p2, p0));
    double l = v3_len(n);
    fn[t] = l > 0.0 && isfinite(l) ? v3_scale(n, 1.0 / l) : v3(0.0, 0.0, 0.0);
    for (int j = 0; j < 3; j++) {
      mesh__corner *k = &c[3 * t + j];
      uint32_t v = tri[j];
      k->key[0] = m->p[3 * v], k->key[1] = m->p[3 * v + 1], k->key[2] = m->p[3 * v + 2];
      k->key[3] = m->uv ? m->uv[2 * v] : 0.0f;
      k->key[4] = m->uv ? m->uv[2 * v + 1] : 0.0f;
      k->tri = t, k->j = j;
    }
  }
  qsort(c, (size_t)nc, sizeof *c, mesh__corner_cmp);
  /* Greedy clustering within each group of equal keys: an unclustered
   * corner opens a vertex, which every later unclustered corner of the
   * group whose face normal is within the angle of the opener's joins. */
  int64_t nv = 0;
  unsigned char *done = calloc((size_t)nc + 1, 1);
  int64_t *opener = malloc((size_t)(nc + 1) * sizeof *opener); /* corner that opened vertex v */
  if (!done || !opener) {
    free(c), free(fn), free(new_idx), free(done), free(opener);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory rebuilding a mesh");
  }
  for (int64_t g = 0; g < nc;) {
    int64_t end = g + 1;
    while (end < nc && memcmp(c[end].key, c[g].key, sizeof c[g].key) == 0) end++;
    for (int64_t a = g; a < end; a++) {
      if (done[a]) continue;
      vec3 n1 = fn[c[a].tri];
      opener[nv] = a;
      for (int64_t b = a; b < end; b++) {
        if (done[b]) continue;
        vec3 n2 = fn[c[b].tri];
        int same = n1.x == n2.x && n1.y == n2.y && n1.z == n2.z;
        if (same || v3_dot(n1, n2) > dp_thresh) {
          new_idx[3 * c[b].tri + c[b].j] = (uint32_t)nv;
          done[b] = 1;
        }
      }
      nv++;
    }
    g = end;
  }
  /* The new mesh: positions and uv from each vertex's opener, smooth
   * normals from the corner-angle-weighted face normals. */
  mesh r = *m;
  r.p = r.n = r.uv = NULL;
  r.idx = NULL;
  lmc_status st = mesh_alloc(&r, nv, nt, 1, m->uv != NULL, err);
  if (st == LMC_OK) {
    for (int64_t v = 0; v < nv; v++) {
      const mesh__corner *k = &c[opener[v]];
      uint32_t src = m->idx[3 * k->tri + k->j];
      memcpy(r.p + 3 * v, m->p + 3 * src, 3 * sizeof(float));
      if (m->uv) memcpy(r.uv + 2 * v, m->uv + 2 * src, 2 * sizeof(float));
    }
    memcpy(r.idx, new_idx, (size_t)nc * sizeof *new_idx);
    double *acc = calloc((size_t)(3 * nv + 1), sizeof *acc);
    if (!acc) st = lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory rebuilding a mesh");
    for (int64_t t = 0; acc && t < nt; t++) {
      if (fn[t].x == 0.0 && fn[t].y == 0.0 && fn[t].z == 0.0) continue;
      for (int j = 0; j < 3; j++) {
        uint32_t v0 = r.idx[3 * t + j], v1 = r.idx[3 * t + (j + 1) % 3], v2 = r.idx[3 * t + (j + 2) % 3];
        vec3 a = v3_sub(mesh_position(&r, v1), mesh_position(&r, v0));
        vec3 b = v3_sub(mesh_position(&r, v2), mesh_position(&r, v0));
        if (!(v3_len2(a) > 0.0) || !(v3_len2(b) > 0.0)) continue;
        double w = mesh__unit_angle(v3_normalize(a), v3_normalize(b));
        acc[3 * v0] += w * fn[t].x, acc[3 * v0 + 1] += w * fn[t].y, acc[3 * v0 + 2] += w * fn[t].z;
      }
    }
    for (int64_t v = 0; acc && v < nv; v++) {
      vec3 n = v3(acc[3 * v], acc[3 * v + 1], acc[3 * v + 2]);
      double l = v3_len(n);
      n = l > 0.0 ? v3_scale(n, 1.0 / l) : v3(1.0, 0.0, 0.0); /* Mitsuba's value for none */
      r.n[3 * v] = (float)n.x, r.n[3 * v + 1] = (float)n.y, r.n[3 * v + 2] = (float)n.z;
    }
    free(acc);
  }
  free(c), free(fn), free(new_idx), free(done), free(opener);
  if (st != LMC_OK) {
    mesh_free(&r);
    return st;
  }
  mesh_free(m);
  *m = r;
  return LMC_OK;
}

