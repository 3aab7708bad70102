/*
 * test_mesh_io.c: mesh readers (OBJ, PLY, Mitsuba serialized), built-in
 * shapes, and mesh_transform / mesh_validate.
 *
 * Hand-written OBJ/PLY files live in tests/data/mesh; binary PLY and
 * serialized files are generated here into /tmp. The torus scene's
 * meshes.serialized (in ../shared) is read when present.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include <cmocka.h>

#include "test_util.h"

#include "render/io/io.h"
#include "render/mesh.h"

#define PI 3.14159265358979323846

static void check_ok(lmc_status st, const lmc_error *err) {
  if (st != LMC_OK) {
    char buf[2048];
    lmc_error_format(err, buf, sizeof buf);
    fail_msg("unexpected error: %s", buf);
  }
}

static double total_area(const mesh *m) {
  double a = 0.0;
  for (int64_t t = 0; t < m->n_triangles; t++) a += mesh_triangle_area(m, t);
  return a;
}

/* Enclosed volume by the divergence theorem: V = (1/6) sum a . (b x c). */
static double volume(const mesh *m) {
  double v = 0.0;
  for (int64_t t = 0; t < m->n_triangles; t++) {
    vec3 a = mesh_position(m, m->idx[3 * t]), b = mesh_position(m, m->idx[3 * t + 1]),
         c = mesh_position(m, m->idx[3 * t + 2]);
    v += v3_dot(a, v3_cross(b, c)) / 6.0;
  }
  return v;
}

/* Number of triangles whose face normal points away from `center`. */
static int64_t count_outward(const mesh *m, vec3 center) {
  int64_t n = 0;
  for (int64_t t = 0; t < m->n_triangles; t++) {
    vec3 c = v3_scale(v3_add(v3_add(mesh_position(m, m->idx[3 * t]), mesh_position(m, m->idx[3 * t + 1])),
                             mesh_position(m, m->idx[3 * t + 2])),
                      1.0 / 3.0);
    if (v3_dot(mesh_face_normal(m, t), v3_sub(c, center)) > 0.0) n++;
  }
  return n;
}

static int write_file(const char *path, const void *data, size_t n) {
  FILE *f = fopen(path, "wb");
  if (!f) return 0;
  size_t w = fwrite(data, 1, n, f);
  fclose(f);
  return w == n;
}

/* ---- OBJ --------------------------------------------------------------- */

static void test_obj_quad(void **state) {
  (void)state;
  mesh m;
  lmc_error err;
  check_ok(mesh_read_obj("data/mesh/quad.obj", &m, &err), &err);
  /* 4 distinct (v, vt, vn) triples; quad (2 triangles) + triangle. */
  assert_int_equal(m.n_vertices, 4);
  assert_int_equal(m.n_triangles, 3);
  assert_non_null(m.n);
  assert_non_null(m.uv);
  /* vt 1 0.25 -> (1, 0.75) with Mitsuba's v flip. */
  int found = 0;
  for (int64_t i = 0; i < m.n_vertices; i++) {
    if (m.p[3 * i] == 1.0f && m.p[3 * i + 1] == 1.0f) {
      assert_near(m.uv[2 * i], 1.0, 1e-7);
      assert_near(m.uv[2 * i + 1], 0.75, 1e-7);
      found++;
    }
    assert_near(m.n[3 * i + 2], 1.0, 0.0);
  }
  assert_int_equal(found, 1);
  for (int64_t t = 0; t < m.n_triangles; t++) assert_true(mesh_face_normal(&m, t).z > 0.99);
  assert_near(total_area(&m), 1.5, 1e-12);
  assert_string_equal(m.name, "quad.obj");
  mesh_free(&m);
}

static void test_obj_cube_dedup(void **state) {
  (void)state;
  mesh m;
  lmc_error err;
  check_ok(mesh_read_obj("data/mesh/cube.obj", &m, &err), &err);
  assert_int_equal(m.n_vertices, 8);
  assert_int_equal(m.n_triangles, 12);
  assert_null(m.n); /* no corner references a normal */
  assert_null(m.uv);
  assert_near(volume(&m), 8.0, 1e-12);
  assert_int_equal(count_outward(&m, v3(0, 0, 0)), 12);
  mesh_free(&m);
}

