/*
 * test_mpi_slow.c: renders over MPI ranks (src/render/dist.h, issue 21):
 * pt and bdpt, and the MCMC integrators (pssmlt, mmlt, lmc, h2mc, mlt),
 * through mpirun on this machine (ranks oversubscribe its cores).
 * Skipped when lmc is built without MPI.
 *
 *  - One rank through mpirun writes the same pixels (bits) and the same
 *    file (bytes) as the plain run, for every integrator: the reduction
 *    of one rank is its own film.
 *  - Two ranks with 1 and with 2 threads each write identical images:
 *    each rank's film does not depend on its threads, and rank 0 adds the
 *    ranks' films in rank order; a different seed changes the image, so
 *    the comparison can fail.
 *  - MCMC over 2 and 3 ranks makes the moves of one process: the same b
 *    (gathered bootstrap, shared large-step tallies) to the last printed
 *    digit, the same image up to float rounding.
 *  - 1, 2 and 4 ranks on the furnace (tests/data/analytic: every pixel's
 *    expectation is exactly 1): the image mean within its tolerance of 1
 *    (see the test), and every pixel has exactly the spp samples asked
 *    for (--spp 6 over 4 ranks: pt's passes 0-5 shared 2, 2, 1, 1).
 *  - Through participating media (bdpt, pssmlt): one rank is the plain
 *    run, two ranks' image does not depend on their threads.
 *  - A rank killed mid-render: mpirun exits non-zero within seconds and no
 *    image is written.
 *  - Ctrl-C (SIGINT) on mpirun, for pt, pssmlt and lmc: it exits non-zero
 *    within seconds and the image of what both ranks rendered is written.
 */
#define _POSIX_C_SOURCE 200809L
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "render/image.h"
#include "render/io/io.h"
#include "test_util.h"
#include "tmp_dir.h"

#define CORNELL LMC_SOURCE_DIR "/scenes/cornell-box/scene.xml"
#define FURNACE LMC_SOURCE_DIR "/tests/data/analytic/furnace.xml"
#define MEDIA_FURNACE LMC_SOURCE_DIR "/tests/data/media/furnace.xml"

static char tmp_dir[256];

/* The launcher's environment: root allowed (these machines run tests as
 * root), no single-copy transport (fails in some containers). */
#define MPI_ENV                                                             \
  "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "              \
  "OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_rmaps_base_oversubscribe=1 "

/* Renders scene_path with `flags` into tmp_dir/NAME.exr (its stderr in
 * NAME.err, with the statistics unless quiet), by mpirun with `ranks`
 * ranks (0: the plain binary); the exit status. The MCMC integrators'
 * bootstrap aims at a 5% error of b instead of 1%: 25 times fewer paths
 * (about 8,000 here, still shared over the ranks), which took nine tenths
 * of each render's time (pt and bdpt ignore the flag). */
static int render_v(int ranks, const char *scene_path, const char *flags, const char *name,
                    int quiet) {
  char cmd[4096], launch[1024] = "";
#ifdef LMC_MPIEXEC
  if (ranks > 0)
    snprintf(launch, sizeof launch, MPI_ENV "timeout -k 5 240 '%s' --bind-to none -n %d ",
             LMC_MPIEXEC, ranks);
#endif
  snprintf(cmd, sizeof cmd,
           "%s'%s' render '%s' %s --bootstrap-error 0.05 %s -o '%s/%s.exr' > /dev/null 2> "
           "'%s/%s.err'",
           launch, LMC_BINARY, scene_path, flags, quiet ? "-q" : "", tmp_dir, name, tmp_dir, name);
  int rc = system(cmd);
  return rc == -1 || !WIFEXITED(rc) ? -1 : WEXITSTATUS(rc);
}

static int render(int ranks, const char *scene_path, const char *flags, const char *name) {
  return render_v(ranks, scene_path, flags, name, 1);
}

/* The integrators under test: pt and bdpt (camera samples per pixel), then
 * the MCMC ones on the driver (mutations per pixel), with their budget. */
static const char *const integrators[] = {"pt", "bdpt", "pssmlt", "mmlt", "lmc", "h2mc", "mlt"};
#define N_INTEGRATORS 7
static int budget(int k) { return k < 2 ? 4 : 2; }

