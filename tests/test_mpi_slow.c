/*
 * test_mpi_slow.c: pt and bdpt over MPI ranks (src/render/dist.h, issue
 * 21), through mpirun on this machine (ranks oversubscribe its cores).
 * Skipped when lmc is built without MPI.
 *
 *  - One rank through mpirun writes the same pixels (bits) and the same
 *    file (bytes) as the plain run: the reduction of one rank is its own
 *    film.
 *  - Two ranks with 1 and with 2 threads each write identical images:
 *    each rank's film does not depend on its threads, and rank 0 adds the
 *    ranks' films in rank order; a different seed changes the image, so
 *    the comparison can fail.
 *  - 1, 2 and 4 ranks on the furnace (tests/data/analytic: every pixel's
 *    expectation is exactly 1): the image mean within 5 standard errors
 *    of 1 (the pixels of pt are independent; bdpt's light tracing ties
 *    them weakly), and every pixel has exactly the spp samples asked for
 *    (--spp 6 over 4 ranks: passes 0-5 shared 2, 2, 1, 1).
 *  - A rank killed mid-render: mpirun exits non-zero within seconds and no
 *    image is written.
 *  - Ctrl-C (SIGINT) on mpirun: it exits non-zero within seconds and the
 *    image of what both ranks rendered is written.
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

#define CORNELL LMC_SOURCE_DIR "/scenes/cornell-box/scene.xml"
#define FURNACE LMC_SOURCE_DIR "/tests/data/analytic/furnace.xml"

static char tmp_dir[256];

/* The launcher's environment: root allowed (these machines run tests as
 * root), no single-copy transport (fails in some containers). */
#define MPI_ENV                                                             \
  "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "              \
  "OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_rmaps_base_oversubscribe=1 "

/* Renders scene_path with `flags` into tmp_dir/NAME.exr, by mpirun with `ranks`
 * ranks (0: the plain binary); the exit status. */
static int render(int ranks, const char *scene_path, const char *flags, const char *name) {
  char cmd[4096], launch[1024] = "";
#ifdef LMC_MPIEXEC
  if (ranks > 0)
    snprintf(launch, sizeof launch, MPI_ENV "timeout -k 5 240 '%s' --bind-to none -n %d ",
             LMC_MPIEXEC, ranks);
#endif
  snprintf(cmd, sizeof cmd, "%s'%s' render '%s' %s -q -o '%s/%s.exr' > /dev/null 2> '%s/%s.err'",
           launch, LMC_BINARY, scene_path, flags, tmp_dir, name, tmp_dir, name);
  int rc = system(cmd);
  return rc == -1 || !WIFEXITED(rc) ? -1 : WEXITSTATUS(rc);
}

static void read_image(const char *name, lmc_image *img) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s.exr", tmp_dir, name);
  lmc_error err;
  assert_int_equal(image_read_exr(path, img, &err), LMC_OK);
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
  static const char *const integrators[] = {"pt", "bdpt"};
  int compared = 0;
  for (int k = 0; k < 2; k++) {
    char flags[256], plain[64], one[64];
    snprintf(flags, sizeof flags,
             "--integrator %s --spp 3 --resolution 40x30 --maxdepth 5 --seed 5 --threads 2",
             integrators[k]);
    snprintf(plain, sizeof plain, "%s_plain", integrators[k]);
    snprintf(one, sizeof one, "%s_one", integrators[k]);
    assert_int_equal(render(0, CORNELL, flags, plain), 0);
    assert_int_equal(render(1, CORNELL, flags, one), 0);
    assert_int_equal(differing(plain, one), 0);
    assert_true(same_file(plain, one));
    compared++;
  }
  assert_int_equal(compared, 2);
}

