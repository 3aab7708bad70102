/*
 * warp.h: maps from the unit square to the domains light transport samples,
 * each as a triple: sample (u -> x), pdf (density of x in the target
 * measure) and invert (x -> u, so that sample(invert(x)) = x). The inverses
 * let MCMC methods map a path back into primary sample space.
 */
#ifndef LMC_RENDER_WARP_H
#define LMC_RENDER_WARP_H

#include "render/vec3.h"

/* Shirley-Chiu concentric map to the unit disk (pdf 1/pi w.r.t. area). */
void warp_square_to_disk_concentric(double u1, double u2, double *x, double *y);
double warp_square_to_disk_concentric_pdf(double x, double y);
void warp_disk_concentric_to_square(double x, double y, double *u1, double *u2);

/* Cosine-weighted hemisphere around +z (Malley's method), pdf cos/pi. */
vec3 warp_square_to_cosine_hemisphere(double u1, double u2);
double warp_square_to_cosine_hemisphere_pdf(vec3 w);
void warp_cosine_hemisphere_to_square(vec3 w, double *u1, double *u2);

/* Uniform sphere, pdf 1/(4 pi). */
vec3 warp_square_to_uniform_sphere(double u1, double u2);
double warp_square_to_uniform_sphere_pdf(vec3 w);
void warp_uniform_sphere_to_square(vec3 w, double *u1, double *u2);

/* Uniform hemisphere around +z, pdf 1/(2 pi). */
vec3 warp_square_to_uniform_hemisphere(double u1, double u2);
double warp_square_to_uniform_hemisphere_pdf(vec3 w);
void warp_uniform_hemisphere_to_square(vec3 w, double *u1, double *u2);

/* Uniform cone around +z with cos(half angle) = cos_max, pdf 1/(2 pi (1-cos_max)). */
vec3 warp_square_to_uniform_cone(double u1, double u2, double cos_max);
double warp_square_to_uniform_cone_pdf(vec3 w, double cos_max);
void warp_uniform_cone_to_square(vec3 w, double cos_max, double *u1, double *u2);

/* Uniform point on a triangle as barycentrics (b1, b2) of vertices 1 and 2
 * (pdf 1/area w.r.t. area on the triangle). */
void warp_square_to_triangle(double u1, double u2, double *b1, double *b2);
void warp_triangle_to_square(double b1, double b2, double *u1, double *u2);

/* A number uniform in [lo, hi) from r in [0, 1): lo + r (hi - lo), kept
 * below hi where rounding reaches it (the inverses' draw inside a discrete
 * choice's interval). */
double warp_uniform_in(double lo, double hi, double r);

/* An angle in radians as a fraction of a turn in [0, 1) (what 2 pi u maps to). */
double warp_turn(double phi);

/* Tent on [-1, 1] (pdf 1 - |x|). */
double warp_interval_to_tent(double u);
double warp_interval_to_tent_pdf(double x);
double warp_tent_to_interval(double x);

#endif