/* The first line of tmp_dir/NAME.err holding `key`, into line; 0 when none. */
static int log_line(const char *name, const char *key, char *line, size_t size) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s.err", tmp_dir, name);
  FILE *f = fopen(path, "r");
  if (!f) return 0;
  int found = 0;
  while (!found && fgets(line, (int)size, f)) found = strstr(line, key) != NULL;
  fclose(f);
  return found;
}

static void read_image(const char *name, lmc_image *img) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s.exr", tmp_dir, name);
  lmc_error err;
  assert_int_equal(image_read_exr(path, img, &err), LMC_OK);
}

/* Drops every rate ("4.27e+04/s", "1.2 Mrays/s") from line, in place. */
static void strip_rates(char *line) {
  char *s;
  while ((s = strstr(line, "/s"))) {
    char *a = s;
    while (a > line && a[-1] != ' ' && a[-1] != '(') a--;
    memmove(a, s + 2, strlen(s + 2) + 1);
  }
}

/* The integrator's own count line (h2mc's proposals, lmc's gradient
 * evaluations), rates dropped; 0 for the other integrators. */
static int count_line(const char *integrator, const char *name, char *line, size_t size) {
  const char *key = !strcmp(integrator, "h2mc")  ? "h2mc: " /* then "proposals" */
                    : !strcmp(integrator, "lmc") ? "gradient evaluations ("
                                                 : NULL;
  if (!key) return 0;
  char path[512];
  snprintf(path, sizeof path, "%s/%s.err", tmp_dir, name);
  FILE *f = fopen(path, "r");
  if (!f) return 0;
  int found = 0;
  while (!found && fgets(line, (int)size, f))
    found = strstr(line, key) && (strcmp(integrator, "h2mc") || strstr(line, "proposals"));
  fclose(f);
  if (found) strip_rates(line);
  return found;
}

/* Pixel channels whose bits differ between two renders. */
static int64_t differing(const char *a, const char *b) {
  lmc_image ia = {0}, ib = {0};
  read_image(a, &ia);
  read_image(b, &ib);
  assert_int_equal(ia.width, ib.width);
  assert_int_equal(ia.height, ib.height);
  int64_t n = (int64_t)ia.width * ia.height * ia.channels, diff = 0;
  for (int64_t i = 0; i < n; i++) diff += memcmp(&ia.data[i], &ib.data[i], sizeof(float)) != 0;
  image_free(&ia);
  image_free(&ib);
  return diff;
}

/* Whether two output files are byte for byte the same. */
static int same_file(const char *a, const char *b) {
  char cmd[1200];
  snprintf(cmd, sizeof cmd, "cmp -s '%s/%s.exr' '%s/%s.exr'", tmp_dir, a, tmp_dir, b);
  return system(cmd) == 0;
}

static int skip_without_mpi(void) {
#ifndef LMC_MPIEXEC
  print_message("lmc is built without MPI: skipped\n");
  return 1;
#else
  return 0;
#endif
}

static void test_one_rank_is_the_plain_run(void **state) {
  (void)state;
  if (skip_without_mpi()) skip();
  int compared = 0;
  for (int k = 0; k < N_INTEGRATORS; k++) {
    char flags[256], plain[64], one[64];
    snprintf(flags, sizeof flags,
             "--integrator %s --spp %d --resolution 40x30 --maxdepth 5 --seed 5 --threads 2",
             integrators[k], budget(k));
    snprintf(plain, sizeof plain, "%s_plain", integrators[k]);
    snprintf(one, sizeof one, "%s_one", integrators[k]);
    assert_int_equal(render(0, CORNELL, flags, plain), 0);
    assert_int_equal(render(1, CORNELL, flags, one), 0);
    assert_int_equal(differing(plain, one), 0);
    assert_true(same_file(plain, one));
    compared++;
  }
  assert_int_equal(compared, N_INTEGRATORS);
}

