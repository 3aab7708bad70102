/*
 * lmcmodule.c: the Python module `lmc` (CPython's C API and NumPy's,
 * nothing else): lmc from Python, as docs/python.md describes it.
 *
 *   scene = lmc.load("scene.xml", **params)     params: the scene's <default>s (-D)
 *   r = lmc.render(scene, integrator="pt", spp=16, seed=1, threads=2, **flags)
 *   r.image, r.error, r.stats, r.save("out.exr")
 *   lmc.read("x.exr"), lmc.compare(a, b)
 *   t = lmc.target(scene, space="bdpt", **flags); t.dim, t.f(u), t.grad(u)
 *
 * Flags. render and target take every flag of `lmc render` by its name,
 * dashes as underscores (largestep=0.3, adapt="cache"); a value is given
 * as a str, a number, a bool (on/off) or a pair (step_range=(a, b)) and
 * goes through the same option tables (render/options.h) with the same
 * checks and messages as the command line: a bad flag or value raises
 * ValueError naming the flag. The settings are merged as `lmc render`
 * merges them (cli/render_settings.c, one function for both), so the same
 * scene, seed and flags give the same image bit for bit.
 *
 * Threads. render releases the GIL while it renders; a Ctrl-C in that
 * time stops the render (render_request_stop, as the command line does)
 * and raises KeyboardInterrupt. A target evaluates with the GIL held (its
 * scratch is one per target object).
 *
 * Ownership. A Scene owns its scene; a Result owns its pixels, which
 * r.image views (the array keeps the Result alive); a Target owns its
 * state space and scratch and keeps its Scene alive.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
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

/* --- errors ----------------------------------------------------------------- */

/* Raises the Python exception for a failed lmc call: ValueError for bad
 * input (a value, a flag, a refused combination, --strict), OSError for
 * a file, MemoryError, else RuntimeError; the message as lmc formats it. */
static PyObject *lmcpy_raise(const lmc_error *err) {
  char msg[2048];
  lmc_error_format(err, msg, sizeof msg);
  PyObject *type = PyExc_RuntimeError;
  switch (err->code) {
  case LMC_EINVAL:
  case LMC_EPARSE:
  case LMC_EUNSUPPORTED:
  case LMC_ESTRICT: type = PyExc_ValueError; break;
  case LMC_EIO: type = PyExc_OSError; break;
  case LMC_ENOMEM: type = PyExc_MemoryError; break;
  default: break;
  }
  PyErr_SetString(type, msg);
  return NULL;
}

/* --- Scene -------------------------------------------------------------------- */

typedef struct {
  PyObject_HEAD
  scene *s;       /* owned */
  PyObject *path; /* str: the file as given */
  int warnings;   /* warnings its load gave (--strict refuses to render it) */
  int busy;       /* renders and targets using it now (its camera must not change then) */
  camera loaded;  /* its camera as loaded, restored when no one uses it */
} lmcpy_scene;

static void lmcpy_scene_dealloc(lmcpy_scene *self) {
  scene_destroy(self->s);
  Py_XDECREF(self->path);
  Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *lmcpy_scene_repr(lmcpy_scene *self) {
  return PyUnicode_FromFormat("<lmc.Scene %R %dx%d>", self->path, self->s->cam.width,
                              self->s->cam.height);
}

static PyObject *lmcpy_scene_get_width(lmcpy_scene *self, void *closure) {
  (void)closure;
  return PyLong_FromLong(self->s->cam.width);
}
static PyObject *lmcpy_scene_get_height(lmcpy_scene *self, void *closure) {
  (void)closure;
  return PyLong_FromLong(self->s->cam.height);
}
static PyObject *lmcpy_scene_get_path(lmcpy_scene *self, void *closure) {
  (void)closure;
  Py_INCREF(self->path);
  return self->path;
}
static PyObject *lmcpy_scene_get_warnings(lmcpy_scene *self, void *closure) {
  (void)closure;
  return PyLong_FromLong(self->warnings);
}
static PyObject *lmcpy_scene_get_lights(lmcpy_scene *self, void *closure) {
  (void)closure;
  return PyLong_FromLong(self->s->n_lights);
}

static PyGetSetDef lmcpy_scene_getset[] = {
    {"path", (getter)lmcpy_scene_get_path, NULL, "the scene file as given to lmc.load", NULL},
    {"width", (getter)lmcpy_scene_get_width, NULL, "film width in pixels", NULL},
    {"height", (getter)lmcpy_scene_get_height, NULL, "film height in pixels", NULL},
    {"lights", (getter)lmcpy_scene_get_lights, NULL, "number of emitters", NULL},
    {"warnings", (getter)lmcpy_scene_get_warnings, NULL,
     "warnings its load gave (render(strict=True) refuses a scene with any)", NULL},
    {NULL, NULL, NULL, NULL, NULL}};

static PyTypeObject lmcpy_scene_type = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "lmc.Scene",
    .tp_basicsize = sizeof(lmcpy_scene),
    .tp_dealloc = (destructor)lmcpy_scene_dealloc,
    .tp_repr = (reprfunc)lmcpy_scene_repr,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "A scene loaded by lmc.load (immutable; shared by renders and targets).",
    .tp_getset = lmcpy_scene_getset,
};

/* A flag's value as the command line's text: str as is, bool on/off,
 * int and float in full precision, a pair "a,b". 0 and an exception when
 * it is none of these. */
