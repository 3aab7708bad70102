/*
 * camera.c: the pinhole camera (Mitsuba's `perspective` sensor).
 *
 * A raster point (rx, ry) maps to the image-plane point at distance 1
 *   x = -(2 rx / W - 1) tan_half_x,   y = -(2 ry / H - 1) tan_half_y
 * (camera +x is the image's left, +y its top), and the ray direction is
 * to_world applied to (x, y, 1). to_world may mirror (Mitsuba scenes use
 * scale x=-1 for that); directions are normalised after transforming.
 *
 * Importance (see camera.h): We = W H / (A cos^4 theta) with A = 4
 * tan_half_x tan_half_y; the density of the direction of a ray through a
 * uniformly chosen raster point is 1 / (A cos^3 theta).
 */
#include "render/camera.h"

#include <stdio.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static void camera__update(camera *c) {
  double t = tan(0.5 * c->fov_deg * M_PI / 180.0);
  double w = c->width, h = c->height;
  const char *axis = c->fov_axis;
  if (strcmp(axis, "smaller") == 0) axis = (w <= h) ? "x" : "y";
  if (strcmp(axis, "larger") == 0) axis = (w >= h) ? "x" : "y";
  if (strcmp(axis, "y") == 0) {
    c->tan_half_y = t;
    c->tan_half_x = t * w / h;
  } else if (strcmp(axis, "diagonal") == 0) {
    double d = sqrt(w * w + h * h);
    c->tan_half_x = t * w / d;
    c->tan_half_y = t * h / d;
  } else {
    c->tan_half_x = t;
    c->tan_half_y = t * h / w;
  }
  c->pos = xform_point(&c->to_world, v3(0.0, 0.0, 0.0));
  c->forward = v3_normalize(xform_vector(&c->to_world, v3(0.0, 0.0, 1.0)));
}

int camera_set_fov(camera *c, double fov_deg, const char *fov_axis, int width, int height) {
  if (!(fov_deg > 0.0 && fov_deg < 180.0) || width <= 0 || height <= 0) return 0;
  if (strcmp(fov_axis, "x") && strcmp(fov_axis, "y") && strcmp(fov_axis, "diagonal") &&
      strcmp(fov_axis, "smaller") && strcmp(fov_axis, "larger"))
    return 0;
  c->fov_deg = fov_deg;
  snprintf(c->fov_axis, sizeof c->fov_axis, "%s", fov_axis);
  c->width = width;
  c->height = height;
  camera__update(c);
  return 1;
}

void camera_set_resolution(camera *c, int width, int height) {
  c->width = width;
  c->height = height;
  camera__update(c);
}

void camera_generate_ray(const camera *c, double rx, double ry, vec3 *org, vec3 *dir) {
  double x = -(2.0 * rx / c->width - 1.0) * c->tan_half_x;
  double y = -(2.0 * ry / c->height - 1.0) * c->tan_half_y;
  *org = c->pos;
  *dir = v3_normalize(xform_vector(&c->to_world, v3(x, y, 1.0)));
}

/* Camera-space unit direction of a world direction. */
static vec3 camera__local(const camera *c, vec3 dir) {
  return v3_normalize(xform_inv_vector(&c->to_world, dir));
}

int camera_raster(const camera *c, vec3 dir, double *rx, double *ry) {
  vec3 d = camera__local(c, dir);
  if (!(d.z > 0.0)) return 0;
  *rx = (1.0 - d.x / d.z / c->tan_half_x) * 0.5 * c->width;
  *ry = (1.0 - d.y / d.z / c->tan_half_y) * 0.5 * c->height;
  return isfinite(*rx) && isfinite(*ry);
}

double camera_we(const camera *c, vec3 dir, double *rx, double *ry) {
  vec3 d = camera__local(c, dir);
  if (!(d.z > 0.0)) return 0.0;
  double x = d.x / d.z, y = d.y / d.z;
  double px = (1.0 - x / c->tan_half_x) * 0.5 * c->width;
  double py = (1.0 - y / c->tan_half_y) * 0.5 * c->height;
  if (!(px >= 0.0 && px < c->width && py >= 0.0 && py < c->height)) return 0.0;
  *rx = px;
  *ry = py;
  double a = 4.0 * c->tan_half_x * c->tan_half_y;
  double cos2 = d.z * d.z;
  return (double)c->width * c->height / (a * cos2 * cos2);
}

double camera_pdf_dir(const camera *c, vec3 dir) {
  vec3 d = camera__local(c, dir);
  if (!(d.z > 0.0)) return 0.0;
  double x = d.x / d.z, y = d.y / d.z;
  if (fabs(x) > c->tan_half_x || fabs(y) > c->tan_half_y) return 0.0;
  double a = 4.0 * c->tan_half_x * c->tan_half_y;
  return 1.0 / (a * d.z * d.z * d.z);
}

int camera_invert(const camera *c, vec3 dir, double *OUT_u1, double *OUT_u2) {
  double rx, ry;
  if (!(camera_we(c, dir, &rx, &ry) > 0.0)) return 0;
  *OUT_u1 = fmin(rx / c->width, nextafter(1.0, 0.0));
  *OUT_u2 = fmin(ry / c->height, nextafter(1.0, 0.0));
  return *OUT_u1 >= 0.0 && *OUT_u2 >= 0.0;
}
