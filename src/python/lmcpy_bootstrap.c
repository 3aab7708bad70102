/*
 * lmcpy_bootstrap.c: t.sample_bootstrap of the module's Target
 * (lmcpy_target.c): the driver's bootstrap samples, starting states and b.
 */
#define NO_IMPORT_ARRAY
#include "lmcpy.h"

#include <limits.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/driver/mcmc_internal.h"
#include "lmc/kernels/pss.h"

/* --- the bootstrap's samples ----------------------------------------------------- */

/* t.sample_bootstrap(n, seed=1, threads=None): the independent samples the
 * MCMC driver's bootstrap draws for this family, by the driver's own
 * functions (mcmc_b.c's mcmc__bootstrap_draw, whose loop alone is
 * written again here): sample j is mc_eval_independent of the stream (seed,
 * mcmc__boot_seq(g, j)); mc_boot_run with a fixed size (--bootstrap n)
 * makes b and its variance (mc_boot_update); the state sample j is, as a
 * chain's start, is what mc_chain_start makes of the same stream (the
 * label drawn from the stream of chain j, mcmc__chain_seq(g, j)), its
 * numbers from the chain's lazy vector. A space with its own estimator of
 * b (mmlt's: every length from whole BDPT samples) gives b by it, with n
 * samples, as the driver does; the samples then only pick starting
 * states, as in the driver. */

typedef struct lmcpy_boot {
  const mc_target *T;
  int family, nthreads;
  uint64_t seed;
  mc_chain **chains; /* one per thread (owned by the caller) */
  double *u;         /* OUT: n x dim, the states' numbers */
  int *label;        /* OUT: n, the states' labels (-1: unlabelled) */
  double *f_state;   /* OUT: n, f of the states (f(u, l) for labelled ones) */
} lmcpy_boot;

/* mc_boot_draw_fn for one family: samples [boot->n, to[0]). */
static void lmcpy_boot_draw(void *ctx, mc_boot *boot, int n_fam, const int64_t *to) {
  lmcpy_boot *C = ctx;
  const mc_target *T = C->T;
  const int dim = T->dim;
  const int64_t from = boot->n, end = to[0];
  (void)n_fam;
#pragma omp parallel num_threads(C->nthreads)
  {
    mc_chain *c = C->chains[omp_get_thread_num()];
#pragma omp for schedule(dynamic, 64)
    for (int64_t j = from; j < end; j++) {
      /* The bootstrap's value, then the state a chain starting there takes. */
      const uint64_t seq = mcmc__boot_seq(C->family, j);
      boot->f[j] = mc_eval_independent(T, c->scratch, C->seed, seq, NULL);
      C->f_state[j] = mc_chain_start(c, C->seed, seq, mcmc__chain_seq(C->family, (int)j));
      C->label[j] = T->n_labels > 0 ? c->x.label : -1;
      mc_pss_materialise(c->pss, C->u + j * dim);
    }
  }
}

/* An int argument in [lo, hi] (0 and ValueError naming it otherwise). */
static int lmcpy_int_arg(PyObject *o, const char *name, long long lo, long long hi,
                         long long *OUT) {
  long long v = -1;
  int overflow = 0;
  if (o && PyLong_Check(o) && !PyBool_Check(o)) v = PyLong_AsLongLongAndOverflow(o, &overflow);
  if (v == -1 && PyErr_Occurred()) return 0;
  if (!o || !PyLong_Check(o) || PyBool_Check(o) || overflow || v < lo || v > hi) {
    PyErr_Format(PyExc_ValueError, "%s: %R is not an integer in [%lld, %lld]", name,
                 o ? o : Py_None, lo, hi);
    return 0;
  }
  *OUT = v;
  return 1;
}

