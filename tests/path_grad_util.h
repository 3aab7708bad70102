/*
 * path_grad_util.h: what the two path-gradient tests (test_path_grad.c,
 * test_path_grad_slow.c) share: evaluating a unidirectional path or one
 * bidirectional strategy (s, t) from a path_vec_sampler, the reference
 * value of bdpt_connect for the same numbers, and the check of the
 * gradient against central differences. Include after <cmocka.h>.
 */
#ifndef LMC_TESTS_PATH_GRAD_UTIL_H
#define LMC_TESTS_PATH_GRAD_UTIL_H

#include <math.h>
#include <string.h>

#include "render/integrators/integrator.h"
#include "ad/dual.h"
#include "render/integrators/path.h"

/* Which estimator: s < 0 is path_eval_pt, otherwise strategy (s, t). */
typedef struct pg_strategy {
  int s, t;
} pg_strategy;

static const pg_strategy PG_PT = {-1, 0};

/* Groups of bidirectional strategies, for counting what was checked. */
enum { PG_S0, PG_S1, PG_T1, PG_ST, PG_GROUPS };
static inline const char *pg_group_name(int g) {
  static const char *const names[PG_GROUPS] = {"s=0 (emitter hit)", "s=1 (light sample)",
                                                 "t=1 (light tracing)", "s,t>=2 (connection)"};
  return names[g];
}

static inline int pg_group(pg_strategy st) {
  if (st.s == 0) return PG_S0;
  if (st.t == 1) return PG_T1;
  if (st.s == 1) return PG_S1;
  return PG_ST;
}

/* A strategy for a random path length in [1, maxdepth], uniform over the
 * strategies of that length that BDPT uses. */
static inline pg_strategy pg_random_strategy(rng *r, int maxdepth) {
  for (;;) {
    int len = 1 + (int)(rng_uniform(r) * maxdepth);
    int t = 1 + (int)(rng_uniform(r) * (len + 1));
    int s = len + 1 - t;
    if (s == 1 && t == 1) continue;
    return (pg_strategy){s, t};
  }
}

static inline void pg_eval(const scene *sc, const render_settings *rs, path_vec_sampler *vs,
                    pg_strategy st, int want_grad, path_scratch *ps, path_eval *ev) {
  if (st.s < 0)
    path_eval_pt(sc, rs, &vs->base, want_grad, ps, ev, NULL);
  else
    path_eval_bdpt(sc, rs, &vs->base, st.s, st.t, want_grad, ps, ev, NULL);
}

/* bdpt_connect for the numbers stored in vs (the plain integrator's
 * subpaths, from the layout of integrator.h); *rx, *ry get the splat's
 * raster position for t = 1. */
static inline rgb pg_bdpt_reference(const scene *sc, const render_settings *rs, path_vec_sampler *vs,
                             pg_strategy st, double *rx, double *ry) {
  static bdpt_vertex cam[BDPT_MAX_VERTICES], lp[BDPT_MAX_VERTICES];
  int s = st.s, t = st.t;
  render_counters cnt = {0};
  path_vec_sampler_rewind(vs);
  *rx = *ry = 0.0;
  int nc;
  if (t >= 2) {
    sampler_use_stream(&vs->base, LMC_STREAM_CAMERA);
    double u0 = sampler_next(&vs->base), u1 = sampler_next(&vs->base);
    nc = bdpt_camera_subpath(sc, rs, &vs->base, u0 * sc->cam.width, u1 * sc->cam.height, t, cam,
                             &cnt);
  } else {
    nc = bdpt_camera_subpath(sc, rs, &vs->base, 0.0, 0.0, 1, cam, &cnt);
  }
  if (nc < t) return rgb_zero();
  if (s >= 2) {
    sampler_use_stream(&vs->base, LMC_STREAM_LIGHT);
    if (bdpt_light_subpath(sc, rs, &vs->base, s, lp, &cnt) < s) return rgb_zero();
  }
  double u[BDPT_DIMS_CONNECT] = {0.0, 0.0, 0.0};
  if (s == 1) {
    sampler_use_stream(&vs->base, LMC_STREAM_CONNECT);
    for (int k = 0; k < BDPT_DIMS_CONNECT * (t - 2); k++) sampler_next(&vs->base);
    for (int k = 0; k < BDPT_DIMS_CONNECT; k++) u[k] = sampler_next(&vs->base);
  }
  return bdpt_connect(sc, cam, t, lp, s, u, rx, ry, NULL, &cnt);
}