/* Mitsuba's maxSmoothAngle on the cube (8 shared corners, faces at 90
 * degrees): below 90 every corner splits into one vertex per face (24), each
 * normal its face's; above 90 the 8 corners stay shared and each normal is
 * the mean of its three faces' (every face meets a corner at 90 degrees in
 * all, whatever its triangulation): (+-1, +-1, +-1) / sqrt(3), pointing
 * out. The triangles keep their corners' positions. */
static void test_max_smooth_angle(void **state) {
  (void)state;
  int checks = 0;
  const double angles[2] = {30.0, 100.0};
  for (int k = 0; k < 2; k++) {
    mesh m;
    lmc_error err;
    check_ok(mesh_read_obj("data/mesh/cube.obj", &m, &err), &err);
    vec3 before[36];
    for (int i = 0; i < 36; i++) before[i] = mesh_position(&m, m.idx[i]);
    check_ok(mesh_rebuild_topology(&m, angles[k], &err), &err);
    assert_int_equal(m.n_vertices, k ? 8 : 24);
    assert_int_equal(m.n_triangles, 12);
    assert_non_null(m.n);
    for (int i = 0; i < 36; i++, checks++) {
      vec3 p = mesh_position(&m, m.idx[i]);
      assert_true(p.x == before[i].x && p.y == before[i].y && p.z == before[i].z);
      vec3 n = v3(m.n[3 * m.idx[i]], m.n[3 * m.idx[i] + 1], m.n[3 * m.idx[i] + 2]);
      vec3 want = k ? v3_scale(p, 1.0 / sqrt(3.0)) : mesh_face_normal(&m, i / 3);
      if (v3_len(v3_sub(n, want)) > 1e-6)
        fail_msg("angle %g corner %d: normal (%g %g %g), want (%g %g %g)", angles[k], i, n.x, n.y,
                 n.z, want.x, want.y, want.z);
    }
    assert_near(volume(&m), 8.0, 1e-12);
    mesh_free(&m);
  }
  assert_int_equal(checks, 72);
}

static void test_obj_errors(void **state) {
  (void)state;
  static const struct {
    const char *text;
    int line;
  } cases[] = {
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n", 5},          /* index out of range */
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", 4},           /* relative out of range */
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", 4},            /* index 0 */
      {"# c\nv 0 0\n", 2},                                    /* short vertex */
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/2 2/1 3/1\n", 5}, /* vt out of range */
      {"v 0 0 0\nv 1 0 0\nf 1 2\n", 3},                       /* two corners */
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3x\n", 4},           /* junk */
  };
  int n_checked = 0;
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    const char *path = "/tmp/lmc_test_meshio_bad.obj";
    assert_true(write_file(path, cases[i].text, strlen(cases[i].text)));
    mesh m;
    lmc_error err;
    lmc_error_clear(&err);
    lmc_status st = mesh_read_obj(path, &m, &err);
    assert_int_not_equal(st, LMC_OK);
    assert_int_equal(err.line, cases[i].line);
    assert_string_equal(err.file, path);
    n_checked++;
    remove(path);
  }
  assert_int_equal(n_checked, 7);
  mesh m;
  lmc_error err;
  assert_int_equal(mesh_read_obj("/tmp/lmc_no_such_file.obj", &m, &err), LMC_EIO);
}

/* ---- PLY --------------------------------------------------------------- */

static void check_quad_ply(const mesh *m, int with_uv) {
  assert_int_equal(m->n_vertices, 4);
  assert_int_equal(m->n_triangles, 2);
  assert_near(total_area(m), 1.0, 1e-12);
  for (int64_t t = 0; t < m->n_triangles; t++) assert_true(mesh_face_normal(m, t).z > 0.99);
  assert_near(m->p[3 * 2], 1.0, 0.0);
  assert_near(m->p[3 * 2 + 1], 1.0, 0.0);
  if (with_uv) {
    assert_non_null(m->uv);
    assert_near(m->uv[2 * 1], 1.0, 0.0);
    assert_near(m->uv[2 * 3 + 1], 1.0, 0.0);
  }
}

static void test_ply_ascii(void **state) {
  (void)state;
  mesh m;
  lmc_error err;
  check_ok(mesh_read_ply("data/mesh/quad_ascii.ply", &m, &err), &err);
  check_quad_ply(&m, 1);
  assert_non_null(m.n);
  assert_near(m.n[2], 1.0, 0.0);
  mesh_free(&m);
}

