/*
 * scene_xml_parse.c: first pass of the Mitsuba scene loader, XML to property
 * sets (see props.h).
 *
 * The document is read with expat as a stream of start/end events. A small
 * stack remembers what kind of element encloses the current one:
 *   - an object element (scene, shape, bsdf, ..., or any unknown tag): its
 *     children are properties, nested objects, <ref>s, <default>s and
 *     <include>s;
 *   - a <transform>: its children are the elementary transforms translate,
 *     rotate, scale, lookat (or lookAt) and matrix, composed in document
 *     order as Mitsuba does (each one is applied after the ones before:
 *     M = M_new * M_old);
 *   - an <animation name> (Mitsuba's keyframed transform): its first
 *     <transform> keyframe becomes the transform `name`, the others are
 *     skipped, with a warning (no motion blur);
 *   - a leaf property, which may not have children.
 *
 * Attribute values go through parameter substitution first: `$name` is
 * replaced by the value of a parameter, where parameters come from the
 * `defines` ("name=value", the -D flag) and from <default name value>
 * elements (which never override a define or an earlier default). An
 * undefined `$name` is an error.
 *
 * <include filename> parses another file (relative to the including file's
 * folder) whose root <scene> element's children are appended to the object
 * that contains the <include>.
 *
 * Values are parsed strictly: a number must use the whole attribute
 * ("1.2.3" is an error), colour and vector lists accept commas and/or
 * blanks. Colours become linear RGB here, as Mitsuba 0.6 compiled in RGB
 * mode makes them: <rgb> as given, <srgb> decoded with the sRGB transfer
 * curve, <spectrum> either one number (that grey), a list of three (taken
 * as RGB), or a sampled spectrum (wavelength:value pairs, or a file of
 * "wavelength value" lines) and <blackbody> (Planck's law), both through
 * the CIE 1931 colour matching functions to linear sRGB (render/spectrum.h).
 * Those values and the elementary transforms are read by
 * scene_xml_values.c; the parser's state is in scene_xml_parse_internal.h.
 */
#include <ctype.h>
#include <errno.h>
#include <expat.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/image.h"
#include "render/io/props.h"
#include "render/spectrum.h"

#include "render/io/scene_xml_parse_internal.h"

static char *parse__strdup(const char *s) {
  size_t n = strlen(s) + 1;
  char *d = malloc(n);
  if (d) memcpy(d, s, n);
  return d;
}

/* ---- Memory of the property tree. -------------------------------------- */

static const char *parse__intern(pdoc *doc, const char *file) {
  for (int i = 0; i < doc->n_files; i++)
    if (strcmp(doc->files[i], file) == 0) return doc->files[i];
  if (doc->n_files == doc->cap_files) {
    int cap = doc->cap_files ? 2 * doc->cap_files : 8;
    char **f = realloc(doc->files, (size_t)cap * sizeof *f);
    if (!f) return NULL;
    doc->files = f;
    doc->cap_files = cap;
  }
  char *d = parse__strdup(file);
  if (!d) return NULL;
  doc->files[doc->n_files++] = d;
  return d;
}

/* Appends a zeroed prop to p; NULL when out of memory. */
static prop *parse__add_prop(pset *p) {
  if (p->n_props == p->cap_props) {
    int cap = p->cap_props ? 2 * p->cap_props : 8;
    prop *np = realloc(p->props, (size_t)cap * sizeof *np);
    if (!np) return NULL;
    p->props = np;
    p->cap_props = cap;
  }
  prop *q = &p->props[p->n_props++];
  memset(q, 0, sizeof *q);
  return q;
}

/* ---- Errors. ------------------------------------------------------------ */

int parse__line(parse_ctx *c) {
  return c->parser ? (int)XML_GetCurrentLineNumber(c->parser) : 0;
}