PyObject *lmcpy_target_sample_bootstrap(lmcpy_target *self, PyObject *args,
                                               PyObject *kwargs) {
  static char *kwlist[] = {"n", "seed", "threads", NULL};
  PyObject *no, *so = NULL, *to = NULL;
  if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O|OO:sample_bootstrap", kwlist, &no, &so, &to))
    return NULL;
  long long n, seed = 1, threads = omp_get_max_threads();
  /* n: the samples live in memory (n x dim doubles), and a chain's stream
   * number is an int. */
  if (!lmcpy_int_arg(no, "n", 1, INT_MAX, &n)) return NULL;
  if (so && so != Py_None && !lmcpy_int_arg(so, "seed", 0, INT64_MAX, &seed)) return NULL;
  if (to && to != Py_None && !lmcpy_int_arg(to, "threads", 1, 1024, &threads)) return NULL;
  const mc_target *T = self->T;
  const int dim = T->dim;
  npy_intp udims[2] = {(npy_intp)n, dim}, ndims[1] = {(npy_intp)n};
  PyArrayObject *uo = (PyArrayObject *)PyArray_SimpleNew(2, udims, NPY_FLOAT64);
  PyArrayObject *fo = (PyArrayObject *)PyArray_SimpleNew(1, ndims, NPY_FLOAT64);
  PyArrayObject *so_ = (PyArrayObject *)PyArray_SimpleNew(1, ndims, NPY_FLOAT64);
  PyArrayObject *lo = (PyArrayObject *)PyArray_SimpleNew(1, ndims, NPY_INT32);
  mc_chain **chains = calloc((size_t)threads, sizeof *chains);
  mc_boot *boot = calloc((size_t)(self->sp.n_fam > 0 ? self->sp.n_fam : 1), sizeof *boot);
  render_counters *cnt = calloc((size_t)threads, sizeof *cnt);
  PyObject *res = NULL;
  if (!uo || !fo || !so_ || !lo) goto done;
  if (!chains || !boot || !cnt) {
    PyErr_NoMemory();
    goto done;
  }
  /* One chain per thread, with the large step alone (it only starts). */
  mc_kernel large;
  memset(&large, 0, sizeof large);
  large.name = "large";
  large.kind = MC_KERNEL_LARGE;
  const double prob = 1.0;
  lmc_error err;
  lmc_error_clear(&err);
  for (int i = 0; i < threads; i++)
    if (mc_chain_create(&chains[i], T, &large, &prob, 1, &err) != LMC_OK) {
      lmcpy_raise(&err);
      goto done;
    }
  lmcpy_boot C = {.T = T,
                  .family = self->family,
                  .nthreads = (int)threads,
                  .seed = (uint64_t)seed,
                  .chains = chains,
                  .u = PyArray_DATA(uo),
                  .label = PyArray_DATA(lo),
                  .f_state = PyArray_DATA(so_)};
  mc_boot_params bp = {.fixed = n, .batch = n, .cap_total = n, .rel_err = 0.0,
                       .seconds = INFINITY, .stop = NULL};
  mc_boot *B = &boot[self->family];
  int failed = 0;
  int64_t shared = 0;
  double b = 0.0, b_var = 0.0;
  Py_BEGIN_ALLOW_THREADS
  /* Draw the samples and estimate b from them (a fixed size: all estimate). */
  failed = mc_boot_run(B, 1, &bp, lmcpy_boot_draw, &C);
  b = B->b, b_var = B->b_var;
  if (!failed && self->sp.estimate_b) {
    /* The space's own estimator of b, of every family, from n samples. */
    mc_space_b_request rq = {n, INFINITY, 0.0, n, (uint64_t)seed, (int)threads};
    mc_boot keep = *B;
    memset(B, 0, sizeof *B);
    shared = self->sp.estimate_b(&self->sp, boot, &rq, cnt);
    failed = shared < 0;
    b = B->b, b_var = B->b_var;
    *B = keep;
  }
  Py_END_ALLOW_THREADS
  if (failed) {
    PyErr_NoMemory();
    goto done;
  }
  memcpy(PyArray_DATA(fo), B->f, (size_t)n * sizeof(double));
  res = PyDict_New();
  if (res && !(lmcpy_dict_set(res, "u", (PyObject *)uo) &&
               lmcpy_dict_set(res, "label",
                              T->n_labels > 0 ? (PyObject *)lo : (Py_INCREF(Py_None), Py_None)) &&
               lmcpy_dict_set(res, "f", (PyObject *)fo) &&
               lmcpy_dict_set(res, "f_state", (PyObject *)so_) &&
               lmcpy_dict_set(res, "b", PyFloat_FromDouble(b)) &&
               lmcpy_dict_set(res, "b_se", PyFloat_FromDouble(sqrt(b_var))) &&
               lmcpy_dict_set(res, "b_samples", PyLong_FromLongLong(shared > 0 ? shared : n)) &&
               lmcpy_dict_set(res, "seed", PyLong_FromLongLong(seed))))
    Py_CLEAR(res);
  uo = fo = so_ = NULL; /* the dict took them (or they went with it) */
  if (T->n_labels > 0) lo = NULL;
done:
  Py_XDECREF(uo);
  Py_XDECREF(fo);
  Py_XDECREF(so_);
  Py_XDECREF(lo);
  for (int i = 0; chains && i < threads; i++) mc_chain_destroy(chains[i]);
  free(chains);
  for (int g = 0; boot && g < self->sp.n_fam; g++) mc_boot_free(&boot[g]);
  free(boot);
  free(cnt);
  return res;
}
