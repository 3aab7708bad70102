/*
 * test_error.c: `lmc render --error on` for pt and bdpt, each pixel's
 * standard error as the EXR's channels error.R, error.G, error.B, and the
 * coverage `lmc compare` reports from them (error_check.h: 12 renders of
 * the Cornell box at 80x60, 16 passes each, against each other).
 *  - agreement of the estimated variance with the renders' spread, |z|
 *    <= 4, for both;
 *  - coverage for bdpt: within one estimated standard error in [0.60,
 *    0.75] (0.68 for normal errors, 0.667 for Student's t with 15 degrees
 *    of freedom), within two in [0.90, 0.98]. pt's is printed, not
 *    bounded: its passes are heavy-tailed (it meets the small light
 *    rarely), so a render that has not met it yet has both a low value and
 *    a low estimated error, and the share falls short of the nominal one
 *    although the variance itself agrees (measured: 0.596 and 0.837 at 16
 *    passes, 0.589 and 0.839 at 64);
 *  - a bad value of the flag is refused naming it; a render without the
 *    flag writes no error channels, one of a single pass writes infinite
 *    errors; `lmc convert --channel error` writes a PNG of the image's
 *    size, and exits 2 naming the file without the channels or the flag
 *    with another value.
 * The MCMC integrators' error: test_error_mcmc.c.
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

#include "render/image.h"
#include "test_util.h"

#define TMP LMC_TEST_TMP "/lmc_test_error"
#include "error_check.h"

static void test_pt(void **state) {
  (void)state;
  spread_check("pt", "", 16, 0);
}

static void test_bdpt(void **state) {
  (void)state;
  spread_check("bdpt", "", 16, 1);
}

static void test_refusals(void **state) {
  (void)state;
  /* A bad value is refused, naming the flag. */
  assert_int_equal(render("--integrator pt --resolution 80x60 --spp 2 --error maybe", "x.exr"), 2);
  assert_non_null(strstr(err_text, "error"));
  /* Without it, no error channels. */
  assert_int_equal(render("--integrator pt --resolution 80x60 --spp 2", "plain.exr"), 0);
  lmc_image img;
  lmc_error err;
  lmc_error_clear(&err);
  assert_int_equal(image_read_exr_layer(TMP "/plain.exr", "error", &img, &err), LMC_EUNSUPPORTED);
  assert_non_null(strstr(err.msg, "error.R"));
  /* One pass: no spread to estimate, the error is infinite. */
  assert_int_equal(render("--integrator pt --resolution 80x60 --spp 1 --error on", "one.exr"), 0);
  read_layer("one.exr", "error", &img);
  long inf = 0;
  for (size_t i = 0; i < 3 * (size_t)EW * EH; i++) inf += isinf(img.data[i]) && img.data[i] > 0.0f;
  assert_int_equal(inf, 3L * EW * EH);
  image_free(&img);
  /* lmc convert --channel error: a PNG of the image's size from a file
   * with the channels; exit 2 naming the file without them, or the flag
   * with a bad value. */
  assert_int_equal(render("--integrator pt --resolution 80x60 --spp 4 --error on", "four.exr"), 0);
  assert_int_equal(run_lmc("convert " TMP "/four.exr " TMP "/four_err.png --channel error"), 0);
  lmc_error_clear(&err);
  assert_int_equal(image_read(TMP "/four_err.png", 1, &img, &err), LMC_OK);
  assert_int_equal(img.width, EW);
  assert_int_equal(img.height, EH);
  image_free(&img);
  assert_int_equal(run_lmc("convert " TMP "/plain.exr " TMP "/x.png --channel error"), 2);
  assert_non_null(strstr(err_text, "plain.exr"));
  assert_int_equal(run_lmc("convert " TMP "/four.exr " TMP "/x.png --channel alpha"), 2);
  assert_non_null(strstr(err_text, "--channel"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup(test_refusals, error_check_setup),
      cmocka_unit_test_setup(test_pt, error_check_setup),
      cmocka_unit_test_setup(test_bdpt, error_check_setup),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
