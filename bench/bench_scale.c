/*
 * bench_scale.c: large scenes (issue 6): load time, Embree build time,
 * peak resident memory, rays per second, and the memory a render needs per
 * thread; and whether memory grows linearly with the triangle count.
 *
 *   bench_scale [--tris N]... [--threads T] [--res WxH] [--keep]
 *
 * Default sizes: 5 million and 20 million triangles. For each size it
 * writes a binary PLY height field (a g x g grid of bumpy quads, two
 * triangles each, with vertex normals; the file goes to $TMPDIR or /tmp
 * and is removed afterwards unless --keep) and a scene that looks at it
 * under an area light, then measures, in this process:
 *   read      mesh_read_ply + mesh_validate of the file alone;
 *   load      scene_load_xml of the whole scene (read, validate, Embree
 *             build, light distributions);
 *   embree    a second accel_create over the loaded meshes alone;
 *   memory    the peak resident set (VmHWM of /proc/self/status, reset
 *             with /proc/self/clear_refs before each stage) minus the
 *             resident set before loading, also per triangle;
 *   rays/s    one pass of pt (maxdepth 5) on all threads;
 *   per thread  the peak resident growth of a render with T threads minus
 *             that with 1 thread, divided by T - 1, for pt, bdpt and the
 *             MCMC integrators when this build has them (mcmc_render_run
 *             returns "not built" otherwise, and the line says so).
 * The figures are printed as one table per size and a last line with the
 * bytes per triangle of each size (linear growth: nearly equal values).
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "lmc/mcmc.h"
#include "render/accel.h"
#include "render/integrators/integrator.h"
#include "render/io/io.h"

/* A field of /proc/self/status in bytes ("VmRSS", "VmHWM"), or -1. */
static long long scale__status_bytes(const char *field) {
  FILE *f = fopen("/proc/self/status", "r");
  if (!f) return -1;
  char line[256];
  long long kb = -1;
  size_t n = strlen(field);
  while (fgets(line, sizeof line, f))
    if (strncmp(line, field, n) == 0 && line[n] == ':') {
      kb = atoll(line + n + 1);
      break;
    }
  fclose(f);
  return kb < 0 ? -1 : kb * 1024;
}

/* Resets the peak resident set to the current one (Linux >= 4.0). */
static void scale__reset_peak(void) {
  FILE *f = fopen("/proc/self/clear_refs", "w");
  if (!f) return;
  fputs("5", f);
  fclose(f);
}

static void scale__put_f32(FILE *f, float v) { fwrite(&v, 4, 1, f); }

/* Writes the height field as a little-endian binary PLY with about
 * n_tris triangles; returns the exact count (0 on failure). */
static int64_t scale__write_ply(const char *path, int64_t n_tris) {
  int64_t g = (int64_t)ceil(sqrt((double)n_tris / 2.0));
  int64_t nv = (g + 1) * (g + 1), nt = 2 * g * g;
  FILE *f = fopen(path, "wb");
  if (!f) return 0;
  fprintf(f,
          "ply\nformat binary_little_endian 1.0\nelement vertex %lld\nproperty float x\n"
          "property float y\nproperty float z\nproperty float nx\nproperty float ny\n"
          "property float nz\nelement face %lld\nproperty list uchar int vertex_indices\n"
          "end_header\n",
          (long long)nv, (long long)nt);
  /* z = a sin(k x) cos(k y) over [-1, 1]^2, with its exact normal. */
  const double a = 0.05, k = 40.0;
  for (int64_t j = 0; j <= g; j++)
    for (int64_t i = 0; i <= g; i++) {
      double x = -1.0 + 2.0 * (double)i / (double)g, y = -1.0 + 2.0 * (double)j / (double)g;
      double z = a * sin(k * x) * cos(k * y);
      double zx = a * k * cos(k * x) * cos(k * y), zy = -a * k * sin(k * x) * sin(k * y);
      double len = sqrt(zx * zx + zy * zy + 1.0);
      scale__put_f32(f, (float)x);
      scale__put_f32(f, (float)y);
      scale__put_f32(f, (float)z);
      scale__put_f32(f, (float)(-zx / len));
      scale__put_f32(f, (float)(-zy / len));
      scale__put_f32(f, (float)(1.0 / len));
    }
  unsigned char rec[13];
  rec[0] = 3;
  for (int64_t j = 0; j < g; j++)
    for (int64_t i = 0; i < g; i++) {
      uint32_t v00 = (uint32_t)(j * (g + 1) + i), v10 = v00 + 1;
      uint32_t v01 = (uint32_t)(v00 + (g + 1)), v11 = v01 + 1;
      uint32_t tri[2][3] = {{v00, v10, v11}, {v00, v11, v01}};
      for (int t = 0; t < 2; t++) {
        memcpy(rec + 1, tri[t], 12);
        fwrite(rec, 1, 13, f);
      }
    }
  if (fclose(f) != 0) return 0;
  return nt;
}

