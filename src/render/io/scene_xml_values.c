/*
 * scene_xml_values.c: the values of the scene loader's first pass
 * (scene_xml_parse_internal.h): colours as linear sRGB (<rgb> as given,
 * <srgb> through the sRGB curve, <spectrum> and <blackbody> through the CIE
 * 1931 functions of spectrum.h, read as --spectra says), points and
 * vectors, and the elementary transforms of <transform> (translate, scale,
 * rotate, lookat or lookAt, matrix).
 */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/image.h"
#include "render/io/scene_xml_parse_internal.h"

/* <blackbody temperature="T[K]" scale="s">: Planck's law through the colour
 * matching functions (spectrum.h), negative components clamped, times s. */
static int parse__blackbody(parse_ctx *c, const char *tag, rgb *out) {
  const char *t = parse__need_attr(c, tag, "temperature");
  if (!t) return 0;
  /* Mitsuba accepts a trailing K ("6500K"). */
  char buf[128];
  snprintf(buf, sizeof buf, "%s", t);
  size_t len = strlen(buf);
  while (len > 0 && isspace((unsigned char)buf[len - 1])) buf[--len] = '\0';
  if (len > 0 && toupper((unsigned char)buf[len - 1]) == 'K') buf[--len] = '\0';
  double temperature, scale = 1.0;
  if (!props_number(buf, &temperature) || !(temperature > 0.0)) {
    parse__fail(c, LMC_EPARSE, "bad temperature '%s' in <%s> (kelvin, positive)", t, tag);
    return 0;
  }
  const char *sc = parse__attr(c, "scale");
  if (sc && !props_number(sc, &scale)) {
    parse__fail(c, LMC_EPARSE, "bad number '%s' in <%s>", sc, tag);
    return 0;
  }
  *out = spectrum_blackbody_rgb(temperature, scale, c->interp);
  return 1;
}

/* <spectrum filename="...">: a file of "wavelength value" lines, converted
 * as a sampled spectrum. Errors inside the file name it and its line. */
static int parse__spectrum_file(parse_ctx *c, const char *fn, rgb *out) {
  char path[1024];
  parse__resolve(c->file, fn, path, sizeof path);
  double *wl, *val;
  int n;
  lmc_status st = props_spectrum_file(path, &wl, &val, &n, c->err);
  if (st == LMC_EIO) {
    parse__fail(c, LMC_EIO, "cannot open spectrum file '%s'", path);
    return 0;
  }
  if (st != LMC_OK) {
    /* The error already names the spectrum file and line. */
    c->status = st;
    if (c->parser) XML_StopParser(c->parser, XML_FALSE);
    return 0;
  }
  *out = spectrum_sampled_rgb(wl, val, n, c->interp);
  free(wl);
  free(val);
  return 1;
}

/* <spectrum value="w1:v1, w2:v2, ...">. */
static int parse__spectrum_pairs(parse_ctx *c, const char *value, rgb *out) {
  /* A pair takes at least two characters with its separator. */
  int max = (int)(strlen(value) / 2) + 1;
  double *wl = malloc(((size_t)max + 2) * sizeof *wl);
  double *val = malloc(((size_t)max + 2) * sizeof *val);
  if (!wl || !val) {
    free(wl);
    free(val);
    parse__fail(c, LMC_ENOMEM, "out of memory");
    return 0;
  }
  char why[256];
  int n = props_spectrum_pairs(value, wl, val, max, why, sizeof why);
  if (n < 0) parse__fail(c, LMC_EPARSE, "bad spectrum '%.200s': %s", value, why);
  else *out = spectrum_sampled_rgb(wl, val, n, c->interp);
  free(wl);
  free(val);
  return n >= 0;
}

/* A colour element (rgb, srgb, spectrum, blackbody) into linear RGB. A
 * <spectrum> is read as Mitsuba 0.6 in RGB mode reads it: one number is
 * that grey, for a reflectance and an emitter alike (its D65 is white in
 * RGB mode); three numbers are linear RGB; wavelength:value pairs or a file
 * go through the colour matching functions (spectrum.h). */
