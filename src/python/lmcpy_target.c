/*
 * lmcpy_target.c: the module's Target (lmc.target): the target a state
 * space's chains sample, f and its gradient on NumPy arrays, evaluated with
 * the same code the C kernels use (lmcmodule.c has the module's overview),
 * and the samples of the MCMC driver's bootstrap with its estimate of b,
 * drawn by the driver's own functions (sample_bootstrap, lmcpy_bootstrap.c).
 *
 * Threads: a batch's loop runs without the GIL under the target's lock
 * (lmcpy_enter); the states are the call's own copy, checked before the
 * loop. A batch of LMCPY_PARALLEL_BATCH states or more is shared among
 * OpenMP threads, each with its own worker (scratch and buffers): each
 * state's numbers are those of one call alone, whatever the threads.
 * sample_bootstrap uses chains of its own, one per OpenMP thread, never
 * the target's workers.
 */
#define NO_IMPORT_ARRAY
#include "lmcpy.h"

#include <math.h>
#include <omp.h>
#include <pythread.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/driver/space.h"
#include "lmc/states/bdpt_states.h"

/* Batches of at least this many states are evaluated without the GIL, and
 * from LMCPY_PARALLEL_BATCH on by every OpenMP thread. */
#define LMCPY_NOGIL_BATCH 16
#define LMCPY_PARALLEL_BATCH 32

/* --- Target ---------------------------------------------------------------------- */


/* An evaluation loop over n states uses the target's scratch under its
 * lock; from LMCPY_NOGIL_BATCH states on it runs without the GIL, so that
 * other Python threads (and other targets' loops) run meanwhile. The lock
 * is taken after the GIL is dropped and released before it is taken back:
 * its holder never waits for the GIL, so a thread that waits for the lock
 * holding the GIL (a small batch) cannot deadlock. */
typedef struct lmcpy_section {
  PyThreadState *ts; /* NULL: the GIL is held */
} lmcpy_section;

static lmcpy_section lmcpy_enter(PyThread_type_lock lock, npy_intp n) {
  lmcpy_section sec = {NULL};
  if (n >= LMCPY_NOGIL_BATCH) sec.ts = PyEval_SaveThread();
  PyThread_acquire_lock(lock, WAIT_LOCK);
  return sec;
}

static void lmcpy_leave(PyThread_type_lock lock, lmcpy_section sec) {
  PyThread_release_lock(lock);
  if (sec.ts) PyEval_RestoreThread(sec.ts);
}

static void lmcpy_worker_free(const mc_target *T, lmcpy_worker *w) {
  if (w->scratch && T->scratch_destroy) T->scratch_destroy(w->scratch);
  free(w->contribs);
  free(w->grad);
  free(w->hidx);
  free(w->hess);
}

/* Makes the target have n workers (and, with hess, their Hessian
 * buffers); 0 when out of memory. Called with the lock held (or before
 * the target is shared). */
static int lmcpy_workers(lmcpy_target *self, int n, int hess) {
  const mc_target *T = self->T;
  if (n > self->n_w) {
    lmcpy_worker *w = realloc(self->w, (size_t)n * sizeof *w);
    if (!w) return 0;
    self->w = w;
    for (; self->n_w < n; self->n_w++) {
      lmcpy_worker *k = &w[self->n_w];
      memset(k, 0, sizeof *k);
      k->scratch = T->scratch_create ? T->scratch_create(T) : NULL;
      k->grad = malloc((size_t)T->dim * sizeof *k->grad);
      k->contribs = calloc((size_t)(T->n_labels > 0 ? T->n_labels : 1), sizeof *k->contribs);
      if ((T->scratch_create && !k->scratch) || !k->grad || !k->contribs) {
        lmcpy_worker_free(T, k);
        return 0;
      }
    }
  }
  for (int i = 0; hess && i < n; i++) {
    lmcpy_worker *k = &self->w[i];
    if (!k->hidx) k->hidx = malloc(MC_HESS_MAX * sizeof *k->hidx);
    if (!k->hess) k->hess = malloc((size_t)MC_HESS_MAX * (MC_HESS_MAX + 1) / 2 * sizeof *k->hess);
    if (!k->hidx || !k->hess) return 0;
  }
  return 1;
}

/* The threads a batch of n states runs on: 1, or (from
 * LMCPY_PARALLEL_BATCH states on) OpenMP's, when their workers can be
 * made; with the lock held. */
