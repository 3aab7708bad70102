/*
 * props.c: the property tree of the scene loader (props.h): its memory,
 * the names of its kinds, and the strict reading of value text (numbers,
 * lists, sampled spectra, spectrum files) that the parser
 * (scene_xml_parse.c) uses.
 */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
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

/* "w1:v1, w2:v2, ..." into wl, val (room for max pairs): the pairs are
 * read as Mitsuba 0.6 reads them (tokens at commas and blanks, each split
 * at one ':'), strictly: both numbers finite, wavelengths non-negative and
 * strictly ascending. */
int props_spectrum_pairs(const char *s, double *wl, double *val, int max, char *why,
                         size_t why_size) {
  int n = 0, r;
  char tok[128];
  while ((r = props__token(&s, tok, sizeof tok)) > 0) {
    if (n == max) {
      snprintf(why, why_size, "more than %d pairs", max);
      return -1;
    }
    char *colon = strchr(tok, ':');
    if (colon) *colon = '\0';
    if (!colon || strchr(colon + 1, ':') || !props_number(tok, &wl[n]) ||
        !props_number(colon + 1, &val[n])) {
      if (colon) *colon = ':';
      snprintf(why, why_size, "'%s' is not a wavelength:value pair", tok);
      return -1;
    }
    if (wl[n] < 0.0) {
      snprintf(why, why_size, "negative wavelength %g", wl[n]);
      return -1;
    }
    if (n > 0 && !(wl[n] > wl[n - 1])) {
      snprintf(why, why_size, "wavelengths must increase (%g after %g)", wl[n], wl[n - 1]);
      return -1;
    }
    n++;
  }
  if (r < 0) {
    snprintf(why, why_size, "a token is too long");
    return -1;
  }
  if (n < 2) {
    snprintf(why, why_size, "at least two wavelength:value pairs are needed");
    return -1;
  }
  return n;
}

/* A spectrum file: lines "wavelength value", blank lines and lines starting
 * with '#' skipped, further columns ignored (Mitsuba 0.6's
 * InterpolatedSpectrum file reader). Where Mitsuba silently stops at the
 * first line it cannot read, this is an error naming the line. */
lmc_status props_spectrum_file(const char *path, double **OUT_wl, double **OUT_val, int *OUT_n,
                               lmc_error *err) {
  *OUT_wl = *OUT_val = NULL;
  *OUT_n = 0;
  FILE *f = fopen(path, "r");
  if (!f) return lmc_error_set(err, LMC_EIO, NULL, 0, "cannot open spectrum file '%s'", path);
  double *wl = NULL, *val = NULL;
  int n = 0, cap = 0, line = 0;
  lmc_status st = LMC_OK;
  char buf[512];
  while (fgets(buf, sizeof buf, f)) {
    line++;
    size_t len = strlen(buf);
    if (len == sizeof buf - 1 && buf[len - 1] != '\n') {
      /* Skip the rest of an overlong line (only a comment may be one). */
      int ch;
      while ((ch = fgetc(f)) != EOF && ch != '\n') {
      }
    }
    /* Each line: two numbers, then nothing, a '#' comment or further
     * columns, which Mitsuba ignores too. */
    const char *p = buf;
    while (isspace((unsigned char)*p)) p++;
    if (!*p || *p == '#') continue;
    char *end;
    double w = strtod(p, &end), v = 0.0;
    int ok = end != p && isfinite(w);
    if (ok) {
      p = end;
      v = strtod(p, &end);
      ok = end != p && isfinite(v) && (!*end || isspace((unsigned char)*end) || *end == '#');
    }
    if (!ok) {
      st = lmc_error_set(err, LMC_EPARSE, path, line,
                         "bad line in a spectrum file (expected: wavelength value)");
      break;
    }
    if (w < 0.0 || (n > 0 && !(w > wl[n - 1]))) {
      st = lmc_error_set(err, LMC_EPARSE, path, line,
                         w < 0.0 ? "negative wavelength %g" : "wavelengths must increase (%g)",
                         w);
      break;
    }
    if (n + 2 >= cap) {
      /* Room for the pairs and the two of the zero extension. */
      int ncap = cap ? 2 * cap : 64;
      double *nw = realloc(wl, (size_t)ncap * sizeof *nw);
      if (nw) wl = nw;
      double *nv = nw ? realloc(val, (size_t)ncap * sizeof *nv) : NULL;
      if (nv) val = nv;
      if (!nw || !nv) {
        st = lmc_error_set(err, LMC_ENOMEM, path, line, "out of memory");
        break;
      }
      cap = ncap;
    }
    wl[n] = w;
    val[n] = v;
    n++;
  }
  fclose(f);
  if (st == LMC_OK && n < 2)
    st = lmc_error_set(err, LMC_EPARSE, path, line,
                       "a spectrum file needs at least two lines 'wavelength value'");
  if (st != LMC_OK) {
    free(wl);
    free(val);
    return st;
  }
  *OUT_wl = wl;
  *OUT_val = val;
  *OUT_n = n;
  return LMC_OK;
}