int parse__color(parse_ctx *c, const char *tag, rgb *out) {
  const char *value = parse__attr(c, "value");
  double v[3];
  if (strcmp(tag, "blackbody") == 0) return parse__blackbody(c, tag, out);
  if (strcmp(tag, "spectrum") == 0) {
    const char *fn = parse__attr(c, "filename"), *intent = parse__attr(c, "intent");
    if (!value == !fn) {
      parse__fail(c, LMC_EPARSE, "<spectrum> needs one of the attributes 'value' or 'filename'");
      return 0;
    }
    /* `intent` (reflectance or illuminant) only matters to Mitsuba's
     * spectral mode, and only with a single value. */
    if (intent) {
      double one;
      char low[16] = {0};
      for (size_t i = 0; intent[i] && i < sizeof low - 1; i++)
        low[i] = (char)tolower((unsigned char)intent[i]);
      if (strcmp(low, "reflectance") != 0 && strcmp(low, "illuminant") != 0) {
        parse__fail(c, LMC_EPARSE, "bad intent '%s' in <%s> (reflectance or illuminant)",
                    intent, tag);
        return 0;
      }
      if (fn || props_list(value, &one, 1) != 1) {
        parse__fail(c, LMC_EPARSE, "<%s>: 'intent' goes only with a single value", tag);
        return 0;
      }
    }
    if (fn) return parse__spectrum_file(c, fn, out);
    if (strchr(value, ':')) return parse__spectrum_pairs(c, value, out);
  }
  if (!value) {
    parse__fail(c, LMC_EPARSE, "<%s> needs the attribute 'value'", tag);
    return 0;
  }
  if (strcmp(tag, "srgb") == 0 && value[strspn(value, " \t\r\n")] == '#') {
    /* "#rrggbb": 8-bit sRGB. */
    const char *h = value + strspn(value, " \t\r\n") + 1;
    unsigned r, g, b;
    char extra;
    if (strlen(h) < 6 || sscanf(h, "%2x%2x%2x%c", &r, &g, &b, &extra) != 3) {
      parse__fail(c, LMC_EPARSE, "bad colour '%s' in <%s>", value, tag);
      return 0;
    }
    *out = rgb_make(srgb_to_linear(r / 255.0), srgb_to_linear(g / 255.0),
                    srgb_to_linear(b / 255.0));
    return 1;
  }
  int n = props_list(value, v, 3);
  if (n != 1 && n != 3) {
    parse__fail(c, LMC_EPARSE, "bad colour '%s' in <%s> (expected 1 or 3 numbers)", value, tag);
    return 0;
  }
  if (n == 1) v[1] = v[2] = v[0];
  if (strcmp(tag, "srgb") == 0)
    for (int i = 0; i < 3; i++) v[i] = srgb_to_linear(v[i]);
  *out = rgb_make(v[0], v[1], v[2]);
  return 1;
}

/* A vector from attributes x, y, z (default `def`) or value="x,y,z". */
int parse__xyz(parse_ctx *c, const char *tag, double def, vec3 *out) {
  const char *value = parse__attr(c, "value");
  double v[3] = {def, def, def};
  if (value) {
    int n = props_list(value, v, 3);
    if (n != 3) {
      parse__fail(c, LMC_EPARSE, "bad value '%s' in <%s> (expected 3 numbers)", value, tag);
      return 0;
    }
  } else {
    const char *names[3] = {"x", "y", "z"};
    for (int i = 0; i < 3; i++) {
      const char *a = parse__attr(c, names[i]);
      if (a && !props_number(a, &v[i])) {
        parse__fail(c, LMC_EPARSE, "bad number '%s' in <%s>", a, tag);
        return 0;
      }
    }
  }
  *out = v3(v[0], v[1], v[2]);
  return 1;
}

