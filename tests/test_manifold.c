/*
 * test_manifold.c: the manifold walk (src/lmc/path/manifold.c; Jakob and
 * Marschner 2012) on three small scenes built from XML strings:
 *
 *   glass    a dielectric sphere (IOR 1.5, radius 1, the loader's UV
 *            sphere with interpolated vertex normals) 0.2 above a diffuse
 *            floor; chains of two refractions (in, out) from a point x_0
 *            above it, in a cone of 0.15 rad (the rays' caustic, where
 *            the end's map folds and a target beyond it cannot be
 *            reached, stays below the floor);
 *   mirror   a flat conductor rectangle beside a diffuse floor; one
 *            reflection;
 *   ball     a conductor sphere above a floor, one reflection on a curved
 *            tessellated surface; and the same with the half vector's
 *            target not zero ("ball-glossy": a glossy vertex treated as
 *            specular, HSLT's case), each chain with its own target in
 *            [-0.1, 0.1]^2.
 *
 * Starting chains are traced (mf_trace) from x_0 along random directions
 * in a cone towards the specular object (fixed seeds); those that do not
 * reach the floor through the chain are drawn again.
 *
 *  1. The walk: from each starting chain to a target drawn uniformly in a
 *     disk of radius 0.005 scene->radius around its end on the floor:
 *     at least 99% of the walks reach the target within the walk's
 *     tolerance (1e-7 scene->radius, mf_options_default); on every success
 *     the end is within that tolerance, every vertex lies on its
 *     triangle's plane to 1e-9 scene->radius and inside its triangle or
 *     at most 1e-6 (1 + |p|_max) outside it (on a neighbouring triangle:
 *     Embree's float hit may name the neighbour of a point within float
 *     precision of an edge; 1e-6 is eight float ulps of the coordinates),
 *     and every constraint holds, |c_i| < 1e-8.
 *  2. The Jacobian blocks from forward-mode AD against central differences
 *     of the plain constraint function (mf_constraint, written apart) in
 *     each vertex's barycentrics, on chains on the manifold and moved off
 *     it (each vertex's barycentrics shifted by up to 0.02). The step is
 *     s = 1e-6 in space (h = s / L in barycentrics, L the triangle's
 *     longest edge). Error of the difference, relative to the entry: c
 *     is a composition of normalisations of vectors of length >= d (the
 *     shortest segment, 0.2 here), amplified at most 3 times by
 *     1 / |wi + eta_r wo| (eta 1.5), so |c'''| / |c'| <= 3 * 15 / d^2 and
 *     the truncation is <= s^2 / 6 * 45 / d^2 ~ 2e-10; rounding, ~10 ulps
 *     of a unit-size c over 2 s, is 1e-9 / |c'| per unit of space, L 1e-9
 *     in barycentrics (L <= 8). Tolerance 1e-6 (1 + |AD|), a hundred times
 *     the larger. The AD values of c against the plain ones to 1e-12.
 *  3. The generalized geometry term against the traced chain's map: the
 *     first direction d(a, b) = normalize(d_0 + a u + b v) (u, v, d_0
 *     orthonormal: a and b are solid-angle coordinates at 0), the chain
 *     traced at a, b = +-h, and dA/dw = |dp/da x dp/db| from central
 *     differences of the end points on the flat floor; G_traced =
 *     |cos theta_0| / (dA/dw), here cos theta_0 = 1 (x_0 a point). Step
 *     h = 5e-6 rad; a stencil whose chains do not keep every vertex's
 *     triangle (the interpolated normals' derivatives jump at edges) is
 *     redone with h / 4, up to three times, else left out (counted).
 *     Error: truncation h^2 / 6 times the map's relative third
 *     derivative, whose angular scale is at least 0.02 rad (the ball's
 *     near-grazing reflections; 0.15 rad for the glass) ~ 1e-8;
 *     rounding 1e-15 / (2 h |p'|) ~ 1e-10; tolerance 1e-6 relative. (The
 *     measured errors fall 16-fold from h = 2e-5 to 5e-6: truncation.)
 *
 *     After a direction start ("sun-glass": the glass scene lit along
 *     (0.05, -1, 0.1) through a disk of radius 0.15 around the sphere's
 *     centre; "sun-mirror": the mirror along (0.8, -1, 0.1)) the stencil
 *     offsets the ray across d instead, x_1 + a u + b v (u, v, d
 *     orthonormal, a and b = +-h in scene units: the area of the plane
 *     perpendicular to d), and G_traced = 1 / (dA/dA_perp). The flat
 *     mirror's G is |cos| of the reflected direction at the floor,
 *     0.7785 for every chain. These two configurations take part in 1 and
 *     2 as well.
 *  4. A direction start's ray (mf_start_ray, mf_trace_through) through
 *     points anywhere in and around sun-mirror: its origin outside the
 *     bounding sphere, the point on the ray; the first hit decides: the
 *     mirror (x_1's mesh) a chain, another mesh MF_ESHAPE, nothing
 *     MF_EMISS; mf_trace refuses a direction start.
 *  5. Chains of path-space paths (mf_chain_from_path, mf_chain_to_path)
 *     on a scene of a glass sphere, a mirror, a glossy ball (ps_glossy), a
 *     point light and a directional light; paths made as bdpt's walks
 *     make their records (scene_intersect, each delta lobe by
 *     bsdf_sample_f), evaluated (ps_eval), of five shapes: the sun through
 *     the glass and through the mirror onto the floor (light walks; the
 *     chain starts at the path's x_k at infinity), the camera via the
 *     mirror (from the pinhole), the point light through the glass (the
 *     chain from x_b, MF_PATH_FROM_B), the camera via the glossy ball
 *     (MF_PATH_GLOSSY). Per path: the chain's start, order, vertices (bit
 *     for bit the records' hits), kinds, eta, and constraints (< 1e-9;
 *     a glossy target its half vector); written back unchanged, the path
 *     bit for bit. Walked to a target within 0.002 scene->radius of the
 *     end (at least 99%), written back: the vertices outside the chain
 *     untouched; each chain vertex's record what scene_intersect finds
 *     along the walked chain's segment to it (triangle, BSDF, light;
 *     barycentrics, point, normals, frame, texture coordinates to 1e-9),
 *     p and n its hit's, wo towards its own walk's neighbour and t the
 *     traced distance from it (1e-9); read back, the walked chain; the
 *     path evaluates to a finite f. Chains that are not (a non-specular
 *     inner vertex, indices out of range, glossy without the flag) are
 *     refused.
 *
 * Every check is counted and the count asserted; the figures are printed.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "lmc/path/manifold.h"
#include "render/io/io.h"
#include "render/rng.h"
#include "test_util.h"
#include "load_scene.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define SENSOR                                                                                 \
  "  <sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/>\n"                        \
  "    <transform name=\"toWorld\"><lookat origin=\"0, 2, 7\" target=\"0, 0.5, 0\" up=\"0, 1, 0\"/></transform>\n" \
  "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer name=\"height\" value=\"16\"/></film>\n" \
  "  </sensor>\n"

static const char *xml_glass =
    "<scene version=\"0.6.0\">\n" SENSOR
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"0\" z=\"0\"/><float name=\"radius\" value=\"1\"/>\n"
    "    <bsdf type=\"dielectric\"><float name=\"intIOR\" value=\"1.5\"/><float name=\"extIOR\" value=\"1\"/></bsdf>\n"
    "  </shape>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/><scale x=\"4\" y=\"1\" z=\"4\"/><translate y=\"-1.2\"/></transform>\n"
    "    <bsdf type=\"diffuse\"/>\n"
    "  </shape>\n"
    "  <emitter type=\"point\"><point name=\"position\" x=\"0.1\" y=\"3\" z=\"0.2\"/><rgb name=\"intensity\" value=\"10, 10, 10\"/></emitter>\n"
    "</scene>\n";

static const char *xml_mirror =
    "<scene version=\"0.6.0\">\n" SENSOR
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"toWorld\"><rotate y=\"1\" angle=\"-90\"/><scale value=\"1.5\"/><translate x=\"1.5\" y=\"1.6\" z=\"0\"/></transform>\n"
    "    <bsdf type=\"conductor\"/>\n"
    "  </shape>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/><scale x=\"5\" y=\"1\" z=\"5\"/></transform>\n"
    "    <bsdf type=\"diffuse\"/>\n"
    "  </shape>\n"
    "  <emitter type=\"point\"><point name=\"position\" x=\"-0.5\" y=\"2.5\" z=\"0.2\"/><rgb name=\"intensity\" value=\"10, 10, 10\"/></emitter>\n"
    "</scene>\n";

static const char *xml_ball =
    "<scene version=\"0.6.0\">\n" SENSOR
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"1.2\" z=\"0\"/><float name=\"radius\" value=\"1\"/>\n"
    "    <bsdf type=\"conductor\"/>\n"
    "  </shape>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/><scale x=\"6\" y=\"1\" z=\"6\"/></transform>\n"
    "    <bsdf type=\"diffuse\"/>\n"
    "  </shape>\n"
    "  <emitter type=\"point\"><point name=\"position\" x=\"-2.5\" y=\"3\" z=\"0.3\"/><rgb name=\"intensity\" value=\"10, 10, 10\"/></emitter>\n"
    "</scene>\n";

/* A scene and the chains drawn on it. */
typedef struct config {
  const char *name;
  const char *const *xml;
  vec3 x0, aim;     /* start point and the cone's axis point */
  double cone;      /* the cone's half angle (rad) */
  int k;            /* specular vertices */
  mf_kind kinds[2];
  int meshes[3];    /* x_1 .. x_{k+1}'s meshes (load order) */
  double glossy;    /* targets drawn in [-glossy, glossy]^2 (0: smooth) */
  uint64_t seed;
  int dir_start;    /* x_0 a direction d (x0 unused; aim the centre and cone the
                       radius of the disk across d that the rays pass through) */
  vec3 d;           /* the direction (unnormalised) */
} config;

