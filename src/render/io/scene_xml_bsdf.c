/*
 * scene_xml_bsdf.c: the scene loader's textures (bitmap, checkerboard)
 * and BSDFs (Mitsuba's names and defaults, bsdf.h), for
 * scene_xml_internal.h.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/bsdf/bsdf_model.h"
#include "render/io/scene_xml_internal.h"
#include "render/plugin.h"

/* ---- Textures. ---------------------------------------------------------- */

/* Counts the texels of img that are NaN or infinite; with `repair`, also
 * those that are negative, and sets all of them to 0. */
int64_t xml__bad_texels(lmc_image *img, int repair) {
  int64_t n = (int64_t)img->width * img->height * img->channels, bad = 0;
  for (int64_t i = 0; i < n; i++) {
    float v = img->data[i];
    if (!isfinite(v) || (repair && v < 0.0f)) {
      bad++;
      if (repair) img->data[i] = 0.0f;
    }
  }
  return bad;
}

/* Loads (once per texture object) the image of a bitmap texture. */
static lmc_status xml__bitmap_image(builder *B, pset *o, tex_filter filter, int *out_index) {
  if (o->index >= 0) {
    *out_index = o->index;
    return LMC_OK;
  }
  char path[1024];
  prop *fp;
  lmc_status st = xml__file(B, o, "filename", "texture", path, sizeof path, &fp);
  if (st != LMC_OK) return st;
  double gamma;
  int has_gamma;
  if ((st = xml__float(B, o, "gamma", -1.0, &gamma, &has_gamma)) != LMC_OK) return st;
  int srgb = 1;
  if (has_gamma && gamma == 1.0) srgb = 0;
  else if (has_gamma && gamma != -1.0)
    lmc_warn(o->file, o->line, "bitmap gamma %g is approximated by the sRGB curve", gamma);
  /* channel: one channel of the file as a grey texture (a mask's opacity
   * from the alpha channel); r, g, b or a, as Mitsuba names them. */
  const char *ch;
  prop *cp;
  if ((st = xml__string(B, o, "channel", NULL, &ch, &cp)) != LMC_OK) return st;
  int channel = -1;
  if (ch) {
    static const char *const names[4] = {"r", "g", "b", "a"};
    for (int k = 0; k < 4; k++)
      if (strcmp(ch, names[k]) == 0) channel = k;
    if (channel < 0)
      return xml__fail(B, LMC_EPARSE, cp->file, cp->line,
                       "bitmap channel \"%s\" is not supported (r, g, b or a)", ch);
  }
  lmc_image img = {0};
  st = image_read(path, srgb, &img, B->err);
  if (st == LMC_OK)
    st = channel >= 0 ? image_select_channel(&img, channel, B->err) : image_to_rgb(&img, B->err);
  if (st != LMC_OK) {
    image_free(&img);
    return xml__relabel(B, st, fp, "texture image");
  }
  /* NaN or Inf texels are kept (the image is the user's), but said: the
   * render drops and counts every sample that meets one. */
  int64_t bad = xml__bad_texels(&img, 0);
  if (bad > 0)
    lmc_warn(fp->file, fp->line,
             "texture image '%s' has %lld NaN or infinite values: samples that meet them will be "
             "dropped",
             fp->s, (long long)bad);
  int idx = scene_add_image(B->s, &img, B->err);
  if (idx < 0) {
    image_free(&img);
    return (lmc_status)idx;
  }
  /* Its MIP levels, right after it (texture.h), when the filter reads them. */
  if (tex_filter_uses_mip(filter)) {
    int n = tex_mip_levels(B->s->images[idx].width, B->s->images[idx].height);
    for (int k = 1; k < n; k++) {
      lmc_image next = {0};
      if ((st = tex_mip_halve(&B->s->images[idx + k - 1], &next, B->err)) != LMC_OK) return st;
      int id = scene_add_image(B->s, &next, B->err);
      if (id < 0) {
        image_free(&next);
        return (lmc_status)id;
      }
    }
  }
  o->index = idx;
  *out_index = idx;
  return LMC_OK;
}