static int lmcpy_value_text(const char *flag, PyObject *v, char *out, size_t n) {
  if (PyUnicode_Check(v)) {
    const char *s = PyUnicode_AsUTF8(v);
    if (!s) return 0;
    snprintf(out, n, "%s", s);
  } else if (PyBool_Check(v)) {
    snprintf(out, n, "%s", v == Py_True ? "on" : "off");
  } else if (PyLong_Check(v)) {
    long long x = PyLong_AsLongLong(v);
    if (x == -1 && PyErr_Occurred()) {
      PyErr_Clear();
      PyErr_Format(PyExc_ValueError, "flag --%s: %R is out of range", flag, v);
      return 0;
    }
    snprintf(out, n, "%lld", x);
  } else if (PyFloat_Check(v)) {
    snprintf(out, n, "%.17g", PyFloat_AsDouble(v));
  } else if (PyTuple_Check(v) && PyTuple_GET_SIZE(v) == 2) {
    char a[64], b[64];
    if (!lmcpy_value_text(flag, PyTuple_GET_ITEM(v, 0), a, sizeof a) ||
        !lmcpy_value_text(flag, PyTuple_GET_ITEM(v, 1), b, sizeof b))
      return 0;
    snprintf(out, n, "%s,%s", a, b);
  } else {
    PyErr_Format(PyExc_ValueError, "flag --%s: %R is not a str, number, bool or pair", flag, v);
    return 0;
  }
  return 1;
}

/* A keyword's name as the command line's flag: dashes for underscores. */
static void lmcpy_flag_name(const char *kw, char *out, size_t n) {
  snprintf(out, n, "%s", kw);
  for (char *p = out; *p; p++)
    if (*p == '_') *p = '-';
}

static PyObject *lmcpy_load(PyObject *mod, PyObject *args, PyObject *kwargs) {
  (void)mod;
  PyObject *path_obj = NULL;
  if (!PyArg_ParseTuple(args, "O&:load", PyUnicode_FSConverter, &path_obj)) return NULL;
  const char *path = PyBytes_AS_STRING(path_obj);
  scene_load_options lopts = {SPECTRUM_INTERP_LINEAR};
  Py_ssize_t nkw = kwargs ? PyDict_Size(kwargs) : 0;
  char **defines = calloc((size_t)nkw + 1, sizeof *defines);
  int n_defines = 0;
  PyObject *key, *value;
  Py_ssize_t pos = 0;
  if (!defines) goto nomem;
  while (kwargs && PyDict_Next(kwargs, &pos, &key, &value)) {
    const char *name = PyUnicode_AsUTF8(key);
    if (!name) goto fail;
    if (!strcmp(name, "spectra")) {
      /* --spectra: how sampled spectra are read (a load option, not a <default>). */
      const char *v = PyUnicode_Check(value) ? PyUnicode_AsUTF8(value) : NULL;
      if (v && !strcmp(v, "linear")) lopts.spectra = SPECTRUM_INTERP_LINEAR;
      else if (v && !strcmp(v, "mitsuba-0.6.0")) lopts.spectra = SPECTRUM_INTERP_MITSUBA_060;
      else {
        PyErr_Format(PyExc_ValueError,
                     "flag --spectra: unknown value %R (linear or mitsuba-0.6.0)", value);
        goto fail;
      }
      continue;
    }
    char text[1024];
    if (!lmcpy_value_text(name, value, text, sizeof text)) goto fail;
    size_t len = strlen(name) + strlen(text) + 2;
    if (!(defines[n_defines] = malloc(len))) goto nomem;
    snprintf(defines[n_defines++], len, "%s=%s", name, text);
  }
  lmc_error err;
  lmc_error_clear(&err);
  scene *s = NULL;
  int warned = lmc_warning_count();
  lmc_status st;
  Py_BEGIN_ALLOW_THREADS
  st = scene_load_xml_opts(path, (const char *const *)defines, n_defines, &lopts, &s, &err);
  Py_END_ALLOW_THREADS
  for (int i = 0; i < n_defines; i++) free(defines[i]);
  free(defines);
  if (st) {
    char msg[2048];
    lmc_error_format(&err, msg, sizeof msg);
    /* A file that is not there: FileNotFoundError (an OSError) naming it. */
    if (st == LMC_EIO) PyErr_SetString(PyExc_FileNotFoundError, msg);
    else PyErr_SetString(PyExc_ValueError, msg);
    Py_DECREF(path_obj);
    return NULL;
  }
  lmcpy_scene *self = PyObject_New(lmcpy_scene, &lmcpy_scene_type);
  if (!self) {
    scene_destroy(s);
    Py_DECREF(path_obj);
    return NULL;
  }
  self->s = s;
  self->warnings = lmc_warning_count() - warned;
  self->busy = 0;
  self->loaded = s->cam;
  self->path = PyUnicode_DecodeFSDefault(path);
  Py_DECREF(path_obj);
  if (!self->path) {
    Py_DECREF(self);
    return NULL;
  }
  return (PyObject *)self;
nomem:
  PyErr_NoMemory();
fail:
  for (int i = 0; i < n_defines; i++) free(defines[i]);
  free(defines);
  Py_DECREF(path_obj);
  return NULL;
}

/* --- flags: keywords through the option tables ----------------------------- */

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