static int scale__write_xml(const char *path, const char *ply, int w, int h) {
  FILE *f = fopen(path, "w");
  if (!f) return 0;
  fprintf(f,
          "<scene version=\"0.5.0\">\n"
          " <sensor type=\"perspective\"><float name=\"fov\" value=\"50\"/>\n"
          "  <transform name=\"toWorld\"><lookat origin=\"0, -1.6, 1.4\" target=\"0, 0, 0\" "
          "up=\"0, 0, 1\"/></transform>\n"
          "  <film type=\"hdrfilm\"><integer name=\"width\" value=\"%d\"/>"
          "<integer name=\"height\" value=\"%d\"/></film></sensor>\n"
          " <shape type=\"ply\"><string name=\"filename\" value=\"%s\"/>"
          "<bsdf type=\"diffuse\"/></shape>\n"
          " <shape type=\"rectangle\"><transform name=\"toWorld\"><scale value=\"0.3\"/>"
          "<rotate x=\"1\" angle=\"180\"/><translate z=\"1.5\"/></transform>\n"
          "  <emitter type=\"area\"><rgb name=\"radiance\" value=\"20\"/></emitter></shape>\n"
          "</scene>\n",
          w, h, ply);
  return fclose(f) == 0;
}

/* Peak resident growth of one render of s with `integrator` (1 spp). */
static long long scale__render_peak(const scene *s, const char *integrator, int threads,
                                    render_stats *st, int *ok) {
  render_settings rs = render_settings_default();
  snprintf(rs.integrator, sizeof rs.integrator, "%s", integrator);
  rs.spp = 1;
  rs.set |= SET_SPP;
  rs.maxdepth = 5;
  rs.threads = threads;
  rs.quiet = 1;
  film f;
  lmc_error err;
  lmc_error_clear(&err);
  scale__reset_peak();
  long long before = scale__status_bytes("VmRSS");
  lmc_status status = mcmc_is_integrator(integrator) ? mcmc_render_run(s, &rs, &f, st, &err)
                                                     : render_run(s, &rs, &f, st, &err);
  long long peak = scale__status_bytes("VmHWM");
  *ok = status == LMC_OK;
  if (status == LMC_OK) film_free(&f);
  else if (status != LMC_EUNSUPPORTED) fprintf(stderr, "bench_scale: %s: %s\n", integrator, err.msg);
  return peak - before;
}

static double scale__mb(long long b) { return (double)b / (1024.0 * 1024.0); }

/* Runs every measurement for one size; returns the bytes per triangle of
 * the loaded scene's peak (or -1). */
