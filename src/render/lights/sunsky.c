/*
 * sunsky.c: the environment map of Mitsuba 0.6's sunsky, sky and sun
 * emitters (sunsky.h states the frame, units and sources).
 *
 * The sky (Hosek and Wilkie 2012, RGB variant). Each channel c has nine
 * parameters A..I and a radiance scale L_M; the radiance towards a view at
 * zenith angle theta and angle gamma from the sun is
 *     L_c = L_M (1 + A exp(B / (cos theta + 0.01)))
 *               (C + D exp(E gamma) + F cos^2 gamma + G chi(H, gamma)
 *                + I sqrt(cos theta)),
 *     chi(H, gamma) = (1 + cos^2 gamma) / (1 + H^2 - 2 H cos gamma)^(3/2).
 * The parameters were fitted for turbidity T = 1..10, ground albedo 0 and
 * 1 and, over the solar elevation e, as the six control points of a quintic
 * Bezier curve in s = (e / (pi/2))^(1/3); a state for (T, albedo, e) is
 *     sum over a in {0, 1}, t in {floor T, floor T + 1} of
 *         w_a w_t sum_k binom(5, k) (1 - s)^(5-k) s^k P[a][t][k],
 * with w_0 = 1 - albedo, w_1 = albedo, w_floor = 1 - frac T, w_ceil = frac T
 * (at T = 10 only the lower term). Mitsuba evaluates channel c from a state
 * made with albedo[c], divides by 106.856980 (the sum of its CIE Y table,
 * turning the tristimulus integral into a mean spectral radiance), clamps
 * negatives, and returns black for cos(theta / stretch) <= 0 unless
 * `extend`, where theta is taken just above the horizon (pi/2 - 1e-4) and
 * the result faded by smoothstep(2 - 2 theta / pi).
 *
 * The sun (Preetham et al. 1999, spectral): for zenith angle theta the
 * relative optical mass is m = 1 / (cos theta + 0.15 (93.885 - theta_deg)^-1.253)
 * and the solar spectrum (380..750 nm, W / (m^2 sr nm)) is multiplied by the
 * transmittances
 *     Rayleigh  exp(-m 0.008735 lambda_um^-4.08)
 *     aerosol   exp(-m beta lambda_um^-1.3),  beta = 0.04608365822050 T - 0.04586025928522
 *     ozone     exp(-m k_o(lambda) 0.35)
 *     gases     exp(-1.41 k_g m / (1 + 118.93 k_g m)^0.45)
 *     water     exp(-0.2385 k_wa 2 m / (1 + 20.07 k_wa 2 m)^0.45)
 * at 350, 355, ..., 800 nm (each table piecewise linear, zero outside its
 * range), and the spectrum is reduced to RGB.
 *
 * The sun in the map. Mitsuba draws N quasi-random directions (the (0, 2)
 * sequence: base-2 radical inverse and Sobol's second dimension) uniformly
 * in the cone of half angle r = sunRadiusScale * SUN_APP_RADIUS / 2 degrees
 * around the sun (its stretched position), with
 *     N = max(100, W H (1 - cos r) / 2 * 1000)  (capped at 10^8 here),
 * and adds to the pixel each falls in
 *     L_sun Omega_sun W H / (2 pi^2 N) / max(1e-3, sin theta_sample),
 * where Omega_sun = 2 pi (1 - cos(SUN_APP_RADIUS / 2)) is the solid angle
 * of the unscaled sun. A pixel covers 2 pi^2 sin theta / (W H) steradians,
 * so the splats integrate to L_sun Omega_sun whatever r and the resolution:
 * the sun's power is preserved.
 */
#include "render/lights/sunsky.h"
#include "render/spectrum.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Earth's mean radius and the astronomical unit in km (parallax). */
#define SUNSKY__EARTH_RADIUS 6371.01
#define SUNSKY__AU 149597890.0
/* Mitsuba's normalisation of the tristimulus sky model. */
#define SUNSKY__CIE_Y_SUM 106.856980

void sunsky_params_default(sunsky_params *p) {
  memset(p, 0, sizeof *p);
  p->sky = 1;
  p->sun = 1;
  p->sun_dir.theta = 0.0;
  p->sun_dir.phi = 0.0;
  p->turbidity = 3.0;
  p->albedo = rgb_gray(0.2);
  p->stretch = 1.0;
  p->extend = 0;
  p->resolution = 512;
  p->sky_scale = 1.0;
  p->sun_scale = 1.0;
  p->sun_radius_scale = 1.0;
}

