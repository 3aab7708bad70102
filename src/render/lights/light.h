/*
 * light.h: Mitsuba's emitters: area, point, spot, directional, constant and
 * envmap, with the sampling routines path tracing and BDPT need.
 *
 * Conventions: `wi` points from the receiving point towards the light; `le`
 * and `li` are radiance (intensity for point and spot, irradiance for
 * directional). Densities are in solid angle at the receiver (pdf_li) or,
 * for emission (sample_le), in area (pdf_pos, for infinite lights the area
 * of the disk of radius scene->radius facing the direction) times solid
 * angle (pdf_dir). Delta lights (point, spot, directional) set `delta`.
 *
 *  area        radiance; attached to a mesh, emits on the side of its
 *              geometric normal (one-sided, as Mitsuba's); triangles are
 *              sampled by area.
 *  point       intensity, position (from toWorld or <point name="position">).
 *  spot        intensity, cutoffAngle, beamWidth (Mitsuba's smooth falloff).
 *  directional irradiance, direction.
 *  constant    radiance from every direction.
 *  envmap      filename, scale, toWorld; latitude-longitude map, Mitsuba's
 *              orientation (+y up), importance sampled by luminance * sin(theta).
 *  sunsky, sky, sun
 *              not light types: the loader rasterizes them into an envmap's
 *              image (sunsky.h), as Mitsuba 0.6 does; with sunRadiusScale 0
 *              the sun is a directional light.
 */
#ifndef LMC_RENDER_LIGHT_H
#define LMC_RENDER_LIGHT_H

#include <stdint.h>

#include "render/distribution.h"
#include "render/frame.h"
#include "render/image.h"
#include "render/transform.h"
#include "render/vec3.h"

struct scene;

typedef enum light_type {
  LIGHT_AREA = 0,
  LIGHT_POINT,
  LIGHT_SPOT,
  LIGHT_DIRECTIONAL,
  LIGHT_CONSTANT,
  LIGHT_ENVMAP
} light_type;

typedef struct light {
  light_type type;
  rgb value;          /* radiance (area, constant), intensity (point, spot), irradiance (directional) */
  /* area */
  int mesh;           /* index into scene->meshes */
  distrib1d tri_dist; /* triangle areas */
  double area;        /* total area */
  /* point, spot */
  vec3 pos;
  frame frm;          /* spot: frm.n is the beam axis; directional: frm.n is the travel direction */
  double cos_cutoff, cos_beam, cutoff, beam_width; /* spot, radians/cosines */
  /* envmap */
  lmc_image image;    /* owned, 3 channels, lat-long */
  distrib2d env_dist;
  xform to_world;
  double scale;
} light;

typedef struct light_li_sample {
  vec3 wi;     /* unit, from the receiver towards the light */
  double dist; /* distance to the light point (INFINITY for infinite lights) */
  vec3 p;      /* point on the light (finite lights) */
  vec3 n;      /* light normal at p (area lights), else 0 */
  rgb li;      /* radiance arriving (intensity / dist^2 for point lights) */
  double pdf;  /* solid-angle density (1 for delta lights) */
  int delta;
  int64_t tri; /* area lights: the triangle of p in the light's mesh; else -1 */
} light_li_sample;

typedef struct light_le_sample {
  vec3 p;         /* origin of the emitted ray */
  vec3 n;         /* normal at p (area lights; for infinite lights the disk normal = dir), else 0 */
  vec3 dir;       /* unit emission direction */
  rgb le;         /* emitted radiance (intensity, irradiance) along dir */
  double pdf_pos; /* area density of p (1 for delta positions) */
  double pdf_dir; /* solid-angle density of dir (1 for delta directions) */
  int delta_pos, delta_dir;
  int64_t tri;    /* area lights: the triangle of p in the light's mesh; else -1 */
} light_le_sample;

/* Prepares sampling distributions once the scene's geometry and bounds are
 * known (called by scene_finalize). */
lmc_status light_prepare(light *l, const struct scene *s, lmc_error *err);
void light_free(light *l);
int light_is_delta(const light *l);
int light_is_infinite(const light *l);
/* Approximate emitted power, for choosing lights in proportion to it. */
double light_power(const light *l, const struct scene *s);

