/*
 * scene_xml_parse_internal.h: what the first pass of the scene loader
 * shares between its files (not API): the parser's state and its error,
 * attribute and value helpers. scene_xml_parse.c walks the XML;
 * scene_xml_values.c reads the values of its elements (colours and spectra,
 * points, elementary transforms).
 */
#ifndef LMC_RENDER_IO_SCENE_XML_PARSE_INTERNAL_H
#define LMC_RENDER_IO_SCENE_XML_PARSE_INTERNAL_H

#include <expat.h>

#include "render/io/props.h"
#include "render/spectrum.h"

#define PARSE_MAX_DEPTH 128
#define PARSE_MAX_ATTRS 32
#define PARSE_MAX_INCLUDE 16
#define PARSE_VALUE_MAX 8192

typedef enum frame_kind { FR_OBJECT = 0, FR_TRANSFORM, FR_ANIMATION, FR_LEAF, FR_SKIP } frame_kind;

typedef struct parse_frame {
  frame_kind kind;
  pset *obj;     /* FR_OBJECT: the object; FR_TRANSFORM, FR_ANIMATION: its owner */
  int prop;      /* FR_TRANSFORM, FR_ANIMATION: index of the transform prop in obj */
  int keyframes; /* FR_ANIMATION: the <transform>s seen so far */
} parse_frame;

typedef struct param {
  char *name, *value;
} param;

typedef struct parse_ctx {
  pdoc *doc;
  lmc_error *err;
  lmc_status status;
  spectrum_interp interp; /* how sampled spectra are read (scene_load_options) */
  param *params;
  int n_params, cap_params;
  parse_frame stack[PARSE_MAX_DEPTH];
  int depth;
  const char *file;   /* interned name of the file being read */
  XML_Parser parser;
  int include_depth;
  pset *include_parent; /* where the root <scene> of the current file maps to (NULL: new root) */
  /* substituted attributes of the current element */
  char *attr_name[PARSE_MAX_ATTRS];
  char *attr_value[PARSE_MAX_ATTRS];
  int n_attrs;
} parse_ctx;

/* The current line of the file being read (0 before parsing starts). */
int parse__line(parse_ctx *c);
/* Records the first error (at the current line) and stops the parser. */
void parse__fail(parse_ctx *c, lmc_status code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* The current element's attribute `name` (substituted), or NULL. */
const char *parse__attr(parse_ctx *c, const char *name);
/* An attribute that must be present (else an error naming it). */
const char *parse__need_attr(parse_ctx *c, const char *tag, const char *name);
/* Resolves `name` against the folder of the file being read. */
void parse__resolve(const char *base_file, const char *name, char *out, size_t size);

/* ---- Values (scene_xml_values.c). ------------------------------------------ */

/* A colour element (<rgb>, <srgb>, <spectrum>, <blackbody>) as linear sRGB;
 * 0 after an error. */
int parse__color(parse_ctx *c, const char *tag, rgb *out);
/* x, y, z attributes (each defaulting to def) or value="x y z"; 0 after an error. */
int parse__xyz(parse_ctx *c, const char *tag, double def, vec3 *out);
/* An attribute "x, y, z" as a point or vector; 0 after an error. */
int parse__vec_attr(parse_ctx *c, const char *tag, const char *name, vec3 *out);
/* One elementary transform inside <transform>, composed after the others. */
void parse__transform_op(parse_ctx *c, prop *xf, const char *tag);

#endif