/* Reads kwargs (may be NULL) into *F, skipping the names in `skip`
 * (NULL-terminated: the caller's own keywords). 0 and ValueError naming
 * the flag on an unknown flag or a bad value. */
static int lmcpy_parse_flags(PyObject *kwargs, const char *const *skip, lmcpy_flags *F) {
  memset(F, 0, sizeof *F);
  F->cli = render_settings_default();
  F->cli.set = 0;
  F->cli.quiet = 1;
  const lmc_opt_table *tables[LMCPY_MAX_TABLES];
  tables[0] = &lmc_render_options;
  int n_tables = 1 + mcmc_option_tables(tables + 1, LMCPY_MAX_TABLES - 1);
  PyObject *key, *value;
  Py_ssize_t pos = 0;
  while (kwargs && PyDict_Next(kwargs, &pos, &key, &value)) {
    const char *kw = PyUnicode_AsUTF8(key);
    if (!kw) return 0;
    int skipped = 0;
    for (int i = 0; skip && skip[i]; i++) skipped |= !strcmp(kw, skip[i]);
    if (skipped || value == Py_None) continue; /* (None: not given) */
    char name[64];
    lmcpy_flag_name(kw, name, sizeof name);
    if (!strcmp(name, "quiet")) {
      int q = PyObject_IsTrue(value);
      if (q < 0) return 0;
      F->cli.quiet = q;
      continue;
    }
    if (!strcmp(name, "strict")) {
      int q = PyObject_IsTrue(value);
      if (q < 0) return 0;
      F->cli.strict = q;
      continue;
    }
    char text[LMC_ADDRESS_MAX];
    if (!lmcpy_value_text(name, value, text, sizeof text)) return 0;
    if (!strcmp(name, "integrator")) {
      if (!lmc_integrator_known(text)) {
        const char *names[16];
        int n = mcmc_integrator_names(names, 16);
        char valid[512] = "pt, bdpt, direct";
        for (int i = 0; i < n; i++)
          snprintf(valid + strlen(valid), sizeof valid - strlen(valid), ", %s", names[i]);
        PyErr_Format(PyExc_ValueError, "flag --integrator: unknown integrator '%s' (valid: %s)",
                     text, valid);
        return 0;
      }
      snprintf(F->cli.integrator, sizeof F->cli.integrator, "%.*s",
               (int)sizeof F->cli.integrator - 1, text); /* (a known name: short) */
      F->cli.set |= SET_INTEGRATOR;
      continue;
    }
    if (!strcmp(name, "resolution")) {
      char tail;
      int w = 0, h = 0;
      if (PyTuple_Check(value) && PyTuple_GET_SIZE(value) == 2) {
        char a[64], b[64];
        if (!lmcpy_value_text(name, PyTuple_GET_ITEM(value, 0), a, sizeof a) ||
            !lmcpy_value_text(name, PyTuple_GET_ITEM(value, 1), b, sizeof b))
          return 0;
        snprintf(text, sizeof text, "%sx%s", a, b);
      }
      if (sscanf(text, "%dx%d%c", &w, &h, &tail) != 2 || w <= 0 || h <= 0 || w > 65536 ||
          h > 65536) {
        PyErr_Format(PyExc_ValueError,
                     "flag --resolution: '%s' is not WIDTHxHEIGHT (e.g. 320x240 or (320, 240))",
                     text);
        return 0;
      }
      F->res_w = w, F->res_h = h;
      continue;
    }
    /* What only the command line does: its files and its viewer. */
    if (!strcmp(name, "output") || !strcmp(name, "exposure") || !strcmp(name, "reference") ||
        !strcmp(name, "snapshot") || !strcmp(name, "display-server") ||
        !strcmp(name, "spectra")) {
      const char *instead = !strcmp(name, "output")     ? "r.save(path)"
                            : !strcmp(name, "exposure") ? "r.save(path.png, exposure=...)"
                            : !strcmp(name, "reference") ? "lmc.compare(r.image, lmc.read(ref))"
                            : !strcmp(name, "spectra")   ? "lmc.load(path, spectra=...)"
                                                          : "lmc render";
      PyErr_Format(PyExc_ValueError, "flag --%s is not a flag of lmc.render: use %s", name,
                   instead);
      return 0;
    }
    /* A flag of the tables, checked as the command line checks it. */
    const lmc_opt_table *ot = NULL;
    const lmc_opt *o = lmc_opt_find(tables, n_tables, name, &ot);
    if (!o) {
      PyErr_Format(PyExc_ValueError, "unknown flag '%s' (--%s; see lmc render --help)", kw, name);
      return 0;
    }
    if (F->n_given == LMCPY_MAX_FLAGS) {
      PyErr_SetString(PyExc_ValueError, "too many flags");
      return 0;
    }
    char msg[512];
    if (!lmc_opt_set(ot, o, text, &F->cli, msg, sizeof msg)) {
      PyErr_SetString(PyExc_ValueError, msg);
      return 0;
    }
    snprintf(F->text[F->n_given], sizeof F->text[0], "%s", text);
    F->given[F->n_given] = (lmc_given){ot, o, F->text[F->n_given]};
    F->n_given++;
  }
  return 1;
}

/* The settings of a render of sc with the flags F, as lmc render makes
 * them; 0 and an exception on failure. */
