/*
 * lmcpy_image.c: the module's lmc.read and lmc.compare (lmcmodule.c has
 * the module's overview): images as NumPy arrays, compared by the function
 * `lmc compare` calls.
 */
#define NO_IMPORT_ARRAY
#include "lmcpy.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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

PyObject *lmcpy_read(PyObject *mod, PyObject *args, PyObject *kwargs) {
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

PyObject *lmcpy_compare(PyObject *mod, PyObject *args) {
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