static void test_two_ranks_independent_of_threads(void **state) {
  (void)state;
  if (skip_without_mpi()) skip();
  int compared = 0;
  for (int k = 0; k < N_INTEGRATORS; k++) {
    char f1[256], f2[256], f3[256], a[64], b[64], c[64], common[128];
    snprintf(common, sizeof common, "--spp %d --resolution 40x30 --maxdepth 5", budget(k));
    snprintf(f1, sizeof f1, "--integrator %s %s --seed 5 --threads 1", integrators[k], common);
    snprintf(f2, sizeof f2, "--integrator %s %s --seed 5 --threads 2", integrators[k], common);
    snprintf(f3, sizeof f3, "--integrator %s %s --seed 6 --threads 2", integrators[k], common);
    snprintf(a, sizeof a, "%s_r2t1", integrators[k]);
    snprintf(b, sizeof b, "%s_r2t2", integrators[k]);
    snprintf(c, sizeof c, "%s_r2seed6", integrators[k]);
    assert_int_equal(render(2, CORNELL, f1, a), 0);
    assert_int_equal(render(2, CORNELL, f2, b), 0);
    assert_int_equal(render(2, CORNELL, f3, c), 0);
    assert_int_equal(differing(a, b), 0);
    assert_true(same_file(a, b));
    assert_true(differing(a, c) > 100);
    compared++;
  }
  assert_int_equal(compared, N_INTEGRATORS);
}

/* The MCMC integrators over 2 and 3 ranks make exactly the moves of one
 * process: the same b (bootstrap values gathered, the chains' large-step
 * tallies shared), printed to the last digit, and the same image up to
 * the order its splats are added in: a relative 1e-6 per channel, the
 * float rounding of sums that differ in their last bits (one mutation's
 * splat weighs about 1e-3 of a pixel here). lmc's and h2mc's own count
 * lines, summed over the ranks, are the one process's too. */
static void test_mcmc_ranks_make_the_moves_of_one_process(void **state) {
  (void)state;
  if (skip_without_mpi()) skip();
  static const int rank_counts[] = {2, 3};
  int compared = 0, owns = 0;
  for (int k = 2; k < N_INTEGRATORS; k++) {
    char flags[256], plain[64], line[512], b_plain[512], bl_plain[512];
    snprintf(flags, sizeof flags,
             "--integrator %s --spp 2 --resolution 40x30 --maxdepth 5 --seed 8 --threads 1",
             integrators[k]);
    snprintf(plain, sizeof plain, "%s_b_plain", integrators[k]);
    assert_int_equal(render_v(0, CORNELL, flags, plain, 0), 0);
    assert_true(log_line(plain, "b = ", b_plain, sizeof b_plain));
    int refined = log_line(plain, "b with large steps = ", bl_plain, sizeof bl_plain);
    char own_plain[1024], own[1024];
    int has_own = count_line(integrators[k], plain, own_plain, sizeof own_plain);
    lmc_image ip = {0};
    read_image(plain, &ip);
    for (int q = 0; q < 2; q++) {
      char name[64];
      snprintf(name, sizeof name, "%s_b_%d", integrators[k], rank_counts[q]);
      assert_int_equal(render_v(rank_counts[q], CORNELL, flags, name, 0), 0);
      /* "b = X +- E (..., N bootstrap paths; ...)": the same to the digit
       * (the line's mutations per second aside). */
      assert_true(log_line(name, "b = ", line, sizeof line));
      assert_string_equal(strstr(line, "b = "), strstr(b_plain, "b = "));
      if (refined) {
        assert_true(log_line(name, "b with large steps = ", line, sizeof line));
        assert_string_equal(line, bl_plain);
      }
      /* The integrator's own counts, summed over the ranks. */
      if (has_own) {
        assert_true(count_line(integrators[k], name, own, sizeof own));
        assert_string_equal(own, own_plain);
        owns++;
      }
      lmc_image ir = {0};
      read_image(name, &ir);
      int64_t n = (int64_t)ip.width * ip.height * ip.channels, off = 0;
      assert_int_equal(ir.width * ir.height * ir.channels, n);
      double sum = 0.0;
      for (int64_t i = 0; i < n; i++) {
        double a = ip.data[i], c = ir.data[i];
        sum += a;
        off += !(fabs(a - c) <= 1e-6 * fmax(fabs(a), 1e-30) + 1e-12);
      }
      print_message("%s on %d ranks: %s", integrators[k], rank_counts[q], strstr(line, "b"));
      assert_true(sum > 0.0);
      assert_int_equal(off, 0);
      image_free(&ir);
      compared++;
    }
    image_free(&ip);
  }
  assert_int_equal(compared, 2 * (N_INTEGRATORS - 2));
  assert_int_equal(owns, 2 * 2); /* lmc and h2mc */
}