/* ---- Coordinates. ------------------------------------------------------- */

sunsky_coords sunsky_from_dir(vec3 d) {
  double len = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
  sunsky_coords c;
  double y = len > 0.0 ? d.y / len : 1.0;
  c.theta = acos(y < -1.0 ? -1.0 : (y > 1.0 ? 1.0 : y));
  c.phi = atan2(d.x, -d.z);
  if (c.phi < 0.0) c.phi += 2.0 * M_PI;
  return c;
}

vec3 sunsky_to_dir(sunsky_coords c) {
  double st = sin(c.theta), ct = cos(c.theta);
  return v3(sin(c.phi) * st, ct, -cos(c.phi) * st);
}

/* ---- The sun's position (PSA algorithm). -------------------------------- */

sunsky_coords sunsky_sun_position(const sunsky_time *time, const sunsky_place *place) {
  /* Universal time in decimal hours, and the days elapsed since
   * JD 2451545.0 (noon UT, 1 January 2000) from the integer Julian day
   * number of the date (integer divisions truncate, as the paper's). */
  double ut = time->hour - place->timezone + (time->minute + time->second / 60.0) / 60.0;
  long long y = time->year, mo = time->month, d = time->day;
  long long a = (mo - 14) / 12;
  long long jdn = (1461 * (y + 4800 + a)) / 4 + (367 * (mo - 2 - 12 * a)) / 12 -
                  (3 * ((y + 4900 + a) / 100)) / 4 + d - 32075;
  double n = (double)jdn - 0.5 + ut / 24.0 - 2451545.0;

  /* Ecliptic longitude and obliquity (radians, not reduced mod 2 pi). */
  double omega = 2.1429 - 0.0010394594 * n;
  double mean_long = 4.8950630 + 0.017202791698 * n;
  double anomaly = 6.2400600 + 0.0172019699 * n;
  double ecl_long = mean_long + 0.03341607 * sin(anomaly) + 0.00034894 * sin(2.0 * anomaly) -
                    0.0001134 - 0.0000203 * sin(omega);
  double obliquity = 0.4090928 - 6.2140e-9 * n + 0.0000396 * cos(omega);

  /* Right ascension and declination. */
  double sin_l = sin(ecl_long);
  double ra = atan2(cos(obliquity) * sin_l, cos(ecl_long));
  if (ra < 0.0) ra += 2.0 * M_PI;
  double dec = asin(sin(obliquity) * sin_l);

  /* Hour angle from the local mean sidereal time, then zenith angle and
   * azimuth (from north through east). */
  double gmst = 6.6974243242 + 0.0657098283 * n + ut;
  double lmst = (gmst * 15.0 + place->longitude) * (M_PI / 180.0);
  double lat = place->latitude * (M_PI / 180.0);
  double hour_angle = lmst - ra;
  double cos_h = cos(hour_angle);
  double cos_zen = cos(lat) * cos_h * cos(dec) + sin(dec) * sin(lat);
  sunsky_coords c;
  c.theta = acos(cos_zen < -1.0 ? -1.0 : (cos_zen > 1.0 ? 1.0 : cos_zen));
  c.phi = atan2(-sin(hour_angle), tan(dec) * cos(lat) - sin(lat) * cos_h);
  if (c.phi < 0.0) c.phi += 2.0 * M_PI;

  /* Parallax: the observer is not at the earth's centre. */
  c.theta += (SUNSKY__EARTH_RADIUS / SUNSKY__AU) * sin(c.theta);
  return c;
}

/* ---- The sky model. ----------------------------------------------------- */

/* Adds w times the quintic Bezier curve of control points P[k][.] at s to
 * out[0..count). P is laid out [6][count]. */
static void sunsky__bezier(const double *P, int count, double s, double w, double *out) {
  static const double binom[6] = {1.0, 5.0, 10.0, 10.0, 5.0, 1.0};
  double b[6];
  for (int k = 0; k < 6; k++) b[k] = binom[k] * pow(1.0 - s, 5 - k) * pow(s, k);
  for (int i = 0; i < count; i++) {
    double v = 0.0;
    for (int k = 0; k < 6; k++) v += b[k] * P[k * count + i];
    out[i] += w * v;
  }
}

