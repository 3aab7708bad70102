/*
 * bsdf_configs.h: the BSDF configurations the tests share (test_bsdf.c's
 * chi-square and consistency tests, test_bsdf_invert.c's inverses): every
 * non-delta model at several roughnesses and incident directions.
 */
#ifndef LMC_TESTS_BSDF_CONFIGS_H
#define LMC_TESTS_BSDF_CONFIGS_H

#include <math.h>
#include <stdio.h>

#include "render/bsdf/bsdf.h"

/* A direction with cos(theta) = z at azimuth phi. */
static inline vec3 dir(double z, double phi) {
  double s = sqrt(fmax(0.0, 1.0 - z * z));
  return v3(s * cos(phi), s * sin(phi), z);
}

/* ---- The configurations under test --------------------------------------- */

typedef struct config {
  char name[96];
  bsdf b;
  vec3 wo;
  transport_mode mode;
  int n_theta, n_phi; /* chi-square grid (finer for the sharpest lobes) */
} config;

#define MAX_CONFIGS 160

/* Every non-delta configuration of the chi-square and consistency tests. */
static inline int make_configs(config *c) {
  int n = 0;
  const double phi0 = 0.7;
  /* Diffuse. */
  const double diff_z[] = {1.0, 0.6, 0.05};
  for (int i = 0; i < 3; i++) {
    bsdf_init_defaults(&c[n].b, "diffuse");
    c[n].wo = dir(diff_z[i], phi0);
    snprintf(c[n].name, sizeof c[n].name, "diffuse wo.z=%.2f", diff_z[i]);
    n++;
  }
  /* Phong: three exponents, three angles. */
  const double exps[] = {3.0, 30.0, 80.0};
  const double ph_z[] = {0.95, 0.5, 0.1};
  for (int e = 0; e < 3; e++)
    for (int i = 0; i < 3; i++) {
      bsdf_init_defaults(&c[n].b, "phong");
      c[n].b.exponent = exps[e];
      c[n].wo = dir(ph_z[i], phi0);
      snprintf(c[n].name, sizeof c[n].name, "phong n=%g wo.z=%.2f", exps[e], ph_z[i]);
      n++;
    }
  /* Rough conductor and dielectric: distribution x alpha x visible x wo.
   * GGX's rough refraction has a jump of its pdf where the generalised half
   * vector becomes horizontal, the plane wi.z = -wo.z / e; the wo chosen
   * here put that plane on a boundary of the chi-square bands (multiples
   * of 1/30 in z), so no cell straddles the jump. */
  const double eta = 1.5046 / 1.000277;
  const double alphas[] = {0.2, 0.6};
  const double rc_z[] = {0.9, 0.4, 0.1};
  const double rd_z[] = {0.6 * eta, 0.1 * eta, -0.7, -0.3 / eta};
  for (int d = 0; d < 2; d++)
    for (int a = 0; a < 2; a++)
      for (int v = 0; v < 2; v++) {
        for (int i = 0; i < 3; i++) {
          if (a == 1 && i == 1) continue; /* keep the count down */
          bsdf_init_defaults(&c[n].b, "roughconductor");
          c[n].b.dist = d ? MF_GGX : MF_BECKMANN;
          c[n].b.alpha = alphas[a];
          c[n].b.sample_visible = v;
          c[n].wo = dir(rc_z[i], phi0);
          snprintf(c[n].name, sizeof c[n].name, "roughconductor %s a=%g vis=%d wo.z=%.2f",
                   d ? "ggx" : "beckmann", alphas[a], v, rc_z[i]);
          n++;
        }
        for (int i = 0; i < 4; i++) {
          bsdf_init_defaults(&c[n].b, "roughdielectric");
          c[n].b.dist = d ? MF_GGX : MF_BECKMANN;
          c[n].b.alpha = alphas[a];
          c[n].b.sample_visible = v;
          c[n].wo = dir(rd_z[i], phi0);
          c[n].mode = (i & 1) ? TRANSPORT_IMPORTANCE : TRANSPORT_RADIANCE;
          snprintf(c[n].name, sizeof c[n].name, "roughdielectric %s a=%g vis=%d wo.z=%.2f",
                   d ? "ggx" : "beckmann", alphas[a], v, rd_z[i]);
          n++;
        }
      }
  /* Mitsuba's default roughness 0.1 on a finer grid (150 x 300 cells). */
  for (int d = 0; d < 2; d++) {
    bsdf_init_defaults(&c[n].b, "roughconductor");
    c[n].b.dist = d ? MF_GGX : MF_BECKMANN;
    c[n].wo = dir(0.7, phi0);
    c[n].n_theta = 150;
    c[n].n_phi = 300;
    snprintf(c[n].name, sizeof c[n].name, "roughconductor %s a=0.1 wo.z=0.70", d ? "ggx" : "beckmann");
    n++;
    bsdf_init_defaults(&c[n].b, "roughdielectric");
    c[n].b.dist = d ? MF_GGX : MF_BECKMANN;
    c[n].b.sample_visible = d;
    c[n].wo = dir(d ? -0.8 : 0.6 * eta, phi0);
    c[n].n_theta = 150;
    c[n].n_phi = 300;
    snprintf(c[n].name, sizeof c[n].name, "roughdielectric %s a=0.1 vis=%d wo.z=%.2f",
             d ? "ggx" : "beckmann", d, c[n].wo.z);
    n++;
  }
  /* Plastic (the diffuse lobe; specular samples count as rejected). */
  const double pl_z[] = {0.9, 0.2};
  for (int i = 0; i < 2; i++) {
    bsdf_init_defaults(&c[n].b, "plastic");
    c[n].b.nonlinear = i;
    c[n].wo = dir(pl_z[i], phi0);
    snprintf(c[n].name, sizeof c[n].name, "plastic nonlinear=%d wo.z=%.2f", i, pl_z[i]);
    n++;
  }
  /* Diffuse transmission, from both sides (the sampler turns away from wo). */
  const double dt_z[] = {0.8, -0.3};
  for (int i = 0; i < 2; i++) {
    bsdf_init_defaults(&c[n].b, "difftrans");
    c[n].b.transmittance = tex_constant(rgb_make(0.6, 0.5, 0.4));
    c[n].wo = dir(dt_z[i], phi0);
    snprintf(c[n].name, sizeof c[n].name, "difftrans wo.z=%.2f", dt_z[i]);
    n++;
  }
  /* Blends (their BSDFs in static storage: the configurations are copied):
   * rough gold over a diffuse base, and smooth glass with a diffuse
   * transmitter (its delta lobes count as rejected, as plastic's). */
  static bsdf blend_parts[4];
  bsdf_init_defaults(&blend_parts[0], "diffuse");
  blend_parts[0].diffuse = tex_constant(rgb_make(0.7, 0.5, 0.3));
  bsdf_init_defaults(&blend_parts[1], "roughconductor");
  blend_parts[1].alpha = 0.3;
  bsdf_init_defaults(&blend_parts[2], "dielectric");
  bsdf_init_defaults(&blend_parts[3], "difftrans");
  const double bl_w[] = {0.3, 0.6}, bl_z[] = {0.7, -0.5};
  for (int i = 0; i < 2; i++) {
    bsdf_init_defaults(&c[n].b, "blendbsdf");
    c[n].b.diffuse = tex_constant(rgb_gray(bl_w[i]));
    c[n].b.nested_bsdf[0] = &blend_parts[2 * i];
    c[n].b.nested_bsdf[1] = &blend_parts[2 * i + 1];
    c[n].wo = dir(bl_z[i], phi0);
    snprintf(c[n].name, sizeof c[n].name, "blendbsdf %s w=%g wo.z=%.2f",
             i ? "dielectric+difftrans" : "diffuse+roughconductor", bl_w[i], bl_z[i]);
    n++;
  }
  /* Rough diffuse (Oren-Nayar): two roughnesses, the full model and the
   * fast approximation, normal / oblique / grazing wo (the sampler is the
   * cosine one; f enters through the consistency test). */
  const double rdf_alpha[] = {0.3, 1.0};
  for (int a = 0; a < 2; a++)
    for (int fa = 0; fa < 2; fa++)
      for (int i = 0; i < 3; i++) {
        bsdf_init_defaults(&c[n].b, "roughdiffuse");
        c[n].b.alpha = rdf_alpha[a];
        c[n].b.fast_approx = fa;
        c[n].wo = dir(diff_z[i], phi0);
        snprintf(c[n].name, sizeof c[n].name, "roughdiffuse a=%g fast=%d wo.z=%.2f", rdf_alpha[a], fa,
                 diff_z[i]);
        n++;
      }
  /* Ward: the three variants, isotropic (0.2) and anisotropic (0.1, 0.3),
   * normal / oblique / grazing wo; the anisotropic lobe on the finer grid. */
  static const char *const ward_names[3] = {"ward", "ward-duer", "balanced"};
  const double ward_z[] = {1.0, 0.6, 0.1};
  for (int v = 0; v < 3; v++)
    for (int an = 0; an < 2; an++)
      for (int i = 0; i < 3; i++) {
        bsdf_init_defaults(&c[n].b, "ward");
        c[n].b.variant = (ward_variant)v;
        c[n].b.alpha_u = an ? 0.1 : 0.2;
        c[n].b.alpha_v = an ? 0.3 : 0.2;
        c[n].wo = dir(ward_z[i], phi0);
        if (an) {
          c[n].n_theta = 150;
          c[n].n_phi = 300;
        }
        snprintf(c[n].name, sizeof c[n].name, "ward %s au=%g av=%g wo.z=%.2f", ward_names[v],
                 c[n].b.alpha_u, c[n].b.alpha_v, ward_z[i]);
        n++;
      }
  /* Rough plastic: distribution x alpha x wo (normal, oblique, grazing);
   * visible normals with the sharper lobe, all normals with the wider,
   * nonlinear on GGX. alpha = 0.1 on the finer grid. */
  const double rp_alpha[] = {0.1, 0.5};
  const double rp_z[] = {1.0, 0.5, 0.08};
  for (int d = 0; d < 2; d++)
    for (int a = 0; a < 2; a++)
      for (int i = 0; i < 3; i++) {
        bsdf_init_defaults(&c[n].b, "roughplastic");
        c[n].b.dist = d ? MF_GGX : MF_BECKMANN;
        c[n].b.alpha = rp_alpha[a];
        c[n].b.sample_visible = !a;
        c[n].b.nonlinear = d;
        c[n].b.diffuse = tex_constant(rgb_make(0.3, 0.5, 0.7));
        bsdf_prepare(&c[n].b);
        c[n].wo = dir(rp_z[i], phi0);
        if (!a) {
          c[n].n_theta = 150;
          c[n].n_phi = 300;
        }
        snprintf(c[n].name, sizeof c[n].name, "roughplastic %s a=%g vis=%d wo.z=%.2f",
                 d ? "ggx" : "beckmann", rp_alpha[a], !a, rp_z[i]);
        n++;
      }
  /* A twosided rough conductor seen from below. */
  bsdf_init_defaults(&c[n].b, "roughconductor");
  c[n].b.twosided = 1;
  c[n].b.alpha = 0.3;
  c[n].b.dist = MF_GGX;
  c[n].wo = dir(-0.5, phi0);
  snprintf(c[n].name, sizeof c[n].name, "twosided roughconductor ggx a=0.3 wo.z=-0.50");
  n++;
  /* Masks (their pass-through counts as rejected): on diffuse, and on the
   * twosided rough conductor seen from below. */
  bsdf_init_defaults(&c[n].b, "diffuse");
  c[n].b.masked = 1;
  c[n].b.opacity = tex_constant(rgb_make(0.3, 0.6, 0.9));
  c[n].wo = dir(0.7, phi0);
  snprintf(c[n].name, sizeof c[n].name, "mask diffuse wo.z=0.70");
  n++;
  c[n] = c[n - 2];
  c[n].b.masked = 1;
  c[n].b.opacity = tex_constant(rgb_gray(0.5));
  snprintf(c[n].name, sizeof c[n].name, "mask twosided roughconductor ggx a=0.3 wo.z=-0.50");
  n++;
  for (int i = 0; i < n; i++)
    if (!c[i].n_theta) {
      c[i].n_theta = 60;
      c[i].n_phi = 120;
    }
  return n;
}

#endif