static int lmcpy_batch_threads(lmcpy_target *self, npy_intp n, int hess) {
  int nt = n >= LMCPY_PARALLEL_BATCH ? omp_get_max_threads() : 1;
  if (nt > n) nt = (int)n;
  while (nt > 1 && !lmcpy_workers(self, nt, hess)) nt--;
  return nt >= 1 && lmcpy_workers(self, 1, hess) ? nt : 0;
}

static void lmcpy_target_dealloc(lmcpy_target *self) {
  for (int i = 0; self->T && i < self->n_w; i++) lmcpy_worker_free(self->T, &self->w[i]);
  free(self->w);
  if (self->created) mc_space_free(&self->sp);
  if (self->lock) PyThread_free_lock(self->lock);
  if (self->scene) lmcpy_release(self->scene);
  Py_XDECREF(self->scene);
  Py_TYPE(self)->tp_free((PyObject *)self);
}

/* A sampler over one state's coordinates, in the target's layout: stream
 * k's j-th number is u[offset(k) + j]; numbers past a stream's block are
 * 0.5 (a chain would draw them fresh). */
typedef struct lmcpy_vec_smp {
  lmc_sampler base;
  const mc_target *T;
  const double *u;
  int stream, pos[LMC_STREAM_COUNT];
} lmcpy_vec_smp;

static double lmcpy_vec_next(lmc_sampler *self) {
  lmcpy_vec_smp *v = (lmcpy_vec_smp *)self;
  int k = v->stream, p = v->pos[k]++;
  if (p >= v->T->stream_dim[k]) return 0.5;
  return v->u[mc_target_stream_offset(v->T, k) + p];
}

static void lmcpy_vec_stream(lmc_sampler *self, int stream) {
  ((lmcpy_vec_smp *)self)->stream = stream;
}

static lmcpy_vec_smp lmcpy_vec_at(const mc_target *T, const double *u) {
  lmcpy_vec_smp v = {{lmcpy_vec_next, lmcpy_vec_stream, NULL}, T, u, 0, {0, 0, 0}};
  return v;
}


PyObject *lmcpy_make_target(PyObject *mod, PyObject *args, PyObject *kwargs) {
  (void)mod;
  static const char *const own[] = {"space", "length", NULL};
  lmcpy_scene *sc = NULL;
  if (!PyArg_ParseTuple(args, "O!:target", &lmcpy_scene_type, &sc)) return NULL;
  const char *space = "bdpt";
  long length = 0;
  PyObject *o;
  if (kwargs && (o = PyDict_GetItemString(kwargs, "space")) && o != Py_None) {
    if (!PyUnicode_Check(o) || !(space = PyUnicode_AsUTF8(o))) {
      if (!PyErr_Occurred()) PyErr_SetString(PyExc_ValueError, "space: a name (bdpt, mmlt, pt)");
      return NULL;
    }
  }
  if (kwargs && (o = PyDict_GetItemString(kwargs, "length")) && o != Py_None) {
    length = PyLong_AsLong(o);
    if (length == -1 && PyErr_Occurred()) return NULL;
  }
  int id = -1;
  for (int i = 0; mc_space_names[i]; i++)
    if (!strcmp(space, mc_space_names[i])) id = mc_space_ids[i];
  const mc_space_type *type = id >= 0 ? mc_space_find(id) : NULL;
  if (!type || id == MCMC_STATES_PATH)
    return PyErr_Format(PyExc_ValueError,
                        "space: unknown state space '%s' (valid: bdpt, mmlt, pt; path's states "
                        "are whole paths, not numbers)",
                        space);
  lmcpy_flags *F = malloc(sizeof *F);
  if (!F) return PyErr_NoMemory();
  render_settings rs;
  if (!lmcpy_parse_flags(kwargs, own, F) || !lmcpy_settings(sc, F, &rs)) {
    free(F);
    return NULL;
  }
  lmcpy_target *self = PyObject_New(lmcpy_target, &lmcpy_target_type);
  if (!self) {
    free(F);
    return NULL;
  }
  memset(&self->sp, 0, sizeof self->sp);
  self->scene = NULL;
  self->created = 0;
  self->T = NULL;
  self->w = NULL;
  self->n_w = 0;
  self->lock = PyThread_allocate_lock();
  if (!self->lock) {
    free(F);
    Py_DECREF(self);
    return PyErr_NoMemory();
  }
  if (!lmcpy_resolution(sc, F)) {
    free(F);
    Py_DECREF(self);
    return NULL;
  }
  free(F);
  Py_INCREF(sc);
  self->scene = sc;
  lmcpy_acquire(sc);
  /* The chains' settings: under --direct separate (the default) pt
   * renders the paths of one and two segments and the chains the rest
   * (mcmc.c's mcmc__direct). */
  const char *direct = lmc_opt_value(&rs, "direct");
  if (!direct || strcmp(direct, "mcmc")) rs.mindepth = rs.mindepth > 3 ? rs.mindepth : 3;
  lmc_error err;
  lmc_error_clear(&err);
  lmc_status st = type->create(&self->sp, sc->s, &rs, &err);
  self->created = 1;
  if (st) {
    Py_DECREF(self);
    return lmcpy_raise(&err);
  }
  /* The family: the only one, or the one of paths of `length` segments. */
  self->family = -1;
  for (int g = 0; g < self->sp.n_fam; g++)
    if (self->sp.n_fam == 1 ? length == 0 || self->sp.fam[g].length == 0 ||
                                  self->sp.fam[g].length == length
                            : self->sp.fam[g].length == length)
      self->family = g;
  if (self->family < 0) {
    if (self->sp.n_fam == 0)
      PyErr_Format(PyExc_ValueError, "space %s: no paths of %d to %d segments", space,
                   self->sp.kmin, self->sp.kmax);
    else
      PyErr_Format(PyExc_ValueError,
                   "length: the %s states have a target per path length: length=k with k in "
                   "%d .. %d (segments)",
                   space, self->sp.fam[0].length, self->sp.fam[self->sp.n_fam - 1].length);
    Py_DECREF(self);
    return NULL;
  }
  if (length != 0 && self->sp.fam[self->family].length == 0) {
    PyErr_Format(PyExc_ValueError,
                 "length: the %s states have one target over every length (length=%ld is for "
                 "space='mmlt')",
                 space, length);
    Py_DECREF(self);
    return NULL;
  }
  self->T = &self->sp.fam[self->family].target;
  self->length = self->sp.fam[self->family].length;
  if (!lmcpy_workers(self, 1, 0)) {
    Py_DECREF(self);
    return PyErr_NoMemory();
  }
  return (PyObject *)self;
}

