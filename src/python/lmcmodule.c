/*
 * lmcmodule.c: the Python module `lmc` (CPython's C API and NumPy's,
 * nothing else): lmc from Python, as docs/python.md describes it.
 *
 *   scene = lmc.load("scene.xml", **params)     params: the scene's <default>s (-D)
 *   r = lmc.render(scene, integrator="pt", spp=16, seed=1, threads=2, **flags)
 *   r.image, r.error, r.stats, r.save("out.exr")
 *   lmc.read("x.exr"), lmc.compare(a, b)
 *   t = lmc.target(scene, space="bdpt", **flags); t.dim, t.f(u), t.grad(u),
 *   t.hessian(u), t.value(u) (alias t.contribution), t.sample_bootstrap(n, seed)
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
 * and raises KeyboardInterrupt. render(progress=fn) hooks fn on the
 * drivers' snapshots (what --snapshot uses): fn(image so far, seconds)
 * with the GIL taken for the call only; an exception from fn stops the
 * render as a Ctrl-C does and propagates. Either exception carries the
 * image of the samples so far as e.lmc_result. A target evaluates a
 * batch of states without the GIL, under the target's own lock (calls on
 * one target take turns, targets run in parallel), a batch of
 * LMCPY_PARALLEL_BATCH states or more on OpenMP threads, each with a
 * scratch of its own; sample_bootstrap draws without the GIL, on OpenMP
 * threads of chains of its own.
 *
 * Ownership. A Scene owns its scene; a Result owns its pixels, which
 * r.image views (each access a new view, which keeps the Result alive;
 * the Result keeps none: no cycle); a Target owns its
 * state space and scratches and keeps its Scene alive.
 */
#include "lmcpy.h"

/* --- errors ----------------------------------------------------------------- */

/* Raises the Python exception for a failed lmc call: ValueError for bad
 * input (a value, a flag, a refused combination, --strict), OSError for
 * a file, MemoryError, else RuntimeError; the message as lmc formats it. */