/* uvscale sets both scales; uscale/vscale override it. */
static lmc_status xml__uv_params(builder *B, pset *o, texture *t) {
  double uv, us, vs;
  lmc_status st;
  if ((st = xml__float(B, o, "uvscale", 1.0, &uv, NULL)) != LMC_OK) return st;
  if ((st = xml__float(B, o, "uscale", uv, &us, NULL)) != LMC_OK) return st;
  if ((st = xml__float(B, o, "vscale", uv, &vs, NULL)) != LMC_OK) return st;
  t->uscale = us;
  t->vscale = vs;
  if ((st = xml__float(B, o, "uoffset", 0.0, &t->uoffset, NULL)) != LMC_OK) return st;
  return xml__float(B, o, "voffset", 0.0, &t->voffset, NULL);
}

static lmc_status xml__texture_object(builder *B, pset *o, rgb def, texture *out, int *image);

lmc_status xml__nested(builder *B, pset *o, const char *tag, pset **OUT_first,
                       prop **OUT_next) {
  *OUT_first = NULL;
  *OUT_next = NULL;
  for (int i = 0; i < o->n_props; i++) {
    prop *p = &o->props[i];
    pset *c = NULL;
    lmc_status st;
    if (p->kind == PROP_OBJECT) c = p->obj;
    else if (p->kind == PROP_REF && (st = xml__deref(B, p, &c)) != LMC_OK) return st;
    if (!c || strcmp(c->tag, tag) != 0) continue;
    if (*OUT_first) {
      *OUT_next = p;
      return LMC_OK;
    }
    p->used = 1;
    *OUT_first = c;
  }
  return LMC_OK;
}


/* Mitsuba's `scale` texture: its nested texture times `scale` (a number
 * or a colour, default 1). A bitmap gets a scaled copy of its image. */
static lmc_status xml__scale_texture(builder *B, pset *o, rgb def, texture *out, int *image) {
  lmc_status st;
  rgb k;
  if ((st = xml__rgb(B, o, "scale", rgb_gray(1.0), &k, NULL)) != LMC_OK) return st;
  pset *inner;
  prop *next; /* a second texture stays unread: warned about as unused */
  if ((st = xml__nested(B, o, "texture", &inner, &next)) != LMC_OK) return st;
  if (!inner)
    return xml__fail(B, LMC_EPARSE, o->file, o->line, "<texture type=\"scale\"> needs a nested texture");
  if ((st = xml__texture_object(B, inner, def, out, image)) != LMC_OK) return st;
  xml__warn_unused(o);
  out->value = rgb_mul(out->value, k);
  out->color0 = rgb_mul(out->color0, k);
  out->color1 = rgb_mul(out->color1, k);
  if (*image < 0) return LMC_OK;
  /* The image and each of its MIP levels scaled, consecutive as theirs. */
  const double kc[3] = {k.r, k.g, k.b};
  int first = -1;
  for (int level = 0; level < out->levels; level++) {
    const lmc_image *src = &B->s->images[*image + level];
    lmc_image img = {0};
    if ((st = image_init(&img, src->width, src->height, 3, B->err)) != LMC_OK) return st;
    size_t n = (size_t)src->width * src->height;
    for (size_t i = 0; i < n; i++)
      for (int c = 0; c < 3; c++) img.data[3 * i + c] = (float)(src->data[3 * i + c] * kc[c]);
    int idx = scene_add_image(B->s, &img, B->err);
    if (idx < 0) {
      image_free(&img);
      return (lmc_status)idx;
    }
    if (level == 0) first = idx;
  }
  *image = first;
  return LMC_OK;
}

/* A bitmap's filter, wrap modes and maximum anisotropy (Mitsuba's names
 * and defaults: ewa, repeat, 20; wrapMode sets both, wrapModeU/V each). */