/* u as a C array of float64, shape (dim,) or (N, dim), every number in
 * [0, 1); *OUT_batch: 1 for (N, dim). NULL and ValueError otherwise. The
 * array is the call's own copy: another thread may change the caller's
 * while the loop runs without the GIL, and must not slip a number past
 * the check. */
static PyArrayObject *lmcpy_states(lmcpy_target *self, PyObject *u, int *OUT_batch) {
  PyArrayObject *a = (PyArrayObject *)PyArray_FROM_OTF(
      u, NPY_FLOAT64, NPY_ARRAY_IN_ARRAY | NPY_ARRAY_FORCECAST | NPY_ARRAY_ENSURECOPY);
  if (!a) return NULL;
  int dim = self->T->dim, nd = PyArray_NDIM(a);
  if (!((nd == 1 && PyArray_DIM(a, 0) == dim) || (nd == 2 && PyArray_DIM(a, 1) == dim))) {
    PyObject *shape = PyObject_GetAttrString((PyObject *)a, "shape");
    PyErr_Format(PyExc_ValueError,
                 "u has shape %R but the target takes (%d,) or (N, %d): dim = %d coordinates",
                 shape, dim, dim, dim);
    Py_XDECREF(shape);
    Py_DECREF(a);
    return NULL;
  }
  const double *x = PyArray_DATA(a);
  npy_intp n = PyArray_SIZE(a);
  for (npy_intp i = 0; i < n; i++)
    if (!(x[i] >= 0.0 && x[i] < 1.0)) {
      char v[64];
      snprintf(v, sizeof v, "%.17g", x[i]);
      if (nd == 2)
        PyErr_Format(PyExc_ValueError, "u[%zd, %zd] is %s: a state's coordinates lie in [0, 1)",
                     (Py_ssize_t)(i / dim), (Py_ssize_t)(i % dim), v);
      else
        PyErr_Format(PyExc_ValueError, "u[%zd] is %s: a state's coordinates lie in [0, 1)",
                     (Py_ssize_t)i, v);
      Py_DECREF(a);
      return NULL;
    }
  *OUT_batch = nd == 2;
  return a;
}

/* The label argument: -1 (none) or a label of the target; 0 and
 * ValueError when it is not one. */
