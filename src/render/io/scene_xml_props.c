/*
 * scene_xml_props.c: the scene loader's errors, warnings and property
 * lookup (scene_xml_internal.h): typed reads of a property set with
 * defaults, every read marking the property used, ids and references,
 * file names resolved against the XML file's folder.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/io/scene_xml_internal.h"

/* ---- Errors and warnings. ----------------------------------------------- */

lmc_status xml__fail(builder *B, lmc_status code, const char *file, int line,
                     const char *fmt, ...) {
  char msg[900];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return lmc_error_set(B->err, code, file, line, "%s", msg);
}

/* Warns about everything on o the builder did not read, then marks it. */
void xml__warn_unused(pset *o) {
  for (int i = 0; i < o->n_props; i++) {
    prop *p = &o->props[i];
    if (p->used) continue;
    p->used = 1;
    if (p->kind == PROP_OBJECT) {
      lmc_warn(p->file, p->line, "unsupported <%s type=\"%s\"> inside <%s type=\"%s\">: ignored",
               p->obj->tag, p->obj->type, o->tag, o->type);
    } else if (p->kind == PROP_REF) {
      lmc_warn(p->file, p->line, "unused <ref id=\"%s\"> inside <%s type=\"%s\">: ignored",
               p->ref, o->tag, o->type);
    } else {
      lmc_warn(p->file, p->line, "unknown property '%s' (<%s>) on <%s type=\"%s\">: ignored",
               p->name, p->tag, o->tag, o->type);
    }
  }
}

/* Passes the unread plain values of an <integrator> or <dpt> block on to
 * the scene's params (scene.h), for the integrators' option tables. */
lmc_status xml__keep_params(builder *B, pset *o) {
  scene *s = B->s;
  for (int i = 0; i < o->n_props; i++) {
    prop *p = &o->props[i];
    if (p->used || (p->kind != PROP_INT && p->kind != PROP_FLOAT && p->kind != PROP_BOOL &&
                    p->kind != PROP_STRING))
      continue;
    scene_param *a = realloc(s->params, (size_t)(s->n_params + 1) * sizeof *a);
    if (!a) return xml__fail(B, LMC_ENOMEM, p->file, p->line, "out of memory");
    s->params = a;
    scene_param *q = &a[s->n_params++];
    memset(q, 0, sizeof *q);
    snprintf(q->name, sizeof q->name, "%s", p->name);
    snprintf(q->file, sizeof q->file, "%s", p->file ? p->file : "");
    q->line = p->line;
    q->is_bool = p->kind == PROP_BOOL;
    if (p->kind == PROP_INT) snprintf(q->value, sizeof q->value, "%lld", p->i);
    else if (p->kind == PROP_FLOAT) snprintf(q->value, sizeof q->value, "%.17g", p->f);
    else if (p->kind == PROP_BOOL) snprintf(q->value, sizeof q->value, "%s", p->b ? "true" : "false");
    else snprintf(q->value, sizeof q->value, "%s", p->s ? p->s : "");
    p->used = 1;
  }
  return LMC_OK;
}

/* Passes a setting the loader translated from p (a Mitsuba parameter) on
 * to the option tables as the flag `name` with `value`, at p's place. */
lmc_status xml__pass(builder *B, const prop *p, const char *name, const char *value) {
  scene *s = B->s;
  scene_param *a = realloc(s->params, (size_t)(s->n_params + 1) * sizeof *a);
  if (!a) return xml__fail(B, LMC_ENOMEM, p->file, p->line, "out of memory");
  s->params = a;
  scene_param *q = &a[s->n_params++];
  memset(q, 0, sizeof *q);
  snprintf(q->name, sizeof q->name, "%s", name);
  snprintf(q->value, sizeof q->value, "%s", value);
  snprintf(q->file, sizeof q->file, "%s", p->file ? p->file : "");
  q->line = p->line;
  return LMC_OK;
}

/* Marks the named properties as read without using them (accepted silently). */
void xml__accept(pset *o, const char *const *names) {
  for (int i = 0; i < o->n_props; i++)
    for (int k = 0; names[k]; k++)
      if (o->props[i].kind != PROP_OBJECT && strcmp(o->props[i].name, names[k]) == 0)
        o->props[i].used = 1;
}

/* ---- Property lookup. --------------------------------------------------- */

