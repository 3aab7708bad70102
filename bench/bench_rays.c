/*
 * bench_rays.c: how close path tracing comes to Embree's raw speed.
 *
 * For each scene: trace path-tracing passes (every pixel, one sample each)
 * and time them (pt rays/s, all shading included); trace the same passes
 * again, untimed, recording every ray pt traces (camera, bounce and shadow
 * rays), so that the log's page faults and copies are not charged to pt;
 * then replay exactly the recorded
 * rays through rtcIntersect1 alone (accel_intersect, closest hit, shadow
 * rays with their own tmax) and time it (raw rays/s). Both on all threads.
 * Prints rays, seconds, rays/s and the ratio pt / raw.
 *
 *   bench_rays [--threads N] [--passes N] [SCENE.xml ...]
 * Default scenes: scenes/ring-caustics/scene.xml and the torus scene from
 * ../shared when present.
 */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "render/integrators/integrator.h"
#include "render/io/io.h"

static int bench_scene(const char *path, int threads, int passes) {
  lmc_error err;
  lmc_error_clear(&err);
  scene *s = NULL;
  if (scene_load_xml(path, NULL, 0, &s, &err)) {
    fprintf(stderr, "bench_rays: %s:%d: %s\n", err.file, err.line, err.msg);
    return 1;
  }
  render_settings rs = s->settings;
  rs.maxdepth = (rs.set & SET_MAXDEPTH) ? rs.maxdepth : -1;
  const int W = s->cam.width, H = s->cam.height;
  int64_t cap = (int64_t)W * H * passes * 24 / threads + 1024;
  ray_log *logs = calloc((size_t)threads, sizeof(ray_log));
  render_counters *cnt = calloc((size_t)threads, sizeof(render_counters));
  for (int t = 0; t < threads; t++) {
    logs[t].rays = malloc((size_t)cap * sizeof(ray_record));
    logs[t].cap = cap;
    cnt[t].log = &logs[t];
  }

  /* Path tracing, timed without the log (recording is the benchmark's work,
   * not pt's), then the same pass again, untimed, recording every ray: the
   * sampler streams are fixed per pixel and pass, so both passes trace the
   * same rays. */
  double t_pt = 0.0;
  int64_t rays = 0, logged = 0, rays_logged = 0;
  for (int rec = 0; rec < 2; rec++) {
    for (int t = 0; t < threads; t++) {
      cnt[t].rays = 0;
      cnt[t].log = rec ? &logs[t] : NULL;
    }
    double t0 = omp_get_wtime();
#pragma omp parallel num_threads(threads)
    {
      int tid = omp_get_thread_num();
      for (int pass = 0; pass < passes; pass++) {
#pragma omp for schedule(static, 1)
        for (int y = 0; y < H; y++)
          for (int x = 0; x < W; x++) {
            lmc_indep_sampler smp;
            indep_sampler_init(&smp, 1, ((uint64_t)y * W + x) * 1000 + pass);
            double rx = x + sampler_next(&smp.base), ry = y + sampler_next(&smp.base);
            vec3 o, d;
            camera_generate_ray(&s->cam, rx, ry, &o, &d);
            rgb L = pt_li(s, &rs, &smp.base, o, d, NULL, &cnt[tid]);
            (void)L;
          }
      }
    }
    int64_t n = 0;
    for (int t = 0; t < threads; t++) n += cnt[t].rays;
    if (rec) {
      rays_logged = n;
    } else {
      t_pt = omp_get_wtime() - t0;
      rays = n;
    }
  }
  for (int t = 0; t < threads; t++) logged += logs[t].n;

  /* Replay the same rays through Embree alone. */
  int64_t hits = 0;
  double t0 = omp_get_wtime();
#pragma omp parallel num_threads(threads) reduction(+ : hits)
  {
    const ray_log *l = &logs[omp_get_thread_num()];
    for (int64_t i = 0; i < l->n; i++) {
      const ray_record *r = &l->rays[i];
      accel_hit h;
      double tmax = r->tmax < 0.0f ? -(double)r->tmax : (double)r->tmax;
      hits += accel_intersect(s->accel, v3(r->org[0], r->org[1], r->org[2]),
                              v3(r->dir[0], r->dir[1], r->dir[2]), r->tmin, tmax, &h);
    }
  }
  double t_raw = omp_get_wtime() - t0;

  double pt_rate = rays / t_pt, raw_rate = logged / t_raw;
  printf("%-40s %4dx%-4d threads %d  rays %9lld  pt %7.3f s %8.3f Mrays/s   "
         "raw rtcIntersect1 %7.3f s %8.3f Mrays/s   pt/raw %5.1f%%  (hits %lld)\n",
         path, W, H, threads, (long long)rays, t_pt, pt_rate / 1e6, t_raw, raw_rate / 1e6,
         100.0 * pt_rate / raw_rate, (long long)hits);
  if (rays_logged != rays)
    printf("  (the logged pass traced %lld rays, the timed one %lld)\n", (long long)rays_logged,
           (long long)rays);
  if (logged != rays_logged)
    printf("  (log kept %lld of %lld rays)\n", (long long)logged, (long long)rays_logged);
  for (int t = 0; t < threads; t++) free(logs[t].rays);
  free(logs);
  free(cnt);
  scene_destroy(s);
  return 0;
}

int main(int argc, char **argv) {
  int threads = omp_get_max_threads(), passes = 4;
  const char *scenes[16];
  int n = 0;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--passes") && i + 1 < argc) passes = atoi(argv[++i]);
    else if (n < 16) scenes[n++] = argv[i];
  }
  static char torus[1024];
  if (n == 0) {
    scenes[n++] = LMC_SOURCE_DIR "/scenes/ring-caustics/scene.xml";
    snprintf(torus, sizeof torus, "%s/scenes/torus/lmc.xml", LMC_SHARED_DIR);
    if (access(torus, R_OK) == 0) scenes[n++] = torus;
  }
  if (threads < 1) threads = 1;
  lmc_warn_set_quiet(1);
  int rc = 0;
  for (int i = 0; i < n; i++) rc |= bench_scene(scenes[i], threads, passes);
  return rc;
}
