/*
 * render.c: the render driver for the pixel-sample integrators (pt, bdpt,
 * direct), and the progress bar.
 *
 * The image is rendered in passes of one sample per pixel; OpenMP threads
 * take the next row whenever they finish one (dynamic schedule: rows differ
 * in cost, and a thread that the system preempts does not hold the others
 * at the end of the pass). Every pixel sample draws from
 * its own random stream, seeded by (seed, pixel, pass), and adds to its own
 * pixel only, in pass order: the camera-ray estimates do not depend on the
 * schedule. Splats (bdpt's light tracing) land anywhere on the film, so
 * they are not added where they are made: each row of the image records
 * its splats in its own list (film_splat_log), and after every block of
 * RENDER_SPLAT_ROWS rows the lists are replayed into the film in row
 * order. Every floating-point sum is therefore taken in an order fixed by
 * the image alone, and the image is bit for bit the same for any --threads
 * (tests/test_threads.c checks 1 against 2 threads for pt and bdpt).
 *
 * Quarantine: a sample that is NaN, infinite or too large to be stored in
 * the float EXR (|value| > FLT_MAX) is dropped and counted, never added.
 *
 * Stopping: the spp budget, the time limit, or render_request_stop (from
 * SIGINT/SIGTERM) end the render at the next row. Pixels keep their own
 * sample counts and splats are normalised by the number of light subpaths
 * actually traced (one per camera sample), so an interrupted render
 * is still a correct image of the samples it has.
 */
#define _POSIX_C_SOURCE 200809L
#include "render/integrators/integrator.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "render/dist.h"

/* Rows per block of bdpt's splat lists (the memory they hold is about
 * RENDER_SPLAT_ROWS * width * path length * 40 bytes). */
#define RENDER_SPLAT_ROWS 32

static volatile sig_atomic_t render__stop_signal;
static volatile sig_atomic_t render__stop;

void render_request_stop(int signal_number) {
  render__stop_signal = signal_number;
  render__stop = 1;
}

int render_stop_signal(void) { return render__stop_signal; }

void render_reset_stop(void) {
  render__stop = 0;
  render__stop_signal = 0;
}

/* --- progress bar --------------------------------------------------------- */

void progress_init(progress *p, const char *label, int quiet) {
  memset(p, 0, sizeof *p);
  p->enabled = !quiet && isatty(STDERR_FILENO);
  p->start = omp_get_wtime();
  p->last_print = -1.0;
  snprintf(p->label, sizeof p->label, "%s", label);
}

void progress_update(progress *p, double fraction) {
  if (!p->enabled) return;
  double now = omp_get_wtime();
  if (p->last_print >= 0.0 && now - p->last_print < 0.2 && fraction < 1.0) return;
  p->last_print = now;
  if (fraction < 0.0) fraction = 0.0;
  if (fraction > 1.0) fraction = 1.0;
  enum { WIDTH = 40 };
  char bar[WIDTH + 1];
  int full = (int)(fraction * WIDTH);
  for (int i = 0; i < WIDTH; i++) bar[i] = i < full ? '=' : (i == full ? '>' : ' ');
  bar[WIDTH] = '\0';
  double elapsed = now - p->start;
  char eta[32] = "ETA -";
  if (fraction > 1e-6) snprintf(eta, sizeof eta, "ETA %.1fs", elapsed * (1.0 - fraction) / fraction);
  char rate[48] = "";
  if (p->rate > 0.0) snprintf(rate, sizeof rate, "  %.3g %s", p->rate, p->rate_unit);
  /* \033[K clears what a longer earlier line left. */
  fprintf(stderr, "\r%s%s%s [%s] %5.1f%%  %.1fs  %s%s\033[K", p->label, p->phase[0] ? " " : "",
          p->phase, bar, 100.0 * fraction, elapsed, eta, rate);
  fflush(stderr);
  p->open = 1;
}

void progress_phase(progress *p, const char *phase, double fraction) {
  snprintf(p->phase, sizeof p->phase, "%s", phase);
  p->rate = 0.0;
  p->last_print = -1.0;
  progress_update(p, fraction);
}

void progress_update_rate(progress *p, double fraction, double rate, const char *unit) {
  p->rate = rate;
  snprintf(p->rate_unit, sizeof p->rate_unit, "%s", unit);
  progress_update(p, fraction);
}

