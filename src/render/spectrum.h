/*
 * spectrum.h: spectra to linear sRGB, as Mitsuba 0.6 compiled in RGB mode
 * (SPECTRUM_SAMPLES == 3) converts them when it loads a scene.
 *
 * A spectrum s(lambda) (lambda in nm) becomes CIE 1931 XYZ by
 *
 *   X = int s xbar / int ybar,  Y = int s ybar / int ybar,  Z = int s zbar / int ybar,
 *
 * every integral over [360, 830] nm with the colour matching functions
 * linear between their 1 nm samples: only Y is normalised, so a constant
 * spectrum 1 gives Y = 1 and the equal-energy white E (x = y = 1/3), not
 * D65. XYZ then becomes linear sRGB (Rec. 709 primaries, D65 white) by the
 * standard matrix with Mitsuba's six-digit coefficients; negative
 * components are clamped to zero by the loader's helpers (`_rgb`), not by
 * spectrum_xyz_to_rgb.
 *
 * A sampled spectrum is piecewise linear between its (wavelength, value)
 * pairs and zero outside them; the loader first applies Mitsuba's zero
 * extension (spectrum_zero_extend), so a spectrum whose end values are not
 * zero ramps down to zero over one mean sample spacing beyond each end.
 *
 * A black body is Planck's law in W m^-2 sr^-1 nm^-1 (spectral radiance
 * per nanometre: the per-metre value times 1e-9), CODATA 2010 constants.
 * In RGB mode Mitsuba treats reflectances and emitted radiance alike here:
 * no conversion intent enters these functions.
 */
#ifndef LMC_RENDER_SPECTRUM_H
#define LMC_RENDER_SPECTRUM_H

#include "render/vec3.h"

/* The wavelength range of the colour matching functions and of every
 * integral here, in nm. */
#define SPECTRUM_LAMBDA_MIN 360.0
#define SPECTRUM_LAMBDA_MAX 830.0

/* CIE 1931 tristimulus values. */
typedef struct spectrum_xyz {
  double x, y, z; /* X, Y, Z */
} spectrum_xyz;

/* How a tabulated spectrum (a sampled spectrum, the colour matching
 * functions) is read between its samples:
 *   SPECTRUM_INTERP_LINEAR        linearly, as Mitsuba 0.6 since 2020-01-31
 *                                 (commit cfeb7766) and every other renderer;
 *   SPECTRUM_INTERP_MITSUBA_060   as the Mitsuba 0.6.0 release and its code
 *                                 until then: on each interval [a, b] the
 *                                 line from f(b) at a to f(a) at b (the ends
 *                                 swapped), for the colour matching functions
 *                                 too. Images made with those builds (most
 *                                 published Mitsuba 0.6 renders) need it. */
typedef enum spectrum_interp { SPECTRUM_INTERP_LINEAR = 0, SPECTRUM_INTERP_MITSUBA_060 } spectrum_interp;

/* The CIE 1931 2-degree colour matching functions at lambda (nm), linear
 * between the 1 nm table's samples, zero outside [360, 830]. */
spectrum_xyz spectrum_cmf(double lambda);

/* The integral of ybar over [360, 830] nm (the normalisation; about 106.857). */
double spectrum_cmf_y_integral(void);

/* XYZ of the piecewise-linear spectrum through (wl[i], val[i]), i < n
 * (wl strictly ascending, n >= 1), zero outside [wl[0], wl[n-1]]. Exact
 * for that function: each stretch between breakpoints of both the
 * spectrum and the 1 nm table is a quadratic, integrated by Simpson's rule.
 * `interp` reads both tables (see spectrum_interp). */
spectrum_xyz spectrum_sampled_xyz(const double *wl, const double *val, int n,
                                  spectrum_interp interp);

/* Mitsuba's zero extension of a sampled spectrum (n >= 2, wl ascending):
 * when val[0] != 0, a zero is put at wl[0] - d before it; when the last
 * value != 0, a zero at wl[n-1] + d after it, d the mean spacing of the
 * given wavelengths. wl and val need room for n + 2 entries. Returns the
 * new count. */
int spectrum_zero_extend(double *wl, double *val, int n);

/* Planck's law: the spectral radiance of a black body at temperature_k
 * (kelvin) and lambda (nm), in W m^-2 sr^-1 nm^-1. */
double spectrum_blackbody(double lambda, double temperature_k);

/* XYZ of a black body at temperature_k (the normalisation above; `interp`
 * reads the colour matching functions). */
spectrum_xyz spectrum_blackbody_xyz(double temperature_k, spectrum_interp interp);

/* Linear sRGB of XYZ (Rec. 709 primaries, D65 white), not clamped. */
rgb spectrum_xyz_to_rgb(spectrum_xyz c);

/* The chromaticity x = X / (X + Y + Z), y = Y / (X + Y + Z) (0, 0 for black). */
void spectrum_chromaticity(spectrum_xyz c, double *OUT_x, double *OUT_y);

/* What the loader stores for a sampled spectrum (n >= 2, wl strictly
 * ascending; wl and val need room for n + 2): zero extension, XYZ, sRGB,
 * negative components set to zero. wl and val are extended in place. */
rgb spectrum_sampled_rgb(double *wl, double *val, int n, spectrum_interp interp);

/* What the loader stores for <blackbody temperature=T scale=s>: the black
 * body's sRGB, negative components set to zero, times scale. */
rgb spectrum_blackbody_rgb(double temperature_k, double scale, spectrum_interp interp);

#endif
