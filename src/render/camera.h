/*
 * camera.h: Mitsuba's `perspective` sensor (a pinhole).
 *
 * Camera space: +z looks forward, +y up, +x to the left of the image (as in
 * Mitsuba's lookat). Raster space: (0,0) is the top-left corner of the film,
 * (width, height) the bottom-right, in pixels.
 *
 * Importance is normalised per pixel: for a direction w through raster point
 * r, camera_we returns W * H / (A cos^4 theta), where A is the area of the
 * image rectangle at distance 1 and theta the angle to the optical axis
 * (W * H / A is the number of pixels per unit of image-plane area). One
 * light path, splatted (film_splat) with this We, estimates every pixel at
 * once; the mean of N such splats (film splat_scale = 1/N) estimates the
 * same pixel values as tracing camera rays.
 */
#ifndef LMC_RENDER_CAMERA_H
#define LMC_RENDER_CAMERA_H

#include "render/transform.h"
#include "render/vec3.h"

typedef struct camera {
  xform to_world;        /* camera to world (no scale) */
  vec3 pos;              /* world position of the pinhole */
  vec3 forward;          /* world optical axis */
  int width, height;     /* film resolution */
  double tan_half_x;     /* half extent of the image at distance 1, x */
  double tan_half_y;     /* half extent of the image at distance 1, y */
  double near_clip, far_clip;
  double fov_deg;        /* the scene's fov and the axis it applies to */
  char fov_axis[16];
  int medium;            /* 1 + index into scene->media of the medium around it; 0: none */
} camera;

/* Sets the projection from Mitsuba's fov (degrees) and fovAxis
 * ("x", "y", "diagonal", "smaller", "larger") for the given film size.
 * Returns 0 when fov is outside (0, 180). */
int camera_set_fov(camera *c, double fov_deg, const char *fov_axis, int width, int height);
/* Changes the resolution keeping the field of view of the fov axis used. */
void camera_set_resolution(camera *c, int width, int height);

/* World-space ray through raster point (rx, ry); dir is unit. */
void camera_generate_ray(const camera *c, double rx, double ry, vec3 *org, vec3 *dir);
/* Importance We along world direction dir leaving the pinhole, and the
 * raster point it passes through; 0 when it misses the film. */
double camera_we(const camera *c, vec3 dir, double *rx, double *ry);
/* The raster point of world direction dir leaving the pinhole, inside the
 * film or not (what camera_generate_ray inverts); 0 behind the camera. */
int camera_raster(const camera *c, vec3 dir, double *rx, double *ry);
/* The inverse of the film sample: the numbers (u1, u2) in [0, 1)^2 whose
 * raster point (u1 W, u2 H) gives the ray along world direction dir;
 * returns 0 when dir misses the film. */
int camera_invert(const camera *c, vec3 dir, double *OUT_u1, double *OUT_u2);
/* Solid-angle density of camera_generate_ray producing dir, for a raster
 * point chosen uniformly over the film (the BDPT s=... pdf). */
double camera_pdf_dir(const camera *c, vec3 dir);

#endif