void progress_finish(progress *p) {
  if (!p->enabled) return;
  progress_update(p, 1.0);
  progress_end(p);
}

void progress_end(progress *p) {
  if (!p->enabled || !p->open) return;
  fprintf(stderr, "\n");
  p->open = 0;
}

/* A thread's counters, alone on their cache line: the integrators bump
 * cnt->rays at every ray, and the counters of two threads on one line would
 * make that line bounce between their cores (false sharing). */
typedef struct render__counters_slot {
  _Alignas(64) render_counters c;
} render__counters_slot;

/* pt's estimate (direct's when ds is not NULL) along the camera ray
 * through raster point (rx, ry); with filtered textures in the scene, with
 * its differentials: towards the film points a step `diff_scale` pixels
 * along x and along y, interpolated as Mitsuba's scaleDifferential does. */
static rgb render__pt(const scene *s, const render_settings *rs, const direct_settings *ds,
                      lmc_sampler *smp, double rx, double ry, double diff_scale,
                      render_counters *cnt) {
  vec3 org, dir;
  camera_generate_ray(&s->cam, rx, ry, &org, &dir);
  ray_diff rd, *prd = NULL;
  if (s->tex_filtered) {
    vec3 o, dx, dy;
    camera_generate_ray(&s->cam, rx + 1.0, ry, &o, &dx);
    camera_generate_ray(&s->cam, rx, ry + 1.0, &o, &dy);
    rd = (ray_diff){v3_add(dir, v3_scale(v3_sub(dx, dir), diff_scale)),
                    v3_add(dir, v3_scale(v3_sub(dy, dir), diff_scale))};
    prd = &rd;
  }
  if (ds) return direct_li(s, rs, ds, smp, org, dir, prd, cnt);
  return render_media_on(s, rs) ? pt_li_media(s, rs, smp, org, dir, prd, cnt)
                                         : pt_li(s, rs, smp, org, dir, prd, cnt);
}

/* Hands rs->snapshot_fn the image so far: the camera estimates plus the
 * splats (already replayed into `out`), normalised as at the end. tmp is
 * the caller's scratch film, kept from one snapshot to the next (zeroed
 * storage at first): a film allocated afresh each time costs its pages
 * again, which frequent snapshots (--display-interval) notice. */
static void render__snapshot(const render_settings *rs, const film *out, film *tmp,
                             int has_splats, int nthreads, const render__counters_slot *counters,
                             double seconds) {
  lmc_error err;
  /* (Collective: a rank out of memory ends the job rather than leave the
   * others waiting in the sums.) */
  if (tmp->sum) {
    film_clear(tmp);
    tmp->splat_scale = 1.0;
  } else if (film_init(tmp, out->width, out->height, &err) ||
             (out->esum && film_error_init(tmp, &err))) {
    if (dist_active()) dist_abort(1);
    film_free(tmp);
    return;
  }
  film_merge(tmp, out);
  film_sum_to_root(tmp);
  int64_t samples = 0;
  for (int t = 0; t < nthreads; t++) samples += counters[t].c.samples;
  dist_sum_to_root_i64(&samples, 1);
  if (has_splats) tmp->splat_scale = samples > 0 ? 1.0 / (double)samples : 0.0;
  if (dist_rank() == 0) rs->snapshot_fn(rs->snapshot_ctx, tmp, seconds);
}

/* The threads' counts into st (this rank's own in rank_rays and
 * rank_samples), then every rank's film and counts on rank 0. */
static void render__totals(render_stats *st, film *out, int nthreads,
                           const render__counters_slot *counters) {
  for (int t = 0; t < nthreads; t++) {
    st->rays += counters[t].c.rays;
    st->samples += counters[t].c.samples;
    st->nan_samples += counters[t].c.nan_samples;
  }
  st->rank_rays = st->rays, st->rank_samples = st->samples;
  int64_t totals[3] = {st->rays, st->samples, st->nan_samples};
  dist_sum_to_root_i64(totals, 3);
  film_sum_to_root(out);
  if (dist_rank() == 0) st->rays = totals[0], st->samples = totals[1], st->nan_samples = totals[2];
}

/* --- the pass loop ----------------------------------------------------------- */

/* One sample of pixel (x, y) in pass `pass`, from the pixel's own stream:
 * pt's, bdpt's or (ds not NULL) direct's estimate (bdpt's splats to
 * row_splats); a non-finite or float-overflowing one counted and dropped
 * (0). */
