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
} config;

static const config CONFIGS[] = {
    {"glass", &xml_glass, {0.1, 3.0, 0.2}, {0.0, 0.0, 0.0}, 0.15, 2, {MF_REFRACT, MF_REFRACT}, {0, 0, 1}, 0.0, 11},
    {"mirror", &xml_mirror, {-0.5, 2.5, 0.2}, {1.5, 1.6, 0.0}, 0.4, 1, {MF_REFLECT, MF_REFLECT}, {0, 1, -1}, 0.0, 12},
    {"ball", &xml_ball, {-2.5, 3.0, 0.3}, {0.0, 1.2, 0.0}, 0.26, 1, {MF_REFLECT, MF_REFLECT}, {0, 1, -1}, 0.0, 13},
    {"ball-glossy", &xml_ball, {-2.5, 3.0, 0.3}, {0.0, 1.2, 0.0}, 0.26, 1, {MF_REFLECT, MF_REFLECT}, {0, 1, -1}, 0.1, 14},
};
#define N_CONFIGS ((int)(sizeof CONFIGS / sizeof CONFIGS[0]))

static scene *load(const config *cf) {
  char path[96];
  snprintf(path, sizeof path, "/tmp/lmc_test_manifold_%d_%s.xml", (int)getpid(), cf->name);
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(*cf->xml, f);
  fclose(f);
  scene *sc = NULL;
  lmc_error err;
  lmc_status st = scene_load_xml(path, NULL, 0, &sc, &err);
  remove(path);
  if (st != LMC_OK) print_error("%s\n", err.msg);
  assert_int_equal(st, LMC_OK);
  return sc;
}

/* The prototype chain of a configuration (meshes, kinds; targets zero). */
static mf_chain proto_of(const config *cf) {
  mf_chain c;
  memset(&c, 0, sizeof c);
  c.k = cf->k;
  c.x0 = cf->x0;
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
  frame f = frame_from_z(v3_normalize(v3_sub(cf->aim, cf->x0)));
  double cmin = cos(cf->cone);
  for (int tries = 0; tries < 100000; tries++) {
    if (cf->glossy > 0.0)
      for (int i = 1; i <= cf->k; i++) {
        proto.v[i].target[0] = cf->glossy * (2.0 * rng_uniform(r) - 1.0);
        proto.v[i].target[1] = cf->glossy * (2.0 * rng_uniform(r) - 1.0);
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

/* The chain traced along direction d with c's meshes and targets; 1 when
 * it keeps every vertex's triangle. */
static int trace_same(const scene *sc, const mf_chain *c, vec3 d, vec3 *OUT_end) {
  mf_chain t;
  if (mf_trace(sc, c, d, &t) != MF_OK) return 0;
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
      /* The stencil around the first direction. */
      vec3 d0 = v3_normalize(v3_sub(c.v[1].p, c.x0));
      frame f = frame_from_z(d0);
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
        double G_traced = 1.0 / dA_dw; /* cos theta_0 = 1: x_0 is a point */
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
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