void parse__fail(parse_ctx *c, lmc_status code, const char *fmt, ...) {
  if (c->status != LMC_OK) return;
  char msg[900];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  c->status = lmc_error_set(c->err, code, c->file, parse__line(c), "%s", msg);
  if (c->parser) XML_StopParser(c->parser, XML_FALSE);
}

/* ---- Parameters and substitution. --------------------------------------- */

static param *parse__find_param(parse_ctx *c, const char *name, size_t len) {
  for (int i = 0; i < c->n_params; i++)
    if (strlen(c->params[i].name) == len && strncmp(c->params[i].name, name, len) == 0)
      return &c->params[i];
  return NULL;
}

/* Adds a parameter unless one of that name exists (defines come first, so a
 * later <default> never overrides them). Returns 0 when out of memory. */
static int parse__add_param(parse_ctx *c, const char *name, size_t len, const char *value) {
  if (parse__find_param(c, name, len)) return 1;
  if (c->n_params == c->cap_params) {
    int cap = c->cap_params ? 2 * c->cap_params : 8;
    param *np = realloc(c->params, (size_t)cap * sizeof *np);
    if (!np) return 0;
    c->params = np;
    c->cap_params = cap;
  }
  char *n = malloc(len + 1);
  char *v = parse__strdup(value);
  if (!n || !v) {
    free(n);
    free(v);
    return 0;
  }
  memcpy(n, name, len);
  n[len] = '\0';
  c->params[c->n_params].name = n;
  c->params[c->n_params].value = v;
  c->n_params++;
  return 1;
}

/* Replaces every $name (name = [A-Za-z0-9_]+) in `in`. Returns a new string,
 * or NULL after recording an error. */
static char *parse__subst(parse_ctx *c, const char *in) {
  size_t cap = strlen(in) + 64, n = 0;
  char *out = malloc(cap);
  if (!out) {
    parse__fail(c, LMC_ENOMEM, "out of memory");
    return NULL;
  }
  for (const char *p = in; *p;) {
    const char *rep = NULL;
    size_t rep_len = 0, skip = 1;
    if (*p == '$') {
      const char *q = p + 1;
      while (isalnum((unsigned char)*q) || *q == '_') q++;
      size_t len = (size_t)(q - p - 1);
      if (len > 0) {
        param *pr = parse__find_param(c, p + 1, len);
        if (!pr) {
          char name[128];
          snprintf(name, sizeof name, "%.*s", (int)(len < 100 ? len : 100), p + 1);
          parse__fail(c, LMC_EPARSE, "undefined parameter $%s (no <default> or -D for it)",
                      name);
          free(out);
          return NULL;
        }
        rep = pr->value;
        rep_len = strlen(rep);
        skip = len + 1;
      }
    }
    if (!rep) {
      rep = p;
      rep_len = 1;
    }
    if (n + rep_len + 1 > cap) {
      cap = 2 * (n + rep_len + 1);
      char *o2 = realloc(out, cap);
      if (!o2) {
        free(out);
        parse__fail(c, LMC_ENOMEM, "out of memory");
        return NULL;
      }
      out = o2;
    }
    memcpy(out + n, rep, rep_len);
    n += rep_len;
    p += skip;
  }
  out[n] = '\0';
  return out;
}

static void parse__clear_attrs(parse_ctx *c) {
  for (int i = 0; i < c->n_attrs; i++) {
    free(c->attr_name[i]);
    free(c->attr_value[i]);
  }
  c->n_attrs = 0;
}

/* Copies the element's attributes with parameters substituted. */
static int parse__load_attrs(parse_ctx *c, const char **atts) {
  parse__clear_attrs(c);
  for (int i = 0; atts[i]; i += 2) {
    if (c->n_attrs == PARSE_MAX_ATTRS) {
      parse__fail(c, LMC_EPARSE, "too many attributes");
      return 0;
    }
    char *v = parse__subst(c, atts[i + 1]);
    if (!v) return 0;
    char *nm = parse__strdup(atts[i]);
    if (!nm) {
      free(v);
      parse__fail(c, LMC_ENOMEM, "out of memory");
      return 0;
    }
    c->attr_name[c->n_attrs] = nm;
    c->attr_value[c->n_attrs] = v;
    c->n_attrs++;
  }
  return 1;
}

