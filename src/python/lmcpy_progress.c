/*
 * lmcpy_progress.c: what lmc.render (lmcmodule.c) hands the drivers while
 * it runs without the GIL: Ctrl-C stops the render and becomes Python's
 * KeyboardInterrupt afterwards, and the progress callable is called from
 * the drivers' snapshot hook.
 */
#define NO_IMPORT_ARRAY
#include "lmcpy.h"

#include <signal.h>
#include <string.h>


/* Ctrl-C while renders run without the GIL: the render stops
 * (render_request_stop) and Python learns of it afterwards. The handler
 * is lmc's from the first render that starts to the last that ends. */
static int lmcpy_renders_running;
static struct sigaction lmcpy_old_sigint;

static void lmcpy_on_sigint(int sig) { render_request_stop(sig); }

void lmcpy_catch_sigint(void) {
  if (lmcpy_renders_running++ > 0) return;
  render_reset_stop();
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = lmcpy_on_sigint;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, &lmcpy_old_sigint);
}

/* 1 when a Ctrl-C stopped the renders. */
int lmcpy_release_sigint(void) {
  if (--lmcpy_renders_running > 0) return render_stop_signal() == SIGINT;
  sigaction(SIGINT, &lmcpy_old_sigint, NULL);
  int hit = render_stop_signal() == SIGINT;
  if (hit) PyErr_SetInterrupt(); /* Python's own handling: KeyboardInterrupt in the main thread */
  render_reset_stop();
  return hit;
}

/* --- progress: the drivers' snapshot hook to a Python callable ----------------- */


/* The exception being raised, taken from the interpreter (a new
 * reference; NULL when none). */
PyObject *lmcpy_take_exception(void) {
#if PY_VERSION_HEX >= 0x030C0000
  return PyErr_GetRaisedException();
#else
  PyObject *type, *value, *tb;
  PyErr_Fetch(&type, &value, &tb);
  if (!type) return NULL;
  PyErr_NormalizeException(&type, &value, &tb);
  if (tb && value) PyException_SetTraceback(value, tb);
  Py_XDECREF(type);
  Py_XDECREF(tb);
  return value;
#endif
}

/* Raises exc again (its reference is taken). */
void lmcpy_restore_exception(PyObject *exc) {
#if PY_VERSION_HEX >= 0x030C0000
  PyErr_SetRaisedException(exc);
#else
  PyObject *type = (PyObject *)Py_TYPE(exc);
  Py_INCREF(type);
  PyErr_Restore(type, exc, PyException_GetTraceback(exc));
#endif
}

/* With an exception being raised: result (a Result, may be NULL) becomes
 * its attribute lmc_result, the image so far. */
void lmcpy_attach_result(PyObject *result) {
  if (!result) return;
  PyObject *exc = lmcpy_take_exception();
  if (!exc) return;
  if (PyObject_SetAttrString(exc, "lmc_result", result) < 0) PyErr_Clear();
  lmcpy_restore_exception(exc);
}

/* Calls p's callable with a copy of img and the seconds (with the GIL);
 * 0 when it raised (the exception kept in p->exc). */
int lmcpy_progress_call(lmcpy_progress *p, const lmc_image *img, double seconds) {
  PyObject *a = lmcpy_image_copy(img);
  PyObject *res = a ? PyObject_CallFunction(p->fn, "Od", a, seconds) : NULL;
  Py_XDECREF(a);
  p->calls++;
  if (res) {
    Py_DECREF(res);
    return 1;
  }
  p->exc = lmcpy_take_exception();
  return 0;
}

/* The drivers' snapshot hook (render_settings.snapshot_fn). */
void lmcpy_on_snapshot(void *ctx, const struct film *f, double seconds) {
  lmcpy_progress *p = ctx;
  if (p->exc) return; /* (stopping) */
  /* Develop the film as at the end, without the GIL. */
  lmc_error err;
  lmc_error_clear(&err);
  if (!p->img.data && image_init(&p->img, f->width, f->height, 3, &err)) return;
  film_develop_to(f, p->img.data);
  /* Call with the GIL; a raise stops the render. */
  PyGILState_STATE g = PyGILState_Ensure();
  int ok = lmcpy_progress_call(p, &p->img, seconds);
  PyGILState_Release(g);
  if (!ok) render_request_stop(LMCPY_STOP_PROGRESS);
}
