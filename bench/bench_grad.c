/*
 * bench_grad.c: cost of the path contribution's gradient (render/integrators/path.h)
 * relative to the contribution alone, on scenes/ring-caustics.
 *
 * For path lengths 3, 5 and 8 (maxdepth = length, no Russian roulette) it
 * collects primary sample vectors whose path reaches that length with a
 * non-zero contribution, then times path_eval_pt over them without and
 * with the gradient, and with gradient and Hessian (PATH_WANT_HESS; one
 * thread). Printed: microseconds per evaluation, the gradient's and the
 * Hessian's ratio to f alone (gradient target: at most 4 at length 5), and
 * gradient and Hessian evaluations per second per core. Then the same for
 * bidirectional strategies (s, t) of path_eval_bdpt at lengths 3, 5 and 8
 * (a quarter as many paths).
 *
 * Usage: bench_grad [paths per length (default 4000)] [repetitions (default 3)]
 */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/io/io.h"
#include "render/integrators/path.h"

/* One stored primary sample vector: its three streams. */
typedef struct bench_vec {
  double *u[LMC_STREAM_COUNT];
  int n[LMC_STREAM_COUNT];
} bench_vec;

/* Bidirectional strategies (s, t) at lengths 3, 5 and 8 (s + t - 1 =
 * length): the emitter hit (0, L+1), the light sample (1, L), a
 * connection (2, L-1) and light tracing (L, 1). On this open, sky-lit
 * scene long light subpaths are rare, so (L, 1) finds few paths. Vectors whose strategy is non-zero
 * are collected first, then path_eval_bdpt is timed without and with the
 * gradient over them. */
static void bench_bdpt(const scene *sc, path_scratch *ps, int n_paths, int reps) {
  printf("\nbidirectional strategies (path_eval_bdpt), %d paths per strategy, best of %d\n",
         n_paths, reps);
  printf("length  (s,t)   f [us]  f+grad [us]  ratio  f+grad+Hess [us]  ratio  n_diff  grad "
         "evals/s/core  Hess evals/s/core\n");
  const int lengths[3] = {3, 5, 8};
  bench_vec *vecs = calloc((size_t)n_paths, sizeof *vecs);
  for (int li = 0; li < 3; li++) {
    int len = lengths[li];
    render_settings rs = sc->settings;
    rs.maxdepth = len;
    rs.rrdepth = 1000;
    const int strat[4][2] = {{0, len + 1}, {1, len}, {2, len - 1}, {len, 1}};
    for (int si = 0; si < 4; si++) {
      int s = strat[si][0], t = strat[si][1];
      path_vec_sampler vs;
      path_vec_sampler_init(&vs, 4321 + (uint64_t)(16 * len + si), NULL);
      int got = 0;
      for (long tries = 0; got < n_paths && tries < 500L * n_paths; tries++) {
        path_vec_sampler_clear(&vs);
        path_eval ev;
        path_eval_bdpt(sc, &rs, &vs.base, s, t, 0, ps, &ev, NULL);
        if (!(ev.lum > 0.0)) continue;
        bench_vec *bv = &vecs[got++];
        for (int k = 0; k < LMC_STREAM_COUNT; k++) {
          bv->n[k] = vs.n[k];
          bv->u[k] = malloc((size_t)(vs.n[k] > 0 ? vs.n[k] : 1) * sizeof(double));
          if (vs.n[k] > 0) memcpy(bv->u[k], vs.u[k], (size_t)vs.n[k] * sizeof(double));
        }
      }
      double best[3] = {1e30, 1e30, 1e30};
      int n_diff = 0;
      double checksum = 0.0;
      for (int r = 0; r < reps; r++) {
        for (int mode = 0; mode < 3; mode++) {
          double t0 = omp_get_wtime();
          for (int i = 0; i < got; i++) {
            /* Replay the stored streams (the buffers are large enough:
             * they held these numbers when the vector was collected). */
            path_vec_sampler_clear(&vs);
            for (int k = 0; k < LMC_STREAM_COUNT; k++) {
              if (vecs[i].n[k] > vs.cap[k]) continue;
              memcpy(vs.u[k], vecs[i].u[k], (size_t)vecs[i].n[k] * sizeof(double));
              vs.n[k] = vecs[i].n[k];
            }
            path_eval ev;
            path_eval_bdpt(sc, &rs, &vs.base, s, t, mode, ps, &ev, NULL); /* 0, grad, Hessian */
            checksum += ev.lum;
            if (mode) n_diff = ev.n_diff;
          }
          double dt = omp_get_wtime() - t0;
          if (dt < best[mode]) best[mode] = dt;
        }
      }
      double tf = got ? best[0] / got : 0.0, tg = got ? best[1] / got : 0.0;
      double th = got ? best[2] / got : 0.0;
      printf("%6d  (%d,%d)  %7.2f  %11.2f  %5.2f  %16.2f  %5.1f  %6d  %17.0f  %17.0f", len, s, t,
             1e6 * tf, 1e6 * tg, tf > 0.0 ? tg / tf : 0.0, 1e6 * th, tf > 0.0 ? th / tf : 0.0,
             n_diff, tg > 0.0 ? 1.0 / tg : 0.0, th > 0.0 ? 1.0 / th : 0.0);
      if (got < n_paths) printf("   (only %d paths found)", got);
      printf("\n");
      if (!(checksum >= 0.0)) printf("        (non-finite checksum)\n");
      for (int i = 0; i < got; i++)
        for (int k = 0; k < LMC_STREAM_COUNT; k++) free(vecs[i].u[k]);
      path_vec_sampler_free(&vs);
    }
  }
  free(vecs);
}