static rgb render__sample(const scene *s, const render_settings *rs, int x, int y, int64_t pass,
                          double diff_scale, int use_bdpt, const direct_settings *ds,
                          film *row_splats, render_counters *cnt) {
  union {
    lmc_indep_sampler indep;
    lmc_sobol_sampler sobol;
  } smp_store;
  lmc_sampler *smp;
  uint64_t pixel = (uint64_t)y * (uint64_t)s->cam.width + (uint64_t)x;
  if (rs->sampler == LMC_SAMPLER_SOBOL) {
    sobol_sampler_init(&smp_store.sobol, rs->seed, pixel, (uint32_t)pass,
                       use_bdpt ? (render_media_on(s, rs) ? &sampler_layout_bdpt_media
                                                                   : &sampler_layout_bdpt)
                       : ds     ? &sampler_layout_direct
                       : render_media_on(s, rs) ? &sampler_layout_pt_media
                                : &sampler_layout_pt);
    smp = &smp_store.sobol.base;
  } else {
    indep_sampler_init(&smp_store.indep, rs->seed, pixel * 0x100000001b3ull + (uint64_t)pass);
    smp = &smp_store.indep.base;
  }
  double dx, dy;
  double u1 = sampler_next(smp), u2 = sampler_next(smp);
  filter_sample(&s->filter, u1, u2, &dx, &dy);
  double rx = x + 0.5 + dx, ry = y + 0.5 + dy;
  rgb L = use_bdpt ? bdpt_li(s, rs, smp, rx, ry, row_splats, cnt)
                   : render__pt(s, rs, ds, smp, rx, ry, diff_scale, cnt);
  if (!rgb_isfinite(L) || fabs(L.r) > FLT_MAX || fabs(L.g) > FLT_MAX || fabs(L.b) > FLT_MAX) {
    cnt->nan_samples++;
    L = rgb_zero();
  }
  return L;
}