static const config CONFIGS[] = {
    {"glass", &xml_glass, {0.1, 3.0, 0.2}, {0.0, 0.0, 0.0}, 0.15, 2, {MF_REFRACT, MF_REFRACT}, {0, 0, 1}, 0.0, 11, 0, {0.0, 0.0, 0.0}},
    {"mirror", &xml_mirror, {-0.5, 2.5, 0.2}, {1.5, 1.6, 0.0}, 0.4, 1, {MF_REFLECT, MF_REFLECT}, {0, 1, -1}, 0.0, 12, 0, {0.0, 0.0, 0.0}},
    {"ball", &xml_ball, {-2.5, 3.0, 0.3}, {0.0, 1.2, 0.0}, 0.26, 1, {MF_REFLECT, MF_REFLECT}, {0, 1, -1}, 0.0, 13, 0, {0.0, 0.0, 0.0}},
    {"ball-glossy", &xml_ball, {-2.5, 3.0, 0.3}, {0.0, 1.2, 0.0}, 0.26, 1, {MF_REFLECT, MF_REFLECT}, {0, 1, -1}, 0.1, 14, 0, {0.0, 0.0, 0.0}},
    {"sun-glass", &xml_glass, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, 0.15, 2, {MF_REFRACT, MF_REFRACT}, {0, 0, 1}, 0.0, 15, 1, {0.05, -1.0, 0.1}},
    {"sun-mirror", &xml_mirror, {0.0, 0.0, 0.0}, {1.5, 1.8, 0.0}, 0.6, 1, {MF_REFLECT, MF_REFLECT}, {0, 1, -1}, 0.0, 16, 1, {0.8, -1.0, 0.1}},
};
#define N_CONFIGS ((int)(sizeof CONFIGS / sizeof CONFIGS[0]))

static scene *load(const config *cf) {
  char tag[64];
  snprintf(tag, sizeof tag, "manifold_%s", cf->name);
  scene *sc = try_load_scene_text(*cf->xml, tag);
  assert_non_null(sc);
  return sc;
}

/* The prototype chain of a configuration (meshes, kinds; targets zero). */
static mf_chain proto_of(const config *cf) {
  mf_chain c;
  memset(&c, 0, sizeof c);
  c.k = cf->k;
  c.x0 = cf->x0;
  if (cf->dir_start) {
    c.start = MF_START_DIRECTION;
    c.d = v3_normalize(cf->d);
  }
  for (int i = 1; i <= cf->k + 1; i++) {
    c.v[i].mesh = cf->meshes[i - 1];
    c.v[i].kind = i <= cf->k ? cf->kinds[i - 1] : MF_REFLECT;
  }
  return c;
}

/* A random starting chain: a direction in the cone, traced; drawn again
 * until the trace reaches the floor through the chain. */
static void draw_chain(const scene *sc, const config *cf, rng *r, mf_chain *OUT) {
  mf_chain proto = proto_of(cf);
  frame f = frame_from_z(cf->dir_start ? proto.d : v3_normalize(v3_sub(cf->aim, cf->x0)));
  double cmin = cos(cf->cone);
  for (int tries = 0; tries < 100000; tries++) {
    if (cf->glossy > 0.0)
      for (int i = 1; i <= cf->k; i++) {
        proto.v[i].target[0] = cf->glossy * (2.0 * rng_uniform(r) - 1.0);
        proto.v[i].target[1] = cf->glossy * (2.0 * rng_uniform(r) - 1.0);
      }
    if (cf->dir_start) {
      /* The ray along d through a point of the disk across d. */
      double rr = cf->cone * sqrt(rng_uniform(r)), ph = 2.0 * M_PI * rng_uniform(r);
      vec3 q = v3_add(cf->aim, frame_to_world(&f, v3(rr * cos(ph), rr * sin(ph), 0.0)));
      if (mf_trace_through(sc, &proto, q, OUT) == MF_OK) return;
      continue;
    }
    double ct = 1.0 - rng_uniform(r) * (1.0 - cmin), st = sqrt(fmax(0.0, 1.0 - ct * ct));
    double ph = 2.0 * M_PI * rng_uniform(r);
    vec3 d = frame_to_world(&f, v3(st * cos(ph), st * sin(ph), ct));
    if (mf_trace(sc, &proto, d, OUT) == MF_OK) return;
  }
  fail_msg("%s: no starting chain", cf->name);
}

