/*
 * test_gcache.c: the gradient cache (src/lmc/kernels/gcache.h): k-d tree nearest
 * neighbours against brute force, per-dimension trees, the preconditioner
 * lookup, capacity and merging, and the independence proposal's density
 * (integrates to one, matches its samples).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include <cmocka.h>

#include "chi2.h"
#include "lmc/kernels/gcache.h"
#include "lmc/kernels/mala.h"
#include "test_util.h"

/* Fills a cache with n random entries of dimension d (clustered in part,
 * with exact duplicates, as chains produce them); m2 of an entry = its
 * index + 1 in every coordinate so lookups can be checked. */
static void fill(gcache *c, int d, int n, rng *r) {
  double u[16], m1[16], m2[16];
  for (int i = 0; i < n; i++) {
    if (i % 5 == 4) {
      /* keep u: a duplicate of the previous entry */
    } else if (i % 3 == 0) {
      for (int k = 0; k < d; k++) u[k] = 0.3 + 0.01 * rng_uniform(r);
    } else {
      for (int k = 0; k < d; k++) u[k] = rng_uniform(r);
    }
    for (int k = 0; k < d; k++) m1[k] = 0.0, m2[k] = (double)(i + 1);
    assert_int_equal(gcache_add(c, d, u, m1, m2, 1.0 + i % 7), 1);
  }
}

/* k nearest by brute force: squared distances, sorted. */
static void brute(const gcache *c, int d, const double *q, int k, double *OUT_d2) {
  int64_t n = gcache_size_dim(c, d);
  for (int j = 0; j < k; j++) OUT_d2[j] = INFINITY;
  for (int64_t i = 0; i < n; i++) {
    const double *p = gcache_entry_u(c, d, i);
    double s = 0.0;
    for (int a = 0; a < d; a++) s += (p[a] - q[a]) * (p[a] - q[a]);
    if (s >= OUT_d2[k - 1]) continue;
    int at = k - 1;
    while (at > 0 && OUT_d2[at - 1] > s) OUT_d2[at] = OUT_d2[at - 1], at--;
    OUT_d2[at] = s;
  }
}

static void test_knn_brute_force(void **state) {
  (void)state;
  gcache *c;
  lmc_error err;
  assert_int_equal(gcache_create(&c, 8, 4000000, &err), LMC_OK);
  rng r;
  rng_seed(&r, 5, 0);
  const int dims[] = {1, 3, 8}, sizes[] = {3000, 5000, 4000};
  for (int t = 0; t < 3; t++) fill(c, dims[t], sizes[t], &r);
  assert_int_equal(gcache_size(c), 12000);
  assert_int_equal(gcache_freeze(c, 0, 0, &err), LMC_OK);
  assert_int_equal(gcache_size_dim(c, 3), 5000);
  assert_int_equal(gcache_size_dim(c, 2), 0);
  int checked = 0;
  for (int t = 0; t < 3; t++) {
    int d = dims[t];
    for (int qi = 0; qi < 300; qi++) {
      double q[8];
      for (int a = 0; a < d; a++) q[a] = qi % 4 == 0 ? 0.3 + 0.01 * rng_uniform(&r) : rng_uniform(&r);
      const int ks[] = {1, 8, GCACHE_MAX_K};
      for (int ki = 0; ki < 3; ki++) {
        int k = ks[ki];
        int64_t idx[GCACHE_MAX_K];
        double d2[GCACHE_MAX_K], want[GCACHE_MAX_K];
        int found = gcache_knn(c, d, q, k, idx, d2);
        assert_int_equal(found, k);
        brute(c, d, q, k, want);
        for (int j = 0; j < k; j++) {
          assert_near(d2[j], want[j], 1e-15);
          /* The index points at an entry at that distance. */
          const double *p = gcache_entry_u(c, d, idx[j]);
          double s = 0.0;
          for (int a = 0; a < d; a++) s += (p[a] - q[a]) * (p[a] - q[a]);
          assert_near(s, d2[j], 0.0);
        }
        checked++;
      }
    }
  }
  assert_int_equal(checked, 3 * 300 * 3);
  /* An empty dimension finds nothing. */
  int64_t idx[4];
  double d2[4], q[2] = {0.5, 0.5};
  assert_int_equal(gcache_knn(c, 2, q, 4, idx, d2), 0);
  gcache_destroy(c);
}

/* The preconditioner: isotropic far from every entry, the inverse-distance
 * mean of m2 near them. */
static void test_precond_lookup(void **state) {
  (void)state;
  gcache *c;
  lmc_error err;
  assert_int_equal(gcache_create(&c, 2, 1000, &err), LMC_OK);
  double u1[2] = {0.2, 0.2}, u2[2] = {0.22, 0.2}, m1[2] = {0, 0};
  double v1[2] = {4.0, 100.0}, v2[2] = {16.0, 100.0};
  assert_int_equal(gcache_add(c, 2, u1, m1, v1, 1.0), 1);
  assert_int_equal(gcache_add(c, 2, u2, m1, v2, 1.0), 1);
  assert_int_equal(gcache_freeze(c, 0, 0, &err), LMC_OK);
  assert_int_equal(gcache_add(c, 2, u2, m1, v2, 1.0), 0); /* frozen */
  gcache_params p = {2, 0.05, 0.0, 1e-3, 1e3};
  double M[2], q[2] = {0.8, 0.8};
  assert_int_equal(gcache_precond(c, 2, q, &p, M), 0);
  assert_near(M[0], 1.0, 0.0);
  assert_near(M[1], 1.0, 0.0);
  /* Midway: equal weights, v = (10, 100). */
  q[0] = 0.21, q[1] = 0.2;
  assert_int_equal(gcache_precond(c, 2, q, &p, M), 2);
  assert_near(M[0], 1.0 / sqrt(10.0), 1e-12);
  assert_near(M[1], 0.1, 1e-12);
  /* The clamp. */
  p.lo = 0.2;
  gcache_precond(c, 2, q, &p, M);
  assert_near(M[1], 0.2, 0.0);
  gcache_destroy(c);
}

