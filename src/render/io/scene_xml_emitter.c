/*
 * scene_xml_emitter.c: the scene loader's emitters (scene_xml_internal.h):
 * point, spot, directional, constant, envmap, and Mitsuba's daylight
 * emitters sunsky, sky and sun rasterized into an environment map
 * (lights/sunsky.h). Area emitters are nested in shapes (scene_xml.c).
 * Unsupported or misplaced emitters warn and are counted
 * (builder.emitters_ignored) for the scene's no-light warning.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/io/scene_xml_internal.h"
#include "render/lights/sunsky.h"

/* ---- Emitters. ---------------------------------------------------------- */

/* The file and line of o's property `name` and 1, or those of o and 0 when
 * it is absent (the property is not marked read). */
static int xml__where(const pset *o, const char *name, const char **file, int *line) {
  *file = o->file;
  *line = o->line;
  for (int i = 0; i < o->n_props; i++)
    if (o->props[i].kind != PROP_OBJECT && strcmp(o->props[i].name, name) == 0) {
      *file = o->props[i].file;
      *line = o->props[i].line;
      return 1;
    }
  return 0;
}

/* An error at o's property `name` (or at o): "<type> emitter: <what>". */
static lmc_status xml__bad_at(builder *B, const pset *o, const char *name, const char *what) {
  const char *file;
  int line;
  xml__where(o, name, &file, &line);
  return xml__fail(B, LMC_EPARSE, file, line, "%s emitter: %s", o->type, what);
}

/* The parameters of sunsky, sky and sun (Mitsuba's names, defaults and
 * ranges) into *p and the emitter's toWorld into *OUT_tw. */
static lmc_status xml__sunsky_params(builder *B, pset *o, sunsky_params *p, xform *OUT_tw) {
  lmc_status st;
  int is_sunsky = strcmp(o->type, "sunsky") == 0, is_sky = strcmp(o->type, "sky") == 0;
  double scale;
  long long res;
  if ((st = xml__xform(B, o, "toWorld", OUT_tw, NULL)) != LMC_OK) return st;
  if ((st = xml__float(B, o, "turbidity", 3.0, &p->turbidity, NULL)) != LMC_OK) return st;
  if ((st = xml__float(B, o, "stretch", 1.0, &p->stretch, NULL)) != LMC_OK) return st;
  if ((st = xml__int(B, o, "resolution", 512, &res, NULL)) != LMC_OK) return st;
  if ((st = xml__float(B, o, "scale", 1.0, &scale, NULL)) != LMC_OK) return st;
  if (!(p->turbidity >= 1.0 && p->turbidity <= 10.0))
    return xml__bad_at(B, o, "turbidity", "turbidity must be in [1, 10]");
  if (!(p->stretch >= 1.0 && p->stretch <= 2.0))
    return xml__bad_at(B, o, "stretch", "stretch must be in [1, 2]");
  if (res < 2 || res > IMAGE_MAX_SIDE)
    return xml__bad_at(B, o, "resolution", "resolution must be in [2, 16384]");
  p->resolution = (int)res;
  if (!(scale >= 0.0)) return xml__bad_at(B, o, "scale", "scale must not be negative");
  p->sky_scale = p->sun_scale = scale;
  if (!is_sky) {
    if ((st = xml__float(B, o, "sunRadiusScale", 1.0, &p->sun_radius_scale, NULL)) != LMC_OK)
      return st;
    /* The disk at most a hemisphere: r = sunRadiusScale * 0.2679 <= 90 degrees. */
    if (!(p->sun_radius_scale >= 0.0 &&
          p->sun_radius_scale * SUNSKY_SUN_APP_RADIUS * 0.5 <= 90.0))
      return xml__bad_at(B, o, "sunRadiusScale",
                         "sunRadiusScale must be in [0, 335.9] (the sun at most a hemisphere)");
  }
  if (is_sunsky) {
    if ((st = xml__float(B, o, "sunScale", scale, &p->sun_scale, NULL)) != LMC_OK) return st;
    if ((st = xml__float(B, o, "skyScale", scale, &p->sky_scale, NULL)) != LMC_OK) return st;
    if (!(p->sun_scale >= 0.0))
      return xml__bad_at(B, o, "sunScale", "sunScale must not be negative");
    if (!(p->sky_scale >= 0.0))
      return xml__bad_at(B, o, "skyScale", "skyScale must not be negative");
  }
  if (p->sky) {
    if ((st = xml__rgb(B, o, "albedo", rgb_gray(0.2), &p->albedo, NULL)) != LMC_OK) return st;
    if (!(p->albedo.r >= 0.0 && p->albedo.r <= 1.0 && p->albedo.g >= 0.0 && p->albedo.g <= 1.0 &&
          p->albedo.b >= 0.0 && p->albedo.b <= 1.0))
      return xml__bad_at(B, o, "albedo", "albedo must be in [0, 1]");
    if ((st = xml__bool(B, o, "extend", 0, &p->extend, NULL)) != LMC_OK) return st;
  }

  return LMC_OK;
}