static int lmcpy_settings(lmcpy_scene *sc, const lmcpy_flags *F, render_settings *OUT) {
  lmc_error err;
  lmc_error_clear(&err);
  const char *path = PyUnicode_AsUTF8(sc->path);
  if (!path) return 0;
  if (lmc_render_settings(sc->s, path, &F->cli, F->given, F->n_given, OUT, &err)) {
    lmcpy_raise(&err);
    return 0;
  }
  return 1;
}

/* Takes sc into use (sc->busy) at F's resolution: its camera is set to
 * it, unless renders or targets using it now have it at another (0 and
 * RuntimeError). lmcpy_release gives it back. */
static int lmcpy_resolution(lmcpy_scene *sc, const lmcpy_flags *F) {
  if (F->res_w <= 0 || (F->res_w == sc->s->cam.width && F->res_h == sc->s->cam.height))
    return 1;
  if (sc->busy) {
    PyErr_SetString(PyExc_RuntimeError,
                    "flag --resolution: the scene is in use at another resolution (by a render "
                    "in another thread or a target); load it again for this one");
    return 0;
  }
  camera_set_resolution(&sc->s->cam, F->res_w, F->res_h);
  return 1;
}

/* Marks sc in use (after lmcpy_resolution). */
static void lmcpy_acquire(lmcpy_scene *sc) { sc->busy++; }

/* Gives sc back: its camera as loaded once no one uses it. */
static void lmcpy_release(lmcpy_scene *sc) {
  if (--sc->busy == 0) sc->s->cam = sc->loaded;
}

/* --- Result -------------------------------------------------------------------- */

typedef struct {
  PyObject_HEAD
  lmc_image img;   /* owned: the developed film, RGB */
  lmc_image eimg;  /* owned: each pixel's standard error (--error on), else empty */
  PyObject *image; /* float32 (H, W, 3) over img's pixels */
  PyObject *error; /* the same over eimg's, or None */
  PyObject *stats; /* dict */
} lmcpy_result;

static void lmcpy_result_dealloc(lmcpy_result *self) {
  Py_XDECREF(self->image);
  Py_XDECREF(self->error);
  Py_XDECREF(self->stats);
  image_free(&self->img);
  image_free(&self->eimg);
  Py_TYPE(self)->tp_free((PyObject *)self);
}

/* r.save(path, exposure=0): path ending in .png: the sRGB preview of
 * lmc render (radiance times 2^exposure, or exposure="auto"); else the
 * EXR of lmc render (with the layer "error" under --error on). What is
 * written is r.image (and r.error) as they are now. */
static PyObject *lmcpy_result_save(lmcpy_result *self, PyObject *args, PyObject *kwargs) {
  static char *kwlist[] = {"path", "exposure", NULL};
  PyObject *path_obj = NULL, *exposure = NULL;
  if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O&|O:save", kwlist, PyUnicode_FSConverter,
                                   &path_obj, &exposure))
    return NULL;
  const char *path = PyBytes_AS_STRING(path_obj);
  size_t len = strlen(path);
  int png = len > 4 && strcasecmp(path + len - 4, ".png") == 0;
  lmc_exposure e = {0, 0.0};
  if (exposure && exposure != Py_None) {
    if (PyUnicode_Check(exposure) && !strcmp(PyUnicode_AsUTF8(exposure), "auto")) {
      e.is_auto = 1;
    } else {
      double stops = PyFloat_AsDouble(exposure);
      if ((stops == -1.0 && PyErr_Occurred()) || !isfinite(stops) || stops < -64.0 ||
          stops > 64.0) {
        PyErr_Clear();
        PyErr_Format(PyExc_ValueError,
                     "flag --exposure: %R is neither a number of stops in [-64, 64] nor 'auto'",
                     exposure);
        Py_DECREF(path_obj);
        return NULL;
      }
      e.stops = stops;
    }
  }
  lmc_error err;
  lmc_error_clear(&err);
  lmc_status st;
  Py_BEGIN_ALLOW_THREADS
  if (png) st = image_write_png(path, &self->img, lmc_exposure_scale(&e, &self->img), &err);
  else if (self->eimg.data) st = image_write_exr_layer(path, &self->img, "error", &self->eimg, &err);
  else st = image_write_exr(path, &self->img, &err);
  Py_END_ALLOW_THREADS
  Py_DECREF(path_obj);
  if (st) return lmcpy_raise(&err);
  Py_RETURN_NONE;
}

static PyMethodDef lmcpy_result_methods[] = {
    {"save", (PyCFunction)(void (*)(void))lmcpy_result_save, METH_VARARGS | METH_KEYWORDS,
     "save(path, exposure=0): the EXR lmc render writes (path *.exr), or its sRGB preview "
     "(path *.png; exposure in stops or 'auto')"},
    {NULL, NULL, 0, NULL}};

static PyObject *lmcpy_result_get_image(lmcpy_result *self, void *closure) {
  (void)closure;
  Py_INCREF(self->image);
  return self->image;
}
static PyObject *lmcpy_result_get_error(lmcpy_result *self, void *closure) {
  (void)closure;
  Py_INCREF(self->error);
  return self->error;
}
static PyObject *lmcpy_result_get_stats(lmcpy_result *self, void *closure) {
  (void)closure;
  Py_INCREF(self->stats);
  return self->stats;
}