static lmc_status xml__bitmap_params(builder *B, pset *o, texture *out) {
  static const char *const filters[] = {"ewa", "trilinear", "bilinear", "nearest", NULL};
  static const char *const wraps[] = {"repeat", "mirror", "clamp", "zero", "one", "black", NULL};
  static const tex_wrap wrap_of[] = {TEX_WRAP_REPEAT, TEX_WRAP_MIRROR, TEX_WRAP_CLAMP,
                                     TEX_WRAP_ZERO,   TEX_WRAP_ONE,    TEX_WRAP_ZERO};
  int f, w, wu, wv;
  lmc_status st;
  if ((st = xml__choice(B, o, "filterType", filters, 0, &f)) != LMC_OK) return st;
  if ((st = xml__choice(B, o, "wrapMode", wraps, 0, &w)) != LMC_OK) return st;
  if ((st = xml__choice(B, o, "wrapModeU", wraps, w, &wu)) != LMC_OK) return st;
  if ((st = xml__choice(B, o, "wrapModeV", wraps, w, &wv)) != LMC_OK) return st;
  out->type = TEX_BITMAP;
  out->filter = (tex_filter)f;
  out->wrap_u = wrap_of[wu], out->wrap_v = wrap_of[wv];
  if ((st = xml__float(B, o, "maxAnisotropy", 20.0, &out->max_aniso, NULL)) != LMC_OK) return st;
  if (!(out->max_aniso >= 1.0)) {
    prop *p = xml__find(o, "maxAnisotropy");
    return xml__fail(B, LMC_EPARSE, p->file, p->line, "bitmap maxAnisotropy must be at least 1");
  }
  return LMC_OK;
}

/* Builds a texture object; *image gets the image index (-1: none). An
 * unsupported texture type warns and gives the constant `def`. */
static lmc_status xml__texture_object(builder *B, pset *o, rgb def, texture *out, int *image) {
  lmc_status st;
  *image = -1;
  *out = tex_constant(def);
  if (strcmp(o->type, "bitmap") == 0) {
    if ((st = xml__bitmap_params(B, o, out)) != LMC_OK) return st;
    if ((st = xml__bitmap_image(B, o, out->filter, image)) != LMC_OK) return st;
    const lmc_image *im = &B->s->images[*image];
    out->levels = tex_filter_uses_mip(out->filter) ? tex_mip_levels(im->width, im->height) : 1;
    if ((st = xml__uv_params(B, o, out)) != LMC_OK) return st;
    static const char *const silent[] = {"cache", NULL};
    xml__accept(o, silent);
  } else if (strcmp(o->type, "scale") == 0) {
    return xml__scale_texture(B, o, def, out, image);
  } else if (strcmp(o->type, "checkerboard") == 0) {
    out->type = TEX_CHECKERBOARD;
    if ((st = xml__rgb(B, o, "color0", rgb_gray(0.4), &out->color0, NULL)) != LMC_OK) return st;
    if ((st = xml__rgb(B, o, "color1", rgb_gray(0.2), &out->color1, NULL)) != LMC_OK) return st;
    if ((st = xml__uv_params(B, o, out)) != LMC_OK) return st;
  } else {
    lmc_warn(o->file, o->line,
             "unsupported texture type \"%s\": using the constant %g %g %g instead", o->type,
             def.r, def.g, def.b);
    for (int i = 0; i < o->n_props; i++) o->props[i].used = 1;
    return LMC_OK;
  }
  xml__warn_unused(o);
  return LMC_OK;
}

/* A BSDF parameter: a colour, a nested <texture name=...> or a
 * <ref name=... id=...> to a texture. */