/* The named property (value, named nested object or named ref); marks it. */
prop *xml__find(pset *o, const char *name) {
  prop *found = NULL;
  for (int i = 0; i < o->n_props; i++) {
    if (strcmp(o->props[i].name, name) == 0) {
      /* A later duplicate overrides an earlier one, as in Mitsuba's
       * property sets; both count as read. */
      o->props[i].used = 1;
      found = &o->props[i];
    }
  }
  return found;
}

lmc_status xml__wrong(builder *B, const prop *p, const char *want) {
  return xml__fail(B, LMC_EPARSE, p->file, p->line, "property '%s' must be %s, not <%s>",
                   p->name, want, p->tag);
}

lmc_status xml__missing(builder *B, const pset *o, const char *name) {
  return xml__fail(B, LMC_EPARSE, o->file, o->line,
                   "<%s type=\"%s\"> needs the property '%s'", o->tag, o->type, name);
}

lmc_status xml__float(builder *B, pset *o, const char *name, double def, double *out,
                      int *found) {
  prop *p = xml__find(o, name);
  if (found) *found = p != NULL;
  if (!p) {
    *out = def;
    return LMC_OK;
  }
  if (p->kind == PROP_FLOAT) *out = p->f;
  else if (p->kind == PROP_INT) *out = (double)p->i;
  else return xml__wrong(B, p, "a <float>");
  return LMC_OK;
}

lmc_status xml__int(builder *B, pset *o, const char *name, long long def, long long *out,
                    int *found) {
  prop *p = xml__find(o, name);
  if (found) *found = p != NULL;
  if (!p) {
    *out = def;
    return LMC_OK;
  }
  if (p->kind != PROP_INT) return xml__wrong(B, p, "an <integer>");
  *out = p->i;
  return LMC_OK;
}

lmc_status xml__bool(builder *B, pset *o, const char *name, int def, int *out,
                     int *found) {
  prop *p = xml__find(o, name);
  if (found) *found = p != NULL;
  if (!p) {
    *out = def;
    return LMC_OK;
  }
  if (p->kind != PROP_BOOL) return xml__wrong(B, p, "a <boolean>");
  *out = p->b;
  return LMC_OK;
}

/* *out is NULL when absent (and def is NULL). */
lmc_status xml__string(builder *B, pset *o, const char *name, const char *def,
                       const char **out, prop **where) {
  prop *p = xml__find(o, name);
  if (where) *where = p;
  if (!p) {
    *out = def;
    return LMC_OK;
  }
  if (p->kind != PROP_STRING) return xml__wrong(B, p, "a <string>");
  *out = p->s;
  return LMC_OK;
}

lmc_status xml__choice(builder *B, pset *o, const char *name, const char *const *names, int def,
                       int *out) {
  const char *v = NULL;
  prop *p = NULL;
  lmc_status st = xml__string(B, o, name, NULL, &v, &p);
  *out = def;
  if (st != LMC_OK || !v) return st;
  char list[256] = "";
  for (int k = 0; names[k]; k++) {
    if (strcmp(v, names[k]) == 0) {
      *out = k;
      return LMC_OK;
    }
    size_t n = strlen(list);
    snprintf(list + n, sizeof list - n, "%s\"%s\"", k ? ", " : "", names[k]);
  }
  return xml__fail(B, LMC_EPARSE, p->file, p->line, "%s \"%s\" is not one of %s", name, v, list);
}

lmc_status xml__rgb(builder *B, pset *o, const char *name, rgb def, rgb *out,
                    int *found) {
  prop *p = xml__find(o, name);
  if (found) *found = p != NULL;
  if (!p) {
    *out = def;
    return LMC_OK;
  }
  if (p->kind == PROP_RGB) *out = p->c;
  else if (p->kind == PROP_FLOAT) *out = rgb_gray(p->f);
  else if (p->kind == PROP_INT) *out = rgb_gray((double)p->i);
  else return xml__wrong(B, p, "a colour (<rgb>, <spectrum>, <srgb>)");
  return LMC_OK;
}

lmc_status xml__vec(builder *B, pset *o, const char *name, vec3 def, vec3 *out,
                    int *found) {
  prop *p = xml__find(o, name);
  if (found) *found = p != NULL;
  if (!p) {
    *out = def;
    return LMC_OK;
  }
  if (p->kind != PROP_POINT && p->kind != PROP_VECTOR)
    return xml__wrong(B, p, "a <point> or <vector>");
  *out = p->v;
  return LMC_OK;
}