int main(int argc, char **argv) {
  int n_paths = argc > 1 ? atoi(argv[1]) : 4000;
  int reps = argc > 2 ? atoi(argv[2]) : 3;
  if (n_paths < 1) n_paths = 1;
  if (reps < 1) reps = 1;
  scene *sc;
  lmc_error err;
  if (scene_load_xml(LMC_SOURCE_DIR "/scenes/ring-caustics/scene.xml", NULL, 0, &sc, &err)) {
    fprintf(stderr, "bench_grad: %s\n", err.msg);
    return 1;
  }
  path_scratch *ps;
  if (path_scratch_create(&ps, &err)) return 1;
  printf("ring-caustics, one thread, %d paths per length, best of %d\n", n_paths, reps);
  printf("length  f [us]  f+grad [us]  ratio  f+grad+Hess [us]  ratio  n_diff  grad evals/s/core  "
         "Hess evals/s/core\n");
  const int lengths[3] = {3, 5, 8};
  for (int li = 0; li < 3; li++) {
    int len = lengths[li];
    render_settings rs = sc->settings;
    rs.maxdepth = len;
    rs.rrdepth = 1000;
    int dims = PT_DIMS_CAMERA + PT_DIMS_PER_BOUNCE * len;

    /* Collect vectors whose path has this length and a non-zero value. */
    double *vecs = malloc((size_t)n_paths * (size_t)dims * sizeof(double));
    path_vec_sampler vs;
    path_vec_sampler_init(&vs, 1234 + (uint64_t)len, NULL);
    int got = 0;
    for (long tries = 0; got < n_paths && tries < 2000L * n_paths; tries++) {
      path_vec_sampler_clear(&vs);
      path_eval ev;
      path_eval_pt(sc, &rs, &vs.base, 0, ps, &ev, NULL);
      if (ev.n_coords != dims || !(ev.lum > 0.0)) continue;
      memcpy(vecs + (size_t)got * dims, vs.u[LMC_STREAM_CAMERA], (size_t)dims * sizeof(double));
      got++;
    }

    /* Time both modes over the same vectors. */
    double best[3] = {1e30, 1e30, 1e30};
    int n_diff = 0;
    double checksum = 0.0;
    for (int r = 0; r < reps; r++) {
      for (int mode = 0; mode < 3; mode++) {
        double t0 = omp_get_wtime();
        for (int i = 0; i < got; i++) {
          path_vec_sampler_clear(&vs);
          memcpy(vs.u[LMC_STREAM_CAMERA], vecs + (size_t)i * dims, (size_t)dims * sizeof(double));
          vs.n[LMC_STREAM_CAMERA] = dims;
          path_eval ev;
          path_eval_pt(sc, &rs, &vs.base, mode, ps, &ev, NULL);
          checksum += ev.lum;
          if (mode) n_diff = ev.n_diff;
        }
        double dt = omp_get_wtime() - t0;
        if (dt < best[mode]) best[mode] = dt;
      }
    }
    double tf = got ? best[0] / got : 0.0, tg = got ? best[1] / got : 0.0;
    double th = got ? best[2] / got : 0.0;
    printf("%6d  %6.2f  %11.2f  %5.2f  %16.2f  %5.1f  %6d  %17.0f  %17.0f\n", len, 1e6 * tf,
           1e6 * tg, tf > 0.0 ? tg / tf : 0.0, 1e6 * th, tf > 0.0 ? th / tf : 0.0, n_diff,
           tg > 0.0 ? 1.0 / tg : 0.0, th > 0.0 ? 1.0 / th : 0.0);
    if (got < n_paths) printf("        (only %d paths of length %d found)\n", got, len);
    if (!(checksum >= 0.0)) printf("        (non-finite checksum)\n");
    path_vec_sampler_free(&vs);
    free(vecs);
  }
  bench_bdpt(sc, ps, n_paths / 4 > 0 ? n_paths / 4 : 1, reps);
  path_scratch_destroy(ps);
  scene_destroy(sc);
  return 0;
}
