/*
 * test_h2mc.c: the H2MC proposal's Gaussian (src/lmc/h2mc.h).
 *
 *  - its density integrates to one: 2-D quadrature over +-9 standard
 *    deviations (midpoint rule on a 600 x 600 grid; the truncated mass is
 *    below 1e-17), for Hessians with both signs of curvature, one near
 *    zero, and for the prior alone; within 1e-6;
 *  - it matches its samples: 3-D, 200,000 offsets from fixed normals,
 *    sample mean and covariance against V m and V diag(1/P) V^T, each
 *    entry within 4.5 standard errors (mean: sqrt(C_ii / N); covariance:
 *    sqrt((C_ii C_jj + C_ij^2) / N)); 9 + 6 entries per case, 3 cases;
 *  - the closed form on a separable model (H diagonal): mean and variance
 *    per coordinate as h2mc.h states them, for l < 0, l > 0 and l = 0;
 *  - the kernel leaves the cube with the probability the Gaussian gives:
 *    from u0 = 1e-3 with the prior alone (sigma 0.01), P(u0 + d < 0) =
 *    Phi(-0.1); 20,000 proposals, within 4.5 binomial standard errors,
 *    each such proposal returning -INFINITY;
 *  - the Gaussians the kernel keeps (h2mc_slot) are those a fresh kernel
 *    builds, bit for bit, and it builds only for a state it does not hold.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "lmc/kernels/h2mc.h"
#include "lmc/kernels/mala.h"

typedef struct gbuf {
  double V[9], P[3], m[3], l[3], k[3], work[16];
} gbuf;

static void gauss_of(const h2mc_params *p, int n, const double *g, const double *H, gbuf *b,
                     h2mc_gauss *G) {
  double A[9];
  memcpy(A, H, (size_t)n * n * sizeof(double));
  G->V = b->V;
  G->P = b->P;
  G->m = b->m;
  G->l = b->l;
  G->k = b->k;
  assert_int_equal(h2mc_gauss_build(p, n, g, A, b->work, 16, G), 0);
}

/* The 2-D cases: (g, H) of log f. */
static const double k_g2[4][2] = {{3.0, -2.0}, {40.0, 10.0}, {-5.0, 1.0}, {1.0, 1.0}};
static const double k_h2[4][4] = {
    {-20000.0, 3000.0, 3000.0, -8000.0}, /* both negative */
    {12000.0, -4000.0, -4000.0, -9000.0}, /* one positive, one negative */
    {-30000.0, 0.0, 0.0, 1e-12},          /* one (numerically) zero */
    {10.0, 0.0, 0.0, 10.0},               /* flat against the prior: isotropic */
};

static void test_integrates_to_one(void **state) {
  (void)state;
  h2mc_params p = h2mc_params_default();
  int checked = 0, isotropic = 0;
  for (int c = 0; c < 4; c++) {
    gbuf b;
    h2mc_gauss G;
    gauss_of(&p, 2, k_g2[c], k_h2[c], &b, &G);
    isotropic += G.isotropic;
    /* Mean and standard deviations in the world frame. */
    double mu[2] = {0.0, 0.0}, sd[2];
    if (G.isotropic) {
      sd[0] = sd[1] = p.sigma;
    } else {
      for (int j = 0; j < 2; j++) {
        double var = 0.0;
        for (int i = 0; i < 2; i++) {
          mu[j] += G.V[i * 2 + j] * G.m[i];
          var += G.V[i * 2 + j] * G.V[i * 2 + j] / G.P[i];
        }
        sd[j] = sqrt(var);
      }
    }
    const int N = 600;
    double sum = 0.0;
    for (int a = 0; a < N; a++)
      for (int bb = 0; bb < N; bb++) {
        double d[2] = {mu[0] + sd[0] * (-9.0 + 18.0 * (a + 0.5) / N),
                       mu[1] + sd[1] * (-9.0 + 18.0 * (bb + 0.5) / N)};
        sum += exp(h2mc_gauss_log_density(&G, d, p.sigma));
      }
    sum *= (18.0 * sd[0] / N) * (18.0 * sd[1] / N);
    printf("  case %d: integral %.9f%s\n", c, sum, G.isotropic ? " (prior alone)" : "");
    assert_true(fabs(sum - 1.0) < 1e-6);
    checked++;
  }
  assert_int_equal(checked, 4);
  assert_int_equal(isotropic, 1);
}

