/*
 * sunsky.h: Mitsuba 0.6's daylight emitters `sunsky`, `sky` and `sun`,
 * which are not lights of their own: each is rasterized once, at load
 * time, into a latitude-longitude environment map that an envmap light
 * (light.h) then renders, as Mitsuba does. This file fills that map.
 *
 * The map's frame is Mitsuba's emitter frame, +y up; a direction is given
 * by its zenith angle theta (from +y) and azimuth phi,
 *     d = (sin phi sin theta, cos theta, -cos phi sin theta),
 * the envmap's own convention (light.c), so pixel (x, y) of a W x H map
 * holds the radiance towards theta = (y + 1/2) pi / H, phi = (x + 1/2) 2 pi / W.
 * The solar azimuth is measured from -z (north) through +x (east).
 *
 * The parts and their sources:
 *  - the sun's position: from a direction, or from date, time and place
 *    by the PSA algorithm (Blanco-Muriel et al., "Computing the solar
 *    vector", Solar Energy 70(5), 2001), accurate to about 0.5 arcminute;
 *  - the sky: the RGB variant of Hosek and Wilkie, "An Analytic Model for
 *    Full Spectral Sky-Dome Radiance" (SIGGRAPH 2012), with their fitted
 *    coefficients (sunsky_data.c), one model state per channel with that
 *    channel's ground albedo, as Mitsuba's RGB build evaluates it;
 *  - the sun: the solar spectrum attenuated by Rayleigh, aerosol, ozone,
 *    mixed-gas and water-vapour transmittance as in Preetham, Shirley and
 *    Smits, "A Practical Analytic Model for Daylight" (SIGGRAPH 1999),
 *    a disk of apparent radius SUNSKY_SUN_APP_RADIUS / 2 degrees (times
 *    sunRadiusScale) splatted into the map with QMC samples so that its
 *    power does not depend on the resolution nor on sunRadiusScale.
 *
 * Units: radiance in W / (m^2 sr nm) averaged over the visible range (the
 * sky model's tristimulus output divided by 106.856980, the sum of the
 * CIE Y table, as Mitsuba does), so the sun is about 10^5 times brighter
 * than the sky, as outdoors.
 */
#ifndef LMC_RENDER_SUNSKY_H
#define LMC_RENDER_SUNSKY_H

#include "render/error.h"
#include "render/image.h"
#include "render/spectrum.h"
#include "render/vec3.h"

/* Apparent diameter of the sun in degrees (Mitsuba's SUN_APP_RADIUS; it
 * is used as a diameter: the disk's half angle is half of it). */
#define SUNSKY_SUN_APP_RADIUS 0.5358
/* Samples of the sun's spectrum: 350, 355, ..., 800 nm. */
#define SUNSKY_SUN_SAMPLES 91

/* The Hosek-Wilkie RGB dataset (sunsky_data.c), layout described there. */
extern const double sunsky__rgb_coeffs[3][2][10][6][9];
extern const double sunsky__rgb_radiances[3][2][10][6];

/* A direction in the map's frame: zenith angle from +y and azimuth from -z
 * towards +x, in radians (Mitsuba calls the zenith angle "elevation"). */
typedef struct sunsky_coords {
  double theta; /* zenith angle, [0, pi] */
  double phi;   /* azimuth, [0, 2 pi) */
} sunsky_coords;

/* Date and local time of the observation. */
typedef struct sunsky_time {
  int year, month, day;
  double hour, minute, second;
} sunsky_time;

/* Place of the observer: degrees north and east, hours ahead of UTC. */
typedef struct sunsky_place {
  double latitude, longitude, timezone;
} sunsky_place;

/* One channel's sky model, the 9 parameters A..I (stored A..G, I, H) and
 * the overall radiance L_M, interpolated for turbidity, albedo and solar
 * elevation. */
typedef struct sunsky_sky_state {
  double config[3][9];
  double radiance[3];
} sunsky_sky_state;

/* What to rasterize: Mitsuba's parameters, in the map's frame. */
typedef struct sunsky_params {
  int sky, sun;            /* include the sky, the sun (sunsky: both) */
  sunsky_coords sun_dir;   /* the sun's position (unstretched) */
  double turbidity;        /* [1, 10] */
  rgb albedo;              /* ground albedo per channel, [0, 1] */
  double stretch;          /* [1, 2]: the sky squeezed over theta <= stretch pi/2 */
  int extend;              /* sky's "extend": continue below the horizon, faded */
  int resolution;          /* map width; height resolution / 2 */
  double sky_scale, sun_scale;
  double sun_radius_scale; /* (0, 335.9]: the disk at most a hemisphere; 0 is a
                              directional sun (sunsky_sun_irradiance) */
  spectrum_interp spectra; /* how the sun's spectrum is read (--spectra) */
} sunsky_params;

/* Mitsuba's defaults, sun at the zenith (the loader sets sun_dir). */
void sunsky_params_default(sunsky_params *p);

/* Direction <-> coordinates in the map's frame (d need not be unit). */
sunsky_coords sunsky_from_dir(vec3 d);
vec3 sunsky_to_dir(sunsky_coords c);

/* The sun's position seen from `place` at `time` (PSA algorithm, with the
 * parallax correction; no refraction). */
sunsky_coords sunsky_sun_position(const sunsky_time *time, const sunsky_place *place);

/* Interpolates the RGB sky model for turbidity in [1, 10], per-channel
 * albedo in [0, 1] and solar elevation (pi/2 - zenith) in [0, pi/2]. */
void sunsky_sky_init(sunsky_sky_state *st, double turbidity, rgb albedo, double elevation);
/* The model's tristimulus radiance in channel c for view zenith angle
 * theta and angle gamma to the sun (not yet divided by 106.856980). */
double sunsky_sky_model(const sunsky_sky_state *st, int c, double theta, double gamma);
/* Mitsuba's sky radiance towards `view` (stretch, horizon, extend, the
 * normalisation, sky_scale), with st made for p. */
rgb sunsky_sky_radiance(const sunsky_sky_state *st, const sunsky_params *p, sunsky_coords view);

/* The sun's spectral radiance for zenith angle theta (<= pi/2) and
 * turbidity, at SUNSKY_SUN_SAMPLES wavelengths 350..800 nm (OUT_lambda in
 * nm, OUT_value in W / (m^2 sr nm)). */
void sunsky_sun_spectrum(double theta, double turbidity, double *OUT_lambda, double *OUT_value);
/* The same as linear RGB (unscaled), the spectrum read with `interp`. */
rgb sunsky_sun_radiance(double theta, double turbidity, spectrum_interp interp);
/* The directional sun of sunRadiusScale = 0: irradiance (radiance times
 * the disk's solid angle, times sun_scale) and the direction towards the
 * sun in the map's frame (stretched as the map is). */
rgb sunsky_sun_irradiance(const sunsky_params *p, vec3 *OUT_to_sun);

/* Fills *OUT_img (initialised here, 3 channels, resolution x
 * resolution / 2) with p's sky and/or sun. LMC_EINVAL for parameters out
 * of range (the loader checks them first, with file and line). */
lmc_status sunsky_rasterize(const sunsky_params *p, lmc_image *OUT_img, lmc_error *err);

#endif