static lmc_status xml__texture(builder *B, pset *o, const char *name, rgb def, texture *out,
                               int *image) {
  *image = -1;
  prop *p = xml__find(o, name);
  if (!p) {
    *out = tex_constant(def);
    return LMC_OK;
  }
  if (p->kind == PROP_RGB || p->kind == PROP_FLOAT || p->kind == PROP_INT) {
    rgb c;
    lmc_status st = xml__rgb(B, o, name, def, &c, NULL);
    if (st != LMC_OK) return st;
    *out = tex_constant(c);
    return LMC_OK;
  }
  pset *t = NULL;
  if (p->kind == PROP_OBJECT) t = p->obj;
  else if (p->kind == PROP_REF) {
    lmc_status st = xml__deref(B, p, &t);
    if (st != LMC_OK) return st;
  } else {
    return xml__wrong(B, p, "a colour or a texture");
  }
  if (strcmp(t->tag, "texture") != 0)
    return xml__fail(B, LMC_EPARSE, p->file, p->line,
                     "property '%s' must be a colour or a texture, not a <%s>", name, t->tag);
  return xml__texture_object(B, t, def, out, image);
}

/* ---- BSDFs. ------------------------------------------------------------- */

static lmc_status xml__add_fixup(builder *B, int bsdf_index, int which, int image) {
  if (image < 0) return LMC_OK;
  if (B->n_fix == B->cap_fix) {
    int cap = B->cap_fix ? 2 * B->cap_fix : 16;
    tex_fixup *f = realloc(B->fix, (size_t)cap * sizeof *f);
    if (!f) return xml__fail(B, LMC_ENOMEM, NULL, 0, "out of memory");
    B->fix = f;
    B->cap_fix = cap;
  }
  B->fix[B->n_fix].bsdf = bsdf_index;
  B->fix[B->n_fix].which = which;
  B->fix[B->n_fix].image = image;
  B->n_fix++;
  return LMC_OK;
}

/* The single nested BSDF of a wrapper (twosided, bumpmap, ...): a nested
 * <bsdf> or a <ref> to one; NULL when there is none. */
static lmc_status xml__inner_bsdf(builder *B, pset *o, pset **out) {
  *out = NULL;
  for (int i = 0; i < o->n_props; i++) {
    prop *p = &o->props[i];
    pset *c = NULL;
    if (p->kind == PROP_OBJECT && strcmp(p->obj->tag, "bsdf") == 0) c = p->obj;
    else if (p->kind == PROP_REF) {
      lmc_status st = xml__deref(B, p, &c);
      if (st != LMC_OK) return st;
      if (strcmp(c->tag, "bsdf") != 0) continue;
    } else {
      continue;
    }
    p->used = 1;
    if (*out) {
      lmc_warn(p->file, p->line, "<%s type=\"%s\"> wraps more than one BSDF: using the first",
               o->tag, o->type);
      continue;
    }
    *out = c;
  }
  return LMC_OK;
}

/* 1 when o has a property `name` (without marking it read). */
static int xml__has(const pset *o, const char *name) {
  for (int i = 0; i < o->n_props; i++)
    if (strcmp(o->props[i].name, name) == 0) return 1;
  return 0;
}

texture *xml__tex_slot(bsdf *b, int which) {
  texture *slots[XML__TEX_SLOTS] = {&b->diffuse, &b->specular, &b->transmittance, &b->opacity,
                                    &b->bump};
  return slots[which];
}

/* A mask's opacity (Mitsuba's default 0.5): a colour or a texture, whose
 * values must lie in [0, 1] (an opacity above 1 would make the
 * pass-through's weight negative). */