/* Distance from p (in the plane of the triangle) to triangle a, b, c: 0
 * inside, else to its nearest edge. */
static double seg_dist(vec3 p, vec3 a, vec3 b) {
  vec3 ab = v3_sub(b, a);
  double t = v3_dot(v3_sub(p, a), ab) / v3_len2(ab);
  t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
  return v3_len(v3_sub(p, v3_fma(a, ab, t)));
}

static void vertex_surface_error(const scene *sc, const mf_vertex *v, double *OUT_plane,
                                 double *OUT_outside) {
  const mesh *m = &sc->meshes[v->mesh];
  const uint32_t *tri = m->idx + 3 * v->prim;
  vec3 p0 = mesh_position(m, tri[0]), p1 = mesh_position(m, tri[1]), p2 = mesh_position(m, tri[2]);
  vec3 n = v3_normalize(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
  *OUT_plane = fabs(v3_dot(v3_sub(v->p, p0), n));
  double b0 = 1.0 - v->b1 - v->b2;
  if (b0 >= 0.0 && v->b1 >= 0.0 && v->b2 >= 0.0) {
    *OUT_outside = 0.0;
    return;
  }
  double d = seg_dist(v->p, p0, p1);
  d = fmin(d, seg_dist(v->p, p1, p2));
  d = fmin(d, seg_dist(v->p, p2, p0));
  *OUT_outside = d;
}

static double max_abs3(vec3 p) { return fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z))); }

/* ---- 1. The walk --------------------------------------------------------------- */

#define WALK_TRIALS 400

static void test_walk(void **state) {
  (void)state;
  long checks = 0, expected = 0;
  for (int ci = 0; ci < N_CONFIGS; ci++) {
    const config *cf = &CONFIGS[ci];
    scene *sc = load(cf);
    rng r;
    rng_seed(&r, cf->seed, 1);
    mf_options o;
    mf_options_default(sc, &o);
    double rho = 0.005 * sc->radius, plane_tol = 1e-9 * sc->radius;
    int ok = 0, fails[16] = {0};
    long steps = 0, traces = 0;
    double max_plane = 0.0, max_out = 0.0, max_c = 0.0, max_dist = 0.0;
    int n_outside = 0;
    for (int t = 0; t < WALK_TRIALS; t++) {
      mf_chain c, res;
      draw_chain(sc, cf, &r, &c);
      /* A target on the floor in a disk of radius rho around the end. */
      frame f = frame_from_z(c.v[c.k + 1].ng);
      double rr = rho * sqrt(rng_uniform(&r)), ph = 2.0 * M_PI * rng_uniform(&r);
      vec3 target = v3_add(c.v[c.k + 1].p, frame_to_world(&f, v3(rr * cos(ph), rr * sin(ph), 0.0)));
      mf_walk_info info;
      int st = mf_walk(sc, &c, target, &o, &res, &info);
      if (st != MF_OK) {
        fails[-st < 16 ? -st : 15]++;
        continue;
      }
      ok++;
      steps += info.steps;
      traces += info.traces;
      /* The end at the target. */
      double dist = v3_len(v3_sub(res.v[res.k + 1].p, target));
      max_dist = fmax(max_dist, dist);
      assert_le(dist, o.tol);
      checks++;
      /* Every vertex on its surface. */
      for (int i = 1; i <= res.k + 1; i++) {
        double plane, outside;
        vertex_surface_error(sc, &res.v[i], &plane, &outside);
        assert_int_equal(res.v[i].mesh, c.v[i].mesh);
        assert_le(plane, plane_tol);
        assert_le(outside, 1e-6 * (1.0 + max_abs3(res.v[i].p)));
        checks += 3;
        max_plane = fmax(max_plane, plane);
        max_out = fmax(max_out, outside);
        n_outside += outside > 0.0;
      }
      /* The specular constraints hold. */
      for (int i = 1; i <= res.k; i++) {
        double cv[2];
        assert_int_equal(mf_constraint(sc, &res, i, cv), MF_OK);
        double cn = sqrt(cv[0] * cv[0] + cv[1] * cv[1]);
        assert_le(cn, 1e-8);
        checks += 2;
        max_c = fmax(max_c, cn);
      }
    }
    double share = (double)ok / WALK_TRIALS;
    printf("walk %-11s: %d/%d reached (%.2f%%), %.2f steps and %.2f traces each; max |end - target| %.2e"
           " (tol %.2e), plane %.2e, outside %.2e (%d vertices), |c| %.2e; failures:",
           cf->name, ok, WALK_TRIALS, 100.0 * share, ok ? (double)steps / ok : 0.0,
           ok ? (double)traces / ok : 0.0, max_dist, o.tol, max_plane, max_out, n_outside, max_c);
    for (int s = 1; s < 16; s++)
      if (fails[s]) printf(" %s %d", mf_status_str(-s), fails[s]);
    printf("\n");
    int n_fail = 0;
    for (int s = 0; s < 16; s++) n_fail += fails[s];
    assert_int_equal(ok + n_fail, WALK_TRIALS);
    assert_true(share >= 0.99);
    checks += 2;
    /* Per success: the end, three per vertex, two per constraint. */
    expected += 2 + (long)ok * (1 + 3 * (cf->k + 1) + 2 * cf->k);
    scene_destroy(sc);
  }
  printf("walk: %ld checks\n", checks);
  assert_int_equal(checks, expected);
}

/* ---- 2. The Jacobian blocks against finite differences --------------------------- */

#define JAC_CHAINS 40

/* The chain with vertex j's barycentrics moved by (d1, d2). */
static mf_chain moved(const scene *sc, const mf_chain *c, int j, double d1, double d2) {
  mf_chain m = *c;
  assert_int_equal(mf_vertex_set(sc, &m.v[j], m.v[j].mesh, m.v[j].prim, m.v[j].b1 + d1, m.v[j].b2 + d2),
                   MF_OK);
  return m;
}

/* The longest edge of vertex v's triangle: a barycentric unit's length at most. */
static double longest_edge(const scene *sc, const mf_vertex *v) {
  const mesh *m = &sc->meshes[v->mesh];
  const uint32_t *tri = m->idx + 3 * v->prim;
  vec3 p0 = mesh_position(m, tri[0]), p1 = mesh_position(m, tri[1]), p2 = mesh_position(m, tri[2]);
  return fmax(v3_len(v3_sub(p1, p0)), fmax(v3_len(v3_sub(p2, p1)), v3_len(v3_sub(p0, p2))));
}