static void test_samples_match_moments(void **state) {
  (void)state;
  h2mc_params p = h2mc_params_default();
  const double g[3][3] = {{5.0, -3.0, 1.0}, {50.0, 20.0, -10.0}, {0.0, 2.0, 4.0}};
  const double H[3][9] = {
      {-20000, 2000, 0, 2000, -15000, 1000, 0, 1000, -9000},
      {15000, 3000, -2000, 3000, -12000, 0, -2000, 0, 7000},
      {-40000, 0, 0, 0, 1e-13, 0, 0, 0, 20000},
  };
  const int N = 200000;
  rng r;
  rng_seed(&r, 5, 7);
  int checked = 0;
  for (int c = 0; c < 3; c++) {
    gbuf b;
    h2mc_gauss G;
    gauss_of(&p, 3, g[c], H[c], &b, &G);
    assert_false(G.isotropic);
    double mu[3] = {0}, C[3][3] = {{0}};
    for (int j = 0; j < 3; j++)
      for (int i = 0; i < 3; i++) mu[j] += G.V[i * 3 + j] * G.m[i];
    for (int j = 0; j < 3; j++)
      for (int l = 0; l < 3; l++)
        for (int i = 0; i < 3; i++) C[j][l] += G.V[i * 3 + j] * G.V[i * 3 + l] / G.P[i];
    double s1[3] = {0}, s2[3][3] = {{0}};
    for (int k = 0; k < N; k++) {
      double z[4], d[3];
      mala_std_normal_pair(&r, &z[0], &z[1]);
      mala_std_normal_pair(&r, &z[2], &z[3]);
      h2mc_gauss_sample(&G, z, p.sigma, d);
      for (int j = 0; j < 3; j++) {
        s1[j] += d[j] - mu[j];
        for (int l = 0; l < 3; l++) s2[j][l] += (d[j] - mu[j]) * (d[l] - mu[l]);
      }
    }
    for (int j = 0; j < 3; j++) {
      double se = sqrt(C[j][j] / N);
      assert_true(fabs(s1[j] / N) < 4.5 * se);
      checked++;
      for (int l = j; l < 3; l++) {
        double cov = s2[j][l] / N, sec = sqrt((C[j][j] * C[l][l] + C[j][l] * C[j][l]) / N);
        if (!(fabs(cov - C[j][l]) < 4.5 * sec))
          print_error("case %d cov (%d,%d): sample %g, model %g (se %g)\n", c, j, l, cov, C[j][l],
                      sec);
        assert_true(fabs(cov - C[j][l]) < 4.5 * sec);
        checked++;
      }
    }
  }
  assert_int_equal(checked, 3 * (3 + 6));
}

static void test_closed_form(void **state) {
  (void)state;
  h2mc_params p = h2mc_params_default();
  double L = p.L, pp = 1.0 / (p.sigma * p.sigma);
  const double g[3] = {7.0, -4.0, 2.0};
  const double l[3] = {-25000.0, 30000.0, 0.0};
  double H[9] = {l[0], 0, 0, 0, l[1], 0, 0, 0, l[2]};
  gbuf b;
  h2mc_gauss G;
  gauss_of(&p, 3, g, H, &b, &G);
  int checked = 0;
  for (int i = 0; i < 3; i++) {
    double o, s;
    if (l[i] < 0) o = (1.0 - cos(L)) * g[i] / -l[i], s = sin(L) * sin(L) / -l[i];
    else if (l[i] > 0) o = (cosh(L) - 1.0) * g[i] / l[i], s = sinh(L) * sinh(L) / l[i];
    else o = 0.5 * g[i] * L * L, s = L * L;
    double P = 1.0 / s + pp, m = o / (s * P);
    /* The eigenvector of l[i] is +-e_i. */
    int e = -1;
    for (int k = 0; k < 3; k++)
      if (fabs(fabs(G.V[k * 3 + i]) - 1.0) < 1e-12) e = k;
    assert_true(e >= 0);
    double sign = G.V[e * 3 + i];
    assert_true(fabs(G.P[e] - P) <= 1e-12 * P);
    assert_true(fabs(sign * G.m[e] - m) <= 1e-12 * fabs(m) + 1e-18);
    checked++;
  }
  assert_int_equal(checked, 3);
}

/* Delayed acceptance's first test at the model (h2mc_gauss_log_screen)
 * on a quadratic log f, log f(x + d) = log f(x) + g . d + d . H d / 2,
 * whose gradient at y = x + d is g + H d and whose Hessian is H: the test
 * equals the full ratio log f(y) / f(x) + log q(x | y) - log q(y | x) with
 * the Gaussian built at y from (g + H d, H), for the 2-D cases (the
 * isotropic one included) and offsets drawn from x's Gaussian; 40 pairs. */
