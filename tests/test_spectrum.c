/*
 * test_spectrum.c: spectra to XYZ and linear sRGB (src/render/spectrum.c),
 * against published colorimetric data and physical identities, never
 * against a second copy of the same computation.
 *
 * What is checked:
 *  - the matrix: the sRGB / Rec. 709 primaries and the D65 white point
 *    (IEC 61966-2-1, ITU-R BT.709) map to the unit colours and to white;
 *  - the colour matching functions at a few wavelengths of the CIE 1931
 *    5 nm table, and the integral of ybar (CIE 15: sum of ybar at 1 nm over
 *    360-830 nm = 106.857);
 *  - an equal-energy spectrum: Y = 1 (Mitsuba normalises Y by the integral
 *    of ybar), chromaticity (1/3, 1/3) (illuminant E), and so linear sRGB
 *    (1.2049, 0.9483, 0.9091), NOT grey: that is E's colour under sRGB's
 *    D65 white, computed here with the 4-digit IEC matrix from the CIE
 *    sums of xbar, ybar, zbar;
 *  - the CIE D65 relative spectral power distribution (its 5 nm table,
 *    below) gives D65's chromaticity (0.31272, 0.32903) and r = g = b;
 *  - narrow spectra (1 nm triangles) land on the spectrum locus at the
 *    published chromaticities of CIE 15 (450, 500, 550, 600, 610 nm) and
 *    at the right hue; 20 nm boxes at 580-600 nm (orange: r > g > 0 > b)
 *    and 600-620 nm (red: r > g > b, g about 0, b < 0 before the loader's
 *    clamp);
 *  - Mitsuba's zero extension of a sampled spectrum;
 *  - Planck's law: its units (W m^-2 sr^-1 nm^-1) by the Stefan-Boltzmann
 *    law and the 1948 candela (a black body at the freezing point of
 *    platinum, 2042 K, has a luminance of 60 cd/cm^2, with 683 lm/W); the
 *    chromaticity of illuminant A (a black body at 2856 K: 0.44757,
 *    0.40745) and of the Planckian locus at 6500 K (0.3135, 0.3236). D65
 *    is not a black body: 6504 K lies 0.005 below it in y.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "test_util.h"

#include "render/spectrum.h"

/* XYZ from chromaticity x, y and luminance Y. */
static spectrum_xyz from_xyY(double x, double y, double Y) {
  spectrum_xyz c = {x * Y / y, Y, (1.0 - x - y) * Y / y};
  return c;
}

/* The IEC 61966-2-1 XYZ -> linear sRGB matrix (4 digits), independent of
 * the code's 6-digit copy. */
static rgb iec_xyz_to_rgb(spectrum_xyz c) {
  return rgb_make(3.2406 * c.x - 1.5372 * c.y - 0.4986 * c.z,
                  -0.9689 * c.x + 1.8758 * c.y + 0.0415 * c.z,
                  0.0557 * c.x - 0.2040 * c.y + 1.0570 * c.z);
}

static void test_matrix(void **state) {
  (void)state;
  int checks = 0;
  /* The primaries (chromaticity, relative luminance) and the white. */
  static const struct {
    double x, y, Y, r, g, b;
  } cases[] = {
      {0.64, 0.33, 0.2126, 1, 0, 0},
      {0.30, 0.60, 0.7152, 0, 1, 0},
      {0.15, 0.06, 0.0722, 0, 0, 1},
      {0.3127, 0.3290, 1.0, 1, 1, 1},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    rgb c = spectrum_xyz_to_rgb(from_xyY(cases[i].x, cases[i].y, cases[i].Y));
    assert_near(c.r, cases[i].r, 1e-3);
    assert_near(c.g, cases[i].g, 1e-3);
    assert_near(c.b, cases[i].b, 1e-3);
    checks += 3;
  }
  assert_int_equal(checks, 12);
}