/* The sun's position into p->sun_dir: sunDirection (in the emitter's frame
 * tw), or date, time and place (Mitsuba's defaults: Tokyo, 2010-07-10 15:00). */
static lmc_status xml__sun_position(builder *B, pset *o, const xform *tw, sunsky_params *p) {
  lmc_status st;
  const char *t = o->type;
  vec3 dir;
  int has_dir;
  if ((st = xml__vec(B, o, "sunDirection", v3(0, 1, 0), &dir, &has_dir)) != LMC_OK) return st;
  if (has_dir) {
    static const char *const place[] = {"latitude", "longitude", "timezone", "day"};
    for (int i = 0; i < 4; i++) {
      const char *file;
      int line;
      if (xml__where(o, place[i], &file, &line))
        return xml__fail(B, LMC_EPARSE, file, line,
                         "%s emitter: sunDirection and %s given: only one of them can be", t,
                         place[i]);
    }
    vec3 local = xform_inv_vector(tw, dir);
    if (!(v3_len2(local) > 0.0) || !v3_isfinite(local))
      return xml__bad_at(B, o, "sunDirection", "sunDirection is zero");
    p->sun_dir = sunsky_from_dir(local);
  } else {
    sunsky_time when;
    sunsky_place where;
    long long year, month, day;
    if ((st = xml__int(B, o, "year", 2010, &year, NULL)) != LMC_OK) return st;
    if ((st = xml__int(B, o, "month", 7, &month, NULL)) != LMC_OK) return st;
    if ((st = xml__int(B, o, "day", 10, &day, NULL)) != LMC_OK) return st;
    if ((st = xml__float(B, o, "hour", 15.0, &when.hour, NULL)) != LMC_OK) return st;
    if ((st = xml__float(B, o, "minute", 0.0, &when.minute, NULL)) != LMC_OK) return st;
    if ((st = xml__float(B, o, "second", 0.0, &when.second, NULL)) != LMC_OK) return st;
    if ((st = xml__float(B, o, "latitude", 35.6894, &where.latitude, NULL)) != LMC_OK) return st;
    if ((st = xml__float(B, o, "longitude", 139.6917, &where.longitude, NULL)) != LMC_OK)
      return st;
    if ((st = xml__float(B, o, "timezone", 9.0, &where.timezone, NULL)) != LMC_OK) return st;
    if (year < -1000000 || year > 1000000)
      return xml__bad_at(B, o, "year", "year out of range");
    if (month < 1 || month > 12) return xml__bad_at(B, o, "month", "month must be in [1, 12]");
    if (day < 1 || day > 31) return xml__bad_at(B, o, "day", "day must be in [1, 31]");
    if (!(where.latitude >= -90.0 && where.latitude <= 90.0))
      return xml__bad_at(B, o, "latitude", "latitude must be in [-90, 90]");
    when.year = (int)year;
    when.month = (int)month;
    when.day = (int)day;
    p->sun_dir = sunsky_sun_position(&when, &where);
  }
  if (!(p->sun_dir.theta <= 0.5 * XML_PI))
    return xml__bad_at(B, o, has_dir ? "sunDirection" : "hour",
                       "the sun is below the horizon, which the sky model does not cover");
  return LMC_OK;
}

/* Mitsuba's sunsky, sky and sun emitters (sunsky.h): the sun's position
 * from sunDirection or from date, time and place, the parameters checked
 * as Mitsuba checks them (turbidity in [1, 10], stretch in [1, 2], albedo
 * in [0, 1], the sun above the horizon, sunDirection not together with
 * latitude, longitude, timezone or day) and a few more that would make
 * nonsense (negative scales, month, day, resolution), then rasterized into
 * an envmap light. `scale` is the default of sunScale and skyScale (the
 * envmap itself has scale 1, as in Mitsuba); with sunRadiusScale = 0 the
 * sun is a directional light of the disk's irradiance instead. */
