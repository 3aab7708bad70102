/*
 * lmcpy.h: what the Python module's files share (lmcmodule.c: the module,
 * Scene, Result, render, read, compare; lmcpy_target.c: Target). Internal
 * to the module. A file other than lmcmodule.c defines NO_IMPORT_ARRAY
 * before including it (NumPy's C API table is lmcmodule.c's).
 */
#ifndef LMC_PYTHON_LMCPY_H
#define LMC_PYTHON_LMCPY_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <pythread.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#define PY_ARRAY_UNIQUE_SYMBOL lmcpy_ARRAY_API
#include <numpy/arrayobject.h>

#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cli/cli.h"
#include "lmc/driver/space.h"
#include "lmc/states/bdpt_states.h"

/* The most flags one call takes (every table's, with room to spare). */
#define LMCPY_MAX_FLAGS 160
#define LMCPY_MAX_TABLES 32

typedef struct {
  PyObject_HEAD
  scene *s;       /* owned */
  PyObject *path; /* str: the file as given */
  int warnings;   /* warnings its load gave (--strict refuses to render it) */
  int busy;       /* renders and targets using it now (its camera must not change then) */
  camera loaded;  /* its camera as loaded, restored when no one uses it */
} lmcpy_scene;

/* What a call's keywords give: the command line's own flags (cli's
 * fields), the flags of the tables (given[], their values in text[]),
 * and the module's own. */
typedef struct lmcpy_flags {
  render_settings cli;
  lmc_given given[LMCPY_MAX_FLAGS];
  char text[LMCPY_MAX_FLAGS][LMC_ADDRESS_MAX];
  int n_given;
  int res_w, res_h; /* resolution (0: the scene's) */
} lmcpy_flags;

/* Raises the Python exception for a failed lmc call (NULL). */
PyObject *lmcpy_raise(const lmc_error *err);
/* Reads kwargs (may be NULL) into *F, skipping the names in `skip`; 0 and
 * ValueError naming the flag on an unknown flag or a bad value. */
int lmcpy_parse_flags(PyObject *kwargs, const char *const *skip, lmcpy_flags *F);
/* The render settings of scene sc with flags F (as lmc render merges them). */
int lmcpy_settings(lmcpy_scene *sc, const lmcpy_flags *F, render_settings *OUT);
/* F's resolution applied to sc's camera (0 and ValueError when bad). */
int lmcpy_resolution(lmcpy_scene *sc, const lmcpy_flags *F);
/* A render or target starts or stops using sc (its camera restored when
 * none does). */
void lmcpy_acquire(lmcpy_scene *sc);
void lmcpy_release(lmcpy_scene *sc);
/* d[key] = v, taking v's reference; 0 on failure. */
int lmcpy_dict_set(PyObject *d, const char *key, PyObject *v);

/* A float32 array (height, width, 3) copied from img. */
PyObject *lmcpy_image_copy(const lmc_image *img);
/* lmc.read(path, layer=None) and lmc.compare(image, reference). */
PyObject *lmcpy_read(PyObject *mod, PyObject *args, PyObject *kwargs);
PyObject *lmcpy_compare(PyObject *mod, PyObject *args);

/* render_request_stop's number for a stop the progress callable asked for
 * by raising (no signal has it). */
#define LMCPY_STOP_PROGRESS (-1)

/* What the drivers' snapshot hook (settings.h's snapshot_fn) hands the
 * progress callable. The drivers call it between their rounds, on the
 * thread that called render (which gave up the GIL): it develops the film
 * without the GIL, then takes the GIL only to copy the image into a new
 * array and call. Once the callable raises, its exception is kept here,
 * the render is asked to stop, and it is not called again. */
typedef struct lmcpy_progress {
  PyObject *fn;        /* borrowed: the callable */
  lmc_image img;       /* owned: the developed film, kept from one call to the next */
  PyObject *exc;       /* owned: what the callable raised (NULL: nothing) */
  int calls;
} lmcpy_progress;

/* lmcpy_progress.c: the SIGINT handler from the first render that starts
 * to the last that ends (release: 1 when a Ctrl-C stopped the renders,
 * with Python's interrupt set); the exception being raised taken (a new
 * reference, NULL when none) and raised again (its reference taken);
 * result (may be NULL) attached to the exception being raised as its
 * lmc_result; p's callable called with a copy of img and the seconds (0
 * when it raised: its exception in p->exc); the drivers' snapshot hook. */
void lmcpy_catch_sigint(void);
int lmcpy_release_sigint(void);
PyObject *lmcpy_take_exception(void);
void lmcpy_restore_exception(PyObject *exc);
void lmcpy_attach_result(PyObject *result);
int lmcpy_progress_call(lmcpy_progress *p, const lmc_image *img, double seconds);
void lmcpy_on_snapshot(void *ctx, const struct film *f, double seconds);

/* What one thread evaluating a target's states uses (lmcpy_target.c). */
typedef struct lmcpy_worker {
  void *scratch;        /* owned */
  mc_contrib *contribs; /* owned: n_labels entries */
  double *grad;         /* owned: dim entries */
  int *hidx;            /* owned: MC_HESS_MAX entries (made by the first hessian call) */
  double *hess;         /* owned: the packed upper triangle of MC_HESS_MAX coordinates */
} lmcpy_worker;

/* lmc.target's Target (lmcpy_target.c). */
typedef struct {
  PyObject_HEAD
  lmcpy_scene *scene;   /* a reference */
  mc_space sp;          /* owned */
  int created;          /* sp was created (mc_space_free it) */
  const mc_target *T;   /* the family's target, in sp */
  int family, length;   /* its index, and its paths' length (0: every length) */
  lmcpy_worker *w;      /* owned: w[0] made with the target, one per OpenMP thread of a
                           batch made by its first batch */
  int n_w;
  PyThread_type_lock lock; /* owned: held while the workers are used */
} lmcpy_target;
/* t.sample_bootstrap(n, seed=1, threads=None) (lmcpy_bootstrap.c). */
PyObject *lmcpy_target_sample_bootstrap(lmcpy_target *self, PyObject *args, PyObject *kwargs);

extern PyTypeObject lmcpy_scene_type;
extern PyTypeObject lmcpy_target_type;
/* lmc.target(scene, space='bdpt', length=None, **flags). */
PyObject *lmcpy_make_target(PyObject *mod, PyObject *args, PyObject *kwargs);

#endif
