/*
 * test_invert_jacobian.c: the Jacobian of BDPT's subpath maps is the
 * strategy's density, the fact on which the inverse path sampler's moves
 * rest (mmlt_jump.h: f_t = n_k w_t C / p_t with p_t the true density of
 * the map from numbers to vertices).
 *
 * A subpath's continuous numbers v (the camera's film position over the
 * whole film and its BSDF direction numbers; the light's position numbers,
 * its emission direction and its BSDF direction numbers) map to its
 * vertices, each a point on its triangle (2 coordinates in the triangle's
 * plane); the discrete numbers (lobes, the light's choice) stay fixed. The
 * Jacobian determinant of that map, by central differences (h = 1e-6) of
 * the walk, must be 1 / prod_i pdf_fwd(x_i), the densities per unit area
 * the walk records and BDPT's MIS weights use (times the light's choice
 * probability for the emitter vertex, which the position numbers do not
 * carry), and with absolute directions (bdpt_param) prod jac / prod pdf,
 * jac the walk's d(direction numbers) / d(spherical coordinates) at each
 * rough vertex: the state's density in those coordinates (bdpt_states.h).
 *
 * The vertices where a density is one lobe's are checked: diffuse and rough
 * conductor surfaces and area lights (a mixture's recorded density sums
 * its lobes, while the map with the lobe number fixed has one lobe's), on
 * tests/data/invert/mixed.xml (GGX gold, diffuse; point and infinite
 * lights make no light vertex here) and the Cornell box. A sample is
 * skipped when a step of the differences lands on another triangle or
 * another lobe kind (edges); the counts of checked samples are asserted.
 * Central differences of smooth maps at h = 1e-6 have a relative error of
 * order h^2 times the ratio of third to first derivatives (about 1e-9 for
 * the scenes' scales) plus rounding, about 1e-16 * |x| / (h |dx/dv|)
 * (below 1e-7 at the Cornell box's size of 550): every determinant must
 * match to 1e-6, and the median to 1e-8; a sample where the determinants
 * at h and 2h differ by more than 3e-7 (Richardson: the error at h is
 * about a third of that) lies where h does not resolve the map's curvature
 * (next to the corner of a triangle's square-root warp) and is counted
 * apart, at most 1% of those checked. A negative control that leaves the
 * absolute directions' jac out of the density must fail (median error
 * above 1e-2).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "render/bsdf/bsdf.h"
#include "render/integrators/integrator.h"
#include "render/io/io.h"
#include "render/rng.h"
#include "arr_sampler.h"
#include "test_util.h"
#include "load_scene.h"

enum { MAXV = 4, DIM = 2 + 4 * MAXV + 8, NV = 2 * MAXV };

static const double H = 1e-6;

typedef struct jac_case {
  const scene *sc;
  render_settings rs;
  const bdpt_param *par;
  int is_cam, nv; /* the subpath and its vertices */
  int control;    /* negative control: the rough vertices' jac left out of the density */
} jac_case;

/* Walks u (camera: film numbers first) into path; the vertex count. */
static int walk(const jac_case *jc, const double *u, bdpt_vertex *path) {
  render_counters cnt = {0};
  if (jc->is_cam) {
    arr_smp a = arr_at(u + 2, DIM - 2);
    return bdpt_camera_subpath_p(jc->sc, &jc->rs, &a.base, u[0] * jc->sc->cam.width,
                                 u[1] * jc->sc->cam.height, jc->nv, jc->par, path, &cnt);
  }
  arr_smp a = arr_at(u, DIM);
  return bdpt_light_subpath_p(jc->sc, &jc->rs, &a.base, jc->nv, jc->par, path, &cnt);
}

/* One lobe's density at this vertex: a surface whose BSDF has one lobe, or
 * an area light's point. */
static int one_lobe(const scene *sc, const bdpt_vertex *v) {
  if (v->type == BDPT_VERTEX_LIGHT)
    return v->light >= 0 && sc->lights[v->light].type == LIGHT_AREA;
  if (v->type != BDPT_VERTEX_SURFACE || v->delta || !v->hit.bsdf) return 0;
  return bsdf_is(v->hit.bsdf, "diffuse") || bsdf_is(v->hit.bsdf, "roughconductor");
}

/* The continuous numbers of the subpath's first nv vertices (indices into
 * u), in the order of the vertices they place. */