static lmc_status xml__opacity(builder *B, pset *o, bsdf *b, int *img) {
  lmc_status st = xml__texture(B, o, "opacity", rgb_gray(0.5), &b->opacity, img);
  if (st != LMC_OK) return st;
  b->masked = 1;
  float lo = 0.0f, hi = 1.0f;
  if (b->opacity.type == TEX_CONSTANT) {
    rgb c = b->opacity.value;
    lo = (float)fmin(c.r, fmin(c.g, c.b));
    hi = (float)fmax(c.r, fmax(c.g, c.b));
  } else if (b->opacity.type == TEX_CHECKERBOARD) {
    rgb c0 = b->opacity.color0, c1 = b->opacity.color1;
    lo = (float)fmin(fmin(c0.r, fmin(c0.g, c0.b)), fmin(c1.r, fmin(c1.g, c1.b)));
    hi = (float)fmax(fmax(c0.r, fmax(c0.g, c0.b)), fmax(c1.r, fmax(c1.g, c1.b)));
  } else if (*img >= 0) {
    const lmc_image *im = &B->s->images[*img];
    size_t n = (size_t)im->width * im->height * im->channels;
    for (size_t i = 0; i < n; i++) lo = fminf(lo, im->data[i]), hi = fmaxf(hi, im->data[i]);
  }
  if (!(lo >= 0.0f && hi <= 1.0f)) {
    prop *p = xml__find(o, "opacity");
    return xml__fail(B, LMC_EPARSE, p->file, p->line,
                     "mask opacity must lie in [0, 1] (its values span %g to %g)", lo, hi);
  }
  return LMC_OK;
}

/* A bump map's displacement: its one <texture> (nested or a <ref>), whose
 * luminance's slope tilts the shading frame (bsdf.h). */
static lmc_status xml__bump(builder *B, pset *o, bsdf *b, int *img) {
  if (b->bumped)
    return xml__fail(B, LMC_EPARSE, o->file, o->line, "a bumpmap inside a bumpmap is not supported");
  pset *tex;
  prop *next;
  lmc_status st = xml__nested(B, o, "texture", &tex, &next);
  if (st != LMC_OK) return st;
  if (next)
    return xml__fail(B, LMC_EPARSE, next->file, next->line,
                     "a bumpmap takes one displacement texture");
  if (!tex)
    return xml__fail(B, LMC_EPARSE, o->file, o->line, "a bumpmap needs a displacement <texture>");
  b->bumped = 1;
  return xml__texture_object(B, tex, rgb_gray(0.0), &b->bump, img);
}

/* ---- The property readers of render/plugin.h, over one pset ----------------- */

const char *props_type(const plugin_props *p) { return p->o->type; }

int props_has(const plugin_props *p, const char *name) { return xml__has(p->o, name); }

lmc_status props_float(plugin_props *p, const char *name, double def, double *OUT,
                       int *OUT_found) {
  return xml__float(p->B, p->o, name, def, OUT, OUT_found);
}

lmc_status props_bool(plugin_props *p, const char *name, int def, int *OUT) {
  return xml__bool(p->B, p->o, name, def, OUT, NULL);
}

lmc_status props_string(plugin_props *p, const char *name, const char *def, const char **OUT) {
  return xml__string(p->B, p->o, name, def, OUT, NULL);
}

lmc_status props_rgb(plugin_props *p, const char *name, rgb def, rgb *OUT) {
  return xml__rgb(p->B, p->o, name, def, OUT, NULL);
}

lmc_status props_ior(plugin_props *p, const char *name, double def, double *OUT) {
  return xml__ior(p->B, p->o, name, def, OUT);
}

lmc_status props_roughness(plugin_props *p, const char *name, double def, double *OUT,
                           int *OUT_found) {
  prop *q = xml__find(p->o, name);
  if (q && (q->kind == PROP_OBJECT || q->kind == PROP_REF)) {
    lmc_warn(q->file, q->line, "a textured roughness '%s' is not supported: using %g", name, def);
    *OUT = def;
    if (OUT_found) *OUT_found = 0;
    return LMC_OK;
  }
  return xml__float(p->B, p->o, name, def, OUT, OUT_found);
}