static PyGetSetDef lmcpy_result_getset[] = {
    {"image", (getter)lmcpy_result_get_image, NULL,
     "the image: float32 array (height, width, 3), linear RGB (what the EXR holds)", NULL},
    {"error", (getter)lmcpy_result_get_error, NULL,
     "each pixel's standard error under error='on' (float32 (height, width, 3)), else None",
     NULL},
    {"stats", (getter)lmcpy_result_get_stats, NULL, "the render's figures (a dict)", NULL},
    {NULL, NULL, NULL, NULL, NULL}};

static PyTypeObject lmcpy_result_type = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "lmc.Result",
    .tp_basicsize = sizeof(lmcpy_result),
    .tp_dealloc = (destructor)lmcpy_result_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "What lmc.render returns: image, error, stats and save().",
    .tp_methods = lmcpy_result_methods,
    .tp_getset = lmcpy_result_getset,
};

/* An array (H, W, 3) of float32 over img's pixels, kept alive by owner. */
static PyObject *lmcpy_image_view(const lmc_image *img, PyObject *owner) {
  npy_intp dims[3] = {img->height, img->width, img->channels};
  PyObject *a = PyArray_SimpleNewFromData(3, dims, NPY_FLOAT32, img->data);
  if (!a) return NULL;
  Py_INCREF(owner);
  if (PyArray_SetBaseObject((PyArrayObject *)a, owner) < 0) {
    Py_DECREF(a);
    return NULL;
  }
  return a;
}

/* An array (H, W, 3) of float32, a copy of img's pixels. */
static PyObject *lmcpy_image_copy(const lmc_image *img) {
  npy_intp dims[3] = {img->height, img->width, img->channels};
  PyObject *a = PyArray_SimpleNew(3, dims, NPY_FLOAT32);
  if (!a) return NULL;
  memcpy(PyArray_DATA((PyArrayObject *)a), img->data,
         (size_t)img->width * (size_t)img->height * (size_t)img->channels * sizeof(float));
  return a;
}

/* Sets d[key] = v (a new reference, stolen); 0 on failure. */
static int lmcpy_dict_set(PyObject *d, const char *key, PyObject *v) {
  if (!v) return 0;
  int r = PyDict_SetItemString(d, key, v);
  Py_DECREF(v);
  return r == 0;
}

/* The render's figures as lmc render prints them in its summary line. */
static PyObject *lmcpy_stats(const render_settings *rs, const film *f, const render_stats *st) {
  PyObject *d = PyDict_New();
  if (!d) return NULL;
  int mcmc = mcmc_is_integrator(rs->integrator);
  int ok = lmcpy_dict_set(d, "integrator", PyUnicode_FromString(rs->integrator)) &&
           lmcpy_dict_set(d, "width", PyLong_FromLong(f->width)) &&
           lmcpy_dict_set(d, "height", PyLong_FromLong(f->height)) &&
           lmcpy_dict_set(d, "seconds", PyFloat_FromDouble(st->seconds)) &&
           lmcpy_dict_set(d, "rays", PyLong_FromLongLong(st->rays)) &&
           lmcpy_dict_set(d, "spp", PyLong_FromLongLong(st->passes)) &&
           lmcpy_dict_set(d, mcmc ? "mutations" : "samples", PyLong_FromLongLong(st->samples)) &&
           lmcpy_dict_set(d, "nan_samples", PyLong_FromLongLong(st->nan_samples)) &&
           lmcpy_dict_set(d, "interrupted", PyBool_FromLong(st->interrupted)) &&
           lmcpy_dict_set(d, "timed_out", PyBool_FromLong(st->timed_out));
  if (ok && mcmc)
    ok = lmcpy_dict_set(d, "mutations_per_second",
                        PyFloat_FromDouble((double)st->samples / fmax(st->seconds, 1e-9))) &&
         lmcpy_dict_set(d, "b", PyFloat_FromDouble(st->mcmc_b)) &&
         lmcpy_dict_set(d, "b_se", PyFloat_FromDouble(st->mcmc_b_se)) &&
         lmcpy_dict_set(d, "b_bootstrap", PyFloat_FromDouble(st->mcmc_b_boot)) &&
         lmcpy_dict_set(d, "b_bootstrap_se", PyFloat_FromDouble(st->mcmc_b_boot_se)) &&
         lmcpy_dict_set(d, "bootstrap_paths", PyLong_FromLongLong(st->mcmc_boot_paths));
  if (!ok) {
    Py_DECREF(d);
    return NULL;
  }
  return d;
}

/* Ctrl-C while renders run without the GIL: the render stops
 * (render_request_stop) and Python learns of it afterwards. The handler
 * is lmc's from the first render that starts to the last that ends. */
static int lmcpy_renders_running;
static struct sigaction lmcpy_old_sigint;

static void lmcpy_on_sigint(int sig) { render_request_stop(sig); }

static void lmcpy_catch_sigint(void) {
  if (lmcpy_renders_running++ > 0) return;
  render_reset_stop();
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = lmcpy_on_sigint;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, &lmcpy_old_sigint);
}

/* 1 when a Ctrl-C stopped the renders. */
static int lmcpy_release_sigint(void) {
  if (--lmcpy_renders_running > 0) return render_stop_signal() == SIGINT;
  sigaction(SIGINT, &lmcpy_old_sigint, NULL);
  int hit = render_stop_signal() == SIGINT;
  if (hit) PyErr_SetInterrupt(); /* Python's own handling: KeyboardInterrupt in the main thread */
  render_reset_stop();
  return hit;
}