static int coords(const jac_case *jc, int *idx) {
  int n = 0;
  if (jc->is_cam) {
    idx[n++] = 0, idx[n++] = 1;
    for (int i = 1; i + 1 < jc->nv; i++)
      idx[n++] = 2 + 4 * (i - 1) + 1, idx[n++] = 2 + 4 * (i - 1) + 2;
  } else {
    idx[n++] = 1, idx[n++] = 2;
    if (jc->nv >= 2) idx[n++] = 3, idx[n++] = 4;
    for (int i = 1; i + 1 < jc->nv; i++)
      idx[n++] = BDPT_DIMS_LIGHT_START + 4 * (i - 1) + 1,
      idx[n++] = BDPT_DIMS_LIGHT_START + 4 * (i - 1) + 2;
  }
  return n;
}

/* |det| of the n x n matrix a (row-major; destroyed), by Gaussian
 * elimination with partial pivoting. */
static double det_abs(double *a, int n) {
  double det = 1.0;
  for (int c = 0; c < n; c++) {
    int piv = c;
    for (int r = c + 1; r < n; r++)
      if (fabs(a[r * n + c]) > fabs(a[piv * n + c])) piv = r;
    if (a[piv * n + c] == 0.0) return 0.0;
    if (piv != c)
      for (int k = 0; k < n; k++) {
        double t = a[c * n + k];
        a[c * n + k] = a[piv * n + k], a[piv * n + k] = t;
      }
    det *= a[c * n + c];
    for (int r = c + 1; r < n; r++) {
      double m = a[r * n + c] / a[c * n + c];
      for (int k = c; k < n; k++) a[r * n + k] -= m * a[c * n + k];
    }
  }
  return fabs(det);
}

/* The placed vertices of a subpath: the camera's 1 .. nv - 1, the light's
 * 0 .. nv - 1. */
static int first_placed(const jac_case *jc) { return jc->is_cam ? 1 : 0; }

/* det(d vertices / d v) * (expected density) for numbers u; 0 when u is
 * not a sample to check (a vertex with a mixture's density, a delta lobe,
 * no full subpath, a difference step across an edge). */
