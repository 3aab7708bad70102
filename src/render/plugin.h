/*
 * plugin.h: what a render model (a BSDF now; emitters, textures and media
 * as they become records) reads from the scene: its plugin's properties by
 * Mitsuba's names, as Mitsuba's plugins read their Properties. The scene
 * loader (render/io) implements it over its property sets; a model never
 * sees XML. Every reader marks what it reads, so what a model leaves is
 * reported by the loader as unused; errors and warnings name the file and
 * line of the property (or of the element when it is absent).
 *
 * Each reader returns LMC_OK or a status whose message is already in the
 * loader's error; `def` is the value when the property is absent.
 */
#ifndef LMC_RENDER_PLUGIN_H
#define LMC_RENDER_PLUGIN_H

#include "render/error.h"
#include "render/spectrum.h"

struct texture;

/* One element's properties as the loader holds them (opaque). */
typedef struct plugin_props plugin_props;

/* The plugin's name (the element's `type`). */
const char *props_type(const plugin_props *p);
/* 1 when the element has the property `name` (without marking it read). */
int props_has(const plugin_props *p, const char *name);
/* A number (<float> or <integer>). *OUT_found (may be NULL): 1 when present. */
lmc_status props_float(plugin_props *p, const char *name, double def, double *OUT, int *OUT_found);
/* A <boolean>. */
lmc_status props_bool(plugin_props *p, const char *name, int def, int *OUT);
/* A <string>; *OUT is NULL when absent and def is NULL. */
lmc_status props_string(plugin_props *p, const char *name, const char *def, const char **OUT);
/* A colour (<rgb>, <srgb>, <spectrum>, <blackbody>, or a number as grey). */
lmc_status props_rgb(plugin_props *p, const char *name, rgb def, rgb *OUT);
/* An index of refraction: a number or a name known to ior_lookup (bsdf.h). */
lmc_status props_ior(plugin_props *p, const char *name, double def, double *OUT);
/* A roughness Mitsuba also takes as a texture: a number, or a texture,
 * which warns (one roughness per model) and counts as absent (*OUT = def,
 * *OUT_found = 0). */
lmc_status props_roughness(plugin_props *p, const char *name, double def, double *OUT,
                           int *OUT_found);
/* A colour or a texture (nested <texture> or <ref>) into *OUT, one of the
 * model's texture slots (the loader keeps its bitmap's image attached). */
lmc_status props_texture(plugin_props *p, const char *name, rgb def, struct texture *OUT);
/* The BSDFs nested in the element (<bsdf> children or <ref>s to BSDFs, in
 * document order), each built into the scene: their scene indices into
 * OUT_index (at most max; more is an error), their number in *OUT_n. */
lmc_status props_bsdfs(plugin_props *p, int max, int *OUT_index, int *OUT_n);
/* An error at the property `name` (the element when name is NULL or
 * absent): LMC_EPARSE with the message; returns that status. */
lmc_status props_fail(plugin_props *p, const char *name, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* A warning at the property `name` (the element when NULL or absent). */
void props_warn(plugin_props *p, const char *name, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

#endif