lmc_status props_texture(plugin_props *p, const char *name, rgb def, texture *OUT) {
  int slot = 0;
  while (slot < XML__TEX_SLOTS && xml__tex_slot(p->b, slot) != OUT) slot++;
  if (slot == XML__TEX_SLOTS)
    return xml__fail(p->B, LMC_EINVAL, p->o->file, p->o->line,
                     "internal: '%s' is not one of the BSDF's texture slots", name);
  return xml__texture(p->B, p->o, name, def, OUT, &p->img[slot]);
}

lmc_status props_bsdfs(plugin_props *p, int max, int *OUT_index, int *OUT_n) {
  *OUT_n = 0;
  for (int i = 0; i < p->o->n_props; i++) {
    prop *q = &p->o->props[i];
    pset *c = NULL;
    if (q->kind == PROP_OBJECT && strcmp(q->obj->tag, "bsdf") == 0) c = q->obj;
    else if (q->kind == PROP_REF) {
      lmc_status st = xml__deref(p->B, q, &c);
      if (st != LMC_OK) return st;
      if (strcmp(c->tag, "bsdf") != 0) continue;
    } else {
      continue;
    }
    q->used = 1;
    if (*OUT_n == max)
      return xml__fail(p->B, LMC_EPARSE, q->file, q->line, "<bsdf type=\"%s\"> takes %d BSDFs",
                       p->o->type, max);
    lmc_status st = xml__bsdf(p->B, c, &OUT_index[(*OUT_n)++]);
    if (st != LMC_OK) return st;
  }
  return LMC_OK;
}

/* The file and line of property `name` of p, or of its element. */
static void props__where(plugin_props *p, const char *name, const char **file, int *line) {
  prop *q = name ? xml__find(p->o, name) : NULL;
  *file = q ? q->file : p->o->file;
  *line = q ? q->line : p->o->line;
}

/* An error (fail: LMC_EPARSE, returned) or a warning (LMC_OK) with the
 * message fmt at property `name` of p (props__where). */
static lmc_status props__report(plugin_props *p, const char *name, int fail, const char *fmt,
                                va_list ap) {
  char msg[900];
  vsnprintf(msg, sizeof msg, fmt, ap);
  const char *file;
  int line;
  props__where(p, name, &file, &line);
  if (fail) return xml__fail(p->B, LMC_EPARSE, file, line, "%s", msg);
  lmc_warn(file, line, "%s", msg);
  return LMC_OK;
}

lmc_status props_fail(plugin_props *p, const char *name, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  lmc_status st = props__report(p, name, 1, fmt, ap);
  va_end(ap);
  return st;
}

void props_warn(plugin_props *p, const char *name, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  props__report(p, name, 0, fmt, ap);
  va_end(ap);
}

/* Fills *b from a bsdf object; img[XML__TEX_SLOTS] get image indices of
 * the textures of xml__tex_slot (-1: none). Does not add to the scene. */