static void test_jacobian(void **state) {
  (void)state;
  const double step = 1e-6; /* in scene units */
  long checks = 0, expected = 0;
  for (int ci = 0; ci < N_CONFIGS; ci++) {
    const config *cf = &CONFIGS[ci];
    scene *sc = load(cf);
    rng r;
    rng_seed(&r, cf->seed, 2);
    double max_err = 0.0, max_rel = 0.0, max_val = 0.0, max_entry = 0.0;
    for (int n = 0; n < JAC_CHAINS; n++) {
      mf_chain c0;
      draw_chain(sc, cf, &r, &c0);
      for (int off = 0; off < 2; off++) {
        /* On the manifold, then every vertex moved off it. */
        mf_chain c = c0;
        if (off)
          for (int j = 1; j <= c.k + 1; j++)
            c = moved(sc, &c, j, 0.02 * (2.0 * rng_uniform(&r) - 1.0), 0.02 * (2.0 * rng_uniform(&r) - 1.0));
        mf_jac J;
        assert_int_equal(mf_jacobian(sc, &c, &J), MF_OK);
        checks++;
        for (int i = 1; i <= c.k; i++) {
          /* The values: AD against plain. */
          double cv[2];
          assert_int_equal(mf_constraint(sc, &c, i, cv), MF_OK);
          for (int q = 0; q < 2; q++) {
            assert_near(J.c[i][q], cv[q], 1e-12);
            max_val = fmax(max_val, fabs(J.c[i][q] - cv[q]));
          }
          checks += 2;
          /* The blocks: columns b1, b2 of x_{i-1}, x_i, x_{i+1}. */
          for (int j = i - 1; j <= i + 1; j++) {
            if (j < 1) continue;
            double(*blk)[2] = j == i - 1 ? J.A[i] : (j == i ? J.B[i] : J.C[i]);
            double h = step / longest_edge(sc, &c.v[j]);
            for (int col = 0; col < 2; col++) {
              mf_chain cp = moved(sc, &c, j, col == 0 ? h : 0.0, col == 1 ? h : 0.0);
              mf_chain cm = moved(sc, &c, j, col == 0 ? -h : 0.0, col == 1 ? -h : 0.0);
              double fp[2], fm[2];
              assert_int_equal(mf_constraint(sc, &cp, i, fp), MF_OK);
              assert_int_equal(mf_constraint(sc, &cm, i, fm), MF_OK);
              for (int row = 0; row < 2; row++) {
                double fd = (fp[row] - fm[row]) / (2.0 * h), a = blk[row][col];
                assert_near(a, fd, 1e-6 * (1.0 + fabs(a)));
                checks++;
                max_err = fmax(max_err, fabs(a - fd));
                max_rel = fmax(max_rel, fabs(a - fd) / (1e-300 + fabs(a)));
                max_entry = fmax(max_entry, fabs(a));
              }
            }
          }
        }
        /* Per chain: the Jacobian, 2 values and (2 or 3 blocks) x 4 entries per constraint. */
        expected += 1;
        for (int i = 1; i <= c.k; i++) expected += 2 + 4 * (i == 1 ? 2 : 3);
      }
    }
    printf("jacobian %-11s: %d chains on and off the manifold; max |AD - FD| %.2e (largest entry %.2e),"
           " max relative %.2e; max |c_AD - c_plain| %.2e\n",
           cf->name, JAC_CHAINS, max_err, max_entry, max_rel, max_val);
    scene_destroy(sc);
  }
  printf("jacobian: %ld checks\n", checks);
  assert_int_equal(checks, expected);
}

/* ---- 3. The generalized geometry term against the traced chain's map ------------------ */

#define G_CHAINS 100

/* The chain traced along direction d (a point start) or along c's d
 * through the point d (a direction start) with c's meshes and targets; 1
 * when it keeps every vertex's triangle. */
static int trace_same(const scene *sc, const mf_chain *c, vec3 d, vec3 *OUT_end) {
  mf_chain t;
  int st = c->start == MF_START_DIRECTION ? mf_trace_through(sc, c, d, &t) : mf_trace(sc, c, d, &t);
  if (st != MF_OK) return 0;
  for (int i = 1; i <= c->k + 1; i++)
    if (t.v[i].prim != c->v[i].prim) return 0;
  *OUT_end = t.v[t.k + 1].p;
  return 1;
}

static void test_geometry_term(void **state) {
  (void)state;
  long checks = 0, expected = 0;
  for (int ci = 0; ci < N_CONFIGS; ci++) {
    const config *cf = &CONFIGS[ci];
    scene *sc = load(cf);
    rng r;
    rng_seed(&r, cf->seed, 3);
    int compared = 0, skipped = 0, retried = 0;
    double max_rel = 0.0, gmin = INFINITY, gmax = 0.0;
    for (int n = 0; n < G_CHAINS; n++) {
      mf_chain c;
      draw_chain(sc, cf, &r, &c);
      double G;
      assert_int_equal(mf_geometry_term(sc, &c, &G), MF_OK);
      checks++;
      /* The stencil around the first direction (a point start: solid
       * angle), or around x_1 across d (a direction start: the rays'
       * offsets in the plane perpendicular to d). */
      int dir = c.start == MF_START_DIRECTION;
      vec3 d0 = dir ? c.v[1].p : v3_normalize(v3_sub(c.v[1].p, c.x0));
      frame f = frame_from_z(dir ? c.d : d0);
      double h = 5e-6;
      int done = 0;
      for (int attempt = 0; attempt < 4 && !done; attempt++, h *= 0.25) {
        vec3 e[4];
        int good = 1;
        for (int s = 0; s < 4 && good; s++) {
          double a = s == 0 ? h : (s == 1 ? -h : 0.0), b = s == 2 ? h : (s == 3 ? -h : 0.0);
          good = trace_same(sc, &c, v3_add(d0, v3_add(v3_scale(f.s, a), v3_scale(f.t, b))), &e[s]);
        }
        if (!good) {
          retried++;
          continue;
        }
        vec3 pa = v3_scale(v3_sub(e[0], e[1]), 0.5 / h), pb = v3_scale(v3_sub(e[2], e[3]), 0.5 / h);
        double dA_dw = v3_len(v3_cross(pa, pb));
        /* cos theta_0 = 1: x_0 is a point; a direction start's rays
         * cross the perpendicular plane in a unit of area per unit of
         * (a, b). */
        double G_traced = 1.0 / dA_dw;
        double rel = fabs(G - G_traced) / G_traced;
        assert_le(rel, 1e-6);
        checks++;
        max_rel = fmax(max_rel, rel);
        gmin = fmin(gmin, G);
        gmax = fmax(gmax, G);
        compared++;
        done = 1;
      }
      if (!done) skipped++;
    }
    printf("G %-11s: %d chains compared (%d stencils redone with a smaller step, %d left out),"
           " G in [%.4g, %.4g], max relative error %.2e\n",
           cf->name, compared, retried, skipped, gmin, gmax, max_rel);
    assert_int_equal(compared + skipped, G_CHAINS);
    assert_true(compared >= G_CHAINS * 9 / 10);
    checks += 2;
    /* G per chain, a comparison per compared chain, the two tallies. */
    expected += G_CHAINS + compared + 2;
    scene_destroy(sc);
  }
  printf("geometry term: %ld checks\n", checks);
  assert_int_equal(checks, expected);
}

/* ---- 4. A direction start's projection ray ------------------------------------------- */

/* mf_start_ray and mf_trace_through after a direction start (sun-mirror):
 * the ray passes through the given point along d from outside the
 * bounding sphere; its first hit is x_1 when it meets the mirror first
 * (the floor behind the mirror: still the mirror), MF_ESHAPE when the
 * floor comes first, MF_EMISS when it meets nothing; mf_trace refuses a
 * direction start. */