const char *parse__attr(parse_ctx *c, const char *name) {
  for (int i = 0; i < c->n_attrs; i++)
    if (strcmp(c->attr_name[i], name) == 0) return c->attr_value[i];
  return NULL;
}

/* An attribute that must be present. */
const char *parse__need_attr(parse_ctx *c, const char *tag, const char *name) {
  const char *v = parse__attr(c, name);
  if (!v) parse__fail(c, LMC_EPARSE, "<%s> needs the attribute '%s'", tag, name);
  return v;
}

/* ---- Elements. ---------------------------------------------------------- */

static int parse__is_property_tag(const char *t) {
  static const char *tags[] = {"integer", "float", "boolean", "string", "rgb",
                               "srgb",    "spectrum", "blackbody", "point", "vector"};
  for (size_t i = 0; i < sizeof tags / sizeof tags[0]; i++)
    if (strcmp(t, tags[i]) == 0) return 1;
  return 0;
}

static void parse__push(parse_ctx *c, frame_kind k, pset *obj, int prop_index) {
  if (c->depth == PARSE_MAX_DEPTH) {
    parse__fail(c, LMC_EPARSE, "elements nested too deeply");
    return;
  }
  c->stack[c->depth].kind = k;
  c->stack[c->depth].obj = obj;
  c->stack[c->depth].prop = prop_index;
  c->stack[c->depth].keyframes = 0;
  c->depth++;
}

/* A new prop on obj with the common fields; name from the attribute. */
static prop *parse__new_prop(parse_ctx *c, pset *obj, const char *tag, prop_kind kind,
                             int need_name) {
  const char *name = parse__attr(c, "name");
  if (need_name && !name) {
    parse__fail(c, LMC_EPARSE, "<%s> needs the attribute 'name'", tag);
    return NULL;
  }
  prop *q = parse__add_prop(obj);
  if (!q) {
    parse__fail(c, LMC_ENOMEM, "out of memory");
    return NULL;
  }
  q->kind = kind;
  snprintf(q->name, sizeof q->name, "%s", name ? name : "");
  snprintf(q->tag, sizeof q->tag, "%s", tag);
  q->file = c->file;
  q->line = parse__line(c);
  return q;
}

/* A value element (integer, float, ...) inside an object. */
static void parse__property(parse_ctx *c, pset *obj, const char *tag) {
  prop_kind kind;
  if (strcmp(tag, "integer") == 0) kind = PROP_INT;
  else if (strcmp(tag, "float") == 0) kind = PROP_FLOAT;
  else if (strcmp(tag, "boolean") == 0) kind = PROP_BOOL;
  else if (strcmp(tag, "string") == 0) kind = PROP_STRING;
  else if (strcmp(tag, "point") == 0) kind = PROP_POINT;
  else if (strcmp(tag, "vector") == 0) kind = PROP_VECTOR;
  else kind = PROP_RGB;
  prop *q = parse__new_prop(c, obj, tag, kind, 1);
  if (!q) return;
  const char *value = NULL;
  if (kind == PROP_INT || kind == PROP_FLOAT || kind == PROP_BOOL || kind == PROP_STRING) {
    value = parse__need_attr(c, tag, "value");
    if (!value) return;
  }
  switch (kind) {
    case PROP_INT:
      if (!props_integer(value, &q->i))
        parse__fail(c, LMC_EPARSE, "bad integer '%s' for '%s'", value, q->name);
      break;
    case PROP_FLOAT:
      if (!props_number(value, &q->f))
        parse__fail(c, LMC_EPARSE, "bad number '%s' for '%s'", value, q->name);
      break;
    case PROP_BOOL: {
      char low[8] = {0};
      size_t len = strlen(value);
      for (size_t i = 0; i < len && i < sizeof low - 1; i++)
        low[i] = (char)tolower((unsigned char)value[i]);
      if (len < sizeof low && (strcmp(low, "true") == 0 || strcmp(low, "1") == 0)) q->b = 1;
      else if (len < sizeof low && (strcmp(low, "false") == 0 || strcmp(low, "0") == 0)) q->b = 0;
      else parse__fail(c, LMC_EPARSE, "bad boolean '%s' for '%s' (true or false)", value, q->name);
      break;
    }
    case PROP_STRING:
      q->s = parse__strdup(value);
      if (!q->s) parse__fail(c, LMC_ENOMEM, "out of memory");
      break;
    case PROP_POINT:
    case PROP_VECTOR:
      parse__xyz(c, tag, 0.0, &q->v);
      break;
    default:
      parse__color(c, tag, &q->c);
      break;
  }
}

