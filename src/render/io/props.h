/*
 * props.h: the property sets between the XML parser and the scene builder
 * (private to src/render/io/scene_xml*.c).
 *
 * The first pass (scene_xml_parse.c) turns a Mitsuba XML document, with its
 * <include>s, <default>s and $name substitutions resolved, into a tree of
 * plain property sets: one `pset` per object element (scene, shape, bsdf,
 * texture, emitter, sensor, film, rfilter, integrator, dpt, or any unknown
 * element), holding its named properties in document order. Nested objects
 * and <ref>s are properties too (of kind PROP_OBJECT / PROP_REF; their name
 * is the `name` attribute, or empty). The second pass (scene_xml.c) reads
 * the sets and never sees XML.
 *
 * Every pset and prop remembers the file and line it came from, and a prop
 * is marked `used` when the builder consumes it, so anything left unused can
 * be reported as a warning naming file, line and element.
 *
 * Ownership: a pset owns its props and nested psets; file names are interned
 * in the pdoc and outlive all psets. pdoc_free frees everything.
 */
#ifndef LMC_RENDER_IO_PROPS_H
#define LMC_RENDER_IO_PROPS_H

#include <stddef.h>

#include "render/error.h"
#include "render/spectrum.h"
#include "render/transform.h"
#include "render/vec3.h"

typedef enum prop_kind {
  PROP_INT = 0,
  PROP_FLOAT,
  PROP_BOOL,
  PROP_STRING,
  PROP_RGB,       /* <rgb>, <srgb>, <spectrum>, <blackbody> (converted to linear RGB) */
  PROP_POINT,
  PROP_VECTOR,
  PROP_TRANSFORM,
  PROP_OBJECT,    /* a nested object element */
  PROP_REF        /* <ref id=...> */
} prop_kind;

struct pset;

typedef struct prop {
  prop_kind kind;
  char name[64];
  const char *file; /* interned in the pdoc */
  int line;
  int used;
  char tag[32];     /* the element's tag ("float", "rgb", "spectrum", ...) */
  long long i;      /* PROP_INT */
  double f;         /* PROP_FLOAT */
  int b;            /* PROP_BOOL */
  char *s;          /* PROP_STRING (owned) */
  rgb c;            /* PROP_RGB */
  vec3 v;           /* PROP_POINT, PROP_VECTOR */
  xform t;          /* PROP_TRANSFORM */
  struct pset *obj; /* PROP_OBJECT (owned) */
  char ref[128];    /* PROP_REF: the referenced id */
} prop;

typedef struct pset {
  char tag[32];     /* object element: "shape", "bsdf", ... */
  char type[64];    /* the plugin `type` attribute ("" when absent) */
  char id[128];     /* `id` attribute ("" when absent) */
  const char *file;
  int line;
  prop *props;
  int n_props, cap_props;
  /* builder bookkeeping (scene_xml.c) */
  int built;        /* 1 once instantiated */
  int building;     /* cycle guard */
  int index;        /* bsdf index, or image index of a bitmap texture */
} pset;

typedef struct pdoc {
  pset *root;       /* the <scene> */
  char **files;     /* interned file names */
  int n_files, cap_files;
} pdoc;

/* Parses `path` into doc (caller-owned, zeroed by the call). `defines` are
 * "name=value" strings that override <default>; sampled spectra are read
 * with `interp`. Errors carry file and line. */
lmc_status pdoc_parse(pdoc *doc, const char *path, const char *const *defines, int n_defines,
                      spectrum_interp interp, lmc_error *err);
void pdoc_free(pdoc *doc);
void pset_free(pset *p);

/* Name of a prop kind for messages ("float", "string", ...). */
const char *prop_kind_name(prop_kind k);

/* Value text (props.c). A strict number: the whole string (blanks around
 * allowed) must be a finite number; returns 1 and *out, or 0. */
int props_number(const char *s, double *out);
/* A strict integer, the same way. */
int props_integer(const char *s, long long *out);
/* s split at commas and/or blanks into at most max strict numbers: their
 * count, or -1 on a bad token or too many values. */
int props_list(const char *s, double *vals, int max);
/* "w1:v1, w2:v2, ..." into wl and val (room for max pairs): the count
 * (>= 2), or -1 with a description of the first problem in why (a token
 * that is not a pair of finite numbers, a negative wavelength, wavelengths
 * not strictly ascending, fewer than two pairs). */
int props_spectrum_pairs(const char *s, double *wl, double *val, int max, char *why,
                         size_t why_size);
/* A spectrum file (Mitsuba's .spd: "wavelength value" per line, blank and
 * '#' lines skipped, further columns ignored) into *OUT_wl, *OUT_val (malloc'ed, caller frees, room
 * for *OUT_n + 2 entries for the zero extension). Errors name the file and
 * line (LMC_EIO without a line when it cannot be opened). */
lmc_status props_spectrum_file(const char *path, double **OUT_wl, double **OUT_val, int *OUT_n,
                               lmc_error *err);

#endif
