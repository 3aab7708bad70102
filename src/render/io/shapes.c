/*
 * shapes.c: Mitsuba's built-in shapes as triangle meshes, in object space.
 *
 * Each shape follows Mitsuba 0.6's definition of the analytic shape and its
 * (u, v) parameterisation, so textures land where Mitsuba puts them:
 *   rectangle  [-1,1]^2 in z = 0, normal +z, uv = ((x+1)/2, (y+1)/2).
 *   cube       [-1,1]^3, 6 faces of 2 triangles, 24 vertices (4 per face so
 *              each face has its own normal and a [0,1]^2 uv square),
 *              face_normals set.
 *   sphere     center c, radius r. A UV sphere: with theta the polar angle
 *              from +z and phi the azimuth from +x,
 *                p = c + r (sin th cos ph, sin th sin ph, cos th),
 *                n = (p - c) / r  (exact, stored per vertex),
 *                uv = (ph / 2pi, th / pi)  (Mitsuba's sphere).
 *              The seam column is duplicated so uv is continuous; at each
 *              pole the quads degenerate to one triangle per segment.
 *   disk       unit disk in z = 0, normal +z, uv = (r, ph / 2pi) (Mitsuba's
 *              disk); the center vertex is repeated per segment so v is
 *              continuous across the fan.
 *   cylinder   radius r around the axis p0 -> p1, open ends, outward vertex
 *              normals, uv = (ph / 2pi, t) with t in [0,1] along the axis.
 * Triangles are wound so (b - a) x (c - a) points outward (or +z).
 * The tessellation error of a chord polygon with N segments is about
 * (2 pi / N)^2 / 24 relative in area, ~1e-4 for the defaults below.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "render/io/io.h"

#define SHAPE_PI 3.14159265358979323846

enum {
  SHAPE_SPHERE_THETA = 64,  /* bands from pole to pole */
  SHAPE_SPHERE_PHI = 128,   /* segments around z */
  SHAPE_DISK_SEGMENTS = 128,
  SHAPE_CYLINDER_SEGMENTS = 128
};

static void shape__begin(mesh *m, const char *name) {
  memset(m, 0, sizeof *m);
  m->light = -1;
  snprintf(m->name, sizeof m->name, "%s", name);
}

static void shape__set(mesh *m, int64_t i, vec3 p, vec3 n, double u, double v) {
  m->p[3 * i] = (float)p.x;
  m->p[3 * i + 1] = (float)p.y;
  m->p[3 * i + 2] = (float)p.z;
  if (m->n) {
    m->n[3 * i] = (float)n.x;
    m->n[3 * i + 1] = (float)n.y;
    m->n[3 * i + 2] = (float)n.z;
  }
  if (m->uv) {
    m->uv[2 * i] = (float)u;
    m->uv[2 * i + 1] = (float)v;
  }
}

static void shape__tri(mesh *m, int64_t *t, int64_t a, int64_t b, int64_t c) {
  m->idx[3 * *t] = (uint32_t)a;
  m->idx[3 * *t + 1] = (uint32_t)b;
  m->idx[3 * *t + 2] = (uint32_t)c;
  (*t)++;
}

lmc_status shape_rectangle(mesh *OUT_mesh, lmc_error *err) {
  shape__begin(OUT_mesh, "rectangle");
  lmc_status st = mesh_alloc(OUT_mesh, 4, 2, 1, 1, err);
  if (st != LMC_OK) return st;
  vec3 n = v3(0, 0, 1);
  shape__set(OUT_mesh, 0, v3(-1, -1, 0), n, 0, 0);
  shape__set(OUT_mesh, 1, v3(1, -1, 0), n, 1, 0);
  shape__set(OUT_mesh, 2, v3(1, 1, 0), n, 1, 1);
  shape__set(OUT_mesh, 3, v3(-1, 1, 0), n, 0, 1);
  int64_t t = 0;
  shape__tri(OUT_mesh, &t, 0, 1, 2);
  shape__tri(OUT_mesh, &t, 0, 2, 3);
  return LMC_OK;
}