void sunsky_sky_init(sunsky_sky_state *st, double turbidity, rgb albedo, double elevation) {
  memset(st, 0, sizeof *st);
  int t0 = (int)turbidity;
  if (t0 < 1) t0 = 1;
  if (t0 > 10) t0 = 10;
  double frac = turbidity - t0;
  double s = pow(fmax(0.0, elevation) / (M_PI / 2.0), 1.0 / 3.0);
  const double alb[3] = {albedo.r, albedo.g, albedo.b};
  for (int c = 0; c < 3; c++) {
    /* Blend the four corners (albedo 0/1, turbidity t0/t0+1). */
    for (int a = 0; a < 2; a++) {
      double wa = a == 0 ? 1.0 - alb[c] : alb[c];
      for (int dt = 0; dt < 2; dt++) {
        if (t0 + dt > 10) continue;
        double w = wa * (dt == 0 ? 1.0 - frac : frac);
        sunsky__bezier(&sunsky__rgb_coeffs[c][a][t0 - 1 + dt][0][0], 9, s, w, st->config[c]);
        sunsky__bezier(&sunsky__rgb_radiances[c][a][t0 - 1 + dt][0], 1, s, w, &st->radiance[c]);
      }
    }
  }
}

double sunsky_sky_model(const sunsky_sky_state *st, int c, double theta, double gamma) {
  const double *p = st->config[c];
  /* Parameters A..G at 0..6, I at 7, H at 8. */
  double cos_t = cos(theta), cos_g = cos(gamma);
  double chi = (1.0 + cos_g * cos_g) / pow(1.0 + p[8] * p[8] - 2.0 * p[8] * cos_g, 1.5);
  double gradation = 1.0 + p[0] * exp(p[1] / (cos_t + 0.01));
  double indicatrix = p[2] + p[3] * exp(p[4] * gamma) + p[5] * cos_g * cos_g + p[6] * chi +
                      p[7] * sqrt(fmax(0.0, cos_t));
  return gradation * indicatrix * st->radiance[c];
}

rgb sunsky_sky_radiance(const sunsky_sky_state *st, const sunsky_params *p, sunsky_coords view) {
  /* The sky squeezed by `stretch`; below the horizon black, or with
   * `extend` the horizon's value faded out. */
  double theta = view.theta / p->stretch;
  if (cos(theta) <= 0.0) {
    if (!p->extend) return rgb_zero();
    theta = 0.5 * M_PI - 1e-4;
  }
  double ts = p->sun_dir.theta;
  double cos_gamma =
      cos(theta) * cos(ts) + sin(theta) * sin(ts) * cos(view.phi - p->sun_dir.phi);
  double gamma = acos(cos_gamma < -1.0 ? -1.0 : (cos_gamma > 1.0 ? 1.0 : cos_gamma));
  double v[3];
  for (int c = 0; c < 3; c++) {
    v[c] = sunsky_sky_model(st, c, theta, gamma) / SUNSKY__CIE_Y_SUM;
    if (!(v[c] > 0.0)) v[c] = 0.0;
  }
  rgb out = rgb_make(v[0], v[1], v[2]);
  if (p->extend) {
    double x = 2.0 - 2.0 * view.theta / M_PI;
    x = x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
    out = rgb_scale(out, x * x * (3.0 - 2.0 * x));
  }
  return rgb_scale(out, p->sky_scale);
}

/* ---- The sun's spectrum. ------------------------------------------------ */

/* Absorption coefficient of ozone (1/cm), Preetham et al. after Iqbal. */
static const double sunsky__ko_wl[64] = {
    300, 305, 310, 315, 320, 325, 330, 335, 340, 345, 350, 355, 445, 450, 455, 460,
    465, 470, 475, 480, 485, 490, 495, 500, 505, 510, 515, 520, 525, 530, 535, 540,
    545, 550, 555, 560, 565, 570, 575, 580, 585, 590, 595, 600, 605, 610, 620, 630,
    640, 650, 660, 670, 680, 690, 700, 710, 720, 730, 740, 750, 760, 770, 780, 790};