static lmc_status parse__file(parse_ctx *c, const char *path, pset *parent);

/* Resolves `name` against the folder of the file being read. */
void parse__resolve(const char *base_file, const char *name, char *out, size_t size) {
  if (name[0] == '/') {
    snprintf(out, size, "%s", name);
    return;
  }
  const char *slash = strrchr(base_file, '/');
  if (!slash) {
    snprintf(out, size, "%s", name);
    return;
  }
  snprintf(out, size, "%.*s/%s", (int)(slash - base_file), base_file, name);
}

/* <include filename>: parses that file into obj (the including element's
 * object), then restores the state of this file's parser. */
static void parse__include(parse_ctx *c, pset *obj, const char *tag) {
  const char *fn = parse__need_attr(c, tag, "filename");
  if (!fn) return;
  if (c->include_depth >= PARSE_MAX_INCLUDE) {
    parse__fail(c, LMC_EPARSE, "<include> nested too deeply (a cycle?) at '%s'", fn);
    return;
  }
  char path[1024];
  parse__resolve(c->file, fn, path, sizeof path);
  /* Parse the included file into this object, then restore our state. */
  parse__clear_attrs(c);
  parse_ctx saved = *c;
  c->depth = 0;
  c->n_attrs = 0;
  c->include_depth++;
  lmc_status st = parse__file(c, path, obj);
  int line = (int)XML_GetCurrentLineNumber(saved.parser);
  c->file = saved.file;
  c->parser = saved.parser;
  c->include_depth = saved.include_depth;
  c->include_parent = saved.include_parent;
  c->depth = saved.depth;
  memcpy(c->stack, saved.stack, sizeof c->stack);
  if (st != LMC_OK) {
    /* A missing include file is reported at the <include>; errors inside
     * it keep their own file and line. */
    if (st == LMC_EIO && c->err && c->err->line == 0) {
      lmc_error_set(c->err, LMC_EIO, c->file, line, "cannot open included file '%s'", path);
    }
    c->status = st;
    XML_StopParser(c->parser, XML_FALSE);
    return;
  }
  parse__push(c, FR_LEAF, NULL, -1);
}