static lmc_status xml__make_bsdf(builder *B, pset *o, bsdf *b, int img[XML__TEX_SLOTS],
                                 int depth) {
  lmc_status st;
  for (int k = 0; k < XML__TEX_SLOTS; k++) img[k] = -1;
  if (depth > 8)
    return xml__fail(B, LMC_EPARSE, o->file, o->line, "BSDFs nested too deeply (a cycle?)");
  const char *t = o->type;
  if (strcmp(t, "twosided") == 0 || strcmp(t, "bumpmap") == 0 || strcmp(t, "normalmap") == 0 ||
      strcmp(t, "mask") == 0 || strcmp(t, "coating") == 0 || strcmp(t, "roughcoating") == 0) {
    /* Wrappers: twosided sets the flag, mask the flag and its opacity,
     * bumpmap the flag and its displacement; the others are not modelled
     * and fall back to the wrapped BSDF. */
    pset *inner;
    if ((st = xml__inner_bsdf(B, o, &inner)) != LMC_OK) return st;
    if (!inner) {
      if (strcmp(t, "twosided") == 0)
        return xml__fail(B, LMC_EPARSE, o->file, o->line, "<bsdf type=\"twosided\"> needs a nested BSDF");
      lmc_warn(o->file, o->line, "BSDF \"%s\" is not supported and wraps nothing: using diffuse", t);
      bsdf_init_defaults(b, "diffuse");
      for (int i = 0; i < o->n_props; i++) o->props[i].used = 1;
      return LMC_OK;
    }
    if ((st = xml__make_bsdf(B, inner, b, img, depth + 1)) != LMC_OK) return st;
    if (strcmp(t, "twosided") == 0) {
      b->twosided = 1;
      xml__warn_unused(o);
    } else if (strcmp(t, "bumpmap") == 0) {
      if ((st = xml__bump(B, o, b, &img[4])) != LMC_OK) return st;
      xml__warn_unused(o);
    } else if (strcmp(t, "mask") == 0) {
      if (b->masked)
        return xml__fail(B, LMC_EPARSE, o->file, o->line,
                         "a mask inside a mask is not supported (multiply the opacities)");
      if ((st = xml__opacity(B, o, b, &img[3])) != LMC_OK) return st;
      xml__warn_unused(o);
    } else {
      lmc_warn(o->file, o->line, "BSDF \"%s\" is not supported: using the BSDF it wraps", t);
      for (int i = 0; i < o->n_props; i++) o->props[i].used = 1;
    }
    if (o->id[0]) snprintf(b->id, sizeof b->id, "%.63s", o->id);
    return LMC_OK;
  }

  /* A model: its record's defaults, then its own parameters. */
  const bsdf_model *m = bsdf_model_find(t);
  if (!m) {
    lmc_warn(o->file, o->line, "unknown BSDF type \"%s\": using diffuse with reflectance 0.5", t);
    bsdf_init_defaults(b, "diffuse");
    for (int i = 0; i < o->n_props; i++) o->props[i].used = 1;
  } else {
    bsdf_init_model(b, m);
    plugin_props props = {B, o, b, img};
    if (m->read && (st = m->read(b, &props)) != LMC_OK) return st;
  }
  if (o->id[0]) snprintf(b->id, sizeof b->id, "%.63s", o->id);
  xml__warn_unused(o);
  return LMC_OK;
}

/* Builds a bsdf object into the scene once; returns its index. */
lmc_status xml__bsdf(builder *B, pset *o, int *out_index) {
  if (o->built) {
    *out_index = o->index;
    return LMC_OK;
  }
  if (o->building)
    return xml__fail(B, LMC_EPARSE, o->file, o->line, "the BSDF contains itself (through a <ref>)");
  bsdf b;
  memset(&b, 0, sizeof b);
  int img[XML__TEX_SLOTS];
  o->building = 1;
  lmc_status st = xml__make_bsdf(B, o, &b, img, 0);
  o->building = 0;
  if (st != LMC_OK) return st;
  bsdf_prepare(&b);
  int idx = scene_add_bsdf(B->s, &b, B->err);
  if (idx < 0) return (lmc_status)idx;
  for (int k = 0; k < XML__TEX_SLOTS; k++)
    if ((st = xml__add_fixup(B, idx, k, img[k])) != LMC_OK) return st;
  o->built = 1;
  o->index = idx;
  *out_index = idx;
  return LMC_OK;
}

lmc_status xml__default_bsdf(builder *B, int black, int *out_index) {
  if (B->default_bsdf[black] < 0) {
    bsdf b;
    memset(&b, 0, sizeof b);
    bsdf_init_defaults(&b, "diffuse");
    b.diffuse = tex_constant(rgb_gray(black ? 0.0 : 0.5));
    snprintf(b.id, sizeof b.id, "%s", black ? "(default black)" : "(default diffuse)");
    int idx = scene_add_bsdf(B->s, &b, B->err);
    if (idx < 0) return (lmc_status)idx;
    B->default_bsdf[black] = idx;
  }
  *out_index = B->default_bsdf[black];
  return LMC_OK;
}

