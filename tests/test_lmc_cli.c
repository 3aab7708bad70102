/*
 * test_lmc_cli.c: `lmc render --integrator lmc --adapt MODE` as a user runs
 * it: each valid mode (both `--adapt MODE` and `--adapt=MODE`) selects
 * that mode, visible in the statistics the render prints; no --adapt means
 * cache; cache prints its stage-1 and cache lines; an invalid mode exits
 * with status 2 and a message that lists the valid ones. --delayed on turns
 * on delayed acceptance (its line in the statistics), off (the default)
 * leaves it out, anything else exits 2 naming the flag. --technique-jump
 * and --path-mutations run on pssmlt's, lmc's and h2mc's default states
 * and are refused on the pt states (exit 2, bad input). mlt's --pss-weight
 * sets the primary-sample step's share, and without --pss-mutation on
 * exits 2 naming the flag.
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
#include <sys/stat.h>
#include <sys/wait.h>

#include "test_util.h"
#include "run_lmc.h"

/* The furnace: light on paths of every length, so the chains have work
 * under the default --direct separate (the diffuse sphere's paths all have
 * one or two segments: pt's pass would render all of it). */
#define SCENE "data/analytic/furnace.xml"
#define TMP LMC_TEST_TMP "/lmc_test_lmc_cli"
#define COMMON "render " SCENE " -o " TMP "/img --resolution 16x12 --spp 8 --threads 1 --integrator lmc"

static char err_text[65536];

static int run_lmc(const char *args) {
  return run_lmc_in(TMP, args, NULL, 0, err_text, sizeof err_text);
}

/* run_lmc of printf-style arguments that must succeed (the command and
 * its messages printed when it does not). */