lmc_status shape_cube(mesh *OUT_mesh, lmc_error *err) {
  shape__begin(OUT_mesh, "cube");
  lmc_status st = mesh_alloc(OUT_mesh, 24, 12, 1, 1, err);
  if (st != LMC_OK) return st;
  OUT_mesh->face_normals = 1;
  /* Each face: its outward normal n and two tangents s, t with s x t = n;
   * corners are n + (+-1) s + (+-1) t, counter-clockwise seen from outside. */
  int64_t v = 0, t = 0;
  for (int axis = 0; axis < 3; axis++) {
    for (int sign = -1; sign <= 1; sign += 2) {
      double e[3] = {0, 0, 0};
      e[axis] = sign;
      vec3 n = v3(e[0], e[1], e[2]);
      double a1[3] = {0, 0, 0}, a2[3] = {0, 0, 0};
      a1[(axis + 1) % 3] = 1;
      a2[(axis + 2) % 3] = 1;
      vec3 s = v3(a1[0], a1[1], a1[2]);
      vec3 tt = v3(a2[0], a2[1], a2[2]);
      if (sign < 0) tt = v3_neg(tt); /* keep s x t = n */
      static const double corner[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
      for (int c = 0; c < 4; c++) {
        vec3 p = v3_add(n, v3_add(v3_scale(s, corner[c][0]), v3_scale(tt, corner[c][1])));
        shape__set(OUT_mesh, v + c, p, n, 0.5 * (corner[c][0] + 1), 0.5 * (corner[c][1] + 1));
      }
      shape__tri(OUT_mesh, &t, v, v + 1, v + 2);
      shape__tri(OUT_mesh, &t, v, v + 2, v + 3);
      v += 4;
    }
  }
  return LMC_OK;
}

lmc_status shape_sphere(vec3 center, double radius, mesh *OUT_mesh, lmc_error *err) {
  shape__begin(OUT_mesh, "sphere");
  if (!(radius > 0.0) || !isfinite(radius) || !v3_isfinite(center))
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "sphere: invalid radius %g", radius);
  const int nt = SHAPE_SPHERE_THETA, np = SHAPE_SPHERE_PHI;
  /* Quads in the inner bands, one triangle per segment in the two polar bands. */
  int64_t n_vert = (int64_t)(nt + 1) * (np + 1);
  int64_t n_tri = 2 * (int64_t)np * (nt - 2) + 2 * (int64_t)np;
  lmc_status st = mesh_alloc(OUT_mesh, n_vert, n_tri, 1, 1, err);
  if (st != LMC_OK) return st;
  for (int i = 0; i <= nt; i++) {
    double th = SHAPE_PI * i / nt;
    double st_ = i == nt ? 0.0 : sin(th), ct = i == 0 ? 1.0 : (i == nt ? -1.0 : cos(th));
    for (int j = 0; j <= np; j++) {
      double ph = 2.0 * SHAPE_PI * j / np;
      vec3 n = v3(st_ * cos(ph), st_ * sin(ph), ct);
      shape__set(OUT_mesh, (int64_t)i * (np + 1) + j, v3_fma(center, n, radius), n,
                 (double)j / np, (double)i / nt);
    }
  }
  /* (i,j) -> (i+1,j) steps along e_theta, (i,j) -> (i,j+1) along e_phi, and
   * e_theta x e_phi = e_r: triangles (a, below, below-right) face outward. */
  int64_t t = 0;
  for (int i = 0; i < nt; i++) {
    for (int j = 0; j < np; j++) {
      int64_t a = (int64_t)i * (np + 1) + j, b = a + (np + 1), c = b + 1, d = a + 1;
      if (i != nt - 1) shape__tri(OUT_mesh, &t, a, b, c);
      if (i != 0) shape__tri(OUT_mesh, &t, a, c, d);
    }
  }
  return LMC_OK;
}

lmc_status shape_disk(mesh *OUT_mesh, lmc_error *err) {
  shape__begin(OUT_mesh, "disk");
  const int ns = SHAPE_DISK_SEGMENTS;
  /* ns center copies, then ns + 1 rim vertices (seam duplicated). */
  lmc_status st = mesh_alloc(OUT_mesh, 2 * ns + 1, ns, 1, 1, err);
  if (st != LMC_OK) return st;
  vec3 n = v3(0, 0, 1);
  for (int j = 0; j < ns; j++) shape__set(OUT_mesh, j, v3(0, 0, 0), n, 0.0, (j + 0.5) / ns);
  for (int j = 0; j <= ns; j++) {
    double ph = 2.0 * SHAPE_PI * j / ns;
    double c = j == ns ? 1.0 : cos(ph), s = j == ns ? 0.0 : sin(ph);
    shape__set(OUT_mesh, ns + j, v3(c, s, 0), n, 1.0, (double)j / ns);
  }
  int64_t t = 0;
  for (int j = 0; j < ns; j++) shape__tri(OUT_mesh, &t, j, ns + j, ns + j + 1);
  return LMC_OK;
}

lmc_status shape_cylinder(vec3 p0, vec3 p1, double radius, mesh *OUT_mesh, lmc_error *err) {
  shape__begin(OUT_mesh, "cylinder");
  vec3 axis = v3_sub(p1, p0);
  double len = v3_len(axis);
  if (!(radius > 0.0) || !isfinite(radius) || !(len > 0.0) || !isfinite(len))
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "cylinder: invalid radius or axis");
  /* An orthonormal frame (x, y, z) with z along the axis (Duff et al. 2017). */
  vec3 z = v3_scale(axis, 1.0 / len);
  double sgn = z.z >= 0.0 ? 1.0 : -1.0;
  double a = -1.0 / (sgn + z.z), b = z.x * z.y * a;
  vec3 x = v3(1.0 + sgn * z.x * z.x * a, sgn * b, -sgn * z.x);
  vec3 y = v3(b, sgn + z.y * z.y * a, -z.y);
  const int ns = SHAPE_CYLINDER_SEGMENTS;
  lmc_status st = mesh_alloc(OUT_mesh, 2 * (ns + 1), 2 * ns, 1, 1, err);
  if (st != LMC_OK) return st;
  for (int j = 0; j <= ns; j++) {
    double ph = 2.0 * SHAPE_PI * j / ns;
    double c = j == ns ? 1.0 : cos(ph), s = j == ns ? 0.0 : sin(ph);
    vec3 n = v3_add(v3_scale(x, c), v3_scale(y, s));
    shape__set(OUT_mesh, j, v3_fma(p0, n, radius), n, (double)j / ns, 0.0);
    shape__set(OUT_mesh, ns + 1 + j, v3_fma(p1, n, radius), n, (double)j / ns, 1.0);
  }
  /* e_phi x e_z = e_r: (bottom j, bottom j+1, top j+1) faces outward. */
  int64_t t = 0;
  for (int j = 0; j < ns; j++) {
    int64_t b0 = j, b1 = j + 1, t0 = ns + 1 + j, t1 = t0 + 1;
    shape__tri(OUT_mesh, &t, b0, b1, t1);
    shape__tri(OUT_mesh, &t, b0, t1, t0);
  }
  return LMC_OK;
}