static int lmcpy_label(lmcpy_target *self, PyObject *label, int *OUT) {
  *OUT = -1;
  if (!label || label == Py_None) return 1;
  long l = PyLong_AsLong(label);
  if (l == -1 && PyErr_Occurred()) return 0;
  if (self->T->n_labels == 0) {
    PyErr_SetString(PyExc_ValueError, "label: this target has no labels (space bdpt has)");
    return 0;
  }
  if (l < 0 || l >= self->T->n_labels) {
    PyErr_Format(PyExc_ValueError, "label: %ld is not in 0 .. %d", l, self->T->n_labels - 1);
    return 0;
  }
  *OUT = (int)l;
  return 1;
}

/* lmcpy_label for a call that needs a label on a labelled target (what:
 * the quantity, call: the method, why: more of the message, or ""). */
static int lmcpy_label_needed(lmcpy_target *self, PyObject *label, const char *what,
                              const char *call, const char *why, int *OUT) {
  if (!lmcpy_label(self, label, OUT)) return 0;
  if (self->T->n_labels == 0 || *OUT >= 0) return 1;
  PyErr_Format(PyExc_ValueError, "label: the %s is a label's (t.%s(u, label=l), l in 0 .. %d)%s",
               what, call, self->T->n_labels - 1, why);
  return 0;
}

/* f at one state (label -1: F(u), the sum over the labels, on a labelled
 * target); with grad (not NULL) also its gradient, NaN where the target
 * gives none. -1 when the evaluation fails. */
static int lmcpy_eval(const mc_target *T, lmcpy_worker *w, const double *u, int label,
                      double *OUT_f, double *grad) {
  lmcpy_vec_smp smp = lmcpy_vec_at(T, u);
  mc_value v;
  memset(&v, 0, sizeof v);
  int ok = 0, r;
  if (T->n_labels > 0 && label < 0) {
    int n = T->eval_all(T, w->scratch, &smp.base, -1, w->contribs);
    if (n < 0) return -1;
    double F = 0.0;
    for (int i = 0; i < n; i++) F += w->contribs[i].v.f;
    *OUT_f = F;
    return 0;
  }
  if (T->n_labels > 0)
    r = T->eval_label(T, w->scratch, &smp.base, label, &v, grad ? w->grad : NULL,
                      grad ? &ok : NULL);
  else
    r = T->eval(T, w->scratch, &smp.base, &v, grad ? w->grad : NULL, grad ? &ok : NULL);
  if (r) return -1;
  *OUT_f = v.f;
  if (grad)
    for (int i = 0; i < T->dim; i++) grad[i] = ok ? w->grad[i] : NAN;
  return 0;
}

/* NULL and ValueError: the target's states have no `what` (gradient,
 * Hessian) through the scene's participating media yet (their eval
 * refuses it; the pt states' gradient goes through them). */
static PyObject *lmcpy_media_refused(lmcpy_target *self, const char *what) {
  int n = self->scene->s->n_media;
  return PyErr_Format(PyExc_ValueError,
                      "%s: no derivatives through participating media on the %s states yet (the "
                      "scene has %d medi%s; t.f and t.value evaluate f through them, and the pt "
                      "states' t.grad)",
                      what, self->sp.name, n, n == 1 ? "um" : "a");
}

