/*
 * scene_xml_internal.h: what the parts of the Mitsuba scene loader's second
 * pass share (not API): the builder, the errors, warnings and property
 * lookup (scene_xml_props.c) and the textures and BSDFs (scene_xml_bsdf.c)
 * that scene_xml.c's shapes, emitters, sensor and integrators use.
 * scene_xml.c's opening comment states the conventions.
 */
#ifndef LMC_RENDER_IO_SCENE_XML_INTERNAL_H
#define LMC_RENDER_IO_SCENE_XML_INTERNAL_H

#include <stdint.h>

#include "render/io/io.h"
#include "render/io/props.h"
#include "render/plugin.h"

#define XML_PI 3.14159265358979323846

typedef struct tex_fixup {
  int bsdf;  /* index into scene->bsdfs */
  int which; /* 0 diffuse, 1 specular, 2 transmittance, 3 opacity, 4 bump (XML__TEX_SLOTS) */
  int image; /* index into scene->images */
} tex_fixup;

/* The texture slots of a bsdf that may hold a bitmap (tex_fixup.which). */
#define XML__TEX_SLOTS 5
texture *xml__tex_slot(bsdf *b, int which);

typedef struct builder {
  scene *s;
  lmc_error *err;
  pdoc *doc;
  pset **ids;
  int n_ids, cap_ids;
  tex_fixup *fix;
  int n_fix, cap_fix;
  int default_bsdf[2]; /* shared default BSDFs: [0] diffuse 0.5, [1] black; -1 until made */
  int emitters_ignored; /* emitters left out (unsupported, misplaced): for the summary */
  spectrum_interp spectra; /* --spectra: how spectra the loader makes are read (the sun's) */
  int have_sensor;
  int spp_from_dpt;
} builder;

/* ---- Errors, warnings and property lookup (scene_xml_props.c). ---------- */

/* Sets B->err to code, file and line with a printf-style message; returns code. */
lmc_status xml__fail(builder *B, lmc_status code, const char *file, int line,
                     const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

/* Warns about everything on o the builder did not read, then marks it. */
void xml__warn_unused(pset *o);

/* Passes the unread plain values of an <integrator> or <dpt> block on to
 * the scene's params (scene.h), for the integrators' option tables. */
lmc_status xml__keep_params(builder *B, pset *o);

/* Passes a setting the loader translated from p (a Mitsuba parameter) on
 * to the option tables as the flag `name` with `value`, at p's place. */
lmc_status xml__pass(builder *B, const prop *p, const char *name, const char *value);

/* Marks the named properties as read without using them (accepted silently). */
void xml__accept(pset *o, const char *const *names);

/* The named property (value, named nested object or named ref); marks it. */
prop *xml__find(pset *o, const char *name);

lmc_status xml__wrong(builder *B, const prop *p, const char *want);

lmc_status xml__missing(builder *B, const pset *o, const char *name);

lmc_status xml__float(builder *B, pset *o, const char *name, double def, double *out,
                      int *found);

lmc_status xml__int(builder *B, pset *o, const char *name, long long def, long long *out,
                    int *found);

lmc_status xml__bool(builder *B, pset *o, const char *name, int def, int *out,
                     int *found);

/* *out is NULL when absent (and def is NULL). */
lmc_status xml__string(builder *B, pset *o, const char *name, const char *def,
                       const char **out, prop **where);

/* A string property that must be one of names[] (NULL-terminated): its
 * index, or def when absent; anything else is an error at its line. */
lmc_status xml__choice(builder *B, pset *o, const char *name, const char *const *names, int def,
                       int *out);

lmc_status xml__rgb(builder *B, pset *o, const char *name, rgb def, rgb *out,
                    int *found);

lmc_status xml__vec(builder *B, pset *o, const char *name, vec3 def, vec3 *out,
                    int *found);

lmc_status xml__xform(builder *B, pset *o, const char *name, xform *out, int *found);

/* An index of refraction: a number or a name known to ior_lookup. */
lmc_status xml__ior(builder *B, pset *o, const char *name, double def, double *out);

pset *xml__lookup_id(builder *B, const char *id);

/* The object a ref points to, or an error naming the ref's line. */
lmc_status xml__deref(builder *B, const prop *p, pset **out);

/* Registers every object with an id, recursively; duplicates are errors. */
lmc_status xml__register_ids(builder *B, pset *o);

/* Resolves a file name against the folder of the XML file `base`. */
void xml__resolve(const char *base, const char *name, char *out, size_t size);

/* A file property, resolved; missing property is an error, and so is a file
 * that cannot be opened (LMC_EIO at the property's line). */
lmc_status xml__file(builder *B, pset *o, const char *name, const char *what,
                     char *out, size_t size, prop **where);

/* Re-labels an error from a reader (which names the data file) with the
 * XML element that asked for it, keeping the reader's text. */
lmc_status xml__relabel(builder *B, lmc_status st, const prop *p, const char *what);

/* ---- Emitters (scene_xml_emitter.c). ---------------------------------------- */

/* Builds a top-level <emitter> into the scene (an unsupported type warns,
 * counted in B->emitters_ignored). */
lmc_status xml__emitter(builder *B, pset *o);

/* scene_xml_integrator.c: an <integrator> (nested: inside another, whose
 * choice of integrator stands) and the reference implementation's <dpt>
 * block, into the scene's settings. */
lmc_status xml__integrator(builder *B, pset *o, int nested);
lmc_status xml__dpt(builder *B, pset *o);

/* ---- Textures and BSDFs (scene_xml_bsdf.c). ------------------------------ */

/* Counts the texels of img that are NaN or infinite; with `repair`, also
 * those that are negative, and sets all of them to 0. */
int64_t xml__bad_texels(lmc_image *img, int repair);

/* Builds a bsdf object into the scene once; returns its index. */
lmc_status xml__bsdf(builder *B, pset *o, int *out_index);

/* render/plugin.h's property set: one element read by a model (a BSDF:
 * b and img give its texture slots; else both NULL). */
struct plugin_props {
  builder *B;
  pset *o;
  bsdf *b;  /* the BSDF being read: its texture slots */
  int *img; /* image index per slot (XML__TEX_SLOTS), -1: none */
};

/* The first object of o with tag `tag` (a nested element or a <ref> to
 * one), marked read, into *OUT_first (NULL: none); the property of the
 * next one, if there is one, into *OUT_next (left unread). */
lmc_status xml__nested(builder *B, pset *o, const char *tag, pset **OUT_first, prop **OUT_next);

/* ---- Media (scene_xml_medium.c). ------------------------------------------- */

/* Builds a <medium> into the scene once: *out_index its index, or -1 for a
 * medium type lmc does not have (warned). */
lmc_status xml__medium(builder *B, pset *o, int *out_index);

/* The BSDF of a shape that names none, as Mitsuba gives it: black when
 * the shape emits (black = 1), else diffuse 0.5; shared, made once. */
lmc_status xml__default_bsdf(builder *B, int black, int *out_index);

#endif