/* Samples a point on the light as seen from `ref`; returns 0 when nothing
 * can be sampled (e.g. ref behind a one-sided light). */
int light_sample_li(const light *l, const struct scene *s, vec3 ref, double u1, double u2,
                    light_li_sample *out);
/* Solid-angle density that light_sample_li picks direction wi from ref,
 * where wi reaches the light at p with normal n (finite area lights); for
 * infinite lights p and n are ignored. 0 for delta lights. */
double light_pdf_li(const light *l, const struct scene *s, vec3 ref, vec3 wi, vec3 p, vec3 n);
/* Radiance leaving area-light point with normal n in direction w. */
rgb light_le_area(const light *l, vec3 n, vec3 w);
/* Radiance arriving from infinite light along direction `dir` (pointing
 * away from the receiver). */
rgb light_le_infinite(const light *l, vec3 dir);
/* light_le_infinite(l, dir) and, in *OUT_pdf, light_pdf_li of the same
 * direction (what path tracing needs when a ray escapes), in one call: the
 * environment map's direction-to-pixel mapping is done once. Infinite
 * lights only (others: black, density 0). */
rgb light_le_pdf_infinite(const light *l, const struct scene *s, vec3 dir, double *OUT_pdf);

/* The solid-angle density of light_sample_le emitting from p (normal n)
 * along the unit travel direction dir (light_pdf_le's pdf_dir). */
double light_pdf_le_dir(const light *l, const struct scene *s, vec3 p, vec3 n, vec3 dir);

/* Samples an emitted ray (BDPT light subpaths) from four numbers. */
int light_sample_le(const light *l, const struct scene *s, double u1, double u2, double u3,
                    double u4, light_le_sample *out);
/* Densities of light_sample_le producing a ray from p (normal n) along dir.
 * For infinite lights dir is the travel direction and p is ignored. */
void light_pdf_le(const light *l, const struct scene *s, vec3 p, vec3 n, vec3 dir,
                  double *OUT_pdf_pos, double *OUT_pdf_dir);

/* The origin light_sample_le gives a ray of an infinite or directional
 * light travelling along the unit dir: a point uniform (density
 * 1 / (pi r^2)) on the disk of the scene's bounding radius r perpendicular
 * to dir, centred at the scene's centre minus r dir. */
vec3 light_disk_point(const struct scene *s, vec3 dir, double u1, double u2);
/* Its density, 1 / (pi r^2). */
double light_disk_pdf(const struct scene *s);

/* The inverse of light_disk_point: the (u1, u2) that give the point p of
 * the disk of direction dir. */
void light_disk_invert(const struct scene *s, vec3 dir, vec3 p, double *OUT_u1, double *OUT_u2);

/* The inverses of the samplers (inverse path sampling): the numbers with
 * which a sampler produces a given point or direction. Numbers the
 * sampler does not read (a delta light's) are copied from r; a point on
 * an area light names its triangle `tri` of the light's mesh. Each
 * returns 0 when the sampler cannot produce what it is given.
 * light_invert_li: (u1, u2) of light_sample_li reaching p (area) or
 * arriving along wi (constant, envmap) from ref. */
int light_invert_li(const light *l, const struct scene *s, vec3 ref, vec3 wi, vec3 p,
                    int64_t tri, const double r[2], double OUT_u[2]);
/* light_invert_le: (u1, u2, u3, u4) of light_sample_le emitting the ray
 * from p along dir (for infinite and directional lights, p on the disk of
 * light_disk_point). */
int light_invert_le(const light *l, const struct scene *s, vec3 p, vec3 dir, int64_t tri,
                    const double r[4], double OUT_u[4]);

/* The direction part of light_sample_le at a given point of a finite light
 * (area: cosine-weighted about the point's normal n; point: uniform; spot:
 * uniform in the cone): the same direction light_sample_le makes from
 * (u3, u4) there, and its solid-angle density (light_pdf_le's pdf_dir).
 * Returns 0 for other lights or when nothing is emitted that way. */
int light_sample_dir(const light *l, vec3 n, double u3, double u4, vec3 *OUT_dir,
                     double *OUT_pdf_dir);

#endif