/* t.f(u, label=None) and t.grad(u, label=None). */
static PyObject *lmcpy_target_call(lmcpy_target *self, PyObject *args, PyObject *kwargs,
                                   int want_grad) {
  static char *kwlist[] = {"u", "label", NULL};
  PyObject *uo, *lo = NULL;
  if (!PyArg_ParseTupleAndKeywords(args, kwargs, want_grad ? "O|O:grad" : "O|O:f", kwlist, &uo,
                                   &lo))
    return NULL;
  int label, batch;
  if (want_grad ? !lmcpy_label_needed(self, lo, "gradient", "grad",
                                      ": the chains differentiate f(u, l), not the sum F(u)",
                                      &label)
                : !lmcpy_label(self, lo, &label))
    return NULL;
  PyArrayObject *a = lmcpy_states(self, uo, &batch);
  if (!a) return NULL;
  int dim = self->T->dim;
  npy_intp n = batch ? PyArray_DIM(a, 0) : 1;
  npy_intp fdims[1] = {n}, gdims[2] = {n, dim};
  PyArrayObject *fo = (PyArrayObject *)PyArray_SimpleNew(1, fdims, NPY_FLOAT64);
  PyArrayObject *go =
      want_grad ? (PyArrayObject *)PyArray_SimpleNew(batch ? 2 : 1, batch ? gdims : gdims + 1,
                                                     NPY_FLOAT64)
                : NULL;
  if (!fo || (want_grad && !go)) {
    Py_XDECREF(fo);
    Py_XDECREF(go);
    Py_DECREF(a);
    return NULL;
  }
  const double *u = PyArray_DATA(a);
  double *f = PyArray_DATA(fo), *g = go ? PyArray_DATA(go) : NULL;
  int failed = 0;
  lmcpy_section sec = lmcpy_enter(self->lock, n);
  int nt = lmcpy_batch_threads(self, n, 0);
  failed = nt == 0;
  const mc_target *T = self->T;
  lmcpy_worker *W = self->w;
#pragma omp parallel for num_threads(nt > 0 ? nt : 1) schedule(dynamic, 4) if (nt > 1)
  for (npy_intp i = 0; i < n; i++) {
    if (nt == 0 || lmcpy_eval(T, &W[omp_get_thread_num()], u + i * dim, label, &f[i],
                              g ? g + i * dim : NULL) != 0) {
#pragma omp atomic write
      failed = 1;
    }
  }
  lmcpy_leave(self->lock, sec);
  Py_DECREF(a);
  if (failed) {
    Py_DECREF(fo);
    Py_XDECREF(go);
    if (want_grad && self->scene->s->n_media > 0) return lmcpy_media_refused(self, "grad");
    PyErr_SetString(PyExc_RuntimeError, "the target's evaluation failed (out of memory)");
    return NULL;
  }
  if (want_grad) {
    Py_DECREF(fo);
    return (PyObject *)go;
  }
  if (batch) return (PyObject *)fo;
  PyObject *res = PyFloat_FromDouble(f[0]);
  Py_DECREF(fo);
  return res;
}

static PyObject *lmcpy_target_f(lmcpy_target *self, PyObject *args, PyObject *kwargs) {
  return lmcpy_target_call(self, args, kwargs, 0);
}
static PyObject *lmcpy_target_grad(lmcpy_target *self, PyObject *args, PyObject *kwargs) {
  return lmcpy_target_call(self, args, kwargs, 1);
}

/* t.value(u, label=None) (and its alias t.contribution): what each state
 * adds to the image, as the chains splat it: its RGB value (the chain's
 * splat is value / f times the normalisation) and its raster position
 * (rx, ry) in pixels (the film grown by the filter's radius: pixel (x, y)
 * covers [x, x + 1) x [y, y + 1) under a box filter). Returns (value,
 * raster): shapes (3,), (2,) or (N, 3), (N, 2). A labelled target needs
 * the label (the value is f(u, l)'s). */
static PyObject *lmcpy_target_value(lmcpy_target *self, PyObject *args, PyObject *kwargs) {
  static char *kwlist[] = {"u", "label", NULL};
  PyObject *uo, *lo = NULL;
  if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O|O:value", kwlist, &uo, &lo)) return NULL;
  const mc_target *T = self->T;
  int label, batch;
  if (!lmcpy_label_needed(self, lo, "value", "value", "", &label)) return NULL;
  PyArrayObject *a = lmcpy_states(self, uo, &batch);
  if (!a) return NULL;
  int dim = T->dim;
  npy_intp n = batch ? PyArray_DIM(a, 0) : 1;
  npy_intp vdims[2] = {n, 3}, rdims[2] = {n, 2};
  PyArrayObject *vo =
      (PyArrayObject *)PyArray_SimpleNew(batch ? 2 : 1, batch ? vdims : vdims + 1, NPY_FLOAT64);
  PyArrayObject *ro =
      (PyArrayObject *)PyArray_SimpleNew(batch ? 2 : 1, batch ? rdims : rdims + 1, NPY_FLOAT64);
  if (!vo || !ro) goto fail;
  const double *u = PyArray_DATA(a);
  double *val = PyArray_DATA(vo), *ras = PyArray_DATA(ro);
  int failed = 0;
  lmcpy_section sec = lmcpy_enter(self->lock, n);
  int nt = lmcpy_batch_threads(self, n, 0);
  failed = nt == 0;
  lmcpy_worker *W = self->w;
#pragma omp parallel for num_threads(nt > 0 ? nt : 1) schedule(dynamic, 4) if (nt > 1)
  for (npy_intp i = 0; i < n; i++) {
    if (nt == 0) continue;
    void *scratch = W[omp_get_thread_num()].scratch;
    lmcpy_vec_smp smp = lmcpy_vec_at(T, u + i * dim);
    mc_value v;
    memset(&v, 0, sizeof v);
    int r = T->n_labels > 0 ? T->eval_label(T, scratch, &smp.base, label, &v, NULL, NULL)
                            : T->eval(T, scratch, &smp.base, &v, NULL, NULL);
    if (r) {
#pragma omp atomic write
      failed = 1;
    }
    val[3 * i] = v.value.r, val[3 * i + 1] = v.value.g, val[3 * i + 2] = v.value.b;
    ras[2 * i] = v.rx, ras[2 * i + 1] = v.ry;
  }
  lmcpy_leave(self->lock, sec);
  if (failed) {
    PyErr_SetString(PyExc_RuntimeError, "the target's evaluation failed (out of memory)");
    goto fail;
  }
  Py_DECREF(a);
  return Py_BuildValue("(NN)", (PyObject *)vo, (PyObject *)ro);
fail:
  Py_DECREF(a);
  Py_XDECREF(vo);
  Py_XDECREF(ro);
  return NULL;
}