/* Appends a value of `size` bytes in the chosen byte order. */
static void put(unsigned char **p, const void *v, int size, int big) {
  const unsigned char *b = v;
  for (int i = 0; i < size; i++) (*p)[i] = big ? b[size - 1 - i] : b[i];
  *p += size;
}

/* A binary quad: double positions, a skipped short, float u v, an extra
 * element with a list, faces with ushort counts and uint indices. */
static size_t make_binary_ply(unsigned char *buf, int big) {
  char hdr[1024];
  snprintf(hdr, sizeof hdr,
           "ply\nformat %s 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
           "property double z\nproperty short junk\nproperty float u\nproperty float v\n"
           "element extra 2\nproperty list uchar int stuff\nproperty float w\n"
           "element face 1\nproperty list ushort uint vertex_index\nend_header\n",
           big ? "binary_big_endian" : "binary_little_endian");
  size_t n = strlen(hdr);
  memcpy(buf, hdr, n);
  unsigned char *p = buf + n;
  static const double xy[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int i = 0; i < 4; i++) {
    double z = 0.0;
    short junk = -7;
    float u = (float)xy[i][0], v = (float)xy[i][1];
    put(&p, &xy[i][0], 8, big);
    put(&p, &xy[i][1], 8, big);
    put(&p, &z, 8, big);
    put(&p, &junk, 2, big);
    put(&p, &u, 4, big);
    put(&p, &v, 4, big);
  }
  for (int e = 0; e < 2; e++) {
    unsigned char cnt = 3;
    put(&p, &cnt, 1, big);
    for (int k = 0; k < 3; k++) {
      int32_t x = 100 + k;
      put(&p, &x, 4, big);
    }
    float w = 2.5f;
    put(&p, &w, 4, big);
  }
  uint16_t c = 4;
  put(&p, &c, 2, big);
  for (uint32_t k = 0; k < 4; k++) put(&p, &k, 4, big);
  return (size_t)(p - buf);
}

static void test_ply_binary(void **state) {
  (void)state;
  unsigned char buf[4096];
  int n_ok = 0;
  for (int big = 0; big <= 1; big++) {
    size_t n = make_binary_ply(buf, big);
    const char *path = "/tmp/lmc_test_meshio.ply";
    assert_true(write_file(path, buf, n));
    mesh m;
    lmc_error err;
    check_ok(mesh_read_ply(path, &m, &err), &err);
    check_quad_ply(&m, 1);
    assert_null(m.n);
    mesh_free(&m);
    n_ok++;
    /* Every truncation of the body is an error, never a crash. */
    size_t body = (size_t)(strstr((char *)buf, "end_header\n") - (char *)buf) + 11;
    int n_err = 0;
    for (size_t cut = body; cut < n; cut += 3) {
      assert_true(write_file(path, buf, cut));
      if (mesh_read_ply(path, &m, &err) != LMC_OK) n_err++;
      else mesh_free(&m);
    }
    assert_int_equal(n_err, (int)((n - body + 2) / 3));
    remove(path);
  }
  assert_int_equal(n_ok, 2);
}

static void test_ply_errors(void **state) {
  (void)state;
  const char *bad_index =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n";
  const char *bad_header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty floot x\nend_header\n";
  const char *path = "/tmp/lmc_test_meshio_bad.ply";
  mesh m;
  lmc_error err;
  assert_true(write_file(path, bad_index, strlen(bad_index)));
  assert_int_equal(mesh_read_ply(path, &m, &err), LMC_EPARSE);
  assert_int_equal(err.line, 13);
  assert_true(write_file(path, bad_header, strlen(bad_header)));
  assert_int_equal(mesh_read_ply(path, &m, &err), LMC_EPARSE);
  assert_int_equal(err.line, 4);
  assert_true(write_file(path, "hello\n", 6));
  assert_int_not_equal(mesh_read_ply(path, &m, &err), LMC_OK);
  /* A header that claims far more vertices than the body can hold (ASCII
   * and binary) is refused before anything is allocated for them. */
  const char *huge[2] = {
      "ply\nformat ascii 1.0\nelement vertex 77777777\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n0 0 0\n",
      "ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n0123456789abcdef0123456789abcdef"};
  /* An element without properties holds no data whatever its count (a
   * count of 2^62 was once walked row by row). */
  const char *empty_elem =
      "ply\nformat ascii 1.0\nelement junk 4611686018427387904\nelement vertex 3\n"
      "property float x\nproperty float y\nproperty float z\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  assert_true(write_file(path, empty_elem, strlen(empty_elem)));
  assert_int_equal(mesh_read_ply(path, &m, &err), LMC_OK);
  assert_int_equal(m.n_vertices, 3);
  assert_int_equal(m.n_triangles, 1);
  mesh_free(&m);
  for (int i = 0; i < 2; i++) {
    assert_true(write_file(path, huge[i], strlen(huge[i])));
    assert_int_equal(mesh_read_ply(path, &m, &err), LMC_EPARSE);
    assert_non_null(strstr(err.msg, "exceeds the file's data"));
  }
  remove(path);
}