#define DIR_TRIALS 200

static void test_direction_start(void **state) {
  (void)state;
  const config *cf = &CONFIGS[5];
  assert_true(cf->dir_start);
  scene *sc = load(cf);
  mf_chain proto = proto_of(cf), out;
  rng r;
  rng_seed(&r, cf->seed, 5);
  long checks = 0;
  int n_ok = 0, n_shape = 0, n_miss = 0;
  double max_line = 0.0, min_out = INFINITY;
  for (int t = 0; t < DIR_TRIALS; t++) {
    /* A point anywhere in a box around the scene and beyond it. */
    vec3 q = v3(-8.0 + 16.0 * rng_uniform(&r), 4.0 * rng_uniform(&r), -8.0 + 16.0 * rng_uniform(&r));
    vec3 org, dir;
    assert_int_equal(mf_start_ray(sc, &proto, q, &org, &dir), MF_OK);
    /* Outside the bounding sphere, on the line through q along d. */
    double out_r = v3_len(v3_sub(org, sc->center)) / sc->radius;
    vec3 off = v3_sub(q, org);
    double line = v3_len(v3_sub(off, v3_scale(dir, v3_dot(off, dir))));
    assert_true(out_r > 1.0);
    assert_true(v3_dot(off, dir) > 0.0);
    assert_le(line, 1e-12 * sc->radius);
    assert_near(v3_len(v3_sub(dir, proto.d)), 0.0, 1e-15);
    checks += 4;
    min_out = fmin(min_out, out_r);
    max_line = fmax(max_line, line);
    /* The first hit decides. */
    surface_hit h;
    int hit = scene_intersect(sc, org, dir, scene_ray_eps(sc, org), INFINITY, &h);
    int st = mf_trace_through(sc, &proto, q, &out);
    int want = !hit ? MF_EMISS : (h.mesh != proto.v[1].mesh ? MF_ESHAPE : -100);
    if (want == -100) {
      /* The mirror first: the chain may still fail later (its reflection
       * missing the floor), but never at x_1. */
      assert_true(st == MF_OK || st == MF_EMISS || st == MF_ESHAPE);
      if (st == MF_OK) assert_true(v3_len(v3_sub(out.v[1].p, h.p)) <= 1e-12 * sc->radius);
      n_ok += st == MF_OK;
    } else {
      assert_int_equal(st, want);
      n_shape += want == MF_ESHAPE;
      n_miss += want == MF_EMISS;
    }
    checks++;
  }
  /* mf_trace takes point starts only. */
  assert_int_equal(mf_trace(sc, &proto, proto.d, &out), MF_EINVAL);
  checks++;
  printf("direction start: %d rays from outside the bounding sphere (min |org - center| %.3f radius,"
         " max distance of the point from the ray %.2e): %d chains, %d first hits on another mesh,"
         " %d misses; %ld checks\n",
         DIR_TRIALS, min_out, max_line, n_ok, n_shape, n_miss, checks);
  assert_true(n_ok > 0 && n_shape > 0 && n_miss > 0);
  assert_int_equal(checks, 5 * DIR_TRIALS + 1);
  scene_destroy(sc);
}

/* ---- 5. Chains of path-space paths ---------------------------------------------------- */

/* A scene for whole paths: the glass sphere (centre 1 above the floor's
 * 1.2 below it, so that the floor lies beyond the focus of the sun's
 * beam, and the end's map does not fold) over the floor, a flat mirror
 * beside them, a glossy ball (roughconductor, alpha 0.05: ps_glossy), a
 * point light and a directional light (the sun). Meshes: 0 glass, 1
 * floor, 2 mirror, 3 ball. */
static const char *xml_paths =
    "<scene version=\"0.6.0\">\n" SENSOR
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"1\" z=\"0\"/><float name=\"radius\" value=\"1\"/>\n"
    "    <bsdf type=\"dielectric\"><float name=\"intIOR\" value=\"1.5\"/><float name=\"extIOR\" value=\"1\"/></bsdf>\n"
    "  </shape>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/><scale x=\"8\" y=\"1\" z=\"8\"/><translate y=\"-1.2\"/></transform>\n"
    "    <bsdf type=\"diffuse\"/>\n"
    "  </shape>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"toWorld\"><rotate y=\"1\" angle=\"-90\"/><scale value=\"1.5\"/><translate x=\"3.5\" y=\"1.6\" z=\"0\"/></transform>\n"
    "    <bsdf type=\"conductor\"/>\n"
    "  </shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"-3\" y=\"0\" z=\"0\"/><float name=\"radius\" value=\"0.8\"/>\n"
    "    <bsdf type=\"roughconductor\"><float name=\"alpha\" value=\"0.05\"/></bsdf>\n"
    "  </shape>\n"
    "  <emitter type=\"point\"><point name=\"position\" x=\"0.1\" y=\"3\" z=\"0.2\"/><rgb name=\"intensity\" value=\"10, 10, 10\"/></emitter>\n"
    "  <emitter type=\"directional\"><vector name=\"direction\" x=\"0.6\" y=\"-1\" z=\"0.1\"/><rgb name=\"irradiance\" value=\"2, 2, 2\"/></emitter>\n"
    "</scene>\n";

enum { PM_GLASS = 0, PM_FLOOR = 1, PM_MIRROR = 2, PM_BALL = 3 };

/* The path shapes: where the chain lies and how its path is made. */
typedef enum path_kind {
  PK_SUN_GLASS,   /* sun -> glass -> glass -> floor -> camera; chain (1, 4) from the sun */
  PK_SUN_MIRROR,  /* sun -> mirror -> floor -> camera; chain (1, 3) from the sun */
  PK_CAM_MIRROR,  /* camera -> mirror -> floor -> point light; chain (0, 2) from the pinhole */
  PK_POINT_GLASS, /* point light -> glass -> glass -> floor -> camera; chain (1, 4) from x_4 */
  PK_CAM_GLOSSY,  /* camera -> glossy ball -> floor -> point light; chain (0, 2), glossy */
  PK_COUNT
} path_kind;

static const struct {
  const char *name;
  int k, a, b;      /* the path's length and the chain's ends */
  unsigned flags;
  int light_side;   /* the chain's records made by a light walk (wo towards x_{j+1}) */
} PATH_KINDS[PK_COUNT] = {
    {"sun-glass", 4, 1, 4, 0, 1},
    {"sun-mirror", 3, 1, 3, 0, 1},
    {"cam-mirror", 3, 0, 2, 0, 0},
    {"point-glass", 4, 1, 4, MF_PATH_FROM_B, 1},
    {"cam-glossy", 3, 0, 2, MF_PATH_GLOSSY, 0},
};

static int light_of_type(const scene *sc, light_type t) {
  for (int i = 0; i < sc->n_lights; i++)
    if (sc->lights[i].type == t) return i;
  fail_msg("no light of type %d", (int)t);
  return -1;
}

