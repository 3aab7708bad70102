/*
 * test_util.h: assertions the tests share, in double precision (cmocka
 * 1.1.5's assert_float_equal converts to float, which would hide errors
 * below 1e-7). Include after <cmocka.h>.
 */
#ifndef LMC_TESTS_TEST_UTIL_H
#define LMC_TESTS_TEST_UTIL_H

#include <math.h>
#include <stdio.h>

/* The file at path into buf (NUL-terminated, at most size - 1 bytes; empty
 * when it cannot be read). */
static inline void slurp_text(const char *path, char *buf, size_t size) {
  buf[0] = '\0';
  FILE *f = fopen(path, "rb");
  if (!f) return;
  size_t n = fread(buf, 1, size - 1, f);
  buf[n] = '\0';
  fclose(f);
}

/* |a - b| <= tol, printing both values when it fails. */
#define assert_near(a, b, tol)                                                    \
  do {                                                                            \
    double a_ = (a), b_ = (b), t_ = (tol);                                        \
    if (!(fabs(a_ - b_) <= t_)) {                                                 \
      print_error("%s = %.17g, %s = %.17g, tolerance %g\n", #a, a_, #b, b_, t_); \
      fail();                                                                     \
    }                                                                             \
  } while (0)

/* a <= b, printing both values when it fails. */
#define assert_le(a, b)                                         \
  do {                                                          \
    double a_ = (a), b_ = (b);                                  \
    if (!(a_ <= b_)) {                                          \
      print_error("%s = %.17g > %s = %.17g\n", #a, a_, #b, b_); \
      fail();                                                   \
    }                                                           \
  } while (0)

#endif