static inline int pg_rel_equal(double a, double b, double tol) {
  return fabs(a - b) <= tol * fmax(fabs(a), fabs(b)) || (a == 0.0 && b == 0.0);
}

static inline int pg_rgb_rel_equal(rgb a, rgb b, double tol) {
  return pg_rel_equal(a.r, b.r, tol) && pg_rel_equal(a.g, b.g, tol) && pg_rel_equal(a.b, b.b, tol);
}

/* Result of a central-difference check over many paths. */
typedef struct pg_fd_stats {
  int paths, components, passed, skipped_topology;
  int nontrivial; /* components whose derivative is not negligible (|fd| > 1e-3 f) */
  int raster;     /* of which raster-position components (t = 1) */
  int failed_unconverged; /* failures where no two successive h agreed to 1e-3 */
} pg_fd_stats;

/* Checks the gradient of the current path of vs (already evaluated into
 * ev0 with want_grad) against central differences: d luminance/du and
 * d rgb/du, and for t = 1 also d rx/du and d ry/du of the splat. */
static inline void pg_fd_check(const scene *sc, path_scratch *ps, const render_settings *rs,
                        path_vec_sampler *vs, pg_strategy st, const path_eval *ev0,
                        pg_fd_stats *fs) {
  int n = ev0->n_coords;
  path_coord coords[512];
  if (n > 512) return;
  memcpy(coords, ev0->coords, (size_t)n * sizeof *coords);
  uint64_t topo = ev0->topology;
  double f0 = ev0->lum;
  int nq = st.t == 1 ? 6 : 4;
  /* A raster derivative is judged against the film's size. */
  double rscale = sc->cam.width + sc->cam.height;
  fs->paths++;
  for (int k = 0; k < n; k++) {
    if (!coords[k].diff) continue;
    double *slot = &vs->u[coords[k].stream][coords[k].pos];
    double u = *slot;
    /* Central differences at steps h, h/2 (Richardson extrapolation,
     * error O(h^4)) for h = 1e-4, 1e-5, 1e-6, 1e-7; the estimate used is
     * the one that agrees best with the next smaller h (light-triangle and
     * envmap remaps stretch u by 1 / width, so no single h suits all
     * coordinates). The topology must be the same at every point used. */
    double rich[4][6];
    int same = 1;
    double hk = 1e-4;
    for (int lev = 0; lev < 4 && same; lev++, hk *= 0.1) {
      const double steps[4] = {hk, -hk, 0.5 * hk, -0.5 * hk};
      double y[6][4];
      for (int e = 0; e < 4; e++) {
        path_eval ev;
        *slot = u + steps[e];
        if (*slot < 0.0 || *slot >= 1.0) {
          same = 0;
          break;
        }
        path_vec_sampler_rewind(vs);
        pg_eval(sc, rs, vs, st, 0, ps, &ev);
        same = same && ev.topology == topo;
        y[0][e] = ev.lum;
        y[1][e] = ev.value.r;
        y[2][e] = ev.value.g;
        y[3][e] = ev.value.b;
        y[4][e] = ev.rx;
        y[5][e] = ev.ry;
      }
      if (!same) break;
      for (int q = 0; q < nq; q++) {
        double d1 = (y[q][0] - y[q][1]) / (2.0 * hk), d2 = (y[q][2] - y[q][3]) / hk;
        rich[lev][q] = (4.0 * d2 - d1) / 3.0;
      }
    }
    *slot = u;
    if (!same) {
      fs->skipped_topology++;
      continue;
    }
    double fd[6];
    for (int q = 0; q < nq; q++) {
      int best = 0;
      for (int lev = 1; lev < 3; lev++)
        if (fabs(rich[lev][q] - rich[lev + 1][q]) < fabs(rich[best][q] - rich[best + 1][q]))
          best = lev;
      fd[q] = rich[best][q];
    }
    double dad[6] = {coords[k].dlum, coords[k].drgb.r, coords[k].drgb.g,
                    coords[k].drgb.b, coords[k].drx,    coords[k].dry};
    for (int q = 0; q < nq; q++) {
      double err = fabs(fd[q] - dad[q]);
      double scale = q < 4 ? f0 : rscale;
      int ok = err <= 1e-4 * fabs(fd[q]) || err <= 1e-6 * scale;
      fs->components++;
      fs->passed += ok;
      if (!ok) {
        /* Diagnosis only: did the difference quotients converge at all
         * (two successive h agreeing to 1e-3)? On very steep paths they do
         * not, and the AD value then usually matches the smallest h. */
        int conv = 0;
        for (int lev = 0; lev < 3; lev++)
          conv = conv || fabs(rich[lev][q] - rich[lev + 1][q]) <= 1e-3 * fabs(rich[lev + 1][q]);
        fs->failed_unconverged += !conv;
      }
      fs->raster += q >= 4;
      fs->nontrivial += fabs(fd[q]) > 1e-3 * scale;
      if (!ok && fs->components - fs->passed < 10)
        print_message("(s,t) = (%d,%d) coord %d (stream %d pos %d) comp %d: ad %.10g fd %.10g "
                      "f %.6g\n",
                      st.s, st.t, k, coords[k].stream, coords[k].pos, q, dad[q], fd[q], f0);
    }
  }
}