static lmc_status xml__sunsky(builder *B, pset *o) {
  lmc_status st;
  const char *t = o->type;
  int is_sky = strcmp(t, "sky") == 0;
  sunsky_params p;
  sunsky_params_default(&p);
  p.spectra = B->spectra;
  p.sky = !strcmp(t, "sun") ? 0 : 1;
  p.sun = is_sky ? 0 : 1;

  xform tw;
  if ((st = xml__sunsky_params(B, o, &p, &tw)) != LMC_OK) return st;
  if ((st = xml__sun_position(B, o, &tw, &p)) != LMC_OK) return st;
  xml__warn_unused(o);

  /* The map; with sunRadiusScale = 0 the sun is a directional light. */
  int directional_sun = p.sun && p.sun_radius_scale == 0.0;
  light l;
  memset(&l, 0, sizeof l);
  l.mesh = -1;
  if (directional_sun) {
    vec3 to_sun;
    l.type = LIGHT_DIRECTIONAL;
    l.value = sunsky_sun_irradiance(&p, &to_sun);
    l.frm = frame_from_z(v3_normalize(v3_scale(xform_vector(&tw, to_sun), -1.0)));
    l.to_world = tw;
    l.scale = 1.0;
    int li = scene_add_light(B->s, &l, B->err);
    if (li < 0) return (lmc_status)li;
    p.sun = 0;
    p.sun_radius_scale = 1.0;
    if (!p.sky) return LMC_OK;
    memset(&l, 0, sizeof l);
    l.mesh = -1;
  }
  l.type = LIGHT_ENVMAP;
  l.value = rgb_gray(1.0);
  l.scale = 1.0;
  l.to_world = tw;
  if ((st = sunsky_rasterize(&p, &l.image, B->err)) != LMC_OK) {
    char msg[sizeof B->err->msg];
    snprintf(msg, sizeof msg, "%s", B->err->msg);
    image_free(&l.image);
    return xml__fail(B, st, o->file, o->line, "%s emitter: %s", t, msg);
  }
  int64_t bad = xml__bad_texels(&l.image, 1);
  if (bad > 0)
    lmc_warn(o->file, o->line, "%s emitter: %lld NaN, infinite or negative values set to 0", t,
             (long long)bad);
  int li = scene_add_light(B->s, &l, B->err);
  if (li < 0) {
    image_free(&l.image);
    return (lmc_status)li;
  }
  return LMC_OK;
}