PyObject *lmcpy_raise(const lmc_error *err) {
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

PyTypeObject lmcpy_scene_type = {
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


/* Reads kwargs (may be NULL) into *F, skipping the names in `skip`
 * (NULL-terminated: the caller's own keywords). 0 and ValueError naming
 * the flag on an unknown flag or a bad value. */
int lmcpy_parse_flags(PyObject *kwargs, const char *const *skip, lmcpy_flags *F) {
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
int lmcpy_settings(lmcpy_scene *sc, const lmcpy_flags *F, render_settings *OUT) {
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
int lmcpy_resolution(lmcpy_scene *sc, const lmcpy_flags *F) {
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
void lmcpy_acquire(lmcpy_scene *sc) { sc->busy++; }

/* Gives sc back: its camera as loaded once no one uses it. */
void lmcpy_release(lmcpy_scene *sc) {
  if (--sc->busy == 0) sc->s->cam = sc->loaded;
}

/* --- Result -------------------------------------------------------------------- */

typedef struct {
  PyObject_HEAD
  lmc_image img;   /* owned: the developed film, RGB */
  lmc_image eimg;  /* owned: each pixel's standard error (--error on), else empty */
  PyObject *stats; /* dict */
} lmcpy_result;

static void lmcpy_result_dealloc(lmcpy_result *self) {
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

static PyObject *lmcpy_image_view(const lmc_image *img, PyObject *owner);

/* r.image and r.error: a new view of the pixels at each access. (A view
 * kept in the Result would make a cycle, Result -> array -> Result, that
 * the collector cannot see: every Result would leak.) */
static PyObject *lmcpy_result_get_image(lmcpy_result *self, void *closure) {
  (void)closure;
  return lmcpy_image_view(&self->img, (PyObject *)self);
}
static PyObject *lmcpy_result_get_error(lmcpy_result *self, void *closure) {
  (void)closure;
  if (!self->eimg.data) Py_RETURN_NONE;
  return lmcpy_image_view(&self->eimg, (PyObject *)self);
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
PyObject *lmcpy_image_copy(const lmc_image *img) {
  npy_intp dims[3] = {img->height, img->width, img->channels};
  PyObject *a = PyArray_SimpleNew(3, dims, NPY_FLOAT32);
  if (!a) return NULL;
  memcpy(PyArray_DATA((PyArrayObject *)a), img->data,
         (size_t)img->width * (size_t)img->height * (size_t)img->channels * sizeof(float));
  return a;
}

/* Sets d[key] = v (a new reference, stolen); 0 on failure. */
int lmcpy_dict_set(PyObject *d, const char *key, PyObject *v) {
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

/* --- render ------------------------------------------------------------------- */

static PyObject *lmcpy_render(PyObject *mod, PyObject *args, PyObject *kwargs) {
  (void)mod;
  static const char *const own[] = {"progress", "progress_interval", NULL};
  lmcpy_scene *sc = NULL;
  if (!PyArg_ParseTuple(args, "O!:render", &lmcpy_scene_type, &sc)) return NULL;
  /* The module's own keywords: progress=callable, progress_interval=seconds. */
  lmcpy_progress prog;
  memset(&prog, 0, sizeof prog);
  double interval = 1.0;
  PyObject *o;
  if (kwargs && (o = PyDict_GetItemString(kwargs, "progress")) && o != Py_None) {
    if (!PyCallable_Check(o))
      return PyErr_Format(PyExc_TypeError,
                          "progress: %R is not callable (progress(image, seconds))", o);
    prog.fn = o;
  }
  if (kwargs && (o = PyDict_GetItemString(kwargs, "progress_interval")) && o != Py_None) {
    interval = PyFloat_AsDouble(o);
    if (interval == -1.0 && PyErr_Occurred()) PyErr_Clear();
    if (!(interval >= 1e-3 && interval <= 1e9))
      return PyErr_Format(PyExc_ValueError,
                          "progress_interval: %R is not a number of seconds in [0.001, 1e9]", o);
  }
  lmcpy_flags *F = malloc(sizeof *F);
  if (!F) return PyErr_NoMemory();
  render_settings rs;
  if (!lmcpy_parse_flags(kwargs, own, F) || !lmcpy_settings(sc, F, &rs)) {
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
  /* The progress callable on the drivers' snapshot hook (what lmc render's
   * --snapshot uses; the snapshots leave the image as it is). */
  if (prog.fn) {
    rs.snapshot = interval;
    rs.snapshot_fn = lmcpy_on_snapshot;
    rs.snapshot_ctx = &prog;
  }

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
  image_free(&prog.img);
  if (rst) {
    Py_XDECREF(prog.exc);
    return lmcpy_raise(&err);
  }

  /* The image as lmc render writes it (also of a render that a Ctrl-C or
   * the callable stopped: the samples it has). */
  lmcpy_result *r = PyObject_New(lmcpy_result, &lmcpy_result_type);
  if (!r) {
    film_free(&f);
    Py_XDECREF(prog.exc);
    return NULL;
  }
  memset(&r->img, 0, sizeof r->img);
  memset(&r->eimg, 0, sizeof r->eimg);
  r->stats = NULL;
  if (film_develop(&f, &r->img, &err) ||
      (film_has_error(&f) && image_init(&r->eimg, f.width, f.height, 3, &err))) {
    film_free(&f);
    Py_DECREF(r);
    Py_XDECREF(prog.exc);
    return lmcpy_raise(&err);
  }
  if (r->eimg.data) film_error_develop_to(&f, r->eimg.data);
  r->stats = lmcpy_stats(&rs, &f, &st);
  film_free(&f);
  if (!r->stats) {
    Py_DECREF(r);
    Py_XDECREF(prog.exc);
    return NULL;
  }

  /* What raises: the callable's exception, else a Ctrl-C's
   * KeyboardInterrupt, each with the image so far as e.lmc_result. */
  if (prog.exc) {
    lmcpy_restore_exception(prog.exc);
    lmcpy_attach_result((PyObject *)r);
    Py_DECREF(r);
    return NULL;
  }
  if (interrupted && PyErr_CheckSignals() < 0) {
    lmcpy_attach_result((PyObject *)r);
    Py_DECREF(r);
    return NULL;
  }
  /* The callable once more, with the final image and the render's seconds. */
  if (prog.fn && !lmcpy_progress_call(&prog, &r->img, st.seconds)) {
    lmcpy_restore_exception(prog.exc);
    lmcpy_attach_result((PyObject *)r);
    Py_DECREF(r);
    return NULL;
  }
  return (PyObject *)r;
}

/* --- the module ----------------------------------------------------------------- */

static PyMethodDef lmcpy_methods[] = {
    {"load", (PyCFunction)(void (*)(void))lmcpy_load, METH_VARARGS | METH_KEYWORDS,
     "load(path, spectra='linear', **params): a Mitsuba XML scene; params set its <default>s "
     "as lmc render's -D name=value"},
    {"render", (PyCFunction)(void (*)(void))lmcpy_render, METH_VARARGS | METH_KEYWORDS,
     "render(scene, progress=None, progress_interval=1.0, **flags): renders as lmc render does "
     "(every flag by its name, dashes as underscores; quiet=True unless given); a Result. "
     "progress(image, seconds) is called every progress_interval seconds with the image so far "
     "and once at the end; an exception from it stops the render and propagates (the image so "
     "far as e.lmc_result)"},
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