static void test_two_ranks_independent_of_threads(void **state) {
  (void)state;
  if (skip_without_mpi()) skip();
  static const char *const integrators[] = {"pt", "bdpt"};
  int compared = 0;
  for (int k = 0; k < 2; k++) {
    char f1[256], f2[256], f3[256], a[64], b[64], c[64];
    const char *common = "--spp 4 --resolution 40x30 --maxdepth 5";
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
  assert_int_equal(compared, 2);
}

static void test_furnace_over_ranks(void **state) {
  (void)state;
  if (skip_without_mpi()) skip();
  static const char *const integrators[] = {"pt", "bdpt"};
  static const int rank_counts[] = {1, 2, 4};
  int checked = 0;
  for (int k = 0; k < 2; k++)
    for (int q = 0; q < 3; q++) {
      char flags[256], name[64];
      snprintf(flags, sizeof flags, "--integrator %s --spp 6 --seed %d --threads 1",
               integrators[k], 20 + q);
      snprintf(name, sizeof name, "furnace_%s_%d", integrators[k], rank_counts[q]);
      assert_int_equal(render(rank_counts[q], FURNACE, flags, name), 0);
      lmc_image img = {0};
      read_image(name, &img);
      int64_t n = (int64_t)img.width * img.height;
      double s = 0.0, s2 = 0.0;
      for (int64_t i = 0; i < n; i++) {
        const float *p = &img.data[i * img.channels];
        double v = (p[0] + p[1] + p[2]) / 3.0;
        s += v, s2 += v * v;
      }
      double mean = s / n, sd = sqrt(fmax(s2 / n - mean * mean, 0.0)), se = sd / sqrt((double)n);
      print_message("%s on %d rank(s): furnace mean %.5f (SE %.5f)\n", integrators[k],
                    rank_counts[q], mean, se);
      assert_true(se > 0.0);
      assert_near(mean, 1.0, 5.0 * se);
      image_free(&img);
      /* Every pixel's 6 samples: the log reports the passes. */
      char path[512], line[512];
      snprintf(path, sizeof path, "%s/%s.err", tmp_dir, name);
      FILE *f = fopen(path, "r");
      assert_non_null(f);
      int found = 0;
      while (fgets(line, sizeof line, f))
        if (strstr(line, " 6 spp (")) found = 1;
      fclose(f);
      assert_true(found);
      checked++;
    }
  assert_int_equal(checked, 6);
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
  /* Ctrl-C on the launcher: mpirun passes the signal on, every rank stops
   * at its next row, and rank 0 writes the image of both. */
  char cmd[4096];
  snprintf(cmd, sizeof cmd,
           MPI_ENV "timeout -k 5 60 '%s' --bind-to none -n 2 '%s' render '%s' --integrator pt "
                   "--time 40 --threads 1 -q -o '%s/int.exr' > /dev/null 2> '%s/int.err' & "
                   "sleep 3; kill -INT $!; wait $!",
           LMC_MPIEXEC, LMC_BINARY, CORNELL, tmp_dir, tmp_dir);
  time_t t0 = time(NULL);
  int rc = system(cmd);
  double took = difftime(time(NULL), t0);
  int status = rc == -1 || !WIFEXITED(rc) ? -1 : WEXITSTATUS(rc);
  print_message("Ctrl-C on mpirun: exited %d after %.0f s\n", status, took);
  assert_true(status != 0);
  assert_true(took < 30.0);
  lmc_image img = {0};
  read_image("int", &img);
  double sum = 0.0;
  int64_t n = (int64_t)img.width * img.height * img.channels;
  for (int64_t i = 0; i < n; i++) sum += img.data[i];
  assert_true(n > 0 && sum > 0.0 && isfinite(sum));
  image_free(&img);
  /* Both ranks' samples: the summary names the processes. */
  char path[512], line[512];
  snprintf(path, sizeof path, "%s/int.err", tmp_dir);
  FILE *f = fopen(path, "r");
  assert_non_null(f);
  int both = 0;
  while (fgets(line, sizeof line, f))
    if (strstr(line, "2 processes (MPI ranks)")) both = 1;
  fclose(f);
  assert_true(both);
#endif
}

static int setup(void **state) {
  (void)state;
  const char *tmp = getenv("TMPDIR");
  snprintf(tmp_dir, sizeof tmp_dir, "%s/lmc-mpi-XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
  return mkdtemp(tmp_dir) ? 0 : -1;
}

static int teardown(void **state) {
  (void)state;
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp_dir);
  return system(cmd) == 0 ? 0 : -1;
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_one_rank_is_the_plain_run),
      cmocka_unit_test(test_two_ranks_independent_of_threads),
      cmocka_unit_test(test_furnace_over_ranks),
      cmocka_unit_test(test_killed_rank_ends_the_job),
      cmocka_unit_test(test_interrupted_job_writes_its_image),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