/* A named 3-vector attribute "x, y, z" (lookat's origin/target/up). */
int parse__vec_attr(parse_ctx *c, const char *tag, const char *name, vec3 *out) {
  const char *a = parse__need_attr(c, tag, name);
  if (!a) return 0;
  double v[3];
  if (props_list(a, v, 3) != 3) {
    parse__fail(c, LMC_EPARSE, "bad vector '%s' in <%s> (expected 3 numbers)", a, tag);
    return 0;
  }
  *out = v3(v[0], v[1], v[2]);
  return 1;
}

/* One elementary transform inside <transform>, composed after the others. */
void parse__transform_op(parse_ctx *c, prop *xf, const char *tag) {
  xform op;
  if (strcmp(tag, "translate") == 0) {
    vec3 d;
    if (!parse__xyz(c, tag, 0.0, &d)) return;
    op = xform_translate(d);
  } else if (strcmp(tag, "scale") == 0) {
    vec3 s = v3(1, 1, 1);
    const char *value = parse__attr(c, "value");
    if (value) {
      double v[3];
      int n = props_list(value, v, 3);
      if (n == 1) s = v3(v[0], v[0], v[0]);
      else if (n == 3) s = v3(v[0], v[1], v[2]);
      else {
        parse__fail(c, LMC_EPARSE, "bad value '%s' in <%s> (1 or 3 numbers)", value, tag);
        return;
      }
    } else if (!parse__xyz(c, tag, 1.0, &s)) {
      return;
    }
    if (s.x == 0.0 || s.y == 0.0 || s.z == 0.0) {
      parse__fail(c, LMC_EPARSE, "<scale> with a zero factor is singular");
      return;
    }
    op = xform_scale(s);
  } else if (strcmp(tag, "rotate") == 0) {
    vec3 axis;
    double angle;
    if (!parse__xyz(c, tag, 0.0, &axis)) return;
    const char *a = parse__need_attr(c, tag, "angle");
    if (!a) return;
    if (!props_number(a, &angle)) {
      parse__fail(c, LMC_EPARSE, "bad number '%s' for the angle of <%s>", a, tag);
      return;
    }
    if (v3_len2(axis) == 0.0) {
      parse__fail(c, LMC_EPARSE, "<rotate> needs a non-zero axis (x, y, z)");
      return;
    }
    op = xform_rotate(axis, angle);
  } else if (strcmp(tag, "lookat") == 0 || strcmp(tag, "lookAt") == 0) {
    /* (Mitsuba 0.6's parser takes both spellings.) */
    vec3 o, t, up;
    if (!parse__vec_attr(c, tag, "origin", &o) || !parse__vec_attr(c, tag, "target", &t)) return;
    if (parse__attr(c, "up")) {
      if (!parse__vec_attr(c, tag, "up", &up)) return;
    } else {
      /* No up given: any direction not parallel to the view direction. */
      vec3 d = v3_normalize(v3_sub(t, o));
      up = fabs(d.y) < 0.9 ? v3(0, 1, 0) : v3(1, 0, 0);
    }
    if (!xform_lookat(o, t, up, &op)) {
      parse__fail(c, LMC_EPARSE,
                  "degenerate <lookat> (origin equals target, or up parallel to the view)");
      return;
    }
  } else if (strcmp(tag, "matrix") == 0) {
    const char *value = parse__need_attr(c, tag, "value");
    if (!value) return;
    double v[16];
    if (props_list(value, v, 16) != 16) {
      parse__fail(c, LMC_EPARSE, "<matrix> needs 16 numbers, got '%s'", value);
      return;
    }
    if (!xform_from_matrix(v, &op)) {
      parse__fail(c, LMC_EPARSE, "<matrix> is singular");
      return;
    }
  } else {
    parse__fail(c, LMC_EPARSE, "unexpected <%s> inside <transform>", tag);
    return;
  }
  xf->t = xform_compose(&op, &xf->t);
}