/* t.hessian(u, label=None, with_grad=False): the Hessian of f by the
 * target's eval_hess, the taped second derivatives H2MC's kernel uses
 * (h2mc.c reads the same packed triangle). eval_hess gives d^2 f/du_i du_j
 * over the coordinates f varies with smoothly (hidx, at most MC_HESS_MAX);
 * every other entry is 0 (f's discrete choices: a light's triangle, a
 * lobe, the roulette). A state without one (f = 0, no gradient, overflow)
 * gives a NaN matrix. with_grad=True: (f, grad, hessian) of the same
 * evaluation. */
static PyObject *lmcpy_target_hessian(lmcpy_target *self, PyObject *args, PyObject *kwargs) {
  static char *kwlist[] = {"u", "label", "with_grad", NULL};
  PyObject *uo, *lo = NULL;
  int with_grad = 0;
  if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O|Op:hessian", kwlist, &uo, &lo, &with_grad))
    return NULL;
  const mc_target *T = self->T;
  if (!T->eval_hess && self->scene->s->n_media > 0) return lmcpy_media_refused(self, "hessian");
  if (!T->eval_hess)
    return PyErr_Format(PyExc_ValueError,
                        "hessian: the %s states have no Hessian (eval_hess; h2mc's spaces are "
                        "bdpt and mmlt)",
                        self->sp.name);
  int label, batch;
  if (!lmcpy_label_needed(self, lo, "Hessian", "hessian", "", &label)) return NULL;
  PyArrayObject *a = lmcpy_states(self, uo, &batch);
  if (!a) return NULL;
  int dim = T->dim;
  npy_intp n = batch ? PyArray_DIM(a, 0) : 1;
  npy_intp hdims[3] = {n, dim, dim}, gdims[2] = {n, dim};
  PyArrayObject *ho = (PyArrayObject *)PyArray_ZEROS(batch ? 3 : 2, batch ? hdims : hdims + 1,
                                                     NPY_FLOAT64, 0);
  PyArrayObject *go = with_grad ? (PyArrayObject *)PyArray_SimpleNew(
                                      batch ? 2 : 1, batch ? gdims : gdims + 1, NPY_FLOAT64)
                                : NULL;
  PyArrayObject *fo = with_grad ? (PyArrayObject *)PyArray_SimpleNew(1, &n, NPY_FLOAT64) : NULL;
  if (!ho || (with_grad && (!go || !fo))) goto fail;
  const double *u = PyArray_DATA(a);
  double *H = PyArray_DATA(ho), *g = go ? PyArray_DATA(go) : NULL;
  double *f = fo ? PyArray_DATA(fo) : NULL;
  int failed = 0;
  lmcpy_section sec = lmcpy_enter(self->lock, n);
  int nt = lmcpy_batch_threads(self, n, 1);
  failed = nt == 0;
  lmcpy_worker *W = self->w;
#pragma omp parallel for num_threads(nt > 0 ? nt : 1) schedule(dynamic, 2) if (nt > 1)
  for (npy_intp i = 0; i < n; i++) {
    if (nt == 0) continue;
    lmcpy_worker *w = &W[omp_get_thread_num()];
    /* Evaluate f, its gradient and its Hessian at state i. */
    lmcpy_vec_smp smp = lmcpy_vec_at(T, u + i * dim);
    mc_value v;
    memset(&v, 0, sizeof v);
    int grad_ok = 0, hess_ok = 0, hn = 0;
    if (T->eval_hess(T, w->scratch, &smp.base, label, &v, w->grad, &grad_ok, &hn, w->hidx,
                     w->hess, &hess_ok)) {
#pragma omp atomic write
      failed = 1;
      continue;
    }
    double *Hi = H + (size_t)i * (size_t)dim * (size_t)dim;
    if (f) f[i] = v.f;
    if (g)
      for (int k = 0; k < dim; k++) g[(size_t)i * dim + k] = grad_ok ? w->grad[k] : NAN;
    if (!(grad_ok && hess_ok)) {
      for (size_t k = 0; k < (size_t)dim * (size_t)dim; k++) Hi[k] = NAN;
      continue;
    }
    /* Unpack the upper triangle over hidx: entry (p, q), p <= q, at
     * p hn - p (p - 1) / 2 + q - p (target.h). */
    for (int p = 0; p < hn; p++) {
      const double *row = w->hess + (size_t)p * hn - (size_t)p * (size_t)(p - 1) / 2 - p;
      for (int q = p; q < hn; q++) {
        int r = w->hidx[p], c = w->hidx[q];
        Hi[(size_t)r * dim + c] = Hi[(size_t)c * dim + r] = row[q];
      }
    }
  }
  lmcpy_leave(self->lock, sec);
  if (failed) {
    PyErr_SetString(PyExc_RuntimeError, "the target's evaluation failed (out of memory)");
    goto fail;
  }
  Py_DECREF(a);
  if (!with_grad) return (PyObject *)ho;
  PyObject *fv = batch ? (PyObject *)fo : PyFloat_FromDouble(f[0]);
  if (!batch) Py_DECREF(fo);
  if (!fv) {
    Py_DECREF(go);
    Py_DECREF(ho);
    return NULL;
  }
  return Py_BuildValue("(NNN)", fv, (PyObject *)go, (PyObject *)ho);
fail:
  Py_DECREF(a);
  Py_XDECREF(ho);
  Py_XDECREF(go);
  Py_XDECREF(fo);
  return NULL;
}