lmc_status xml__xform(builder *B, pset *o, const char *name, xform *out, int *found) {
  prop *p = xml__find(o, name);
  if (found) *found = p != NULL;
  if (!p) {
    *out = xform_identity();
    return LMC_OK;
  }
  if (p->kind != PROP_TRANSFORM) return xml__wrong(B, p, "a <transform>");
  *out = p->t;
  return LMC_OK;
}

/* An index of refraction: a number or a name known to ior_lookup. */
lmc_status xml__ior(builder *B, pset *o, const char *name, double def, double *out) {
  prop *p = xml__find(o, name);
  if (!p) {
    *out = def;
    return LMC_OK;
  }
  if (p->kind == PROP_FLOAT) *out = p->f;
  else if (p->kind == PROP_INT) *out = (double)p->i;
  else if (p->kind == PROP_STRING) {
    if (!ior_lookup(p->s, out))
      return xml__fail(B, LMC_EPARSE, p->file, p->line, "unknown IOR name '%s' for '%s'", p->s,
                       p->name);
  } else {
    return xml__wrong(B, p, "a <float> or an IOR name <string>");
  }
  if (!(*out > 0.0))
    return xml__fail(B, LMC_EPARSE, p->file, p->line, "'%s' must be positive", p->name);
  return LMC_OK;
}

pset *xml__lookup_id(builder *B, const char *id) {
  for (int i = 0; i < B->n_ids; i++)
    if (strcmp(B->ids[i]->id, id) == 0) return B->ids[i];
  return NULL;
}

/* The object a ref points to, or an error naming the ref's line. */
lmc_status xml__deref(builder *B, const prop *p, pset **out) {
  *out = xml__lookup_id(B, p->ref);
  if (!*out)
    return xml__fail(B, LMC_EPARSE, p->file, p->line, "<ref id=\"%s\">: no object has this id",
                     p->ref);
  return LMC_OK;
}

/* Registers every object with an id, recursively; duplicates are errors. */
lmc_status xml__register_ids(builder *B, pset *o) {
  if (o->id[0]) {
    pset *prev = xml__lookup_id(B, o->id);
    if (prev)
      return xml__fail(B, LMC_EPARSE, o->file, o->line,
                       "duplicate id \"%s\" (first defined at %s:%d)", o->id, prev->file,
                       prev->line);
    if (B->n_ids == B->cap_ids) {
      int cap = B->cap_ids ? 2 * B->cap_ids : 16;
      pset **n = realloc(B->ids, (size_t)cap * sizeof *n);
      if (!n) return xml__fail(B, LMC_ENOMEM, NULL, 0, "out of memory");
      B->ids = n;
      B->cap_ids = cap;
    }
    B->ids[B->n_ids++] = o;
  }
  for (int i = 0; i < o->n_props; i++) {
    if (o->props[i].kind != PROP_OBJECT) continue;
    lmc_status st = xml__register_ids(B, o->props[i].obj);
    if (st != LMC_OK) return st;
  }
  return LMC_OK;
}

/* Resolves a file name against the folder of the XML file `base`. */
void xml__resolve(const char *base, const char *name, char *out, size_t size) {
  const char *slash = strrchr(base, '/');
  if (name[0] == '/' || !slash) snprintf(out, size, "%s", name);
  else snprintf(out, size, "%.*s/%s", (int)(slash - base), base, name);
}

/* A file property, resolved; missing property is an error, and so is a file
 * that cannot be opened (LMC_EIO at the property's line). */
lmc_status xml__file(builder *B, pset *o, const char *name, const char *what,
                     char *out, size_t size, prop **where) {
  const char *fn = NULL;
  prop *p = NULL;
  lmc_status st = xml__string(B, o, name, NULL, &fn, &p);
  if (st != LMC_OK) return st;
  if (!fn) return xml__missing(B, o, name);
  xml__resolve(p->file, fn, out, size);
  FILE *f = fopen(out, "rb");
  if (!f) return xml__fail(B, LMC_EIO, p->file, p->line, "cannot open %s file '%s'", what, out);
  fclose(f);
  if (where) *where = p;
  return LMC_OK;
}

/* Re-labels an error from a reader (which names the data file) with the
 * XML element that asked for it, keeping the reader's text. */
lmc_status xml__relabel(builder *B, lmc_status st, const prop *p, const char *what) {
  char inner[1100];
  lmc_error_format(B->err, inner, sizeof inner);
  return xml__fail(B, st, p->file, p->line, "cannot read %s: %s", what, inner);
}

