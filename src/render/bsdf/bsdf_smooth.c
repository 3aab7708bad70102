/*
 * bsdf_smooth.c: the models without microfacets, as Mitsuba 0.6 defines
 * them. Conventions of bsdf.h: local frame, z-up, wo toward the viewer,
 * f without the cosine, weight = f |cos wi| / pdf, delta lobes only from
 * sampling (pdf = lobe probability).
 *
 * diffuse     f = R / pi; cosine-weighted sampling, pdf = cos(wi) / pi.
 *
 * phong       Mitsuba's energy-normalised modified Phong (Lafortune and
 *             Willems 1994):
 *               f = kd / pi + ks (n + 2) / (2 pi) cos^n(a),  cos(a) = wi . r,
 *             with r = (-wo.x, -wo.y, wo.z) the mirror direction (cos^n taken
 *             as 0 when cos(a) <= 0). The specular lobe is chosen with
 *             probability w = lum(mean ks) / (lum(mean ks) + lum(mean kd)),
 *             and sampled around r with density (n + 1) / (2 pi) cos^n(a)
 *             (cos(a) = u2^(1/(n+1)), azimuth 2 pi u1); directions below the
 *             surface are rejected, so the pdf, the mixture
 *               pdf = w (n + 1)/(2 pi) cos^n(a) + (1 - w) cos(wi) / pi,
 *             integrates to less than 1 over the upper hemisphere.
 *
 * conductor   delta reflection with weight specularReflectance F_cond(cos).
 *
 * dielectric  delta reflection (probability F) and refraction (1 - F),
 *             F = fresnel_dielectric(cos wo); weights specularReflectance,
 *             and specularTransmittance times (eta_o / eta_i)^2 in radiance
 *             mode (the 1/eta^2 radiance scaling) or 1 in importance mode.
 *             Total internal reflection: F = 1.
 *
 * thindielectric  Mitsuba's thin slab of glass: both faces of a plate of
 *             relative IOR eta at one surface. With R = F(|cos wo|) at the
 *             outer face, the light reflected after any number of passes
 *             (R, T R T, T R^3 T, ...) sums to
 *               R' = R + (1 - R)^2 R / (1 - R^2),
 *             and the rest, 1 - R' = (1 - R) / (1 + R), leaves the far face
 *             parallel to where it came in: wi = -wo, no bending, no 1/eta^2
 *             scaling, sample eta 1. Delta reflection (probability R', weight
 *             specularReflectance) and delta transmission (probability
 *             1 - R', weight specularTransmittance); the same from both sides.
 *
 * plastic     Mitsuba's smooth plastic: a dielectric coating (eta) on a
 *             Lambertian base with reflectance kd. Specular: delta reflection
 *             with weight ks F_i. Diffuse, including the infinite series of
 *             internal reflections (F_dr: diffuse Fresnel reflectance seen
 *             from inside, at 1/eta):
 *               f = kd' (1 - F_i) (1 - F_o) / (pi eta^2),
 *               kd' = kd / (1 - F_dr)         (default, colour preserving),
 *               kd' = kd / (1 - kd F_dr)      (nonlinear = 1).
 *             F_i = F(cos wo), F_o = F(cos wi). The specular lobe is chosen
 *             with probability p = F_i w / (F_i w + (1 - F_i)(1 - w)), w the
 *             specular weight as for phong; pdf = (1 - p) cos(wi) / pi.
 *
 * The models are written once (bsdf_smooth_generic.h) and compiled here
 * twice, in doubles and in duals (render/real.h).
 */
#include <math.h>
#include <stddef.h>

#include "render/bsdf/bsdf_ad_internal.h"
#include "render/bsdf/bsdf_internal.h"
#include "render/frame.h"
#include "render/warp.h"

/* The models in doubles (bsdf_internal.h), then in duals
 * (bsdf_ad_internal.h), from one source. */
#define R_DUAL 0
#include "render/real.h"
#include "render/bsdf/bsdf_smooth_generic.h"
#undef R_DUAL
#define R_DUAL 1
#include "render/real.h"
#include "render/bsdf/bsdf_smooth_generic.h"