static void test_screen_is_exact_on_quadratics(void **state) {
  (void)state;
  h2mc_params p = h2mc_params_default();
  int checked = 0;
  for (int c = 0; c < 4; c++) {
    const double *g = k_g2[c], *H = k_h2[c];
    gbuf bx, by;
    h2mc_gauss Gx, Gy;
    gauss_of(&p, 2, g, H, &bx, &Gx);
    rng r;
    rng_seed(&r, 41, (uint64_t)c);
    for (int t = 0; t < 10; t++) {
      double z[2], d[2], nd[2], gy[2];
      mala_std_normal_pair(&r, &z[0], &z[1]);
      h2mc_gauss_sample(&Gx, z, p.sigma, d);
      for (int i = 0; i < 2; i++) gy[i] = g[i] + H[2 * i] * d[0] + H[2 * i + 1] * d[1];
      gauss_of(&p, 2, gy, H, &by, &Gy);
      nd[0] = -d[0], nd[1] = -d[1];
      double lf = g[0] * d[0] + g[1] * d[1] +
                  0.5 * (d[0] * (H[0] * d[0] + H[1] * d[1]) + d[1] * (H[2] * d[0] + H[3] * d[1]));
      double full = lf + h2mc_gauss_log_density(&Gy, nd, p.sigma) -
                    h2mc_gauss_log_density(&Gx, d, p.sigma);
      double screen = h2mc_gauss_log_screen(&Gx, d, lf);
      if (fabs(screen - full) > 1e-9 * (1.0 + fabs(full)))
        print_message("case %d: screen %.12g, full ratio %.12g\n", c, screen, full);
      assert_true(fabs(screen - full) <= 1e-9 * (1.0 + fabs(full)));
      checked++;
    }
  }
  assert_int_equal(checked, 40);
}

/* A toy target for the kernel over its dim (1 or 2) coordinates: f = 1
 * everywhere, the coordinates as the raster position. */
static int flat_eval(const mc_target *t, void *scratch, lmc_sampler *smp, mc_value *OUT_value,
                     double *OUT_grad, int *OUT_grad_ok) {
  (void)scratch;
  sampler_use_stream(smp, 0);
  OUT_value->f = 1.0;
  OUT_value->value = (rgb){1, 1, 1};
  OUT_value->rx = sampler_next(smp);
  OUT_value->ry = t->dim > 1 ? sampler_next(smp) : 0.0;
  if (OUT_grad) {
    for (int i = 0; i < t->dim; i++) OUT_grad[i] = 0.0;
    *OUT_grad_ok = 1;
  }
  return 0;
}

/* The flat target over dim coordinates. */
static mc_target flat_target(int dim) {
  mc_target tg;
  memset(&tg, 0, sizeof tg);
  tg.dim = dim;
  tg.stream_dim[0] = dim;
  tg.eval = flat_eval;
  return tg;
}

static void test_outside_rejected(void **state) {
  (void)state;
  mc_target tg = flat_target(1);
  h2mc_params p = h2mc_params_default();
  h2mc_kernel k;
  lmc_error err;
  assert_int_equal(h2mc_kernel_init(&k, &tg, &p, &err), LMC_OK);
  mc_kernel kn = h2mc_kernel_make(&k);
  assert_int_equal(kn.needs_grad, 2);
  double u = 1e-3, y;
  mc_state x;
  memset(&x, 0, sizeof x);
  x.dim = 1;
  x.u = &u;
  x.v.f = 1.0; /* no Hessian: the prior alone */
  rng r;
  rng_seed(&r, 3, 1);
  const int N = 20000;
  int out = 0;
  for (int i = 0; i < N; i++) {
    double lq = kn.propose(kn.self, &r, &x, &y);
    if (lq == -INFINITY) out++;
    else assert_true(y >= 0.0 && y < 1.0 && isfinite(lq));
  }
  double pe = 0.5 * erfc(0.1 / sqrt(2.0)); /* Phi(-0.1) */
  double se = sqrt(pe * (1.0 - pe) / N);
  printf("  outside: %d of %d (expected %.4f)\n", out, N, pe);
  assert_true(fabs((double)out / N - pe) < 4.5 * se);
  assert_int_equal(k.st.outside, out);
  assert_int_equal(k.st.proposed, N);
  h2mc_kernel_free(&k);
}

/* A 2-D state at u with f, gradient g and Hessian h (packed: h00, h01,
 * h11) of f. */
typedef struct tstate {
  double u[2], grad[2], hess[3];
  int hidx[2];
  mc_state s;
} tstate;