static PyObject *lmcpy_render(PyObject *mod, PyObject *args, PyObject *kwargs) {
  (void)mod;
  lmcpy_scene *sc = NULL;
  if (!PyArg_ParseTuple(args, "O!:render", &lmcpy_scene_type, &sc)) return NULL;
  lmcpy_flags *F = malloc(sizeof *F);
  if (!F) return PyErr_NoMemory();
  render_settings rs;
  if (!lmcpy_parse_flags(kwargs, NULL, F) || !lmcpy_settings(sc, F, &rs)) {
    free(F);
    return NULL;
  }
  /* --strict: a scene that loaded with warnings is not rendered. */
  if (rs.strict && sc->warnings > 0) {
    PyErr_Format(PyExc_ValueError, "--strict: %S loaded with %d warning%s: not rendering",
                 sc->path, sc->warnings, sc->warnings == 1 ? "" : "s");
    free(F);
    return NULL;
  }
  if (!lmcpy_resolution(sc, F)) {
    free(F);
    return NULL;
  }
  free(F);

  /* The render, without the GIL. */
  film f;
  render_stats st;
  lmc_error err;
  lmc_error_clear(&err);
  lmc_status rst;
  lmcpy_acquire(sc);
  lmcpy_catch_sigint();
  Py_BEGIN_ALLOW_THREADS
  rst = mcmc_is_integrator(rs.integrator) ? mcmc_render_run(sc->s, &rs, &f, &st, &err)
                                           : render_run(sc->s, &rs, &f, &st, &err);
  Py_END_ALLOW_THREADS
  int interrupted = lmcpy_release_sigint();
  lmcpy_release(sc);
  if (rst) return lmcpy_raise(&err);
  if (interrupted && PyErr_CheckSignals() < 0) {
    film_free(&f);
    return NULL;
  }

  /* The image as lmc render writes it. */
  lmcpy_result *r = PyObject_New(lmcpy_result, &lmcpy_result_type);
  if (!r) {
    film_free(&f);
    return NULL;
  }
  memset(&r->img, 0, sizeof r->img);
  memset(&r->eimg, 0, sizeof r->eimg);
  r->image = r->error = r->stats = NULL;
  if (film_develop(&f, &r->img, &err) ||
      (film_has_error(&f) && image_init(&r->eimg, f.width, f.height, 3, &err))) {
    film_free(&f);
    Py_DECREF(r);
    return lmcpy_raise(&err);
  }
  if (r->eimg.data) film_error_develop_to(&f, r->eimg.data);
  r->stats = lmcpy_stats(&rs, &f, &st);
  film_free(&f);
  r->image = lmcpy_image_view(&r->img, (PyObject *)r);
  if (r->eimg.data) {
    r->error = lmcpy_image_view(&r->eimg, (PyObject *)r);
  } else {
    r->error = Py_None;
    Py_INCREF(Py_None);
  }
  if (!r->stats || !r->image || !r->error) {
    Py_DECREF(r);
    return NULL;
  }
  return (PyObject *)r;
}

/* --- images: read and compare -------------------------------------------------- */

/* Reads path as lmc compare does (any of PNG, JPEG, EXR by content; RGB). */
static int lmcpy_read_image(const char *path, lmc_image *OUT) {
  lmc_error err;
  lmc_error_clear(&err);
  lmc_status st;
  Py_BEGIN_ALLOW_THREADS
  st = image_read(path, 0, OUT, &err);
  if (!st) st = image_to_rgb(OUT, &err);
  Py_END_ALLOW_THREADS
  if (st) {
    image_free(OUT);
    char msg[2048];
    lmc_error_format(&err, msg, sizeof msg);
    PyErr_SetString(st == LMC_EIO ? PyExc_FileNotFoundError : PyExc_ValueError, msg);
    return 0;
  }
  return 1;
}

static PyObject *lmcpy_read(PyObject *mod, PyObject *args, PyObject *kwargs) {
  (void)mod;
  static char *kwlist[] = {"path", "layer", NULL};
  PyObject *path_obj = NULL;
  const char *layer = NULL;
  if (!PyArg_ParseTupleAndKeywords(args, kwargs, "O&|z:read", kwlist, PyUnicode_FSConverter,
                                   &path_obj, &layer))
    return NULL;
  lmc_image img = {0};
  int ok;
  if (layer) {
    lmc_error err;
    lmc_error_clear(&err);
    lmc_status st = image_read_exr_layer(PyBytes_AS_STRING(path_obj), layer, &img, &err);
    if (!st) st = image_to_rgb(&img, &err);
    ok = !st;
    if (st) {
      image_free(&img);
      lmcpy_raise(&err);
    }
  } else {
    ok = lmcpy_read_image(PyBytes_AS_STRING(path_obj), &img);
  }
  Py_DECREF(path_obj);
  if (!ok) return NULL;
  PyObject *a = lmcpy_image_copy(&img);
  image_free(&img);
  return a;
}

/* An image argument of compare: a path (read as lmc compare reads it)
 * or an array of shape (H, W, 3), as float32. OUT borrows an array's
 * data (*OUT_arr holds it) or owns a file's. */