/* --error on over ranks (the chains' groups summed to rank 0, pt's passes
 * of --direct separate too): pssmlt and mmlt (one family, several) on 2
 * ranks write the error channels of one process, to a relative 1e-5 (the
 * order of the sums aside: the groups' spread is a difference of such
 * sums, so it keeps less of their precision than the image). */
static void test_error_over_ranks(void **state) {
  (void)state;
  if (skip_without_mpi()) skip();
  static const char *const which[] = {"pssmlt", "mmlt"};
  int compared = 0;
  for (int k = 0; k < 2; k++) {
    char flags[256], plain[64], two[64], path[512];
    snprintf(flags, sizeof flags,
             "--integrator %s --spp 4 --resolution 40x30 --maxdepth 5 --seed 8 --threads 1 "
             "--error on",
             which[k]);
    snprintf(plain, sizeof plain, "%s_err_plain", which[k]);
    snprintf(two, sizeof two, "%s_err_2", which[k]);
    assert_int_equal(render(0, CORNELL, flags, plain), 0);
    assert_int_equal(render(2, CORNELL, flags, two), 0);
    lmc_image ep = {0}, e2 = {0};
    lmc_error err;
    snprintf(path, sizeof path, "%s/%s.exr", tmp_dir, plain);
    assert_int_equal(image_read_exr_layer(path, "error", &ep, &err), LMC_OK);
    snprintf(path, sizeof path, "%s/%s.exr", tmp_dir, two);
    assert_int_equal(image_read_exr_layer(path, "error", &e2, &err), LMC_OK);
    int64_t n = (int64_t)ep.width * ep.height * ep.channels, off = 0, positive = 0;
    assert_int_equal(e2.width * e2.height * e2.channels, n);
    for (int64_t i = 0; i < n; i++) {
      double a = ep.data[i], c = e2.data[i];
      assert_true(isfinite(a));
      positive += a > 0.0;
      off += !(fabs(a - c) <= 1e-5 * fabs(a) + 1e-12);
    }
    print_message("%s --error on 2 ranks: %lld of %lld values positive, %lld differ\n", which[k],
                  (long long)positive, (long long)n, (long long)off);
    assert_true(positive > n / 2);
    assert_int_equal(off, 0);
    image_free(&ep);
    image_free(&e2);
    compared++;
  }
  assert_int_equal(compared, 2);
}

/* The mean over the pixels and channels of tmp_dir/NAME.exr, and the
 * standard error of that mean over its pixels in OUT_se. */
static double image_mean(const char *name, double *OUT_se) {
  lmc_image img = {0};
  read_image(name, &img);
  int64_t n = (int64_t)img.width * img.height;
  double s = 0.0, s2 = 0.0;
  for (int64_t i = 0; i < n; i++) {
    const float *p = &img.data[i * img.channels];
    double v = (p[0] + p[1] + p[2]) / 3.0;
    s += v, s2 += v * v;
  }
  image_free(&img);
  double mean = s / n, sd = sqrt(fmax(s2 / n - mean * mean, 0.0));
  *OUT_se = sd / sqrt((double)n);
  return mean;
}

/* Furnace renders (tests/data/analytic: every pixel's expectation is
 * exactly 1) over 1, 2 and 4 ranks. pt and bdpt: the image mean within 5
 * standard errors of 1 (the pixels of pt are independent; bdpt's light
 * tracing ties them weakly). The MCMC integrators (every path, --direct
 * mcmc, of up to 16 segments: longer ones carry below 1e-6 here): their
 * pixels are tied by the chains, and the mean's error is b's and the
 * chains' (the share of splats that fall outside the frame, about 5%
 * here), so its spread is measured: 8 plain runs of other seeds give a
 * standard deviation s, and each run over ranks must lie within
 * t_7(0.9995) s sqrt(1 + 1/8) = 5.74 s of 1 (a prediction interval that a
 * correct render leaves once in a thousand), their mean within 5.41 s /
 * sqrt(8). Every run has exactly 6 samples (mutations) per pixel. */