static double jac_ratio(const jac_case *jc, const double *u, double h) {
  bdpt_vertex base[MAXV + 1], pp[MAXV + 1], pm[MAXV + 1];
  if (walk(jc, u, base) != jc->nv) return 0.0;
  int f0 = first_placed(jc);
  double expect = 1.0; /* prod pdf / prod jac: 1 / det when right */
  for (int i = f0; i < jc->nv; i++) {
    if (!one_lobe(jc->sc, &base[i]) || !(base[i].pdf_fwd > 0.0)) return 0.0;
    expect *= base[i].pdf_fwd;
    /* The direction leaving vertex i places vertex i + 1: its numbers read
     * absolutely at a rough vertex. */
    if (i + 1 < jc->nv && base[i].type == BDPT_VERTEX_SURFACE && jc->par && base[i].rough &&
        !jc->control)
      expect /= base[i].jac;
  }
  if (!jc->is_cam) {
    double pmf, ur;
    scene_sample_light(jc->sc, u[0], &pmf, &ur);
    expect /= pmf;
  }
  /* Each placed vertex's tangent frame (its triangle's plane). */
  vec3 e1[MAXV + 1], e2[MAXV + 1];
  for (int i = f0; i < jc->nv; i++) {
    vec3 n = v3_normalize(base[i].n);
    vec3 a = fabs(n.x) < 0.9 ? v3(1.0, 0.0, 0.0) : v3(0.0, 1.0, 0.0);
    e1[i] = v3_normalize(v3_cross(n, a));
    e2[i] = v3_cross(n, e1[i]);
  }
  int idx[NV], n = coords(jc, idx);
  if (n != 2 * (jc->nv - f0)) return 0.0;
  double J[NV * NV], up[DIM], um[DIM];
  for (int c = 0; c < n; c++) {
    memcpy(up, u, sizeof up);
    memcpy(um, u, sizeof um);
    up[idx[c]] += h, um[idx[c]] -= h;
    if (walk(jc, up, pp) != jc->nv || walk(jc, um, pm) != jc->nv) return 0.0;
    for (int i = f0; i < jc->nv; i++) {
      const bdpt_vertex *a = &pp[i], *b = &pm[i];
      if (a->type != base[i].type || b->type != base[i].type || a->hit.mesh != base[i].hit.mesh ||
          b->hit.mesh != base[i].hit.mesh || a->hit.prim != base[i].hit.prim ||
          b->hit.prim != base[i].hit.prim || a->delta != base[i].delta ||
          b->delta != base[i].delta)
        return 0.0;
      vec3 d = v3_scale(v3_sub(a->p, b->p), 1.0 / (2.0 * h));
      int r = 2 * (i - f0);
      J[r * n + c] = v3_dot(d, e1[i]);
      J[(r + 1) * n + c] = v3_dot(d, e2[i]);
    }
  }
  return det_abs(J, n) * expect;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* Checks n_samples random numbers of one subpath kind; the count checked. */
static int check_case(const jac_case *jc, int n_samples, uint64_t seed, const char *scene_name,
                      const char *what) {
  rng g;
  rng_seed(&g, seed, 1);
  static double err[200000];
  int m = 0, unresolved = 0;
  double worst = 0.0;
  for (int q = 0; q < n_samples && m < (int)(sizeof err / sizeof err[0]); q++) {
    double u[DIM];
    /* Away from the unit square's edges, where a step would wrap. */
    for (int i = 0; i < DIM; i++) u[i] = 1e-3 + (1.0 - 2e-3) * rng_uniform(&g);
    double r = jac_ratio(jc, u, H), r2 = r != 0.0 ? jac_ratio(jc, u, 2.0 * H) : 0.0;
    if (r == 0.0 || r2 == 0.0) continue;
    /* Richardson: the difference error at h is about a third of this; a
     * map whose curvature h does not resolve (near the sqrt of a triangle
     * sampler's corner) is counted apart. */
    if (fabs(r2 - r) > 3e-7) {
      unresolved++;
      continue;
    }
    err[m] = fabs(r - 1.0);
    if (err[m] > worst) worst = err[m];
    m++;
  }
  qsort(err, (size_t)m, sizeof err[0], cmp_double);
  double median = m > 0 ? err[m / 2] : 0.0;
  print_message("%s: %s, %d vertices%s: %d of %d checked (%d unresolved at h), |det pdf - 1| "
                "median %.2e, worst %.2e\n",
                scene_name, what, jc->nv, jc->par ? " (absolute directions)" : "", m, n_samples,
                unresolved, median, worst);
  if (jc->control) {
    assert_true(median > 1e-2); /* the control must fail */
    return m;
  }
  assert_true(worst < 1e-6);
  assert_true(median < 1e-8);
  assert_true(unresolved <= m / 100 + 1);
  return m;
}

static const bdpt_param g_abs = {100, 0.05};

static void run_scene(const char *path, int *OUT_cam, int *OUT_lt, int *OUT_abs) {
  scene *sc = load_scene(path);
  jac_case jc = {sc, render_settings_default(), NULL, 1, 2, 0};
  jc.rs.maxdepth = 2 * MAXV;
  jc.rs.rrdepth = 100; /* no Russian roulette: its number is discrete */
  const char *name = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
  for (int is_cam = 1; is_cam >= 0; is_cam--)
    for (int nv = is_cam ? 2 : 1; nv <= MAXV; nv++)
      for (int abs = 0; abs < 2; abs++) {
        jc.is_cam = is_cam, jc.nv = nv, jc.par = abs ? &g_abs : NULL;
        int m = check_case(&jc, 20000, 77 + (uint64_t)(100 * is_cam + 10 * nv + abs), name,
                           is_cam ? "camera" : "light");
        *(abs ? OUT_abs : is_cam ? OUT_cam : OUT_lt) += m;
      }
  /* The negative control: absolute directions without their jac. */
  jc.is_cam = 1, jc.nv = 3, jc.par = &g_abs, jc.control = 1;
  int m = check_case(&jc, 2000, 999, name, "camera, control without jac");
  assert_true(m > 0);
  scene_destroy(sc);
}

static void test_jacobian(void **state) {
  (void)state;
  int cam = 0, lt = 0, abs = 0;
  run_scene(LMC_SOURCE_DIR "/tests/data/invert/mixed.xml", &cam, &lt, &abs);
  int cam1 = cam, lt1 = lt, abs1 = abs;
  run_scene(LMC_SOURCE_DIR "/scenes/cornell-box/scene.xml", &cam, &lt, &abs);
  print_message("checked: camera %d, light %d, absolute directions %d (mixed.xml %d, %d, %d)\n",
                cam, lt, abs, cam1, lt1, abs1);
  assert_true(cam1 > 1000 && lt1 > 1000 && abs1 > 1000);
  assert_true(cam - cam1 > 1000 && lt - lt1 > 1000 && abs - abs1 > 1000);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_jacobian),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