static const double sunsky__ko[64] = {
    10.0,  4.8,   2.7,   1.35,  .8,    .380,  .160,  .075,  .04,   .019,  .007,  .0,   .003,
    .003,  .004,  .006,  .008,  .009,  .012,  .014,  .017,  .021,  .025,  .03,   .035, .04,
    .045,  .048,  .057,  .063,  .07,   .075,  .08,   .085,  .095,  .103,  .110,  .12,  .122,
    .12,   .118,  .115,  .12,   .125,  .130,  .12,   .105,  .09,   .079,  .067,  .057, .048,
    .036,  .028,  .023,  .018,  .014,  .011,  .010,  .009,  .007,  .004,  .0,    .0};
/* Absorption coefficient of the mixed gases (oxygen A band). */
static const double sunsky__kg_wl[4] = {759, 760, 770, 771};
static const double sunsky__kg[4] = {0, 3.0, 0.210, 0};
/* Absorption coefficient of water vapour. */
static const double sunsky__kwa_wl[13] = {689, 690, 700, 710, 720, 730, 740,
                                          750, 760, 770, 780, 790, 800};
static const double sunsky__kwa[13] = {0,       0.160e-1, 0.240e-1, 0.125e-1, 0.100e+1,
                                       0.870,   0.610e-1, 0.100e-2, 0.100e-4, 0.100e-4,
                                       0.600e-3, 0.175e-1, 0.360e-1};
/* Extraterrestrial solar spectral radiance, W / (m^2 sr nm), 380..750 nm. */
static const double sunsky__sol[38] = {
    16559.0, 16233.7, 21127.5, 25888.2, 25829.1, 24232.3, 26760.5, 29658.3,
    30545.4, 30057.5, 30663.7, 28830.4, 28712.1, 27825.0, 27100.6, 27233.6,
    26361.3, 25503.8, 25060.2, 25311.6, 25355.9, 25134.2, 24631.5, 24173.2,
    23685.3, 23212.1, 22827.7, 22339.8, 21970.2, 21526.7, 21097.9, 20728.3,
    20240.4, 19870.8, 19427.2, 19072.4, 18628.9, 18259.2};

/* A table sampled at wl[0..n) read piecewise linearly, zero outside. */
static double sunsky__table(const double *wl, const double *val, int n, double x) {
  if (x < wl[0] || x > wl[n - 1]) return 0.0;
  int i = 1;
  while (i < n - 1 && wl[i] < x) i++;
  double t = (x - wl[i - 1]) / (wl[i] - wl[i - 1]);
  return val[i - 1] + t * (val[i] - val[i - 1]);
}

/* The solar table, sampled every 10 nm from 380 nm. */
static double sunsky__sol_at(double x) {
  if (x < 380.0 || x > 750.0) return 0.0;
  int i = (int)((x - 380.0) / 10.0);
  if (i > 36) i = 36;
  double t = (x - (380.0 + 10.0 * i)) / 10.0;
  return sunsky__sol[i] + t * (sunsky__sol[i + 1] - sunsky__sol[i]);
}

void sunsky_sun_spectrum(double theta, double turbidity, double *OUT_lambda, double *OUT_value) {
  double beta = 0.04608365822050 * turbidity - 0.04586025928522;
  /* Relative optical mass (Kasten's formula). */
  double m = 1.0 / (cos(theta) + 0.15 * pow(93.885 - theta / M_PI * 180.0, -1.253));
  for (int i = 0; i < SUNSKY_SUN_SAMPLES; i++) {
    double lambda = 350.0 + 5.0 * i, um = lambda / 1000.0;
    double ko = sunsky__table(sunsky__ko_wl, sunsky__ko, 64, lambda);
    double kg = sunsky__table(sunsky__kg_wl, sunsky__kg, 4, lambda);
    double kwa = sunsky__table(sunsky__kwa_wl, sunsky__kwa, 13, lambda);
    double tau_r = exp(-m * 0.008735 * pow(um, -4.08));
    double tau_a = exp(-m * beta * pow(um, -1.3));
    double tau_o = exp(-m * ko * 0.35);
    double tau_g = exp(-1.41 * kg * m / pow(1.0 + 118.93 * kg * m, 0.45));
    double tau_wa = exp(-0.2385 * kwa * 2.0 * m / pow(1.0 + 20.07 * kwa * 2.0 * m, 0.45));
    OUT_lambda[i] = lambda;
    OUT_value[i] = sunsky__sol_at(lambda) * tau_r * tau_a * tau_o * tau_g * tau_wa;
  }
}