/* A surface record as bdpt's walks make one, the ray along dir. */
static bdpt_vertex surface_record(const surface_hit *h, vec3 dir) {
  bdpt_vertex v;
  memset(&v, 0, sizeof v);
  v.type = BDPT_VERTEX_SURFACE;
  v.light = h->light;
  v.p = h->p;
  v.n = h->ng;
  v.wo = v3_neg(dir);
  v.hit = *h;
  v.jac = 1.0;
  return v;
}

/* From org along dir: n specular scatterings through each hit's delta
 * lobe (trans[i]: its transmission, else its reflection; bsdf_sample_f as
 * bdpt's walks), onto end_mesh; the n + 1 records into OUT. 0 when the
 * walk goes elsewhere. */
static int walk_specular(const scene *sc, vec3 org, vec3 dir, int n, const int *meshes,
                         const int *trans, bdpt_vertex *OUT) {
  for (int i = 0; i <= n; i++) {
    surface_hit h;
    if (!scene_intersect(sc, org, dir, scene_ray_eps(sc, org), INFINITY, &h)) return 0;
    if (h.mesh != meshes[i]) return 0;
    OUT[i] = surface_record(&h, dir);
    if (i == n) break;
    bsdf_sample bs;
    vec3 wo_l = frame_to_local(&h.sh, v3_neg(dir));
    if (!bsdf_sample_f(h.bsdf, h.tu, h.tv, wo_l, trans[i] ? 1.0 - 1e-9 : 0.0, 0.5, 0.5,
                       TRANSPORT_RADIANCE, &bs))
      return 0;
    if (!(bs.flags & BSDF_DELTA) || !!(bs.flags & BSDF_TRANSMISSION) != !!trans[i]) return 0;
    org = h.p;
    dir = v3_normalize(frame_to_world(&h.sh, bs.wi));
  }
  return 1;
}

/* A random path of kind pk (drawn again until it is made), evaluated
 * (ps_eval: the delta and inf flags). */
static void make_path(const scene *sc, const ps_context *ctx, path_kind pk, rng *r, ps_path *OUT) {
  const int sun = light_of_type(sc, LIGHT_DIRECTIONAL), pt = light_of_type(sc, LIGHT_POINT);
  const vec3 sun_d = sc->lights[sun].frm.n, light_p = sc->lights[pt].pos;
  bdpt_vertex cam, lig, rec[3];
  memset(&cam, 0, sizeof cam);
  cam.type = BDPT_VERTEX_CAMERA;
  cam.p = sc->cam.pos;
  cam.light = -1;
  for (int tries = 0; tries < 100000; tries++) {
    memset(OUT, 0, sizeof *OUT);
    memset(&lig, 0, sizeof lig);
    lig.type = BDPT_VERTEX_LIGHT;
    double u1 = rng_uniform(r), u2 = rng_uniform(r);
    int ok = 0, k = PATH_KINDS[pk].k;
    if (pk == PK_SUN_GLASS || pk == PK_SUN_MIRROR) {
      /* The sun's ray through a disk across it (around the sphere's
       * centre or the mirror's), from outside the scene. */
      frame f = frame_from_z(sun_d);
      vec3 c = pk == PK_SUN_GLASS ? v3(0.0, 1.0, 0.0) : v3(3.5, 1.8, 0.0);
      double rad = pk == PK_SUN_GLASS ? 0.15 : 0.5, rr = rad * sqrt(u1), ph = 2.0 * M_PI * u2;
      vec3 q = v3_add(c, frame_to_world(&f, v3(rr * cos(ph), rr * sin(ph), 0.0)));
      vec3 org = v3_fma(q, sun_d, -(v3_dot(v3_sub(q, sc->center), sun_d) + 2.0 * sc->radius));
      static const int mg[3] = {PM_GLASS, PM_GLASS, PM_FLOOR}, mm[2] = {PM_MIRROR, PM_FLOOR};
      static const int tg[2] = {1, 1}, tm[1] = {0};
      int n = pk == PK_SUN_GLASS ? 2 : 1;
      ok = walk_specular(sc, org, sun_d, n, pk == PK_SUN_GLASS ? mg : mm, pk == PK_SUN_GLASS ? tg : tm,
                         rec);
      lig.light = sun;
      lig.dir = sun_d;
      lig.p = org;
      /* x_0 the camera, x_1 .. x_{k-1} the light walk's records reversed. */
      for (int j = 1; j < k; j++) OUT->x[j].v = rec[k - 1 - j];
    } else if (pk == PK_POINT_GLASS) {
      /* From the point light towards the sphere's upper cap. */
      vec3 aim = v3(0.12 * (2.0 * u1 - 1.0), 2.0, 0.12 * (2.0 * u2 - 1.0));
      static const int mg[3] = {PM_GLASS, PM_GLASS, PM_FLOOR}, tg[2] = {1, 1};
      ok = walk_specular(sc, light_p, v3_normalize(v3_sub(aim, light_p)), 2, mg, tg, rec);
      lig.light = pt;
      lig.p = light_p;
      for (int j = 1; j < k; j++) OUT->x[j].v = rec[k - 1 - j];
    } else if (pk == PK_CAM_MIRROR) {
      /* From the pinhole towards the mirror. */
      vec3 aim = v3(3.5, 0.3 + 2.6 * u1, -1.3 + 2.6 * u2);
      static const int mm[2] = {PM_MIRROR, PM_FLOOR}, tm[1] = {0};
      ok = walk_specular(sc, cam.p, v3_normalize(v3_sub(aim, cam.p)), 1, mm, tm, rec);
      lig.light = pt;
      lig.p = light_p;
      for (int j = 1; j < k; j++) OUT->x[j].v = rec[j - 1];
    } else {
      /* From the pinhole to the ball's lower half, reflected about a
       * tilted normal (a glossy lobe's microfacet) onto the floor. */
      vec3 aim = v3(-3.0 + 0.5 * (2.0 * u1 - 1.0), -0.5 * u2, 0.8);
      vec3 dir = v3_normalize(v3_sub(aim, cam.p));
      surface_hit h, h2;
      if (scene_intersect(sc, cam.p, dir, scene_ray_eps(sc, cam.p), INFINITY, &h) && h.mesh == PM_BALL) {
        vec3 m = v3_normalize(v3_add(h.sh.n, v3(0.05 * (2.0 * rng_uniform(r) - 1.0), 0.0,
                                                 0.05 * (2.0 * rng_uniform(r) - 1.0))));
        vec3 d2 = v3_normalize(v3_reflect(v3_neg(dir), m));
        if (v3_dot(d2, h.ng) > 0.0 && scene_intersect(sc, h.p, d2, scene_ray_eps(sc, h.p), INFINITY, &h2) &&
            h2.mesh == PM_FLOOR) {
          rec[0] = surface_record(&h, dir);
          rec[1] = surface_record(&h2, d2);
          ok = 1;
        }
      }
      lig.light = pt;
      lig.p = light_p;
      for (int j = 1; j < k; j++) OUT->x[j].v = rec[j - 1];
    }
    if (!ok) continue;
    OUT->k = k;
    OUT->x[0].v = cam;
    OUT->x[k].v = lig;
    ps_eval(ctx, OUT);
    return;
  }
  fail_msg("%s: no path", PATH_KINDS[pk].name);
}