/* Checks the Hessian of the luminance of the current path of vs (ev0,
 * evaluated with PATH_WANT_HESS) against central differences of its
 * gradient: coordinate k is moved by +-h, +-h/2 (Richardson, as
 * pg_fd_check, the best converged of h = 1e-4 ... 1e-7), the gradient is
 * evaluated there (PATH_WANT_GRAD, same topology), and its change along k
 * is compared with row k of the Hessian, entry by entry: relative error
 * under 1e-4 or absolute error under 1e-6 |f|, as for the gradient. Also
 * checks that the second-order pass leaves the value and the gradient bit
 * for bit as the first-order pass gives them (counted in fs->mismatched).
 * Entries whose difference quotients converge at no h (two successive h
 * within 1e-3) are counted in fs->unconverged and not compared. */
typedef struct pg_hess_stats {
  int paths, entries, passed, nontrivial, offdiag, skipped_topology, mismatched;
  int unconverged; /* entries whose difference quotients did not converge (not compared) */
} pg_hess_stats;

static inline void pg_hess_check(const scene *sc, path_scratch *ps, const render_settings *rs,
                          path_vec_sampler *vs, pg_strategy st, const path_eval *ev0,
                          pg_hess_stats *fs) {
  enum { NMAX = 512, VMAX = AD_H_CAPACITY };
  int n = ev0->n_coords, nd = ev0->n_diff;
  if (n > NMAX || !ev0->hess_ok || nd > VMAX) return;
  static path_coord coords[NMAX];
  static double H[VMAX * (VMAX + 1) / 2];
  memcpy(coords, ev0->coords, (size_t)n * sizeof *coords);
  memcpy(H, ev0->hlum, (size_t)nd * (size_t)(nd + 1) / 2 * sizeof(double));
  uint64_t topo = ev0->topology;
  double f0 = ev0->lum;
  fs->paths++;

  /* The first-order pass at the same point: the same value and gradient. */
  {
    path_eval ev;
    path_vec_sampler_rewind(vs);
    pg_eval(sc, rs, vs, st, PATH_WANT_GRAD, ps, &ev);
    int same = ev.n_coords == n && memcmp(&ev.lum, &f0, sizeof f0) == 0;
    for (int k = 0; same && k < n; k++)
      same = memcmp(&ev.coords[k].dlum, &coords[k].dlum, sizeof(double)) == 0 &&
             ev.coords[k].var == coords[k].var;
    fs->mismatched += !same;
  }

  for (int k = 0; k < n; k++) {
    int j = coords[k].var;
    if (j < 0) continue;
    double *slot = &vs->u[coords[k].stream][coords[k].pos];
    double u = *slot;
    static double rich[4][VMAX];
    int same = 1;
    double hk = 1e-4;
    for (int lev = 0; lev < 4 && same; lev++, hk *= 0.1) {
      const double steps[4] = {hk, -hk, 0.5 * hk, -0.5 * hk};
      static double g[4][VMAX];
      for (int e = 0; e < 4 && same; e++) {
        path_eval ev;
        *slot = u + steps[e];
        if (*slot < 0.0 || *slot >= 1.0) {
          same = 0;
          break;
        }
        path_vec_sampler_rewind(vs);
        pg_eval(sc, rs, vs, st, PATH_WANT_GRAD, ps, &ev);
        same = ev.topology == topo && ev.grad_ok && ev.n_diff == nd;
        for (int q = 0; same && q < ev.n_coords; q++)
          if (ev.coords[q].var >= 0) g[e][ev.coords[q].var] = ev.coords[q].dlum;
      }
      if (!same) break;
      for (int i = 0; i < nd; i++) {
        double d1 = (g[0][i] - g[1][i]) / (2.0 * hk), d2 = (g[2][i] - g[3][i]) / hk;
        rich[lev][i] = (4.0 * d2 - d1) / 3.0;
      }
    }
    *slot = u;
    if (!same) {
      fs->skipped_topology++;
      continue;
    }
    for (int i = 0; i < nd; i++) {
      int best = 0;
      for (int lev = 1; lev < 3; lev++)
        if (fabs(rich[lev][i] - rich[lev + 1][i]) < fabs(rich[best][i] - rich[best + 1][i]))
          best = lev;
      double fd = rich[best][i];
      /* A reference needs two successive h agreeing to 1e-3 (on very
       * steep paths no h does: counted, not compared). */
      int conv = 0;
      for (int lev = 0; lev < 3; lev++)
        conv = conv || fabs(rich[lev][i] - rich[lev + 1][i]) <= 1e-3 * fabs(rich[lev + 1][i]) ||
               fabs(rich[lev][i] - rich[lev + 1][i]) <= 1e-7 * f0;
      if (!conv) {
        fs->unconverged++;
        continue;
      }
      int a = i < j ? i : j, b = i < j ? j : i;
      double ha = H[(size_t)a * (size_t)nd - (size_t)a * (size_t)(a - 1) / 2 + (size_t)(b - a)];
      double err = fabs(fd - ha);
      int ok = err <= 1e-4 * fabs(fd) || err <= 1e-6 * f0;
      fs->entries++;
      fs->passed += ok;
      fs->nontrivial += fabs(fd) > 1e-3 * f0;
      fs->offdiag += i != j && fabs(fd) > 1e-3 * f0;
      if (!ok && fs->entries - fs->passed < 10)
        print_message("(s,t) = (%d,%d) d2 f / du%d du%d (coord %d): ad %.10g fd %.10g f %.6g\n",
                      st.s, st.t, j, i, k, ha, fd, f0);
    }
  }
}

/* The tangent length path_eval_bdpt must use for a complete strategy:
 * 2 film + 2 per camera vertex that a next vertex follows, 4 emitter + 2
 * per such light vertex, 2 for a light sample. The last vertex of each
 * subpath draws its two numbers but uses none (the subpath stops there),
 * and an escaped camera ray (s = 0) draws nothing at its end: neither gets
 * a slot. */
static inline int pg_bdpt_n_diff(pg_strategy st) {
  int n = 0;
  if (st.t >= 2) n += 2 + 2 * (st.t - 2);
  if (st.s >= 2) n += 4 + 2 * (st.s - 2);
  if (st.s == 1) n += 2;
  return n;
}

#endif