/* A sampled spectrum (wavelengths ascending) as linear RGB, negative
 * channels clamped to 0. Mitsuba's RGB build integrates the spectrum
 * against the CIE 1931 matching functions, divides by the integral of
 * y-bar and converts XYZ to linear sRGB. For now this is the loader's
 * reduction of sampled spectra (props_spectrum_pairs in io/props.c): the
 * piecewise-linear spectrum, clamped to its end values outside its range,
 * averaged over 20 evenly spaced wavelengths in each of the bands
 * B 400-500, G 500-600 and R 600-700 nm. */
/* A spectrum of the sun as Mitsuba's RGB build makes it
 * (fromContinuousSpectrum: the CIE 1931 functions, no zero extension, zero
 * outside the samples), negative components set to zero. */
static rgb sunsky__spectrum_rgb(const double *lambda, const double *value, int n,
                                spectrum_interp interp) {
  rgb c = spectrum_xyz_to_rgb(spectrum_sampled_xyz(lambda, value, n, interp));
  return rgb_make(fmax(0.0, c.r), fmax(0.0, c.g), fmax(0.0, c.b));
}

rgb sunsky_sun_radiance(double theta, double turbidity, spectrum_interp interp) {
  double lambda[SUNSKY_SUN_SAMPLES], value[SUNSKY_SUN_SAMPLES];
  sunsky_sun_spectrum(theta, turbidity, lambda, value);
  return sunsky__spectrum_rgb(lambda, value, SUNSKY_SUN_SAMPLES, interp);
}

/* Half the apparent diameter of the unscaled sun, radians. */
static double sunsky__sun_half_angle(void) { return SUNSKY_SUN_APP_RADIUS * 0.5 * M_PI / 180.0; }

rgb sunsky_sun_irradiance(const sunsky_params *p, vec3 *OUT_to_sun) {
  sunsky_coords c = p->sun_dir;
  rgb L = rgb_scale(sunsky_sun_radiance(c.theta, p->turbidity, p->spectra), p->sun_scale);
  c.theta *= p->stretch;
  *OUT_to_sun = sunsky_to_dir(c);
  return rgb_scale(L, 2.0 * M_PI * (1.0 - cos(sunsky__sun_half_angle())));
}

/* ---- Rasterization. ----------------------------------------------------- */

/* The (0, 2) sequence: base-2 radical inverse and Sobol's second
 * dimension, with 53 bits. */
static double sunsky__radical_inverse2(uint64_t n) {
  uint64_t r = 0;
  for (int b = 0; b < 64; b++, n >>= 1) r = (r << 1) | (n & 1);
  return (double)(r >> 11) / 9007199254740992.0;
}

static double sunsky__sobol2(uint64_t n) {
  uint64_t r = 0;
  for (uint64_t v = 1ULL << 52; n != 0; n >>= 1, v ^= v >> 1)
    if (n & 1) r ^= v;
  return (double)r / 9007199254740992.0;
}

/* Mitsuba's orthonormal basis around unit n: t is perpendicular to n in a
 * coordinate plane, s = t x n. */
static void sunsky__basis(vec3 n, vec3 *s, vec3 *t) {
  if (fabs(n.x) > fabs(n.y)) {
    double inv = 1.0 / sqrt(n.x * n.x + n.z * n.z);
    *t = v3(n.z * inv, 0.0, -n.x * inv);
  } else {
    double inv = 1.0 / sqrt(n.y * n.y + n.z * n.z);
    *t = v3(0.0, n.z * inv, -n.y * inv);
  }
  *s = v3_cross(*t, n);
}

