/*
 * microfacet.h: isotropic microfacet distributions (Beckmann and GGX) for
 * the rough conductor, rough dielectric and rough plastic models.
 *
 * Walter, Marschner, Li, Torrance 2007, "Microfacet Models for Refraction
 * through Rough Surfaces": the normal distribution D(m), the separable
 * Smith shadowing-masking G(wi, wo, m) = G1(wi, m) G1(wo, m), and sampling
 * of D(m) cos(theta_m). Visible normals: Heitz and d'Eon 2014, "Importance
 * Sampling Microfacet-Based BSDFs using the Distribution of Visible
 * Normals" (Beckmann, by slope inversion) and Heitz 2018, "Sampling the GGX
 * Distribution of Visible Normals" (GGX), with density
 *   D_v(m) = G1(v, m) max(0, v.m) D(m) / v.z.
 *
 * G1 is the exact Smith term of each distribution (for Beckmann with erf;
 * Mitsuba 0.6 uses Walter's rational approximation instead, which differs by
 * under 0.4% but would make the visible-normal density integrate to slightly
 * less or more than 1). All vectors are in the shading frame (z-up); m is
 * the microfacet normal, upper hemisphere.
 */
#ifndef LMC_RENDER_MICROFACET_H
#define LMC_RENDER_MICROFACET_H

#include "render/bsdf/bsdf.h"
#include "render/vec3.h"

/* D(m): microfacet normal density per unit solid angle, normalised so that
 * the integral of D(m) cos(theta_m) over the hemisphere is 1. */
double mf_D(mf_dist dist, double alpha, vec3 m);
/* Smith's Lambda(v) for direction v (|v.z| used). */
double mf_lambda(mf_dist dist, double alpha, vec3 v);
/* Smith G1(v, m); 0 when v and m are on opposite sides (v.m * v.z <= 0). */
double mf_G1(mf_dist dist, double alpha, vec3 v, vec3 m);
/* Separable Smith G(wi, wo, m) = G1(wi, m) G1(wo, m). */
double mf_G(mf_dist dist, double alpha, vec3 wi, vec3 wo, vec3 m);

/* Samples a microfacet normal: from D(m) cos(theta_m) when !visible, from
 * the visible normals seen from v (v.z > 0) when visible. */
vec3 mf_sample(mf_dist dist, double alpha, vec3 v, int visible, double u1, double u2);
/* Density of mf_sample producing m (per unit solid angle of m). */
double mf_pdf(mf_dist dist, double alpha, vec3 v, vec3 m, int visible);
/* mf_pdf from d = D(m) and, when visible, g1 = G1(v, m) that the caller
 * already has (the same value, bit for bit). */
double mf_pdf_known(double d, double g1, vec3 v, vec3 m, int visible);
/* The inverse of mf_sample: the (u1, u2) in [0, 1)^2 from which mf_sample
 * returns the unit normal m (m.z > 0; when visible, v.m > 0). Returns 0
 * when m is outside what mf_sample produces. */
int mf_invert(mf_dist dist, double alpha, vec3 v, int visible, vec3 m, double *OUT_u1,
              double *OUT_u2);

/* Inverse error function on (-1, 1) (erfinv(+-1) = +-inf). */
double mf_erfinv(double x);

#endif