/* t.labels(u): the labels with f > 0 at the numbers u (large-step
 * coordinates) and their f, as a dict {label: f}. */
static PyObject *lmcpy_target_labels(lmcpy_target *self, PyObject *uo) {
  if (self->T->n_labels == 0)
    return PyErr_Format(PyExc_ValueError, "labels: this target has no labels (space bdpt has)");
  int batch;
  PyArrayObject *a = lmcpy_states(self, uo, &batch);
  if (!a) return NULL;
  if (batch) {
    Py_DECREF(a);
    return PyErr_Format(PyExc_ValueError, "labels: u of one state, shape (%d,)", self->T->dim);
  }
  lmcpy_vec_smp smp = lmcpy_vec_at(self->T, PyArray_DATA(a));
  lmcpy_section sec = lmcpy_enter(self->lock, 1);
  lmcpy_worker *w = &self->w[0];
  int n = self->T->eval_all(self->T, w->scratch, &smp.base, -1, w->contribs);
  PyObject *d = n < 0 ? NULL : PyDict_New();
  for (int i = 0; d && i < n; i++) {
    PyObject *k = PyLong_FromLong(w->contribs[i].label);
    PyObject *v = PyFloat_FromDouble(w->contribs[i].v.f);
    if (!k || !v || PyDict_SetItem(d, k, v) < 0) Py_CLEAR(d);
    Py_XDECREF(k);
    Py_XDECREF(v);
  }
  lmcpy_leave(self->lock, sec);
  Py_DECREF(a);
  if (n < 0) return PyErr_Format(PyExc_RuntimeError, "the target's evaluation failed");
  return d;
}

/* t.strategy(label): the bdpt states' (s, t) of a label. */
static PyObject *lmcpy_target_strategy(lmcpy_target *self, PyObject *lo) {
  int label;
  if (!lmcpy_label(self, lo, &label)) return NULL;
  if (label < 0 || strcmp(self->sp.name, "bdpt"))
    return PyErr_Format(PyExc_ValueError, "strategy: a label of the bdpt states");
  const mc_bdpt_states *B = self->T->ctx;
  return Py_BuildValue("(ii)", B->strat[label].s, B->strat[label].t);
}