static void test_cmf_table(void **state) {
  (void)state;
  int checks = 0;
  /* CIE 1931 2-degree observer, 5 nm table. */
  static const double cie[][4] = {
      {380, 0.001368, 0.000039, 0.006450}, {450, 0.336200, 0.038000, 1.772110},
      {500, 0.004900, 0.323000, 0.272000}, {555, 0.512050, 1.000000, 0.005750},
      {600, 1.062200, 0.631000, 0.000800}, {700, 0.011359, 0.004102, 0.000000},
  };
  for (size_t i = 0; i < sizeof cie / sizeof cie[0]; i++) {
    spectrum_xyz c = spectrum_cmf(cie[i][0]);
    assert_near(c.x, cie[i][1], 1e-6);
    assert_near(c.y, cie[i][2], 1e-6);
    assert_near(c.z, cie[i][3], 1e-6);
    checks += 3;
  }
  /* Zero outside the table; the integral of ybar. */
  assert_true(spectrum_cmf(359.5).y == 0.0 && spectrum_cmf(830.5).x == 0.0);
  assert_near(spectrum_cmf_y_integral(), 106.857, 1e-3);
  checks += 2;
  assert_int_equal(checks, 20);
}

/* The CIE sums of xbar, ybar, zbar at 1 nm over 360-830 nm (CIE 15). */
#define SUM_X 106.865
#define SUM_Y 106.857
#define SUM_Z 106.892

static void test_equal_energy(void **state) {
  (void)state;
  int checks = 0;
  double wl[4] = {360.0, 830.0}, val[4] = {1.0, 1.0};
  spectrum_xyz c = spectrum_sampled_xyz(wl, val, 2, SPECTRUM_INTERP_LINEAR);
  double x, y;
  spectrum_chromaticity(c, &x, &y);
  assert_near(c.y, 1.0, 1e-12);
  assert_near(x, 1.0 / 3.0, 2e-4);
  assert_near(y, 1.0 / 3.0, 2e-4);
  checks += 3;
  /* What the loader stores (zero extension lies outside 360-830 here). */
  spectrum_xyz e = {SUM_X / SUM_Y, 1.0, SUM_Z / SUM_Y};
  rgb want = iec_xyz_to_rgb(e), got = spectrum_sampled_rgb(wl, val, 2, SPECTRUM_INTERP_LINEAR);
  assert_near(got.r, want.r, 1e-3);
  assert_near(got.g, want.g, 1e-3);
  assert_near(got.b, want.b, 1e-3);
  assert_true(got.r > 1.2 && got.g < 0.95 && got.b < 0.92); /* not grey */
  checks += 4;
  /* Extra collinear samples change nothing. */
  double wl3[5] = {360.0, 500.0, 830.0}, val3[5] = {1.0, 1.0, 1.0};
  spectrum_xyz c3 = spectrum_sampled_xyz(wl3, val3, 3, SPECTRUM_INTERP_LINEAR);
  assert_near(c3.x, c.x, 1e-12);
  assert_near(c3.z, c.z, 1e-12);
  checks += 2;
  assert_int_equal(checks, 9);
}

/* CIE standard illuminant D65, relative spectral power, 360-830 nm at 5 nm
 * (CIE 15 / ISO 11664-2). */
static const double d65[] = {
    46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118, 54.6482, 68.7015,
    82.7549, 87.1204, 91.486,  92.4589, 93.4318, 90.057,  86.6823, 95.7736,
    104.865, 110.936, 117.008, 117.41,  117.812, 116.336, 114.861, 115.392,
    115.923, 112.367, 108.811, 109.082, 109.354, 108.578, 107.802, 106.296,
    104.79,  106.239, 107.689, 106.047, 104.405, 104.225, 104.046, 102.023,
    100,     98.1671, 96.3342, 96.0611, 95.788,  92.2368, 88.6856, 89.3459,
    90.0062, 89.8026, 89.5991, 88.6489, 87.6987, 85.4936, 83.2886, 83.4939,
    83.6992, 81.863,  80.0268, 80.1207, 80.2146, 81.2462, 82.2778, 80.281,
    78.2842, 74.0027, 69.7213, 70.6652, 71.6091, 72.979,  74.349,  67.9765,
    61.604,  65.7448, 69.8856, 72.4863, 75.087,  69.3398, 63.5927, 55.0054,
    46.4182, 56.6118, 66.8054, 65.0941, 63.3828, 63.8434, 64.304,  61.8779,
    59.4519, 55.7054, 51.959,  54.6998, 57.4406, 58.8765, 60.3125,
};
#define N_D65 ((int)(sizeof d65 / sizeof d65[0]))