static void XMLCALL parse__start(void *user, const XML_Char *tag, const XML_Char **atts) {
  parse_ctx *c = user;
  if (c->status != LMC_OK) return;
  if (!parse__load_attrs(c, atts)) return;

  /* The root element. */
  if (c->depth == 0) {
    if (strcmp(tag, "scene") != 0) {
      parse__fail(c, LMC_EPARSE, "the root element must be <scene>, not <%s>", tag);
      return;
    }
    pset *root = c->include_parent;
    if (!root) {
      root = calloc(1, sizeof *root);
      if (!root) {
        parse__fail(c, LMC_ENOMEM, "out of memory");
        return;
      }
      snprintf(root->tag, sizeof root->tag, "scene");
      root->file = c->file;
      root->line = parse__line(c);
      root->index = -1;
      c->doc->root = root;
    }
    parse__push(c, FR_OBJECT, root, -1);
    return;
  }

  parse_frame *top = &c->stack[c->depth - 1];
  if (top->kind == FR_SKIP) {
    parse__push(c, FR_SKIP, NULL, -1);
    return;
  }
  if (top->kind == FR_LEAF) {
    parse__fail(c, LMC_EPARSE, "unexpected <%s> inside a value element", tag);
    return;
  }
  if (top->kind == FR_TRANSFORM) {
    parse__transform_op(c, &top->obj->props[top->prop], tag);
    parse__push(c, FR_LEAF, NULL, -1);
    return;
  }
  if (top->kind == FR_ANIMATION) {
    /* Its keyframes: the first is the transform, the others are skipped. */
    if (strcmp(tag, "transform") != 0) {
      parse__fail(c, LMC_EPARSE, "unexpected <%s> inside <animation> (only <transform>)", tag);
      return;
    }
    parse__push(c, top->keyframes++ == 0 ? FR_TRANSFORM : FR_SKIP, top->obj, top->prop);
    return;
  }

  /* Inside an object. */
  pset *obj = top->obj;
  if (parse__is_property_tag(tag)) {
    parse__property(c, obj, tag);
    parse__push(c, FR_LEAF, NULL, -1);
  } else if (strcmp(tag, "transform") == 0) {
    prop *q = parse__new_prop(c, obj, tag, PROP_TRANSFORM, 1);
    if (!q) return;
    q->t = xform_identity();
    parse__push(c, FR_TRANSFORM, obj, obj->n_props - 1);
  } else if (strcmp(tag, "ref") == 0) {
    const char *id = parse__need_attr(c, tag, "id");
    if (!id) return;
    prop *q = parse__new_prop(c, obj, tag, PROP_REF, 0);
    if (!q) return;
    snprintf(q->ref, sizeof q->ref, "%s", id);
    parse__push(c, FR_LEAF, NULL, -1);
  } else if (strcmp(tag, "default") == 0) {
    const char *name = parse__need_attr(c, tag, "name");
    const char *value = name ? parse__need_attr(c, tag, "value") : NULL;
    if (!value) return;
    if (!parse__add_param(c, name, strlen(name), value)) {
      parse__fail(c, LMC_ENOMEM, "out of memory");
      return;
    }
    parse__push(c, FR_LEAF, NULL, -1);
  } else if (strcmp(tag, "include") == 0) {
    parse__include(c, obj, tag);
  } else if (strcmp(tag, "animation") == 0) {
    /* Motion (Mitsuba's keyframed transform): the shutter opens at the
     * first keyframe, which is what lmc renders. */
    prop *q = parse__new_prop(c, obj, tag, PROP_TRANSFORM, 1);
    if (!q) return;
    q->t = xform_identity();
    lmc_warn(c->file, q->line,
             "<animation name=\"%s\">: motion blur is not supported; rendered at its first "
             "keyframe", q->name);
    parse__push(c, FR_ANIMATION, obj, obj->n_props - 1);
  } else if (strcmp(tag, "alias") == 0) {
    lmc_warn(c->file, parse__line(c), "<%s> is not supported: ignored", tag);
    parse__push(c, FR_SKIP, NULL, -1);
  } else {
    /* An object element (known or not: the builder judges). */
    pset *child = calloc(1, sizeof *child);
    if (!child) {
      parse__fail(c, LMC_ENOMEM, "out of memory");
      return;
    }
    snprintf(child->tag, sizeof child->tag, "%s", tag);
    const char *type = parse__attr(c, "type");
    const char *id = parse__attr(c, "id");
    snprintf(child->type, sizeof child->type, "%s", type ? type : "");
    snprintf(child->id, sizeof child->id, "%s", id ? id : "");
    child->file = c->file;
    child->line = parse__line(c);
    child->index = -1;
    prop *q = parse__new_prop(c, obj, tag, PROP_OBJECT, 0);
    if (!q) {
      free(child);
      return;
    }
    q->obj = child;
    parse__push(c, FR_OBJECT, child, -1);
  }
}