static double scale__one(int64_t want, int threads, int w, int h, int keep) {
  const char *tmp = getenv("TMPDIR");
  if (!tmp || !tmp[0]) tmp = "/tmp";
  char ply[512], xml[512];
  snprintf(ply, sizeof ply, "%s/lmc_bench_scale_%lld.ply", tmp, (long long)want);
  snprintf(xml, sizeof xml, "%s/lmc_bench_scale_%lld.xml", tmp, (long long)want);

  /* Generate the scene on disk (not timed as loading). */
  double t0 = omp_get_wtime();
  int64_t nt = scale__write_ply(ply, want);
  if (!nt || !scale__write_xml(xml, ply, w, h)) {
    fprintf(stderr, "bench_scale: cannot write %s\n", ply);
    return -1;
  }
  double t_gen = omp_get_wtime() - t0;
  printf("\n== %lld triangles (%s, generated in %.1f s)\n", (long long)nt, ply, t_gen);
  lmc_error err;
  lmc_error_clear(&err);

  /* The mesh reader alone. */
  long long base = scale__status_bytes("VmRSS");
  scale__reset_peak();
  mesh m;
  t0 = omp_get_wtime();
  lmc_status st = mesh_read_ply(ply, &m, &err);
  if (st == LMC_OK) st = mesh_validate(&m, ply, 0, &err);
  double t_read = omp_get_wtime() - t0;
  long long peak_read = scale__status_bytes("VmHWM") - base;
  if (st != LMC_OK) {
    fprintf(stderr, "bench_scale: %s\n", err.msg);
    mesh_free(&m);
    return -1;
  }
  long long mesh_bytes = (long long)((3 * m.n_vertices + 1) * 4 + (m.n ? 3 * m.n_vertices * 4 : 0) +
                                     3 * m.n_triangles * 4);
  mesh_free(&m);

  /* The whole scene: read, validate, Embree build, light distributions. */
  base = scale__status_bytes("VmRSS");
  scale__reset_peak();
  scene *s = NULL;
  t0 = omp_get_wtime();
  if (scene_load_xml(xml, NULL, 0, &s, &err) != LMC_OK) {
    fprintf(stderr, "bench_scale: %s:%d: %s\n", err.file, err.line, err.msg);
    return -1;
  }
  double t_load = omp_get_wtime() - t0;
  long long peak_load = scale__status_bytes("VmHWM") - base;
  long long resident = scale__status_bytes("VmRSS") - base;

  /* Embree alone: a second build over the same meshes. */
  accel *a = NULL;
  scale__reset_peak();
  long long before_accel = scale__status_bytes("VmRSS");
  t0 = omp_get_wtime();
  st = accel_create(&a, s->meshes, s->n_meshes, 0, &err);
  double t_embree = omp_get_wtime() - t0;
  long long accel_bytes = scale__status_bytes("VmRSS") - before_accel;
  accel_destroy(a);

  printf("  read (mesh_read_ply + validate)   %8.2f s   peak +%8.1f MB  (mesh arrays %.1f MB)\n",
         t_read, scale__mb(peak_read), scale__mb(mesh_bytes));
  printf("  load (scene_load_xml, all)        %8.2f s   peak +%8.1f MB  resident +%.1f MB "
         "(process: %.1f MB before, %.1f MB peak)\n",
         t_load, scale__mb(peak_load), scale__mb(resident), scale__mb(base),
         scale__mb(base + peak_load));
  printf("  Embree build alone                %8.2f s   resident +%.1f MB%s\n", t_embree,
         scale__mb(accel_bytes), st == LMC_OK ? "" : "  (FAILED)");
  printf("  bytes per triangle: peak %.1f, resident %.1f\n", (double)peak_load / (double)nt,
         (double)resident / (double)nt);

  /* Rays per second and the memory a render adds per thread. A first,
   * unmeasured render starts OpenMP's threads, so their stacks are not
   * counted as the integrators' memory. */
  static const char *const integrators[] = {"pt", "bdpt", "pssmlt", "mmlt", "lmc"};
  {
    render_stats warm;
    int ok;
    scale__render_peak(s, "pt", threads, &warm, &ok);
  }
  for (int k = 0; k < 5; k++) {
    render_stats rst1, rstT;
    int ok1, okT;
    long long m1 = scale__render_peak(s, integrators[k], 1, &rst1, &ok1);
    long long mT = threads > 1 ? scale__render_peak(s, integrators[k], threads, &rstT, &okT) : m1;
    if (threads <= 1) {
      rstT = rst1;
      okT = ok1;
    }
    if (!ok1 || !okT) {
      printf("  %-7s not built in this tree (no figures)\n", integrators[k]);
      continue;
    }
    double per_thread = threads > 1 ? (double)(mT - m1) / (threads - 1) : (double)m1;
    printf("  %-7s %dx%d 1 spp: %.3g rays/s on %d threads; render peak +%.2f MB (1 thread), "
           "+%.2f MB (%d); per extra thread %.3f MB\n",
           integrators[k], w, h, (double)rstT.rays / rstT.seconds, threads, scale__mb(m1),
           scale__mb(mT), threads, per_thread / (1024.0 * 1024.0));
  }
  scene_destroy(s);
  if (!keep) {
    remove(ply);
    remove(xml);
  }
  return (double)peak_load / (double)nt;
}

int main(int argc, char **argv) {
  int64_t sizes[8];
  int n_sizes = 0, threads = omp_get_max_threads(), w = 320, h = 240, keep = 0;
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--tris") == 0 && i + 1 < argc && n_sizes < 8)
      sizes[n_sizes++] = atoll(argv[++i]);
    else if (strcmp(argv[i], "--threads") == 0 && i + 1 < argc)
      threads = atoi(argv[++i]);
    else if (strcmp(argv[i], "--res") == 0 && i + 1 < argc)
      sscanf(argv[++i], "%dx%d", &w, &h);
    else if (strcmp(argv[i], "--keep") == 0)
      keep = 1;
    else {
      fprintf(stderr, "usage: bench_scale [--tris N]... [--threads T] [--res WxH] [--keep]\n");
      return 2;
    }
  }
  if (n_sizes == 0) {
    sizes[n_sizes++] = 5000000;
    sizes[n_sizes++] = 20000000;
  }
  if (threads < 1) threads = 1;
  lmc_warn_set_quiet(1);
  printf("bench_scale: %d thread(s), film %dx%d\n", threads, w, h);
  double bpt[8];
  for (int i = 0; i < n_sizes; i++) bpt[i] = scale__one(sizes[i], threads, w, h, keep);
  printf("\nlinearity: peak bytes per triangle of the loaded scene:");
  for (int i = 0; i < n_sizes; i++) printf("  %lld: %.1f", (long long)sizes[i], bpt[i]);
  printf("\n");
  return 0;
}