static void run_ok(const char *fmt, ...) {
  char args[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(args, sizeof args, fmt, ap);
  va_end(ap);
  int rc = run_lmc(args);
  if (rc != 0) print_error("%s\n%s", args, err_text);
  assert_int_equal(rc, 0);
}

static int setup(void **state) {
  (void)state;
  mkdir(TMP, 0755);
  return 0;
}

/* Every valid mode, in both spellings, shows up in the statistics. */
static void test_each_mode_selected(void **state) {
  (void)state;
  static const char *modes[] = {"none", "adam", "diminish", "cache"};
  static const char *shown[] = {"lmc: adapt none,", "lmc: adapt adam (biased),",
                                "lmc: adapt diminish,", "lmc: adapt cache,"};
  int checked = 0;
  for (int m = 0; m < 4; m++)
    for (int form = 0; form < 2; form++) {
      run_ok(form ? "%s --adapt=%s" : "%s --adapt %s", COMMON, modes[m]);
      if (!strstr(err_text, shown[m]))
        fail_msg("--adapt %s does not print '%s':\n%s", modes[m], shown[m], err_text);
      /* Only the chosen mode is named. */
      for (int o = 0; o < 4; o++)
        if (o != m) assert_null(strstr(err_text, shown[o]));
      checked++;
    }
  assert_int_equal(checked, 8);
}

/* Without --adapt, lmc uses the cache; the cache lines are printed. */
static void test_default_is_cache(void **state) {
  (void)state;
  assert_int_equal(run_lmc(COMMON), 0);
  assert_non_null(strstr(err_text, "lmc: adapt cache,"));
  assert_non_null(strstr(err_text, "lmc: cache: stage 1"));
  assert_non_null(strstr(err_text, "image kept"));
  assert_non_null(strstr(err_text, " gradient evaluations ("));
  assert_non_null(strstr(err_text, "chains stalled"));
}

/* An invalid mode: exit status 2, the message names it and the valid ones. */
static void test_invalid_mode(void **state) {
  (void)state;
  static const char *bad[] = {"fast", "Cache"};
  for (int i = 0; i < 2; i++) {
    char args[1024];
    snprintf(args, sizeof args, "%s --adapt=%s", COMMON, bad[i]);
    assert_int_equal(run_lmc(args), 2);
    assert_non_null(strstr(err_text, "--adapt"));
    static const char *valid[] = {"none", "adam", "diminish", "cache"};
    for (int v = 0; v < 4; v++)
      if (!strstr(err_text, valid[v])) fail_msg("message lacks '%s':\n%s", valid[v], err_text);
  }
}

/* --delayed on|off, on ring-caustics (paths long enough for Langevin steps). */
static void test_delayed_flag(void **state) {
  (void)state;
  static const char *base =
      "render ../scenes/ring-caustics/scene.xml -o " TMP "/img --resolution 16x12 --spp 8 "
      "--threads 1 --integrator lmc --adapt none --bootstrap 2048";
  static const char *flag[] = {"", " --delayed off", " --delayed on", " --delayed=on"};
  int checked = 0;
  for (int i = 0; i < 4; i++) {
    run_ok("%s%s", base, flag[i]);
    assert_non_null(strstr(err_text, "lmc: mala       length 3"));
    int shown = strstr(err_text, "lmc: delayed acceptance:") != NULL;
    assert_int_equal(shown, i >= 2);
    checked++;
  }
  char args[1024];
  snprintf(args, sizeof args, "%s --delayed yes", base);
  assert_int_equal(run_lmc(args), 2);
  assert_non_null(strstr(err_text, "--delayed"));
  assert_non_null(strstr(err_text, "off or on"));
  assert_int_equal(checked, 4);
}

/* Stage 2 of --adapt cache (all of it with --cache-fraction 0) evaluates
 * no gradient by default: its cached walk proposes from the cache alone.
 * --cache-gradient on brings back the gradient-evaluating stage 2. */
static void test_stage2_without_gradients(void **state) {
  (void)state;
  int rc = run_lmc(COMMON " --adapt cache --cache-fraction 0");
  if (rc != 0) print_error("%s", err_text);
  assert_int_equal(rc, 0);
  assert_non_null(strstr(err_text, "lmc: stage 2: cached walk (no gradients), proposed "));
  assert_null(strstr(err_text, "cached walk (no gradients), proposed 0,"));
  assert_non_null(strstr(err_text, "lmc: 0 gradient evaluations ("));
  assert_non_null(strstr(err_text, "with neighbours), 0 gradient evaluations\n"));
  rc = run_lmc(COMMON " --adapt cache --cache-fraction 0 --cache-gradient on");
  assert_int_equal(rc, 0);
  assert_null(strstr(err_text, "cached walk"));
  assert_non_null(strstr(err_text, " gradient evaluations ("));
  assert_null(strstr(err_text, "lmc: 0 gradient evaluations ("));
  assert_non_null(strstr(err_text, "lmc: stage 2: Langevin proposals with the cached M, "));
  assert_null(strstr(err_text, "with neighbours), 0 gradient evaluations\n"));
  rc = run_lmc(COMMON " --adapt cache --cache-gradient maybe");
  assert_int_equal(rc, 2);
  assert_non_null(strstr(err_text, "--cache-gradient"));
}

/* --technique-jump and --path-mutations on the default states of pssmlt,
 * lmc and h2mc (the bdpt states): each run reports its moves, proposed and
 * accepted; on the pt states both are an error naming the states (exit 2:
 * a combination of flags refused is bad input). */
static void test_state_moves_flags(void **state) {
  (void)state;
  static const char *base =
      "render ../scenes/ring-caustics/scene.xml -o " TMP "/img --resolution 16x12 --spp 16 "
      "--threads 1 --bootstrap 2048 --technique-jump 0.2 --path-mutations 0.3";
  static const char *integ[] = {"pssmlt", "lmc", "h2mc"};
  int checked = 0;
  for (int i = 0; i < 3; i++) {
    run_ok("%s --integrator %s", base, integ[i]);
    static const char *const lines[2] = {"lmc: technique jumps: ", "lmc: path mutations (fused): "};
    for (int q = 0; q < 2; q++) {
      const char *l = strstr(err_text, lines[q]);
      if (!l) fail_msg("%s: no '%s' line:\n%s", integ[i], lines[q], err_text);
      long long proposed = 0;
      double acc = 0.0;
      int got = sscanf(l + strlen(lines[q]), "%lld proposed, %lf%% accepted", &proposed, &acc);
      assert_int_equal(got, 2);
      assert_true(proposed > 100);
      assert_true(acc > 0.0);
      checked++;
    }
  }
  char args[1024];
  snprintf(args, sizeof args, "%s --integrator pssmlt --states pt", base);
  int rc = run_lmc(args);
  assert_int_equal(rc, 2);
  assert_non_null(strstr(err_text, "not the pt states"));
  assert_int_equal(checked, 6);
}

/* mlt's --pss-weight: the primary-sample step's share of the proposals.
 * At a path where m of the other five moves apply, the step is chosen
 * with probability W / (W + m), m in [1, 5]; each choice is a fresh draw
 * given the path, so the share over n steps lies within
 * [W / (W + 5), W / (W + 1)] up to 5 binomial standard errors (at most
 * 0.5 / sqrt(n)). Weight 1 would give at most 1/2, above 1/8's bound and
 * below 8's. The statistics line of the inverses is there. And the
 * weight without the step is refused as bad input (exit 2, as README
 * promises for a bad flag). */
static void test_pss_weight(void **state) {
  (void)state;
  static const char *base =
      "render ../scenes/ring-caustics/scene.xml -o " TMP "/img --resolution 16x12 --spp 64 "
      "--threads 1 --bootstrap 2048 --integrator mlt --pss-mutation on";
  static const double weights[2] = {0.125, 8.0};
  static const char *const moves[6] = {"bidir", "lens", "multichain", "caustic", "lenssub", "pss"};
  int checked = 0;
  for (int i = 0; i < 2; i++) {
    run_ok("%s --pss-weight %g", base, weights[i]);
    long long n[6] = {0}, all = 0;
    for (int j = 0; j < 6; j++) {
      char key[64];
      snprintf(key, sizeof key, "lmc: %-10s proposed ", moves[j]);
      const char *l = strstr(err_text, key);
      if (!l) fail_msg("no '%s' line:\n%s", key, err_text);
      assert_int_equal(sscanf(l + strlen(key), "%lld", &n[j]), 1);
      all += n[j];
    }
    assert_true(all > 2000);
    /* The inverse path sampler's line: subpaths inverted (one or two per
     * step), and a failed round trip rare. */
    const char *l = strstr(err_text, "lmc: pss        ");
    l = l ? strstr(l + 1, "lmc: pss        ") : NULL;
    if (!l) fail_msg("no inversion line for pss:\n%s", err_text);
    long long inverted = 0;
    double per_s = 0.0, refused = 0.0, elsewhere = 0.0;
    int got = sscanf(l + strlen("lmc: pss        "),
                     "%lld subpaths inverted (%lf/s), %lf%% refused (a path its walks cannot "
                     "reach), %lf%% walked elsewhere",
                     &inverted, &per_s, &refused, &elsewhere);
    assert_int_equal(got, 4);
    assert_true(inverted >= n[5] / 2 && inverted <= 2 * n[5] && per_s > 0.0);
    assert_true(refused >= 0.0 && elsewhere <= 0.1);
    double w = weights[i], share = (double)n[5] / (double)all, tol = 5.0 * 0.5 / sqrt((double)all);
    fprintf(stderr, "  --pss-weight %g: the step %.3f of %lld proposals (bounds %.3f-%.3f)\n", w,
            share, all, w / (w + 5.0), w / (w + 1.0));
    assert_true(share > w / (w + 5.0) - tol);
    assert_true(share < w / (w + 1.0) + tol);
    checked++;
  }
  int rc = run_lmc("render ../scenes/ring-caustics-glass/scene.xml -o " TMP "/img --resolution "
                   "16x12 --spp 1 --integrator mlt --pss-weight 2");
  assert_int_equal(rc, 2);
  assert_non_null(strstr(err_text, "--pss-weight"));
  assert_int_equal(checked, 2);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_each_mode_selected),
      cmocka_unit_test(test_default_is_cache),
      cmocka_unit_test(test_invalid_mode),
      cmocka_unit_test(test_delayed_flag),
      cmocka_unit_test(test_stage2_without_gradients),
      cmocka_unit_test(test_state_moves_flags),
      cmocka_unit_test(test_pss_weight),
  };
  return cmocka_run_group_tests(tests, setup, NULL);
}