/* ---- serialized ---------------------------------------------------------- */

/* Appends one shape (a unit quad) to buf: version 3 (single precision, no
 * extras) or 4 (double precision, name, normals, uvs, colours). */
static size_t make_shape(unsigned char *buf, int version) {
  unsigned char raw[1024], *p = raw;
  uint32_t flags = version == 4 ? (0x2000u | 0x0001u | 0x0002u | 0x0008u) : 0x1000u;
  put(&p, &flags, 4, 0);
  if (version == 4) {
    memcpy(p, "quad", 5);
    p += 5;
  }
  uint64_t nv = 4, nt = 2;
  put(&p, &nv, 8, 0);
  put(&p, &nt, 8, 0);
  static const double pos[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  int blocks = version == 4 ? 4 : 1; /* positions, normals, uvs, colours */
  for (int blk = 0; blk < blocks; blk++) {
    int dim = blk == 2 ? 2 : 3;
    for (int i = 0; i < 4; i++)
      for (int k = 0; k < dim; k++) {
        double v = blk == 0 ? pos[i][k] : blk == 1 ? (k == 2 ? 1.0 : 0.0) : blk == 2 ? pos[i][k] : 0.5;
        if (version == 4) put(&p, &v, 8, 0);
        else {
          float f = (float)v;
          put(&p, &f, 4, 0);
        }
      }
  }
  static const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
  for (int i = 0; i < 6; i++) put(&p, &idx[i], 4, 0);
  uint16_t id = 0x041C, ver = (uint16_t)version;
  unsigned char *q = buf;
  put(&q, &id, 2, 0);
  put(&q, &ver, 2, 0);
  uLongf clen = 4096;
  assert_int_equal(compress(q, &clen, raw, (uLong)(p - raw)), Z_OK);
  return 4 + (size_t)clen;
}

static void test_serialized_generated(void **state) {
  (void)state;
  unsigned char buf[16384];
  const char *path = "/tmp/lmc_test_meshio.serialized";
  int n_ok = 0;
  for (int version = 3; version <= 4; version++) {
    /* Two shapes, then the offset table and the count. */
    size_t n0 = make_shape(buf, version);
    size_t n1 = make_shape(buf + n0, version);
    unsigned char *p = buf + n0 + n1;
    uint64_t off[2] = {0, n0};
    for (int i = 0; i < 2; i++) {
      if (version == 4) put(&p, &off[i], 8, 0);
      else {
        uint32_t o = (uint32_t)off[i];
        put(&p, &o, 4, 0);
      }
    }
    uint32_t count = 2;
    put(&p, &count, 4, 0);
    size_t n = (size_t)(p - buf);
    assert_true(write_file(path, buf, n));
    for (int s = 0; s < 2; s++) {
      mesh m;
      lmc_error err;
      check_ok(mesh_read_serialized(path, s, &m, &err), &err);
      check_quad_ply(&m, version == 4);
      if (version == 4) {
        assert_non_null(m.n);
        assert_near(m.n[2], 1.0, 0.0);
        assert_string_equal(m.name, "quad");
      }
      mesh_free(&m);
      n_ok++;
    }
    mesh m;
    lmc_error err;
    assert_int_not_equal(mesh_read_serialized(path, 2, &m, &err), LMC_OK);
    assert_int_not_equal(mesh_read_serialized(path, -1, &m, &err), LMC_OK);
    /* Corrupt the compressed data of shape 1 (keep the table): an error. */
    for (size_t i = n0 + 8; i < n0 + n1; i++) buf[i] ^= 0x5A;
    assert_true(write_file(path, buf, n));
    assert_int_not_equal(mesh_read_serialized(path, 1, &m, &err), LMC_OK);
    check_ok(mesh_read_serialized(path, 0, &m, &err), &err);
    mesh_free(&m);
  }
  assert_int_equal(n_ok, 4);
  /* A file that is cut in the middle of the first stream. */
  size_t n0 = make_shape(buf, 4);
  assert_true(write_file(path, buf, n0 / 2));
  mesh m;
  lmc_error err;
  assert_int_not_equal(mesh_read_serialized(path, 0, &m, &err), LMC_OK);
  remove(path);
}

static void test_serialized_torus(void **state) {
  (void)state;
  char path[1024];
  snprintf(path, sizeof path, "%s/scenes/torus/data/meshes.serialized", LMC_SHARED_DIR);
  FILE *f = fopen(path, "rb");
  if (!f) skip();
  fclose(f);
  int n_ok = 0;
  for (int s = 0; s < 6; s++) {
    mesh m;
    lmc_error err;
    check_ok(mesh_read_serialized(path, s, &m, &err), &err);
    assert_true(m.n_vertices >= 3 && m.n_vertices < 10000000);
    assert_true(m.n_triangles >= 1 && m.n_triangles < 20000000);
    int64_t bad = 0;
    for (int64_t i = 0; i < 3 * m.n_vertices; i++) bad += !isfinite(m.p[i]) || fabsf(m.p[i]) > 1e6f;
    assert_int_equal(bad, 0);
    lmc_warn_set_quiet(1);
    check_ok(mesh_validate(&m, "torus.xml", 1, &err), &err);
    lmc_warn_set_quiet(0);
    assert_true(total_area(&m) > 0.0);
    printf("  shape %d: %lld vertices, %lld triangles, area %g%s%s\n", s, (long long)m.n_vertices,
           (long long)m.n_triangles, total_area(&m), m.n ? ", normals" : "", m.uv ? ", uvs" : "");
    mesh_free(&m);
    n_ok++;
  }
  assert_int_equal(n_ok, 6);
  mesh m;
  lmc_error err;
  assert_int_not_equal(mesh_read_serialized(path, 6, &m, &err), LMC_OK);
  assert_string_equal(err.file, path);
}

/* ---- shapes ---------------------------------------------------------------- */

static void test_shape_sphere(void **state) {
  (void)state;
  mesh m;
  lmc_error err;
  vec3 c = v3(1, -2, 0.5);
  double r = 2.0;
  check_ok(shape_sphere(c, r, &m, &err), &err);
  /* Inscribed polyhedron: its area is below 4 pi r^2. For a UV sphere with
   * angular steps dth = pi/64 and dph = 2pi/128 the relative deficit is
   * about (dth^2 + dph^2) / 12 ~ 4e-4 (chord vs arc, second order); allow
   * twice that. */
  double exact = 4.0 * PI * r * r, a = total_area(&m);
  double dth = PI / 64, dph = 2 * PI / 128, tol = 2.0 * (dth * dth + dph * dph) / 12.0;
  printf("  sphere area %.9g vs %.9g (rel. deficit %.3g, tol %.3g)\n", a, exact, 1 - a / exact, tol);
  assert_true(a < exact);
  assert_true(1.0 - a / exact < tol);
  /* Every face outward; vertex normals exact and unit. */
  assert_int_equal(count_outward(&m, c), m.n_triangles);
  int64_t good = 0;
  for (int64_t i = 0; i < m.n_vertices; i++) {
    vec3 n = v3(m.n[3 * i], m.n[3 * i + 1], m.n[3 * i + 2]);
    vec3 d = v3_scale(v3_sub(mesh_position(&m, (uint32_t)i), c), 1.0 / r);
    if (fabs(v3_len(n) - 1.0) < 1e-6 && v3_len(v3_sub(n, d)) < 1e-6) good++;
    assert_true(m.uv[2 * i] >= 0.0f && m.uv[2 * i] <= 1.0f);
  }
  assert_int_equal(good, m.n_vertices);
  /* Enclosed volume (4/3) pi r^3 with a deficit of the same order. */
  assert_true(fabs(volume(&m) / (4.0 / 3.0 * PI * r * r * r) - 1.0) < 2 * tol);
  /* mesh_validate keeps everything (no degenerate triangles at the poles). */
  int64_t nt = m.n_triangles;
  int w0 = lmc_warning_count();
  check_ok(mesh_validate(&m, "x.xml", 3, &err), &err);
  assert_int_equal(m.n_triangles, nt);
  assert_int_equal(lmc_warning_count(), w0);
  mesh_free(&m);
}

static void test_shape_cube_rect_disk_cylinder(void **state) {
  (void)state;
  mesh m;
  lmc_error err;
  check_ok(shape_cube(&m, &err), &err);
  assert_int_equal(m.n_vertices, 24);
  assert_int_equal(m.n_triangles, 12);
  assert_true(m.face_normals);
  assert_near(volume(&m), 8.0, 1e-12);
  assert_near(total_area(&m), 24.0, 1e-12);
  assert_int_equal(count_outward(&m, v3(0, 0, 0)), 12);
  mesh_free(&m);

  check_ok(shape_rectangle(&m, &err), &err);
  assert_near(total_area(&m), 4.0, 1e-12);
  for (int64_t t = 0; t < m.n_triangles; t++) assert_near(mesh_face_normal(&m, t).z, 1.0, 1e-12);
  m.flip_normals = 1;
  assert_near(mesh_face_normal(&m, 0).z, -1.0, 1e-12);
  mesh_free(&m);

  /* Disk: inscribed 128-gon, area (N/2) sin(2 pi/N) exactly. */
  check_ok(shape_disk(&m, &err), &err);
  assert_near(total_area(&m), 64.0 * sin(2 * PI / 128), 1e-6);
  for (int64_t t = 0; t < m.n_triangles; t++) assert_true(mesh_face_normal(&m, t).z > 0.999999);
  mesh_free(&m);

  /* Cylinder from p0 to p1: lateral area 2 pi r L up to the 128-gon's perimeter. */
  vec3 p0 = v3(1, 2, 3), p1 = v3(2, 0, 5);
  double r = 0.5, L = v3_len(v3_sub(p1, p0));
  check_ok(shape_cylinder(p0, p1, r, &m, &err), &err);
  assert_near(total_area(&m), 128.0 * 2.0 * r * sin(PI / 128) * L, 1e-5);
  /* Outward: away from the nearest axis point. */
  int64_t out = 0;
  vec3 z = v3_scale(v3_sub(p1, p0), 1.0 / L);
  for (int64_t t = 0; t < m.n_triangles; t++) {
    vec3 c = v3_scale(v3_add(v3_add(mesh_position(&m, m.idx[3 * t]), mesh_position(&m, m.idx[3 * t + 1])),
                             mesh_position(&m, m.idx[3 * t + 2])),
                      1.0 / 3.0);
    vec3 axis_pt = v3_fma(p0, z, v3_dot(v3_sub(c, p0), z));
    if (v3_dot(mesh_face_normal(&m, t), v3_sub(c, axis_pt)) > 0.0) out++;
  }
  assert_int_equal(out, m.n_triangles);
  mesh_free(&m);
  assert_int_not_equal(shape_cylinder(p0, p0, r, &m, &err), LMC_OK);
  assert_int_not_equal(shape_sphere(p0, -1.0, &m, &err), LMC_OK);
}

/* ---- transform and validate ---------------------------------------------- */

static void test_transform_mirror(void **state) {
  (void)state;
  mesh m;
  lmc_error err;
  check_ok(shape_sphere(v3(0, 0, 0), 1.0, &m, &err), &err);
  /* Mirror and stretch: faces must stay outward, vertex normals unit and
   * on the same side as the face normals. */
  xform s = xform_scale(v3(-2.0, 1.0, 0.5));
  xform t = xform_translate(v3(3, 0, 0));
  xform st = xform_compose(&t, &s);
  mesh_transform(&m, &st);
  assert_int_equal(count_outward(&m, v3(3, 0, 0)), m.n_triangles);
  int64_t agree = 0;
  for (int64_t f = 0; f < m.n_triangles; f++) {
    uint32_t i = m.idx[3 * f];
    vec3 n = v3(m.n[3 * i], m.n[3 * i + 1], m.n[3 * i + 2]);
    assert_near(v3_len(n), 1.0, 1e-6);
    if (v3_dot(n, mesh_face_normal(&m, f)) > 0.0) agree++;
  }
  assert_int_equal(agree, m.n_triangles);
  /* Volume scales by |det| = 1. */
  assert_near(volume(&m), 4.0 / 3.0 * PI, 0.01);
  mesh_free(&m);
}

static void test_validate(void **state) {
  (void)state;
  lmc_error err;
  mesh m;
  memset(&m, 0, sizeof m);
  lmc_warn_set_quiet(1);

  /* Out-of-range index: error with the caller's file and line. */
  check_ok(shape_rectangle(&m, &err), &err);
  m.idx[5] = 4;
  assert_int_equal(mesh_validate(&m, "scene.xml", 42, &err), LMC_EPARSE);
  assert_string_equal(err.file, "scene.xml");
  assert_int_equal(err.line, 42);
  mesh_free(&m);

  /* NaN position, infinite normal. */
  check_ok(shape_rectangle(&m, &err), &err);
  m.p[4] = NAN;
  assert_int_equal(mesh_validate(&m, "scene.xml", 7, &err), LMC_EPARSE);
  assert_int_equal(err.line, 7);
  mesh_free(&m);
  check_ok(shape_rectangle(&m, &err), &err);
  m.n[0] = INFINITY;
  assert_int_equal(mesh_validate(&m, "scene.xml", 8, &err), LMC_EPARSE);
  mesh_free(&m);

  /* Zero-area triangles dropped, with one warning. */
  check_ok(shape_cube(&m, &err), &err);
  m.idx[3 * 4 + 2] = m.idx[3 * 4 + 1];   /* repeated index */
  for (int k = 0; k < 3; k++) m.p[3 * m.idx[3 * 7 + 1] + k] = m.p[3 * m.idx[3 * 7] + k]; /* collapsed */
  int64_t before = m.n_triangles;
  int w0 = lmc_warning_count();
  check_ok(mesh_validate(&m, "scene.xml", 9, &err), &err);
  assert_int_equal(lmc_warning_count(), w0 + 1);
  assert_true(m.n_triangles <= before - 2 && m.n_triangles >= before - 3);
  for (int64_t t = 0; t < m.n_triangles; t++) assert_true(mesh_triangle_area(&m, t) > 0.0);
  mesh_free(&m);

  /* Zero normals are recomputed from the faces. */
  check_ok(shape_rectangle(&m, &err), &err);
  for (int k = 0; k < 3; k++) m.n[3 * 2 + k] = 0.0f;
  w0 = lmc_warning_count();
  check_ok(mesh_validate(&m, "scene.xml", 10, &err), &err);
  assert_int_equal(lmc_warning_count(), w0 + 1);
  assert_non_null(m.n);
  assert_near(m.n[3 * 2 + 2], 1.0, 1e-7);
  mesh_free(&m);

  /* Empty mesh: a warning and zero triangles. */
  check_ok(mesh_alloc(&m, 0, 0, 0, 0, &err), &err);
  w0 = lmc_warning_count();
  check_ok(mesh_validate(&m, "scene.xml", 11, &err), &err);
  assert_int_equal(m.n_triangles, 0);
  assert_int_equal(lmc_warning_count(), w0 + 1);
  mesh_free(&m);
  mesh_free(NULL);
  lmc_warn_set_quiet(0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_obj_quad),
      cmocka_unit_test(test_obj_cube_dedup),
      cmocka_unit_test(test_max_smooth_angle),
      cmocka_unit_test(test_obj_errors),
      cmocka_unit_test(test_ply_ascii),
      cmocka_unit_test(test_ply_binary),
      cmocka_unit_test(test_ply_errors),
      cmocka_unit_test(test_serialized_generated),
      cmocka_unit_test(test_serialized_torus),
      cmocka_unit_test(test_shape_sphere),
      cmocka_unit_test(test_shape_cube_rect_disk_cylinder),
      cmocka_unit_test(test_transform_mirror),
      cmocka_unit_test(test_validate),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