static int lmcpy_image_arg(PyObject *o, const char *which, lmc_image *OUT, PyObject **OUT_arr) {
  *OUT_arr = NULL;
  memset(OUT, 0, sizeof *OUT);
  if (PyUnicode_Check(o) || PyBytes_Check(o)) {
    PyObject *p = NULL;
    if (!PyUnicode_FSConverter(o, &p)) return 0;
    int ok = lmcpy_read_image(PyBytes_AS_STRING(p), OUT);
    Py_DECREF(p);
    return ok;
  }
  PyObject *a = PyArray_FROM_OTF(o, NPY_FLOAT32, NPY_ARRAY_IN_ARRAY | NPY_ARRAY_FORCECAST);
  if (!a) return 0;
  PyArrayObject *arr = (PyArrayObject *)a;
  if (PyArray_NDIM(arr) != 3 || PyArray_DIM(arr, 2) != 3 || PyArray_DIM(arr, 0) < 1 ||
      PyArray_DIM(arr, 1) < 1 || PyArray_DIM(arr, 0) > IMAGE_MAX_SIDE ||
      PyArray_DIM(arr, 1) > IMAGE_MAX_SIDE) {
    PyErr_Format(PyExc_ValueError, "%s: an image is an array of shape (height, width, 3)", which);
    Py_DECREF(a);
    return 0;
  }
  OUT->height = (int)PyArray_DIM(arr, 0);
  OUT->width = (int)PyArray_DIM(arr, 1);
  OUT->channels = 3;
  OUT->data = PyArray_DATA(arr);
  *OUT_arr = a;
  return 1;
}

static PyObject *lmcpy_compare(PyObject *mod, PyObject *args) {
  (void)mod;
  PyObject *ao, *bo;
  if (!PyArg_ParseTuple(args, "OO:compare", &ao, &bo)) return NULL;
  lmc_image img[2];
  PyObject *arr[2] = {NULL, NULL};
  PyObject *res = NULL;
  if (!lmcpy_image_arg(ao, "image", &img[0], &arr[0])) return NULL;
  if (!lmcpy_image_arg(bo, "reference", &img[1], &arr[1])) goto out0;
  if (img[0].width != img[1].width || img[0].height != img[1].height) {
    PyErr_Format(PyExc_ValueError, "the image is %dx%d but the reference is %dx%d", img[0].width,
                 img[0].height, img[1].width, img[1].height);
    goto out;
  }
  lmc_image_error ie;
  lmc_error err;
  lmc_error_clear(&err);
  if (image_error(&img[0], &img[1], &ie, &err)) {
    lmcpy_raise(&err);
    goto out;
  }
  res = Py_BuildValue("{s:d,s:d,s:d,s:d}", "mse", ie.mse, "relmse", ie.relmse, "relmse_trimmed",
                      ie.relmse_trimmed, "mean_ratio", ie.mean_ratio);
out:
  if (arr[1]) Py_DECREF(arr[1]);
  else image_free(&img[1]);
out0:
  if (arr[0]) Py_DECREF(arr[0]);
  else image_free(&img[0]);
  return res;
}

/* --- Target ---------------------------------------------------------------------- */

typedef struct {
  PyObject_HEAD
  lmcpy_scene *scene;   /* a reference */
  mc_space sp;          /* owned */
  int created;          /* sp was created (mc_space_free it) */
  const mc_target *T;   /* the family's target, in sp */
  int family, length;   /* its index, and its paths' length (0: every length) */
  void *scratch;        /* owned */
  mc_contrib *contribs; /* owned: n_labels entries */
  double *grad;         /* owned: dim entries */
} lmcpy_target;