lmc_status xml__emitter(builder *B, pset *o) {
  lmc_status st;
  light l;
  memset(&l, 0, sizeof l);
  l.mesh = -1;
  l.scale = 1.0;
  l.to_world = xform_identity();
  const char *t = o->type;
  xform tw;
  int has_tw;
  static const char *const silent[] = {"samplingWeight", NULL};
  xml__accept(o, silent);

  if (strcmp(t, "point") == 0) {
    l.type = LIGHT_POINT;
    if ((st = xml__rgb(B, o, "intensity", rgb_gray(1.0), &l.value, NULL)) != LMC_OK) return st;
    if ((st = xml__xform(B, o, "toWorld", &tw, &has_tw)) != LMC_OK) return st;
    vec3 p = xform_point(&tw, v3(0, 0, 0));
    if ((st = xml__vec(B, o, "position", p, &l.pos, NULL)) != LMC_OK) return st;
    l.to_world = tw;
  } else if (strcmp(t, "spot") == 0) {
    l.type = LIGHT_SPOT;
    double cutoff, beam;
    if ((st = xml__rgb(B, o, "intensity", rgb_gray(1.0), &l.value, NULL)) != LMC_OK) return st;
    if ((st = xml__float(B, o, "cutoffAngle", 20.0, &cutoff, NULL)) != LMC_OK) return st;
    if ((st = xml__float(B, o, "beamWidth", cutoff * 0.75, &beam, NULL)) != LMC_OK) return st;
    if (!(cutoff > 0.0 && cutoff <= 180.0) || !(beam > 0.0))
      return xml__fail(B, LMC_EPARSE, o->file, o->line, "bad spot angles (cutoff %g, beam %g)",
                       cutoff, beam);
    if (beam > cutoff) beam = cutoff;
    if ((st = xml__xform(B, o, "toWorld", &tw, NULL)) != LMC_OK) return st;
    l.to_world = tw;
    l.pos = xform_point(&tw, v3(0, 0, 0));
    l.frm = frame_from_z(v3_normalize(xform_vector(&tw, v3(0, 0, 1))));
    l.cutoff = cutoff * XML_PI / 180.0;
    l.beam_width = beam * XML_PI / 180.0;
    l.cos_cutoff = cos(l.cutoff);
    l.cos_beam = cos(l.beam_width);
  } else if (strcmp(t, "directional") == 0) {
    l.type = LIGHT_DIRECTIONAL;
    if ((st = xml__rgb(B, o, "irradiance", rgb_gray(1.0), &l.value, NULL)) != LMC_OK) return st;
    if ((st = xml__xform(B, o, "toWorld", &tw, NULL)) != LMC_OK) return st;
    vec3 d;
    if ((st = xml__vec(B, o, "direction", xform_vector(&tw, v3(0, 0, 1)), &d, NULL)) != LMC_OK)
      return st;
    if (!(v3_len2(d) > 0.0))
      return xml__fail(B, LMC_EPARSE, o->file, o->line, "directional emitter: zero direction");
    l.frm = frame_from_z(v3_normalize(d));
    l.to_world = tw;
  } else if (strcmp(t, "constant") == 0) {
    l.type = LIGHT_CONSTANT;
    if ((st = xml__rgb(B, o, "radiance", rgb_gray(1.0), &l.value, NULL)) != LMC_OK) return st;
  } else if (strcmp(t, "envmap") == 0) {
    l.type = LIGHT_ENVMAP;
    char path[1024];
    prop *fp;
    if ((st = xml__file(B, o, "filename", "environment map", path, sizeof path, &fp)) != LMC_OK)
      return st;
    if ((st = xml__float(B, o, "scale", 1.0, &l.scale, NULL)) != LMC_OK) return st;
    if ((st = xml__xform(B, o, "toWorld", &l.to_world, NULL)) != LMC_OK) return st;
    double gamma;
    int has_gamma;
    if ((st = xml__float(B, o, "gamma", -1.0, &gamma, &has_gamma)) != LMC_OK) return st;
    if (has_gamma && gamma != -1.0 && gamma != 1.0)
      lmc_warn(o->file, o->line, "envmap gamma %g is approximated by the sRGB curve", gamma);
    static const char *const env_silent[] = {"cache", NULL};
    xml__accept(o, env_silent);
    l.value = rgb_gray(1.0);
    st = image_read(path, !(has_gamma && gamma == 1.0), &l.image, B->err);
    if (st == LMC_OK) st = image_to_rgb(&l.image, B->err);
    if (st != LMC_OK) {
      image_free(&l.image);
      return xml__relabel(B, st, fp, "environment map");
    }
    /* The light's sampling distribution needs finite, non-negative values. */
    int64_t bad = xml__bad_texels(&l.image, 1);
    if (bad > 0)
      lmc_warn(fp->file, fp->line,
               "environment map '%s' has %lld NaN, infinite or negative values: set to 0", fp->s,
               (long long)bad);
  } else if (strcmp(t, "sunsky") == 0 || strcmp(t, "sky") == 0 || strcmp(t, "sun") == 0) {
    return xml__sunsky(B, o);
  } else if (strcmp(t, "area") == 0) {
    lmc_warn(o->file, o->line, "an area emitter must be nested in a shape: ignored");
    for (int i = 0; i < o->n_props; i++) o->props[i].used = 1;
    B->emitters_ignored++;
    return LMC_OK;
  } else {
    lmc_warn(o->file, o->line, "unsupported emitter type \"%s\": ignored", t);
    for (int i = 0; i < o->n_props; i++) o->props[i].used = 1;
    B->emitters_ignored++;
    return LMC_OK;
  }
  xml__warn_unused(o);
  int li = scene_add_light(B->s, &l, B->err);
  if (li < 0) {
    image_free(&l.image);
    return (lmc_status)li;
  }
  return LMC_OK;
}