static void test_d65(void **state) {
  (void)state;
  int checks = 0;
  assert_int_equal(N_D65, 95);
  double wl[N_D65 + 2], val[N_D65 + 2];
  for (int i = 0; i < N_D65; i++) {
    wl[i] = 360.0 + 5.0 * i;
    val[i] = d65[i];
  }
  double x, y;
  spectrum_chromaticity(spectrum_sampled_xyz(wl, val, N_D65, SPECTRUM_INTERP_LINEAR), &x, &y);
  assert_near(x, 0.31272, 2e-4);
  assert_near(y, 0.32903, 2e-4);
  checks += 3;
  rgb c = spectrum_sampled_rgb(wl, val, N_D65, SPECTRUM_INTERP_LINEAR);
  assert_near(c.r / c.g, 1.0, 1e-3);
  assert_near(c.b / c.g, 1.0, 1e-3);
  checks += 2;
  assert_int_equal(checks, 5);
}

static void test_narrow(void **state) {
  (void)state;
  int checks = 0;
  /* The spectrum locus (CIE 15, 1931 observer); the sign of r, g, b
   * before clamping, from the matrix applied to the table's xbar, ybar,
   * zbar at that wavelength. */
  static const struct {
    double lambda, x, y;
    int r, g, b; /* +1 positive, -1 negative */
  } locus[] = {
      {450, 0.1566, 0.0177, +1, -1, +1}, {500, 0.0082, 0.5384, -1, +1, +1},
      {550, 0.3016, 0.6923, -1, +1, -1}, {600, 0.6270, 0.3725, +1, +1, -1},
      {610, 0.6658, 0.3340, +1, -1, -1},
  };
  for (size_t i = 0; i < sizeof locus / sizeof locus[0]; i++) {
    double l = locus[i].lambda;
    double wl[5] = {l - 1.0, l, l + 1.0}, val[5] = {0.0, 1.0, 0.0};
    spectrum_xyz c = spectrum_sampled_xyz(wl, val, 3, SPECTRUM_INTERP_LINEAR);
    double x, y;
    spectrum_chromaticity(c, &x, &y);
    assert_near(x, locus[i].x, 3e-4);
    assert_near(y, locus[i].y, 3e-4);
    /* A unit-area triangle: Y is about ybar(l) / 106.857. */
    assert_near(c.y * SUM_Y, spectrum_cmf(l).y, 2e-3 * spectrum_cmf(l).y + 1e-6);
    rgb u = spectrum_xyz_to_rgb(c), k = spectrum_sampled_rgb(wl, val, 3, SPECTRUM_INTERP_LINEAR);
    assert_true((u.r > 0) == (locus[i].r > 0) && (u.g > 0) == (locus[i].g > 0) &&
                (u.b > 0) == (locus[i].b > 0));
    /* The loader's clamp keeps the positive parts. */
    assert_true(k.r == fmax(u.r, 0.0) && k.g == fmax(u.g, 0.0) && k.b == fmax(u.b, 0.0));
    checks += 5;
  }
  /* Boxes of 20 nm (zero ends): 580-600 nm is orange (r > g > 0 > b);
   * 600-620 nm is red, r > g > b, with g about 0 since g's matching
   * function (the matrix's second row on xbar, ybar, zbar) changes sign near
   * 606 nm (g > 0 at 600 nm, < 0 at 610 nm in the table above). */
  double wl[6] = {579.0, 580.0, 600.0, 601.0}, val[6] = {0.0, 1.0, 1.0, 0.0};
  rgb u = spectrum_xyz_to_rgb(spectrum_sampled_xyz(wl, val, 4, SPECTRUM_INTERP_LINEAR));
  assert_true(u.r > u.g && u.g > 0.0 && u.b < 0.0);
  for (int i = 0; i < 4; i++) wl[i] += 20.0;
  u = spectrum_xyz_to_rgb(spectrum_sampled_xyz(wl, val, 4, SPECTRUM_INTERP_LINEAR));
  assert_true(u.r > u.g && u.g > u.b && fabs(u.g) < 0.01 * u.r);
  checks += 2;
  assert_int_equal(checks, 27);
}