static void test_furnace_over_ranks(void **state) {
  (void)state;
  if (skip_without_mpi()) skip();
  static const int rank_counts[] = {1, 2, 4};
  int checked = 0;
  for (int k = 0; k < N_INTEGRATORS; k++) {
    const char *mc = k < 2 ? "" : " --direct mcmc --maxdepth 16";
    double s_runs = 0.0;
    if (k >= 2) {
      double m[8], mbar = 0.0, var = 0.0, se;
      for (int r = 0; r < 8; r++) {
        char flags[256], name[64];
        snprintf(flags, sizeof flags, "--integrator %s --spp 6 --seed %d --threads 2%s",
                 integrators[k], 100 + r, mc);
        snprintf(name, sizeof name, "furnace_%s_seed%d", integrators[k], r);
        assert_int_equal(render(0, FURNACE, flags, name), 0);
        m[r] = image_mean(name, &se);
        mbar += m[r] / 8.0;
      }
      for (int r = 0; r < 8; r++) var += (m[r] - mbar) * (m[r] - mbar) / 7.0;
      s_runs = sqrt(var);
      print_message("%s, 8 plain runs: furnace mean %.5f, spread %.5f\n", integrators[k], mbar,
                    s_runs);
      assert_true(s_runs > 0.0);
      assert_near(mbar, 1.0, 5.41 * s_runs / sqrt(8.0));
    }
    for (int q = 0; q < 3; q++) {
      char flags[256], name[64], line[512];
      snprintf(flags, sizeof flags, "--integrator %s --spp 6 --seed %d --threads 1%s",
               integrators[k], 20 + q, mc);
      snprintf(name, sizeof name, "furnace_%s_%d", integrators[k], rank_counts[q]);
      assert_int_equal(render(rank_counts[q], FURNACE, flags, name), 0);
      double se, mean = image_mean(name, &se);
      double tol = k < 2 ? 5.0 * se : 5.74 * s_runs;
      print_message("%s on %d rank(s): furnace mean %.5f (tolerance %.5f)\n", integrators[k],
                    rank_counts[q], mean, tol);
      assert_true(tol > 0.0);
      assert_near(mean, 1.0, tol);
      assert_true(log_line(name, " 6 spp (", line, sizeof line));
      checked++;
    }
  }
  assert_int_equal(checked, 3 * N_INTEGRATORS);
}

/* Through participating media (tests/data/media/furnace.xml's fogs), bdpt
 * and pssmlt: one rank writes the plain run's file, and two ranks with 1
 * and with 2 threads each write the same image. */
static void test_media_over_ranks(void **state) {
  (void)state;
  if (skip_without_mpi()) skip();
  static const char *const which[] = {"bdpt", "pssmlt"};
  int compared = 0;
  for (int k = 0; k < 2; k++) {
    char f1[256], f2[256], plain[64], one[64], a[64], b[64];
    snprintf(f1, sizeof f1, "--integrator %s --spp 4 --seed 5 --threads 1", which[k]);
    snprintf(f2, sizeof f2, "--integrator %s --spp 4 --seed 5 --threads 2", which[k]);
    snprintf(plain, sizeof plain, "media_%s_plain", which[k]);
    snprintf(one, sizeof one, "media_%s_one", which[k]);
    snprintf(a, sizeof a, "media_%s_r2t1", which[k]);
    snprintf(b, sizeof b, "media_%s_r2t2", which[k]);
    assert_int_equal(render(0, MEDIA_FURNACE, f2, plain), 0);
    assert_int_equal(render(1, MEDIA_FURNACE, f2, one), 0);
    assert_true(same_file(plain, one));
    assert_int_equal(render(2, MEDIA_FURNACE, f1, a), 0);
    assert_int_equal(render(2, MEDIA_FURNACE, f2, b), 0);
    assert_int_equal(differing(a, b), 0);
    assert_true(same_file(a, b));
    compared++;
  }
  assert_int_equal(compared, 2);
}

