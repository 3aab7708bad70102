/*
 * props.c: the property tree of the scene loader (props.h): its memory,
 * the names of its kinds, and the strict reading of value text (numbers,
 * lists, sampled spectra) that the parser (scene_xml_parse.c) uses.
 */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "render/io/props.h"

const char *prop_kind_name(prop_kind k) {
  switch (k) {
    case PROP_INT: return "integer";
    case PROP_FLOAT: return "float";
    case PROP_BOOL: return "boolean";
    case PROP_STRING: return "string";
    case PROP_RGB: return "color";
    case PROP_POINT: return "point";
    case PROP_VECTOR: return "vector";
    case PROP_TRANSFORM: return "transform";
    case PROP_OBJECT: return "object";
    case PROP_REF: return "reference";
  }
  return "?";
}

void pset_free(pset *p) {
  if (!p) return;
  for (int i = 0; i < p->n_props; i++) {
    free(p->props[i].s);
    pset_free(p->props[i].obj);
  }
  free(p->props);
  free(p);
}

void pdoc_free(pdoc *doc) {
  if (!doc) return;
  pset_free(doc->root);
  for (int i = 0; i < doc->n_files; i++) free(doc->files[i]);
  free(doc->files);
  memset(doc, 0, sizeof *doc);
}

/* Strict number: the whole string (blanks around allowed) must be a finite
 * number. */
int props_number(const char *s, double *out) {
  while (isspace((unsigned char)*s)) s++;
  if (!*s) return 0;
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (end == s) return 0;
  while (isspace((unsigned char)*end)) end++;
  if (*end || !isfinite(v)) return 0;
  *out = v;
  return 1;
}

int props_integer(const char *s, long long *out) {
  while (isspace((unsigned char)*s)) s++;
  if (!*s) return 0;
  char *end;
  errno = 0;
  long long v = strtoll(s, &end, 10);
  if (end == s || errno == ERANGE) return 0;
  while (isspace((unsigned char)*end)) end++;
  if (*end) return 0;
  *out = v;
  return 1;
}

/* Splits s at commas and/or blanks into at most `max` strict numbers.
 * Returns the count, or -1 on a bad token or too many values. */
/* The next token of a list separated by commas and/or blanks, from *p into
 * tok (room for size): 1, or 0 at the end of the string, or -1 when the
 * token does not fit. */
static int props__token(const char **p, char *tok, size_t size) {
  const char *a = *p;
  while (*a && (isspace((unsigned char)*a) || *a == ',')) a++;
  if (!*a) return 0;
  const char *q = a;
  while (*q && !isspace((unsigned char)*q) && *q != ',') q++;
  size_t len = (size_t)(q - a);
  if (len >= size) return -1;
  memcpy(tok, a, len);
  tok[len] = '\0';
  *p = q;
  return 1;
}

int props_list(const char *s, double *vals, int max) {
  int n = 0, r;
  char tok[128];
  while ((r = props__token(&s, tok, sizeof tok)) > 0) {
    if (n == max || !props_number(tok, &vals[n])) return -1;
    n++;
  }
  return r < 0 ? -1 : n;
}

/* Piecewise-linear interpolation of a sampled spectrum (wavelengths sorted
 * ascending), clamped to the end values outside the sampled range. */
static double props__spectrum_at(const double *wl, const double *val, int n, double x) {
  if (x <= wl[0]) return val[0];
  if (x >= wl[n - 1]) return val[n - 1];
  for (int i = 0; i + 1 < n; i++) {
    if (x <= wl[i + 1]) {
      double span = wl[i + 1] - wl[i];
      double t = span > 0.0 ? (x - wl[i]) / span : 0.0;
      return val[i] + t * (val[i + 1] - val[i]);
    }
  }
  return val[n - 1];
}

/* "w1:v1, w2:v2, ..." -> RGB by band averages (B 400-500, G 500-600,
 * R 600-700 nm), each the mean of 20 evenly spaced samples of the
 * interpolated spectrum. Returns 0 on a syntax error. */
int props_spectrum_pairs(const char *s, rgb *out) {
  enum { MAXP = 512 };
  double wl[MAXP], val[MAXP];
  int n = 0, r;
  char tok[128];
  while ((r = props__token(&s, tok, sizeof tok)) > 0) {
    if (n == MAXP) return 0;
    char *colon = strchr(tok, ':');
    if (!colon) return 0;
    *colon = '\0';
    if (!props_number(tok, &wl[n]) || !props_number(colon + 1, &val[n])) return 0;
    if (n > 0 && !(wl[n] > wl[n - 1])) return 0;
    n++;
  }
  if (r < 0) return 0;
  if (n == 0) return 0;
  double band[3];
  for (int b = 0; b < 3; b++) {
    double lo = 600.0 - 100.0 * b, acc = 0.0;
    for (int k = 0; k < 20; k++) acc += props__spectrum_at(wl, val, n, lo + 5.0 * (k + 0.5));
    band[b] = acc / 20.0;
  }
  *out = rgb_make(band[0], band[1], band[2]);
  return 1;
}