static void XMLCALL parse__end(void *user, const XML_Char *tag) {
  parse_ctx *c = user;
  (void)tag;
  if (c->status != LMC_OK) return;
  if (c->depth > 0 && c->stack[c->depth - 1].kind == FR_ANIMATION &&
      c->stack[c->depth - 1].keyframes == 0) {
    parse__fail(c, LMC_EPARSE, "<animation> without a keyframe (<transform>)");
    return;
  }
  if (c->depth > 0) c->depth--;
}

/* Reads one file with its own expat parser; children of its root <scene>
 * go to `parent` (NULL: this is the main file). */
static lmc_status parse__file(parse_ctx *c, const char *path, pset *parent) {
  const char *file = parse__intern(c->doc, path);
  if (!file) return lmc_error_set(c->err, LMC_ENOMEM, path, 0, "out of memory");
  FILE *fp = fopen(path, "rb");
  if (!fp) return lmc_error_set(c->err, LMC_EIO, path, 0, "cannot open the scene file: %s", strerror(errno));
  XML_Parser p = XML_ParserCreate(NULL);
  if (!p) {
    fclose(fp);
    return lmc_error_set(c->err, LMC_ENOMEM, path, 0, "out of memory");
  }
  XML_SetUserData(p, c);
  XML_SetElementHandler(p, parse__start, parse__end);
  c->parser = p;
  c->file = file;
  c->include_parent = parent;
  c->depth = 0;

  char buf[65536];
  for (;;) {
    size_t n = fread(buf, 1, sizeof buf, fp);
    int final = n < sizeof buf;
    if (ferror(fp)) {
      if (c->status == LMC_OK)
        c->status = lmc_error_set(c->err, LMC_EIO, path, 0, "read error");
      break;
    }
    if (XML_Parse(p, buf, (int)n, final) == XML_STATUS_ERROR) {
      if (c->status == LMC_OK) {
        c->status = lmc_error_set(c->err, LMC_EPARSE, file, (int)XML_GetCurrentLineNumber(p),
                                  "malformed XML: %s", XML_ErrorString(XML_GetErrorCode(p)));
      }
      break;
    }
    if (final) break;
  }
  if (c->status == LMC_OK && parent == NULL && !c->doc->root)
    c->status = lmc_error_set(c->err, LMC_EPARSE, file, 0, "no <scene> element");
  XML_ParserFree(p);
  c->parser = NULL;
  fclose(fp);
  parse__clear_attrs(c);
  return c->status;
}

lmc_status pdoc_parse(pdoc *doc, const char *path, const char *const *defines, int n_defines,
                      spectrum_interp interp, lmc_error *err) {
  memset(doc, 0, sizeof *doc);
  parse_ctx c;
  memset(&c, 0, sizeof c);
  c.interp = interp;
  c.doc = doc;
  c.err = err;
  c.status = LMC_OK;
  /* The -D defines come first, so <default> cannot override them. */
  for (int i = 0; i < n_defines; i++) {
    const char *eq = strchr(defines[i], '=');
    if (!eq || eq == defines[i]) {
      c.status = lmc_error_set(err, LMC_EINVAL, NULL, 0,
                               "bad define '%s' (expected name=value)", defines[i]);
      break;
    }
    if (!parse__add_param(&c, defines[i], (size_t)(eq - defines[i]), eq + 1)) {
      c.status = lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory");
      break;
    }
  }
  if (c.status == LMC_OK) {
    lmc_status fst = parse__file(&c, path, NULL);
    if (c.status == LMC_OK) c.status = fst;
  }
  for (int i = 0; i < c.n_params; i++) {
    free(c.params[i].name);
    free(c.params[i].value);
  }
  free(c.params);
  if (c.status != LMC_OK) pdoc_free(doc);
  return c.status;
}