static void test_zero_extend(void **state) {
  (void)state;
  int checks = 0;
  /* Both ends non-zero: a zero one mean spacing (300 nm) beyond each. */
  double wl[4] = {400.0, 700.0}, val[4] = {0.2, 0.2};
  assert_int_equal(spectrum_zero_extend(wl, val, 2), 4);
  assert_true(wl[0] == 100.0 && val[0] == 0.0 && wl[1] == 400.0 && val[1] == 0.2);
  assert_true(wl[2] == 700.0 && val[2] == 0.2 && wl[3] == 1000.0 && val[3] == 0.0);
  checks += 3;
  /* The first value zero: only the end is extended (100 nm spacing). */
  double wl2[6] = {400, 500, 600, 700}, val2[6] = {0, 8, 15.6, 18.4};
  assert_int_equal(spectrum_zero_extend(wl2, val2, 4), 5);
  assert_true(wl2[0] == 400.0 && wl2[4] == 800.0 && val2[4] == 0.0);
  checks += 2;
  assert_int_equal(checks, 5);
}

static void test_blackbody(void **state) {
  (void)state;
  int checks = 0;
  /* Stefan-Boltzmann: pi * int B dlambda = sigma T^4 (CODATA sigma). */
  const double T = 5000.0, sigma = 5.670373e-8;
  double sum = 0.0;
  for (double l = 10.0; l < 2e5; l += 0.5) sum += 0.5 * spectrum_blackbody(l + 0.25, T);
  assert_near(3.14159265358979 * sum / (sigma * T * T * T * T), 1.0, 1e-4);
  checks++;
  /* Wien: the peak at 2.897772e6 nm K / T. */
  double peak = 2.897772e6 / T;
  assert_true(spectrum_blackbody(peak, T) > spectrum_blackbody(peak - 2.0, T) &&
              spectrum_blackbody(peak, T) > spectrum_blackbody(peak + 2.0, T));
  checks++;
  /* The 1948 candela: 60 cd/cm^2 at 2042 K; L = 683 lm/W * int B ybar. */
  double lum = 683.0 * spectrum_blackbody_xyz(2042.0, SPECTRUM_INTERP_LINEAR).y * SUM_Y;
  assert_near(lum / 6.0e5, 1.0, 0.01);
  checks++;
  /* Illuminant A and the Planckian locus at 6500 K. */
  double x, y;
  spectrum_chromaticity(spectrum_blackbody_xyz(2856.0, SPECTRUM_INTERP_LINEAR), &x, &y);
  assert_near(x, 0.44757, 2e-4);
  assert_near(y, 0.40745, 2e-4);
  spectrum_chromaticity(spectrum_blackbody_xyz(6500.0, SPECTRUM_INTERP_LINEAR), &x, &y);
  assert_near(x, 0.3135, 3e-4);
  assert_near(y, 0.3236, 3e-4);
  checks += 4;
  /* D65 (0.3127, 0.3290) is off the locus. */
  spectrum_chromaticity(spectrum_blackbody_xyz(6504.0, SPECTRUM_INTERP_LINEAR), &x, &y);
  assert_near(x, 0.3127, 2e-3);
  assert_true(0.3290 - y > 0.004);
  checks += 2;
  /* The loader's form: clamped, times scale. */
  rgb one = spectrum_blackbody_rgb(2856.0, 1.0, SPECTRUM_INTERP_LINEAR), three = spectrum_blackbody_rgb(2856.0, 3.0, SPECTRUM_INTERP_LINEAR);
  assert_near(three.r, 3.0 * one.r, 1e-12 * three.r);
  assert_true(one.r > one.g && one.g > one.b && one.b > 0.0);
  checks += 2;
  assert_int_equal(checks, 11);
}