/* Capacity is respected; merge appends. */
static void test_capacity_merge(void **state) {
  (void)state;
  gcache *a, *b;
  lmc_error err;
  assert_int_equal(gcache_create(&a, 4, 3 * (3 * 4 + 2), &err), LMC_OK);
  assert_int_equal(gcache_create(&b, 4, 1000, &err), LMC_OK);
  double u[4] = {0.1, 0.2, 0.3, 0.4}, m[4] = {0};
  assert_int_equal(gcache_add(a, 4, u, m, m, 1.0), 1);
  assert_int_equal(gcache_add(a, 5, u, m, m, 1.0), 0); /* dimension out of range */
  for (int i = 0; i < 5; i++) gcache_add(b, 1 + i % 4, u, m, m, 2.0);
  gcache_merge(a, b);
  /* a holds 42 doubles: its own entry takes 14, b's entries of 1, 2 and 3
   * dims 5 + 8 + 11 more; the next (4 dims: 14) would overflow, and the
   * merge stops there. */
  assert_int_equal(gcache_size(a), 4);
  assert_int_equal(gcache_size_dim(a, 1), 1);
  assert_int_equal(gcache_size_dim(a, 3), 1);
  assert_int_equal(gcache_size_dim(a, 4), 1);
  gcache_destroy(a);
  gcache_destroy(b);
  gcache_destroy(NULL);
}

/* A capped freeze keeps that many entries per dimension, evenly spread. */
static void test_freeze_cap(void **state) {
  (void)state;
  gcache *c;
  lmc_error err;
  assert_int_equal(gcache_create(&c, 2, 100000, &err), LMC_OK);
  double m[2] = {0, 0};
  for (int i = 0; i < 3000; i++) {
    double u[2] = {(i + 0.5) / 3000.0, 0.5};
    gcache_add(c, 2, u, m, m, 1.0);
  }
  for (int i = 0; i < 10; i++) gcache_add(c, 1, m, m, m, 1.0);
  assert_int_equal(gcache_freeze(c, 0, 1000, &err), LMC_OK);
  assert_int_equal(gcache_size_dim(c, 2), 1000);
  assert_int_equal(gcache_size_dim(c, 1), 10);
  assert_int_equal(gcache_size(c), 1010);
  /* Evenly spread: every query point has a kept entry within 3/3000. */
  int checked = 0;
  for (int i = 0; i < 100; i++) {
    double q[2] = {(i + 0.5) / 100.0, 0.5}, d2;
    int64_t idx;
    assert_int_equal(gcache_knn(c, 2, q, 1, &idx, &d2), 1);
    assert_le(sqrt(d2), 3.0 / 3000.0);
    checked++;
  }
  assert_int_equal(checked, 100);
  gcache_destroy(c);
}

/* The independence proposal: its density integrates to one (a 2-D state,
 * anchors of dimension 1 and 2) and matches its samples. */
static void test_indep_density(void **state) {
  (void)state;
  gcache *c;
  lmc_error err;
  assert_int_equal(gcache_create(&c, 2, 100000, &err), LMC_OK);
  rng r;
  rng_seed(&r, 9, 0);
  double m[2] = {0, 0};
  for (int i = 0; i < 300; i++) {
    double u[2] = {rng_uniform(&r), 0.97 + 0.05 * rng_uniform(&r)};
    u[1] = mala_wrap(u[1]);
    gcache_add(c, 1 + i % 2, u, m, m, 1.0);
  }
  assert_int_equal(gcache_freeze(c, 40, 0, &err), LMC_OK);
  assert_int_equal(gcache_anchor_count(c), 40);
  const double sigma = 0.03;
  const int n = 600;
  double sum = 0.0;
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++) {
      double y[2] = {(i + 0.5) / n, (j + 0.5) / n};
      sum += exp(gcache_indep_log_density(c, 2, sigma, y));
    }
  sum /= (double)n * n;
  assert_near(sum, 1.0, 1e-4);
  /* Chi-square of samples on a 20 x 20 grid (level 1e-3). */
  enum { NB = 20, NS = 200000 };
  static double obs[NB * NB], ex[NB * NB];
  for (int i = 0; i < NS; i++) {
    double y[2];
    gcache_indep_sample(c, 2, sigma, &r, y);
    obs[(int)(y[0] * NB) * NB + (int)(y[1] * NB)] += 1.0;
  }
  const int sub = 12;
  for (int a = 0; a < NB; a++)
    for (int b = 0; b < NB; b++) {
      double acc = 0.0;
      for (int s = 0; s < sub; s++)
        for (int t = 0; t < sub; t++) {
          double y[2] = {(a + (s + 0.5) / sub) / NB, (b + (t + 0.5) / sub) / NB};
          acc += exp(gcache_indep_log_density(c, 2, sigma, y));
        }
      ex[a * NB + b] = acc / ((double)sub * sub * NB * NB) * NS;
    }
  int dof;
  double stat, p = chi2_pvalue(obs, ex, NB * NB, 5.0, &dof, &stat);
  if (p < 1e-3) print_error("indep: p = %g, stat %g, dof %d\n", p, stat, dof);
  assert_true(p >= 1e-3);
  assert_true(dof > 50);
  gcache_destroy(c);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_knn_brute_force),
      cmocka_unit_test(test_precond_lookup),
      cmocka_unit_test(test_capacity_merge),
      cmocka_unit_test(test_freeze_cap),
      cmocka_unit_test(test_indep_density),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