static void tstate_set(tstate *t, double u0, double u1, double f, int hess_ok) {
  memset(t, 0, sizeof *t);
  t->u[0] = u0, t->u[1] = u1;
  /* log f curving down steeply (|H| far above the prior's 1e4), so that
   * the model, not the prior, makes the Gaussian; its derivatives depend
   * on f (those of f do not), so another f is another Gaussian. */
  t->grad[0] = 30.0, t->grad[1] = -20.0;
  t->hess[0] = -4e4, t->hess[1] = 5e3, t->hess[2] = -3e4;
  t->hidx[0] = 0, t->hidx[1] = 1;
  t->s.dim = 2;
  t->s.u = t->u;
  t->s.v.f = f;
  t->s.grad = t->grad;
  t->s.grad_ok = 1;
  t->s.grad_eval = 2;
  t->s.hess_ok = hess_ok;
  t->s.hn = 2;
  t->s.hidx = t->hidx;
  t->s.hess = t->hess;
}

/* The kernel keeps the Gaussians of the last two states (h2mc_slot): every
 * proposal and density it gives equals, bit for bit, that of a fresh
 * kernel that builds them anew, and it builds only for a state it does not
 * hold (a changed f, coordinate or Hessian counts as another state). */
static void test_kept_gaussians_are_rebuilt_ones(void **state) {
  (void)state;
  mc_target tg = flat_target(2);
  h2mc_params p = h2mc_params_default();
  lmc_error err;
  h2mc_kernel k;
  assert_int_equal(h2mc_kernel_init(&k, &tg, &p, &err), LMC_OK);
  mc_kernel kn = h2mc_kernel_make(&k);
  tstate a, b, c, a_f, a_u, a_noh;
  tstate_set(&a, 0.4, 0.5, 2.0, 1);
  tstate_set(&b, 0.41, 0.49, 1.5, 1);
  tstate_set(&c, 0.39, 0.52, 3.0, 1);
  tstate_set(&a_f, 0.4, 0.5, 2.5, 1);       /* a with another f */
  tstate_set(&a_u, 0.4, 0.5 + 1e-12, 2.0, 1); /* a moved by 1e-12 */
  tstate_set(&a_noh, 0.4, 0.5, 2.0, 0);     /* a without its Hessian */
  /* A chain's calls: propose at the current state, the reverse density at
   * the proposal; (state, 1: propose / 0: density, builds so far). */
  const struct {
    const tstate *t;
    int propose;
    int built;
  } seq[] = {
      {&a, 1, 1},     /* first: built */
      {&b, 0, 2},     /* the proposal: built */
      {&a, 1, 2},     /* rejected: a kept */
      {&c, 0, 3},     /* another proposal: built over b */
      {&c, 1, 3},     /* accepted: c kept */
      {&a, 0, 3},     /* a again: still held in the other slot */
      {&a_f, 1, 4},   /* same u, another f */
      {&a_u, 1, 5},   /* another u */
      {&a_noh, 1, 6}, /* no Hessian: the prior's Gaussian */
      {&a_noh, 0, 6},
  };
  const int n = (int)(sizeof seq / sizeof seq[0]);
  rng r;
  rng_seed(&r, 9, 2);
  int compared = 0;
  for (int i = 0; i < n; i++) {
    h2mc_kernel fresh;
    assert_int_equal(h2mc_kernel_init(&fresh, &tg, &p, &err), LMC_OK);
    mc_kernel fk = h2mc_kernel_make(&fresh);
    double to[2] = {0.405, 0.497}, y1[2], y2[2], l1, l2;
    if (seq[i].propose) {
      rng r2 = r;
      l1 = kn.propose(kn.self, &r, &seq[i].t->s, y1);
      l2 = fk.propose(fk.self, &r2, &seq[i].t->s, y2);
      assert_memory_equal(y1, y2, sizeof y1);
    } else {
      l1 = kn.log_density(kn.self, &seq[i].t->s, to);
      l2 = fk.log_density(fk.self, &seq[i].t->s, to);
    }
    assert_true(isfinite(l1));
    assert_memory_equal(&l1, &l2, sizeof l1);
    assert_int_equal(k.st.built, seq[i].built);
    h2mc_kernel_free(&fresh);
    compared++;
  }
  assert_int_equal(compared, n);
  assert_true(k.st.model > 0); /* the model, not only the prior, was compared */
  h2mc_kernel_free(&k);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_integrates_to_one),
      cmocka_unit_test(test_samples_match_moments),
      cmocka_unit_test(test_closed_form),
      cmocka_unit_test(test_screen_is_exact_on_quadratics),
      cmocka_unit_test(test_outside_rejected),
      cmocka_unit_test(test_kept_gaussians_are_rebuilt_ones),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