static int vec_close(vec3 a, vec3 b, double tol) { return v3_len(v3_sub(a, b)) <= tol; }

#define PATHS_PER_KIND 200
/* Targets within PATH_RHO scene->radius (about 0.023) of the end: the
 * glass's beams converge on the floor (the point light's towards its
 * image), and a target much farther can lie beyond the fold of the end's
 * map (0.005 scene->radius: 96.5% of the point-glass walks arrive). */
#define PATH_RHO 0.002

static void test_path_chains(void **state) {
  (void)state;
  static const config pcf = {"paths", &xml_paths, {0, 0, 0}, {0, 0, 0}, 0.0, 1, {MF_REFLECT, MF_REFLECT},
                             {0, 0, 0}, 0.0, 0, 0, {0, 0, 0}};
  scene *sc = load(&pcf);
  ps_context ctx;
  render_settings rs = sc->settings;
  rs.maxdepth = 8;
  rs.mindepth = -1;
  ps_context_init(&ctx, sc, &rs);
  mf_options o;
  mf_options_default(sc, &o);
  long checks = 0, expected = 0;
  for (int pk = 0; pk < PK_COUNT; pk++) {
    const int a = PATH_KINDS[pk].a, b = PATH_KINDS[pk].b, k = b - a - 1;
    const unsigned flags = PATH_KINDS[pk].flags;
    rng r;
    rng_seed(&r, 21 + (uint64_t)pk, 6);
    int ok = 0;
    double max_c = 0.0, max_hit = 0.0, max_t = 0.0;
    for (int n = 0; n < PATHS_PER_KIND; n++) {
      ps_path path, q, tmp;
      make_path(sc, &ctx, (path_kind)pk, &r, &path);
      /* The chain's start and its order: x_0 is path vertex s, x_i is s + i step. */
      int from_b = pk == PK_SUN_GLASS || pk == PK_SUN_MIRROR || pk == PK_POINT_GLASS;
      int s = from_b ? b : a, step = from_b ? -1 : 1;

      /* 1. The chain read from the path. */
      mf_chain c;
      assert_int_equal(mf_chain_from_path(&ctx, &path, a, b, flags, &c), MF_OK);
      assert_int_equal(c.k, k);
      if (pk == PK_SUN_GLASS || pk == PK_SUN_MIRROR) {
        assert_int_equal(c.start, MF_START_DIRECTION);
        assert_true(path.x[b].inf);
        assert_true(vec_close(c.d, path.x[b].v.dir, 1e-15));
      } else {
        assert_int_equal(c.start, MF_START_POINT);
        assert_true(vec_close(c.x0, path.x[s].v.p, 0.0));
        assert_true(vec_close(c.n0, path.x[s].v.type == BDPT_VERTEX_CAMERA ? sc->cam.forward : v3(0, 0, 0), 0.0));
      }
      checks += 4;
      for (int i = 1; i <= k + 1; i++) {
        const bdpt_vertex *x = &path.x[s + i * step].v;
        assert_int_equal(c.v[i].mesh, x->hit.mesh);
        assert_true(c.v[i].prim == x->hit.prim && c.v[i].b1 == x->hit.b1 && c.v[i].b2 == x->hit.b2);
        checks += 2;
        if (i > k) continue;
        int glass = pk == PK_SUN_GLASS || pk == PK_POINT_GLASS;
        assert_int_equal(c.v[i].kind, glass ? MF_REFRACT : MF_REFLECT);
        assert_true(!glass || c.v[i].eta == 1.5);
        assert_int_equal(path.x[s + i * step].delta, pk != PK_CAM_GLOSSY);
        double cv[2];
        assert_int_equal(mf_constraint(sc, &c, i, cv), MF_OK);
        assert_le(hypot(cv[0], cv[1]), 1e-9);
        max_c = fmax(max_c, hypot(cv[0], cv[1]));
        /* A glossy vertex's target is its half vector, not zero here. */
        assert_true(pk != PK_CAM_GLOSSY || hypot(c.v[i].target[0], c.v[i].target[1]) > 1e-4);
        checks += 6;
      }

      /* 2. Written back unchanged: the identity, bit for bit. */
      q = path;
      assert_int_equal(mf_chain_to_path(sc, &c, a, b, flags, &q), MF_OK);
      assert_memory_equal(&q, &path, sizeof q);
      checks += 2;

      /* 3. Walked to a target near its end, written back. */
      mf_chain res;
      frame f = frame_from_z(c.v[k + 1].ng);
      double rr = PATH_RHO * sc->radius * sqrt(rng_uniform(&r)), ph = 2.0 * M_PI * rng_uniform(&r);
      vec3 target = v3_add(c.v[k + 1].p, frame_to_world(&f, v3(rr * cos(ph), rr * sin(ph), 0.0)));
      if (mf_walk(sc, &c, target, &o, &res, NULL) != MF_OK) continue;
      ok++;
      q = path;
      assert_int_equal(mf_chain_to_path(sc, &res, a, b, flags, &q), MF_OK);
      checks++;
      /* The vertices outside the chain are untouched. */
      for (int j = 0; j <= path.k; j++) {
        int in_chain = (j - s) * step >= 1 && (j - s) * step <= k + 1;
        if (!in_chain) assert_memory_equal(&q.x[j], &path.x[j], sizeof q.x[j]);
        checks += !in_chain;
      }
      /* Each written vertex is what scene_intersect finds along the walked
       * chain's segment to it. */
      for (int i = 1; i <= k + 1; i++) {
        int j = s + i * step;
        const bdpt_vertex *x = &q.x[j].v;
        vec3 org, dir;
        if (i == 1)
          assert_int_equal(mf_start_ray(sc, &res, res.v[1].p, &org, &dir), MF_OK);
        else
          org = res.v[i - 1].p, dir = v3_normalize(v3_sub(res.v[i].p, org));
        surface_hit h;
        assert_true(scene_intersect(sc, org, dir, scene_ray_eps(sc, org), INFINITY, &h));
        assert_true(h.mesh == x->hit.mesh && h.prim == x->hit.prim && h.bsdf == x->hit.bsdf &&
                    h.light == x->hit.light && x->light == h.light);
        double e = fmax(fabs(h.b1 - x->hit.b1), fabs(h.b2 - x->hit.b2));
        e = fmax(e, v3_len(v3_sub(h.p, x->hit.p)));
        e = fmax(e, v3_len(v3_sub(h.ng, x->hit.ng)));
        e = fmax(e, v3_len(v3_sub(h.sh.n, x->hit.sh.n)));
        e = fmax(e, v3_len(v3_sub(h.sh.s, x->hit.sh.s)));
        e = fmax(e, fmax(fabs(h.tu - x->hit.tu), fabs(h.tv - x->hit.tv)));
        assert_le(e, 1e-9);
        assert_true(vec_close(x->p, x->hit.p, 0.0) && vec_close(x->n, x->hit.ng, 0.0));
        max_hit = fmax(max_hit, e);
        /* wo towards its own walk's neighbour; t the distance along the
         * ray from it (traced). */
        int nb = PATH_KINDS[pk].light_side ? j + 1 : j - 1;
        vec3 wo_want = ps_dir(&q, j, nb);
        assert_true(vec_close(x->wo, wo_want, 0.0));
        vec3 org2 = q.x[nb].inf ? v3_fma(x->p, q.x[nb].v.dir, -(v3_dot(v3_sub(x->p, sc->center),
                                                                          q.x[nb].v.dir) + 2.0 * sc->radius))
                                : q.x[nb].v.p;
        surface_hit h2;
        vec3 dir2 = v3_neg(x->wo);
        assert_true(scene_intersect(sc, org2, dir2, scene_ray_eps(sc, org2), INFINITY, &h2));
        assert_true(h2.mesh == x->hit.mesh);
        assert_near(h2.t, x->hit.t, 1e-9);
        max_t = fmax(max_t, fabs(h2.t - x->hit.t));
        checks += 7;
      }
      /* Read back: the walked chain, its targets its half vectors. */
      mf_chain back;
      assert_int_equal(mf_chain_from_path(&ctx, &q, a, b, flags, &back), MF_OK);
      for (int i = 1; i <= k + 1; i++) {
        assert_true(back.v[i].mesh == res.v[i].mesh && back.v[i].prim == res.v[i].prim &&
                    back.v[i].b1 == res.v[i].b1 && back.v[i].b2 == res.v[i].b2 &&
                    back.v[i].kind == res.v[i].kind);
        assert_near(back.v[i].target[0], res.v[i].target[0], 1e-8);
        assert_near(back.v[i].target[1], res.v[i].target[1], 1e-8);
        checks += 3;
      }
      /* The path evaluates (f is the caller's business; its caches fill). */
      tmp = q;
      ps_eval(&ctx, &tmp);
      assert_true(rgb_isfinite(tmp.f));
      checks += 2;
    }
    /* Paths that are not chains. */
    {
      ps_path path;
      mf_chain c;
      make_path(sc, &ctx, (path_kind)pk, &r, &path);
      /* An inner vertex that is not specular: the chain widened by one
       * vertex at its non-specular end. */
      int wa = a > 0 ? a - 1 : a, wb = a > 0 ? b : b + 1;
      assert_int_equal(mf_chain_from_path(&ctx, &path, wa, wb, flags, &c), MF_EINVAL);
      /* Out of range, too short. */
      assert_int_equal(mf_chain_from_path(&ctx, &path, a, path.k + 1, flags, &c), MF_EINVAL);
      assert_int_equal(mf_chain_from_path(&ctx, &path, a, a + 1, flags, &c), MF_EINVAL);
      /* Glossy vertices only when asked. */
      if (pk == PK_CAM_GLOSSY) assert_int_equal(mf_chain_from_path(&ctx, &path, a, b, 0, &c), MF_EINVAL);
      checks += 4;
    }
    printf("path chains %-11s: %d paths (k = %d, chain x_%d .. x_%d%s), read, written back unchanged"
           " (identity); %d/%d walks reached (%.1f%%), written back: max |hit - scene_intersect| %.2e,"
           " |t - traced| %.2e; |c| on reading %.2e\n",
           PATH_KINDS[pk].name, PATHS_PER_KIND, PATH_KINDS[pk].k, a, b,
           flags & MF_PATH_GLOSSY ? ", glossy" : (pk == PK_SUN_GLASS || pk == PK_SUN_MIRROR ? ", from the sun" : (flags & MF_PATH_FROM_B ? ", from x_b" : "")), ok, PATHS_PER_KIND,
           100.0 * ok / PATHS_PER_KIND, max_hit, max_t, max_c);
    assert_true(ok >= PATHS_PER_KIND * 99 / 100);
    checks++;
    /* Per path: 4 + 2 per vertex + 6 per specular vertex + 2; per walk
     * 1 + the untouched + 7 per vertex + 3 per vertex + 2; 4 refusals; the share. */
    int untouched = PATH_KINDS[pk].k + 1 - (k + 1);
    expected += (long)PATHS_PER_KIND * (4 + 2 * (k + 1) + 6 * k + 2) +
                (long)ok * (1 + untouched + 7 * (k + 1) + 3 * (k + 1) + 2) + 4 + 1;
  }
  printf("path chains: %ld checks\n", checks);
  assert_int_equal(checks, expected);
  scene_destroy(sc);
}