static PyMethodDef lmcpy_target_methods[] = {
    {"f", (PyCFunction)(void (*)(void))lmcpy_target_f, METH_VARARGS | METH_KEYWORDS,
     "f(u, label=None): the target at u, shape (dim,) -> float or (N, dim) -> (N,). Labelled "
     "targets (bdpt): F(u), the sum over the labels in the large step's coordinates, or with "
     "label=l f(u, l) in label l's own coordinates"},
    {"grad", (PyCFunction)(void (*)(void))lmcpy_target_grad, METH_VARARGS | METH_KEYWORDS,
     "grad(u, label=None): df/du by lmc's forward-mode AD, shape (dim,) or (N, dim); NaN rows "
     "where the target gives no gradient (f = 0); labelled targets need label="},
    {"hessian", (PyCFunction)(void (*)(void))lmcpy_target_hessian, METH_VARARGS | METH_KEYWORDS,
     "hessian(u, label=None, with_grad=False): d^2 f/du^2 by the target's eval_hess (h2mc's), "
     "shape (dim, dim) or (N, dim, dim); 0 off the coordinates f varies with smoothly, NaN "
     "where the target gives none; with_grad=True: (f, grad, hessian) of one evaluation"},
    {"value", (PyCFunction)(void (*)(void))lmcpy_target_value, METH_VARARGS | METH_KEYWORDS,
     "value(u, label=None): (value, raster): what the state adds to the image (RGB, shape (3,) "
     "or (N, 3); its luminance is f) and where (rx, ry) in pixels, shape (2,) or (N, 2)"},
    {"contribution", (PyCFunction)(void (*)(void))lmcpy_target_value,
     METH_VARARGS | METH_KEYWORDS, "contribution(u, label=None): an alias of value(u, label)"},
    {"sample_bootstrap", (PyCFunction)(void (*)(void))lmcpy_target_sample_bootstrap,
     METH_VARARGS | METH_KEYWORDS,
     "sample_bootstrap(n, seed=1, threads=None): the n independent samples the MCMC driver's "
     "bootstrap draws (render seed `seed`, --bootstrap n): a dict with u (n, dim), label (n,) "
     "or None, f (n,: what b averages), f_state (n,: f of the state a chain starts at), b, "
     "b_se, b_samples, seed"},
    {"labels", (PyCFunction)lmcpy_target_labels, METH_O,
     "labels(u): {label: f} of every label with f > 0 at u (labelled targets; large-step "
     "coordinates)"},
    {"strategy", (PyCFunction)lmcpy_target_strategy, METH_O,
     "strategy(label): the bdpt states' BDPT strategy (s, t) of a label"},
    {NULL, NULL, 0, NULL}};

static PyObject *lmcpy_target_get_dim(lmcpy_target *self, void *closure) {
  (void)closure;
  return PyLong_FromLong(self->T->dim);
}
static PyObject *lmcpy_target_get_n_labels(lmcpy_target *self, void *closure) {
  (void)closure;
  return PyLong_FromLong(self->T->n_labels);
}
static PyObject *lmcpy_target_get_space(lmcpy_target *self, void *closure) {
  (void)closure;
  return PyUnicode_FromString(self->sp.name);
}
static PyObject *lmcpy_target_get_length(lmcpy_target *self, void *closure) {
  (void)closure;
  return PyLong_FromLong(self->length);
}
static PyObject *lmcpy_target_get_lengths(lmcpy_target *self, void *closure) {
  (void)closure;
  return Py_BuildValue("(ii)", self->sp.kmin, self->sp.kmax);
}

static PyGetSetDef lmcpy_target_getset[] = {
    {"dim", (getter)lmcpy_target_get_dim, NULL, "coordinates of a state", NULL},
    {"n_labels", (getter)lmcpy_target_get_n_labels, NULL, "labels (0: an unlabelled target)",
     NULL},
    {"space", (getter)lmcpy_target_get_space, NULL, "the state space's name", NULL},
    {"length", (getter)lmcpy_target_get_length, NULL,
     "the family's path length in segments (0: every length)", NULL},
    {"lengths", (getter)lmcpy_target_get_lengths, NULL,
     "(kmin, kmax): the path lengths the space covers (kmax -1: unbounded)", NULL},
    {NULL, NULL, NULL, NULL, NULL}};

PyTypeObject lmcpy_target_type = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "lmc.Target",
    .tp_basicsize = sizeof(lmcpy_target),
    .tp_dealloc = (destructor)lmcpy_target_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "What the chains sample (lmc.target): dim, f(u), grad(u), hessian(u).",
    .tp_methods = lmcpy_target_methods,
    .tp_getset = lmcpy_target_getset,
};