static void lmcpy_target_dealloc(lmcpy_target *self) {
  if (self->scratch && self->T->scratch_destroy) self->T->scratch_destroy(self->scratch);
  if (self->created) mc_space_free(&self->sp);
  free(self->contribs);
  free(self->grad);
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

static PyTypeObject lmcpy_target_type; /* (below) */

static PyObject *lmcpy_make_target(PyObject *mod, PyObject *args, PyObject *kwargs) {
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
  self->scratch = NULL;
  self->contribs = NULL;
  self->grad = NULL;
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
  self->scratch = self->T->scratch_create ? self->T->scratch_create(self->T) : NULL;
  self->grad = malloc((size_t)self->T->dim * sizeof *self->grad);
  self->contribs = calloc((size_t)(self->T->n_labels > 0 ? self->T->n_labels : 1),
                          sizeof *self->contribs);
  if ((self->T->scratch_create && !self->scratch) || !self->grad || !self->contribs) {
    Py_DECREF(self);
    return PyErr_NoMemory();
  }
  return (PyObject *)self;
}

/* u as a C array of float64, shape (dim,) or (N, dim), every number in
 * [0, 1); *OUT_batch: 1 for (N, dim). NULL and ValueError otherwise. */
static PyArrayObject *lmcpy_states(lmcpy_target *self, PyObject *u, int *OUT_batch) {
  PyArrayObject *a =
      (PyArrayObject *)PyArray_FROM_OTF(u, NPY_FLOAT64, NPY_ARRAY_IN_ARRAY | NPY_ARRAY_FORCECAST);
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

/* f at one state (label -1: F(u), the sum over the labels, on a labelled
 * target); with grad (not NULL) also its gradient, NaN where the target
 * gives none. -1 when the evaluation fails. */
static int lmcpy_eval(lmcpy_target *self, const double *u, int label, double *OUT_f,
                      double *grad) {
  const mc_target *T = self->T;
  lmcpy_vec_smp smp = lmcpy_vec_at(T, u);
  mc_value v;
  memset(&v, 0, sizeof v);
  int ok = 0, r;
  if (T->n_labels > 0 && label < 0) {
    int n = T->eval_all(T, self->scratch, &smp.base, -1, self->contribs);
    if (n < 0) return -1;
    double F = 0.0;
    for (int i = 0; i < n; i++) F += self->contribs[i].v.f;
    *OUT_f = F;
    return 0;
  }
  if (T->n_labels > 0)
    r = T->eval_label(T, self->scratch, &smp.base, label, &v, grad ? self->grad : NULL,
                      grad ? &ok : NULL);
  else
    r = T->eval(T, self->scratch, &smp.base, &v, grad ? self->grad : NULL, grad ? &ok : NULL);
  if (r) return -1;
  *OUT_f = v.f;
  if (grad)
    for (int i = 0; i < T->dim; i++) grad[i] = ok ? self->grad[i] : NAN;
  return 0;
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
  if (!lmcpy_label(self, lo, &label)) return NULL;
  if (want_grad && self->T->n_labels > 0 && label < 0)
    return PyErr_Format(PyExc_ValueError,
                        "label: the gradient is a label's (t.grad(u, label=l), l in 0 .. %d): "
                        "the chains differentiate f(u, l), not the sum F(u)",
                        self->T->n_labels - 1);
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
  for (npy_intp i = 0; i < n; i++)
    if (lmcpy_eval(self, u + i * dim, label, &f[i], g ? g + i * dim : NULL)) {
      Py_DECREF(a);
      Py_DECREF(fo);
      Py_XDECREF(go);
      PyErr_SetString(PyExc_RuntimeError, "the target's evaluation failed (out of memory)");
      return NULL;
    }
  Py_DECREF(a);
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
  int n = self->T->eval_all(self->T, self->scratch, &smp.base, -1, self->contribs);
  Py_DECREF(a);
  if (n < 0) return PyErr_Format(PyExc_RuntimeError, "the target's evaluation failed");
  PyObject *d = PyDict_New();
  for (int i = 0; d && i < n; i++) {
    PyObject *k = PyLong_FromLong(self->contribs[i].label);
    PyObject *v = PyFloat_FromDouble(self->contribs[i].v.f);
    if (!k || !v || PyDict_SetItem(d, k, v) < 0) Py_CLEAR(d);
    Py_XDECREF(k);
    Py_XDECREF(v);
  }
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

static PyTypeObject lmcpy_target_type = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "lmc.Target",
    .tp_basicsize = sizeof(lmcpy_target),
    .tp_dealloc = (destructor)lmcpy_target_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "What the chains sample (lmc.target): dim, f(u), grad(u).",
    .tp_methods = lmcpy_target_methods,
    .tp_getset = lmcpy_target_getset,
};

/* --- the module ----------------------------------------------------------------- */

static PyMethodDef lmcpy_methods[] = {
    {"load", (PyCFunction)(void (*)(void))lmcpy_load, METH_VARARGS | METH_KEYWORDS,
     "load(path, spectra='linear', **params): a Mitsuba XML scene; params set its <default>s "
     "as lmc render's -D name=value"},
    {"render", (PyCFunction)(void (*)(void))lmcpy_render, METH_VARARGS | METH_KEYWORDS,
     "render(scene, **flags): renders as lmc render does (every flag by its name, dashes as "
     "underscores; quiet=True unless given); a Result"},
    {"read", (PyCFunction)(void (*)(void))lmcpy_read, METH_VARARGS | METH_KEYWORDS,
     "read(path, layer=None): an image file (EXR, PNG, JPEG) as float32 (height, width, 3)"},
    {"compare", (PyCFunction)lmcpy_compare, METH_VARARGS,
     "compare(image, reference): lmc compare's figures (mse, relmse, relmse_trimmed, "
     "mean_ratio); each an array (height, width, 3) or a file's path"},
    {"target", (PyCFunction)(void (*)(void))lmcpy_make_target, METH_VARARGS | METH_KEYWORDS,
     "target(scene, space='bdpt', length=None, **flags): the target the chains sample on a "
     "state space (bdpt, pt, mmlt with length=k)"},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef lmcpy_module = {
    PyModuleDef_HEAD_INIT, "lmc",
    "lmc, the renderer for Markov chain Monte Carlo light transport, from Python "
    "(docs/python.md).",
    -1, lmcpy_methods, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit_lmc(void);
PyMODINIT_FUNC PyInit_lmc(void) {
  import_array();
  if (PyType_Ready(&lmcpy_scene_type) < 0 || PyType_Ready(&lmcpy_result_type) < 0 ||
      PyType_Ready(&lmcpy_target_type) < 0)
    return NULL;
  PyObject *m = PyModule_Create(&lmcpy_module);
  if (!m) return NULL;
  Py_INCREF(&lmcpy_scene_type);
  Py_INCREF(&lmcpy_result_type);
  Py_INCREF(&lmcpy_target_type);
  if (PyModule_AddObject(m, "Scene", (PyObject *)&lmcpy_scene_type) < 0 ||
      PyModule_AddObject(m, "Result", (PyObject *)&lmcpy_result_type) < 0 ||
      PyModule_AddObject(m, "Target", (PyObject *)&lmcpy_target_type) < 0 ||
      PyModule_AddStringConstant(m, "__version__", LMC_VERSION) < 0) {
    Py_DECREF(m);
    return NULL;
  }
  return m;
}