/* ---- The solver on its own: the block Thomas solution satisfies the system --------- */

static void test_solve(void **state) {
  (void)state;
  rng r;
  rng_seed(&r, 5, 4);
  long checks = 0, n_rows = 0;
  double max_res = 0.0;
  for (int trial = 0; trial < 200; trial++) {
    mf_jac J;
    memset(&J, 0, sizeof J);
    J.k = 1 + (int)rng_uniform_u32(&r, MF_MAX_CHAIN);
    double rhs[2 * (MF_MAX_CHAIN + 1)], d[2 * (MF_MAX_CHAIN + 2)], d_end[2];
    for (int i = 1; i <= J.k; i++)
      for (int a = 0; a < 2; a++) {
        rhs[2 * i + a] = 2.0 * rng_uniform(&r) - 1.0;
        for (int b = 0; b < 2; b++) {
          J.A[i][a][b] = i > 1 ? 2.0 * rng_uniform(&r) - 1.0 : 0.0;
          J.C[i][a][b] = 2.0 * rng_uniform(&r) - 1.0;
          /* Diagonally dominant B: the system is well conditioned. */
          J.B[i][a][b] = (a == b ? 6.0 : 0.0) + 2.0 * rng_uniform(&r) - 1.0;
        }
      }
    d_end[0] = 2.0 * rng_uniform(&r) - 1.0;
    d_end[1] = 2.0 * rng_uniform(&r) - 1.0;
    assert_int_equal(mf_solve(&J, rhs, d_end, d), MF_OK);
    checks++;
    n_rows += J.k;
    d[2 * (J.k + 1)] = d_end[0];
    d[2 * (J.k + 1) + 1] = d_end[1];
    for (int i = 1; i <= J.k; i++)
      for (int a = 0; a < 2; a++) {
        double s = 0.0;
        for (int b = 0; b < 2; b++)
          s += J.A[i][a][b] * d[2 * (i - 1) + b] + J.B[i][a][b] * d[2 * i + b] +
               J.C[i][a][b] * d[2 * (i + 1) + b];
        /* Residual: a few ulps of the O(10) terms, times the k steps. */
        assert_near(s, rhs[2 * i + a], 1e-12);
        checks++;
        max_res = fmax(max_res, fabs(s - rhs[2 * i + a]));
      }
  }
  printf("solve: 200 random block tridiagonal systems (k in 1 .. %d), max residual %.2e; %ld checks\n",
         MF_MAX_CHAIN, max_res, checks);
  assert_int_equal(checks, 200 + 2 * n_rows);
}

int main(void) {
  setvbuf(stdout, NULL, _IOLBF, 0);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_solve),
      cmocka_unit_test(test_jacobian),
      cmocka_unit_test(test_walk),
      cmocka_unit_test(test_geometry_term),
      cmocka_unit_test(test_direction_start),
      cmocka_unit_test(test_path_chains),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