/* Mitsuba 0.6.0's reading (SPECTRUM_INTERP_MITSUBA_060): every interval of
 * the sampled spectrum and of the colour matching functions read with its
 * ends swapped. Against a brute-force midpoint sum of that product
 * (0.001 nm steps, the knots from the table at whole nanometres), against
 * the Cornell box emitter's RGB an independent implementation gives for
 * the two readings, (36.8, 22.0, 5.5) and (41.6, 21.7, 5.5), and a flat
 * spectrum is the same either way. */
static void test_mitsuba_060(void **state) {
  (void)state;
  int checks = 0;
  /* 400:0, 500:8, 600:15.6, 700:18.4 as the loader extends it (800:0). */
  const double wl[5] = {400, 500, 600, 700, 800}, val[5] = {0.0, 8.0, 15.6, 18.4, 0.0};
  double sum[3] = {0, 0, 0}, ysum = 0.0;
  const double h = 0.001;
  for (long k = 0; k < 470000; k++) {
    double x = 360.0 + (k + 0.5) * h;
    int i = (int)floor(x - 360.0);
    double t = x - (360.0 + i);
    spectrum_xyz c0 = spectrum_cmf(360.0 + i), c1 = spectrum_cmf(361.0 + i);
    /* The swapped line: c1 at the cell's start, c0 at its end. */
    double cx = c1.x + t * (c0.x - c1.x), cy = c1.y + t * (c0.y - c1.y),
           cz = c1.z + t * (c0.z - c1.z);
    ysum += h * (c0.y + c1.y) * 0.5; /* per cell, the trapezoid of ybar */
    double f = 0.0;
    for (int j = 0; j < 4; j++)
      if (x >= wl[j] && x < wl[j + 1]) {
        double u = (x - wl[j]) / (wl[j + 1] - wl[j]);
        f = val[j + 1] + u * (val[j] - val[j + 1]);
      }
    sum[0] += h * f * cx, sum[1] += h * f * cy, sum[2] += h * f * cz;
  }
  spectrum_xyz got = spectrum_sampled_xyz(wl, val, 5, SPECTRUM_INTERP_MITSUBA_060);
  const double g[3] = {got.x, got.y, got.z};
  for (int c = 0; c < 3; c++, checks++)
    if (fabs(g[c] - sum[c] / ysum) > 1e-6 * fabs(sum[c] / ysum))
      fail_msg("channel %d: %.9g, brute force %.9g", c, g[c], sum[c] / ysum);
  /* The loader's RGB of the emitter of a public Cornell box (twice the
   * spectrum above), both readings. */
  double w2[6] = {400, 500, 600, 700}, v2[6] = {0.0, 16.0, 31.2, 36.8};
  rgb old = spectrum_sampled_rgb(w2, v2, 4, SPECTRUM_INTERP_MITSUBA_060);
  double w3[6] = {400, 500, 600, 700}, v3[6] = {0.0, 16.0, 31.2, 36.8};
  rgb lin = spectrum_sampled_rgb(w3, v3, 4, SPECTRUM_INTERP_LINEAR);
  assert_near(old.r, 36.8, 0.1);
  assert_near(old.g, 22.0, 0.1);
  assert_near(old.b, 5.5, 0.1);
  assert_near(lin.r, 41.6, 0.1);
  assert_near(lin.g, 21.7, 0.1);
  assert_near(lin.b, 5.5, 0.1);
  checks += 6;
  /* Flat: the same either way. */
  double wf[4] = {360.0, 830.0}, vf[4] = {0.7, 0.7};
  spectrum_xyz a = spectrum_sampled_xyz(wf, vf, 2, SPECTRUM_INTERP_LINEAR);
  spectrum_xyz b = spectrum_sampled_xyz(wf, vf, 2, SPECTRUM_INTERP_MITSUBA_060);
  assert_near(a.x, b.x, 1e-12);
  assert_near(a.y, b.y, 1e-12);
  assert_near(a.z, b.z, 1e-12);
  checks += 3;
  assert_int_equal(checks, 12);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_matrix),    cmocka_unit_test(test_cmf_table),
      cmocka_unit_test(test_equal_energy), cmocka_unit_test(test_d65),
      cmocka_unit_test(test_narrow),    cmocka_unit_test(test_zero_extend),
      cmocka_unit_test(test_blackbody),   cmocka_unit_test(test_mitsuba_060),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
