/*
 * bench_target.c: the C side of bench/python_speed.py's (a): the chains'
 * target on the Cornell box's pt states (scenes/cornell-box at 64x48, the
 * states the chains see under --direct separate: paths of 3 segments or
 * more), evaluated in a plain C loop, one thread, with no Python in the
 * process: f at uniform states, f and f with its gradient at states with
 * f > 0, in microseconds per evaluation (best of 5 passes over 10^4
 * states). Its own states, drawn here with lmc's generator: the same kind
 * as python_speed.py's (NumPy's), not the same numbers.
 *
 * usage: build/bench/bench_target [--width W] [--height H] [--n N]
 * prints one line per quantity; python_speed.py runs it when it is built
 * and sets its batched figures against these.
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/driver/space.h"
#include "render/io/io.h"
#include "render/rng.h"

/* A sampler over one state's coordinates in the target's layout (numbers
 * past a stream's block are 0.5, as the Python module's). */
typedef struct bt_smp {
  lmc_sampler base;
  const mc_target *T;
  const double *u;
  int stream, pos[LMC_STREAM_COUNT];
} bt_smp;

static double bt_next(lmc_sampler *self) {
  bt_smp *v = (bt_smp *)self;
  int k = v->stream, p = v->pos[k]++;
  if (p >= v->T->stream_dim[k]) return 0.5;
  return v->u[mc_target_stream_offset(v->T, k) + p];
}

static void bt_stream(lmc_sampler *self, int stream) { ((bt_smp *)self)->stream = stream; }

/* f at u (with the gradient into grad when not NULL). */
static double bt_eval(const mc_target *T, void *scratch, const double *u, double *grad) {
  bt_smp s = {{bt_next, bt_stream, NULL}, T, u, 0, {0, 0, 0}};
  mc_value v;
  int ok = 0;
  if (T->eval(T, scratch, &s.base, &v, grad, grad ? &ok : NULL)) return NAN;
  return v.f;
}

/* Best of `reps` passes over n states (each dim numbers): us per evaluation. */
static double bt_time(const mc_target *T, void *scratch, const double *U, int n, double *grad,
                      int reps, double *OUT_sum) {
  double best = INFINITY;
  for (int r = 0; r < reps; r++) {
    double sum = 0.0, t0 = omp_get_wtime();
    for (int i = 0; i < n; i++) sum += bt_eval(T, scratch, U + (size_t)i * T->dim, grad);
    double dt = omp_get_wtime() - t0;
    if (dt < best) best = dt;
    *OUT_sum = sum;
  }
  return best / n * 1e6;
}

int main(int argc, char **argv) {
  int width = 64, height = 48, n = 10000;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!strcmp(argv[i], "--width")) width = atoi(argv[i + 1]);
    else if (!strcmp(argv[i], "--height")) height = atoi(argv[i + 1]);
    else if (!strcmp(argv[i], "--n")) n = atoi(argv[i + 1]);
    else {
      fprintf(stderr, "bench_target: unknown flag %s\n", argv[i]);
      return 2;
    }
  }
  if (width < 1 || height < 1 || n < 1) {
    fprintf(stderr, "bench_target: --width, --height and --n must be positive\n");
    return 2;
  }
  char dw[32], dh[32];
  snprintf(dw, sizeof dw, "width=%d", width);
  snprintf(dh, sizeof dh, "height=%d", height);
  const char *defines[2] = {dw, dh};
  scene *s = NULL;
  lmc_error err;
  if (scene_load_xml(LMC_SOURCE_DIR "/scenes/cornell-box/scene.xml", defines, 2, &s, &err)) {
    fprintf(stderr, "bench_target: %s\n", err.msg);
    return 1;
  }
  render_settings rs = s->settings;
  rs.mindepth = rs.mindepth > 3 ? rs.mindepth : 3; /* the chains' share (--direct separate) */
  mc_space sp;
  memset(&sp, 0, sizeof sp);
  if (mc_space_find(MCMC_STATES_PT)->create(&sp, s, &rs, &err)) {
    fprintf(stderr, "bench_target: %s\n", err.msg);
    return 1;
  }
  const mc_target *T = &sp.fam[0].target;
  void *scratch = T->scratch_create(T);
  int dim = T->dim;
  double *U = malloc((size_t)n * dim * sizeof *U), *P = malloc((size_t)n * dim * sizeof *P);
  double *grad = malloc((size_t)dim * sizeof *grad), *u = malloc((size_t)dim * sizeof *u);
  if (!scratch || !U || !P || !grad || !u) {
    fprintf(stderr, "bench_target: out of memory\n");
    return 1;
  }
  rng r;
  rng_seed(&r, 1, 1);
  for (size_t i = 0; i < (size_t)n * dim; i++) U[i] = rng_uniform(&r);
  /* States with f > 0 (where the chains are and the gradient is defined). */
  int got = 0, positive = 0;
  for (long tries = 0; got < n && tries < 100L * n; tries++) {
    for (int j = 0; j < dim; j++) u[j] = rng_uniform(&r);
    if (!(bt_eval(T, scratch, u, NULL) > 0.0)) continue;
    memcpy(P + (size_t)got++ * dim, u, (size_t)dim * sizeof *u);
  }
  for (int i = 0; i < n; i++) positive += bt_eval(T, scratch, U + (size_t)i * dim, NULL) > 0.0;
  printf("bench_target: Cornell box %dx%d, space pt, dim %d, P(f > 0) = %.2f, one thread, "
         "best of 5 over %d states\n",
         width, height, dim, (double)positive / n, n);
  double sum;
  printf("  f, uniform u           %8.2f us/eval\n", bt_time(T, scratch, U, n, NULL, 5, &sum));
  printf("  f, states f > 0        %8.2f us/eval\n", bt_time(T, scratch, P, got, NULL, 5, &sum));
  printf("  grad, states f > 0     %8.2f us/eval\n", bt_time(T, scratch, P, got, grad, 5, &sum));
  free(U), free(P), free(grad), free(u);
  T->scratch_destroy(scratch);
  mc_space_free(&sp);
  scene_destroy(s);
  return 0;
}