static void test_killed_rank_ends_the_job(void **state) {
  (void)state;
  if (skip_without_mpi()) skip();
#ifdef LMC_MPIEXEC
  /* A long render by 2 ranks; after 3 s the newest lmc process of this
   * render (a rank, not the launcher) is killed. */
  char cmd[4096];
  snprintf(cmd, sizeof cmd,
           MPI_ENV "timeout -k 5 60 '%s' --bind-to none -n 2 '%s' render '%s' --integrator pt "
                   "--time 40 --threads 1 -q -o '%s/killed.exr' > /dev/null 2> '%s/killed.err' & "
                   "sleep 3; pkill -9 -n -f '%s/killed.exr'; wait $!",
           LMC_MPIEXEC, LMC_BINARY, CORNELL, tmp_dir, tmp_dir, tmp_dir);
  time_t t0 = time(NULL);
  int rc = system(cmd);
  double took = difftime(time(NULL), t0);
  int status = rc == -1 || !WIFEXITED(rc) ? -1 : WEXITSTATUS(rc);
  print_message("a killed rank: mpirun exited %d after %.0f s\n", status, took);
  assert_true(status != 0);
  assert_true(took < 30.0);
  char path[512];
  snprintf(path, sizeof path, "%s/killed.exr", tmp_dir);
  assert_int_equal(access(path, F_OK), -1);
#endif
}

static void test_interrupted_job_writes_its_image(void **state) {
  (void)state;
  if (skip_without_mpi()) skip();
#ifdef LMC_MPIEXEC
  /* Ctrl-C on the launcher, 4 s in (the chains' bootstrap a fixed 20,000
   * paths, well under a second, instead of a tenth of --time): mpirun
   * passes the signal on, every rank stops (pt at its next row, the MCMC
   * chains at the end of their round, which every rank drops), rank 0
   * writes the image of both and the others wait for it. timeout runs in --foreground so that the signal
   * reaches mpirun once: without it timeout also sends it to its whole
   * process group, and mpirun takes a second SIGINT as an order to kill the
   * ranks at once (1 run in 6 ended without an image that way). */
  static const char *const which[] = {"pt", "pssmlt", "lmc"};
  int checked = 0;
  for (int k = 0; k < 3; k++) {
    char cmd[4096];
    snprintf(cmd, sizeof cmd,
             MPI_ENV "timeout --foreground -k 5 60 '%s' --bind-to none -n 2 '%s' render '%s' "
                     "--integrator %s --time 40 --bootstrap 20000 --threads 1 -q "
                     "-o '%s/int_%s.exr' > /dev/null 2> '%s/int_%s.err' & "
                     "sleep 4; kill -INT $!; wait $!",
             LMC_MPIEXEC, LMC_BINARY, CORNELL, which[k], tmp_dir, which[k], tmp_dir, which[k]);
    time_t t0 = time(NULL);
    int rc = system(cmd);
    double took = difftime(time(NULL), t0);
    int status = rc == -1 || !WIFEXITED(rc) ? -1 : WEXITSTATUS(rc);
    print_message("%s, Ctrl-C on mpirun: exited %d after %.0f s\n", which[k], status, took);
    assert_true(status != 0);
    assert_true(took < 30.0);
    char name[64], line[512];
    snprintf(name, sizeof name, "int_%s", which[k]);
    lmc_image img = {0};
    read_image(name, &img);
    double sum = 0.0;
    int64_t n = (int64_t)img.width * img.height * img.channels;
    for (int64_t i = 0; i < n; i++) sum += img.data[i];
    assert_true(n > 0 && sum > 0.0 && isfinite(sum));
    image_free(&img);
    /* Both ranks' samples: the summary names the processes. */
    assert_true(log_line(name, "2 processes (MPI ranks)", line, sizeof line));
    checked++;
  }
  assert_int_equal(checked, 3);
#endif
}

static int setup(void **state) {
  (void)state;
  return tmp_dir_make(tmp_dir, sizeof tmp_dir, "lmc-mpi");
}

static int teardown(void **state) {
  (void)state;
  return tmp_dir_remove(tmp_dir);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_one_rank_is_the_plain_run),
      cmocka_unit_test(test_two_ranks_independent_of_threads),
      cmocka_unit_test(test_mcmc_ranks_make_the_moves_of_one_process),
      cmocka_unit_test(test_error_over_ranks),
      cmocka_unit_test(test_furnace_over_ranks),
      cmocka_unit_test(test_media_over_ranks),
      cmocka_unit_test(test_killed_rank_ends_the_job),
      cmocka_unit_test(test_interrupted_job_writes_its_image),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