/* Splats the sun into img as described at the top of this file. */
static void sunsky__splat_sun(const sunsky_params *p, lmc_image *img) {
  int w = img->width, h = img->height;
  double half = sunsky__sun_half_angle();
  double cos_cone = cos(half * p->sun_radius_scale);
  double covered = 0.5 * (1.0 - cos_cone);
  double pixel_count = (double)(((long long)p->resolution * p->resolution) / 2);
  /* Mitsuba's count; lmc caps it at 10^8 (a sun as large as a hemisphere
   * in a 16384-pixel map would ask for 7 10^10). */
  size_t n = (size_t)fmin(1e8, fmax(100.0, pixel_count * covered * 1000.0));

  rgb L = rgb_scale(sunsky_sun_radiance(p->sun_dir.theta, p->turbidity, p->spectra), p->sun_scale);
  rgb value = rgb_scale(L, 2.0 * M_PI * (1.0 - cos(half)) * (double)w * (double)h /
                               (2.0 * M_PI * M_PI * (double)n));
  sunsky_coords c = p->sun_dir;
  c.theta *= p->stretch;
  vec3 axis = sunsky_to_dir(c), s, t;
  sunsky__basis(axis, &s, &t);

  for (size_t i = 0; i < n; i++) {
    /* A uniform direction in the cone around the sun. */
    double u1 = sunsky__radical_inverse2(i), u2 = sunsky__sobol2(i);
    double cos_t = (1.0 - u1) + u1 * cos_cone;
    double sin_t = sqrt(fmax(0.0, 1.0 - cos_t * cos_t));
    double phi = 2.0 * M_PI * u2;
    double lx = cos(phi) * sin_t, ly = sin(phi) * sin_t;
    vec3 d = v3(s.x * lx + t.x * ly + axis.x * cos_t, s.y * lx + t.y * ly + axis.y * cos_t,
                s.z * lx + t.z * ly + axis.z * cos_t);

    /* Its pixel, weighted by 1 / sin(theta) for the pixel's solid angle. */
    double sin_theta = sqrt(fmax(0.0, 1.0 - d.y * d.y));
    sunsky_coords dc = sunsky_from_dir(d);
    int px = (int)(dc.phi * w / (2.0 * M_PI)), py = (int)(dc.theta * h / M_PI);
    px = px < 0 ? 0 : (px > w - 1 ? w - 1 : px);
    py = py < 0 ? 0 : (py > h - 1 ? h - 1 : py);
    float *pix = img->data + 3 * ((size_t)py * w + px);
    double k = 1.0 / fmax(1e-3, sin_theta);
    pix[0] += (float)(value.r * k);
    pix[1] += (float)(value.g * k);
    pix[2] += (float)(value.b * k);
  }
}

lmc_status sunsky_rasterize(const sunsky_params *p, lmc_image *OUT_img, lmc_error *err) {
  memset(OUT_img, 0, sizeof *OUT_img);
  /* Parameters: the loader reports these with file and line first. */
  int albedo_ok = p->albedo.r >= 0.0 && p->albedo.r <= 1.0 && p->albedo.g >= 0.0 &&
                  p->albedo.g <= 1.0 && p->albedo.b >= 0.0 && p->albedo.b <= 1.0;
  if (!(p->turbidity >= 1.0 && p->turbidity <= 10.0) || !(p->stretch >= 1.0 && p->stretch <= 2.0) ||
      !albedo_ok || !(p->resolution >= 2 && p->resolution <= IMAGE_MAX_SIDE) ||
      !(p->sky_scale >= 0.0 && isfinite(p->sky_scale)) ||
      !(p->sun_scale >= 0.0 && isfinite(p->sun_scale)) ||
      !(p->sun_radius_scale > 0.0 &&
        p->sun_radius_scale * sunsky__sun_half_angle() <= 0.5 * M_PI) ||
      !(p->sun_dir.theta >= 0.0 && p->sun_dir.theta <= 0.5 * M_PI))
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "sunsky: parameters out of range");
  lmc_status st = image_init(OUT_img, p->resolution, p->resolution / 2, 3, err);
  if (st != LMC_OK) return st;
  int w = OUT_img->width, h = OUT_img->height;

  /* The sky at every pixel centre. */
  if (p->sky) {
    sunsky_sky_state state;
    sunsky_sky_init(&state, p->turbidity, p->albedo, 0.5 * M_PI - p->sun_dir.theta);
    for (int y = 0; y < h; y++) {
      sunsky_coords view;
      view.theta = (y + 0.5) * M_PI / h;
      for (int x = 0; x < w; x++) {
        view.phi = (x + 0.5) * 2.0 * M_PI / w;
        rgb L = sunsky_sky_radiance(&state, p, view);
        float *pix = OUT_img->data + 3 * ((size_t)y * w + x);
        pix[0] = (float)L.r;
        pix[1] = (float)L.g;
        pix[2] = (float)L.b;
      }
    }
  }

  /* Then the sun on top. */
  if (p->sun) sunsky__splat_sun(p, OUT_img);
  return LMC_OK;
}