lmc_status render_run(const scene *s, const render_settings *rs, film *out, render_stats *st,
                      lmc_error *err) {
  memset(st, 0, sizeof *st);
  int use_bdpt = strcmp(rs->integrator, "bdpt") == 0;
  int use_direct = strcmp(rs->integrator, "direct") == 0;
  if (!use_bdpt && !use_direct && strcmp(rs->integrator, "pt") != 0)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "render_run: unknown integrator '%s'",
                         rs->integrator);
  /* direct's own settings (its flags, render_settings.params). */
  direct_settings dset;
  if (use_direct) {
    lmc_status dst = direct_read_settings(rs, &dset, err);
    if (dst) return dst;
  }
  const direct_settings *ds = use_direct ? &dset : NULL;
  const int W = s->cam.width, H = s->cam.height;
  lmc_status status = film_init(out, W, H, err);
  if (!status && rs->error) status = film_error_init(out, err);
  if (status) {
    film_free(out);
    return status;
  }

  int nthreads = rs->threads > 0 ? rs->threads : omp_get_max_threads();
  /* bdpt: one splat list per row of a block; pt needs none and renders a
   * whole pass as one block. */
  const int block = use_bdpt ? RENDER_SPLAT_ROWS : H;
  film_splat_log *logs = use_bdpt ? calloc((size_t)block, sizeof *logs) : NULL;
  render__counters_slot *counters = aligned_alloc(64, (size_t)nthreads * sizeof *counters);
  if (counters) memset(counters, 0, (size_t)nthreads * sizeof *counters);
  if (!counters || (use_bdpt && !logs)) {
    free(logs);
    free(counters);
    film_free(out);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory");
  }

  const int rank = dist_rank(), ranks = dist_size();
  progress bar;
  progress_init(&bar, rs->integrator, rs->quiet || rank != 0);
  double t0 = omp_get_wtime();
  int64_t max_passes = rs->time_limit > 0.0 && !(rs->set & SET_SPP) ? INT64_MAX : rs->spp;
  if (max_passes <= 0) max_passes = 1;
  volatile int stop = 0;

  /* Render passes until the budget, the clock or a signal says stop. With
   * several ranks (dist.h), round r has pass r * ranks + rank on each rank
   * (none where that passes the budget), and the ranks agree between
   * rounds on the stop and the snapshots. */
  int64_t pass = 0, round;
  double next_snapshot = rs->snapshot;
  film snap_film; /* (render__snapshot's scratch) */
  memset(&snap_film, 0, sizeof snap_film);
  for (round = 0; !stop && (max_passes == INT64_MAX || round * ranks < max_passes); round++) {
    /* An intermediate image (--snapshot) between passes. */
    if (rs->snapshot > 0.0 && rs->snapshot_fn && round > 0 &&
        dist_any(omp_get_wtime() - t0 >= next_snapshot)) {
      render__snapshot(rs, out, &snap_film, use_bdpt, nthreads, counters, omp_get_wtime() - t0);
      while (next_snapshot <= omp_get_wtime() - t0) next_snapshot += rs->snapshot;
    }
    pass = round * ranks + rank;
    if (pass >= max_passes) goto agree;
    /* The ray differentials' step: a pixel over the square root of the
     * samples per pixel (Mitsuba's), of those so far under --time. */
    const double diff_scale =
        1.0 / sqrt((double)(max_passes == INT64_MAX ? pass + 1 : max_passes));
    for (int yb = 0; yb < H && !stop; yb += block) {
      const int ye = yb + block < H ? yb + block : H;
#pragma omp parallel num_threads(nthreads)
      {
        int tid = omp_get_thread_num();
        render_counters *cnt = &counters[tid].c;
#pragma omp for schedule(dynamic, 1)
        for (int y = yb; y < ye; y++) {
          if (stop) continue;
          if (render__stop) {
            stop = 1;
            continue;
          }
          if (rs->time_limit > 0.0 && omp_get_wtime() - t0 >= rs->time_limit) {
            stop = 2;
            continue;
          }
          /* bdpt's splats of this row go to the row's own list. */
          film row_splats;
          memset(&row_splats, 0, sizeof row_splats);
          row_splats.width = W;
          row_splats.height = H;
          row_splats.log = logs ? &logs[y - yb] : NULL;
          for (int x = 0; x < W; x++) {
            rgb L = render__sample(s, rs, x, y, pass, diff_scale, use_bdpt, ds, &row_splats, cnt);
            film_add(out, x, y, L);
            if (out->pass_val) {
              double *pv = out->pass_val + 3 * ((size_t)y * (size_t)W + (size_t)x);
              pv[0] = L.r, pv[1] = L.g, pv[2] = L.b;
            }
            cnt->samples++;
          }
          if (tid == 0) {
            double frac;
            if (max_passes == INT64_MAX)
              frac = (omp_get_wtime() - t0) / rs->time_limit;
            else
              frac = ((double)pass + (double)y / H) / (double)max_passes;
            progress_update(&bar, frac);
          }
        }
      }
      /* The block's splats, into the film in row order. */
      if (logs)
        for (int y = yb; y < ye; y++) film_splat_log_replay(out, &s->filter, &logs[y - yb]);
    }
    /* --error: a complete pass is one more estimate of every pixel (its
     * light subpaths, one per pixel, splat as W H estimates of the image). */
    if (!stop) film_error_pass(out, 1.0 / ((double)W * (double)H));
  agree:
    /* A signal or the clock on any rank stops them all. */
    if (ranks > 1) {
      int sig = dist_any(stop == 1), clock = dist_any(stop == 2);
      stop = sig ? 1 : clock ? 2 : 0;
    }
  }
  if (stop == 1) st->interrupted = 1;
  if (stop == 2) st->timed_out = 1;
  progress_finish(&bar);
  film_free(&snap_film);

  /* Totals, and the splat normalisation: one light subpath per sample, and
   * each light subpath (with the per-pixel importance of camera.h) is an
   * estimate of every pixel, so splats are divided by their total number. */
  render__totals(st, out, nthreads, counters);
  st->passes = st->samples / ((int64_t)W * H);
  if (use_bdpt) {
    int64_t lost = 0;
    for (int k = 0; k < block; k++) {
      lost += logs[k].lost;
      film_splat_log_free(&logs[k]);
    }
    if (lost > 0)
      lmc_warn(NULL, 0, "%lld light-tracing splats lost: out of memory for the splat lists",
               (long long)lost);
    out->splat_scale = st->samples > 0 ? 1.0 / (double)st->samples : 0.0;
  }
  free(logs);
  free(counters);
  st->seconds = omp_get_wtime() - t0;
  return LMC_OK;
}
