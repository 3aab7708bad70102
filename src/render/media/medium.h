/*
 * medium.h: participating media, Mitsuba 0.6's `homogeneous` medium: the
 * transmittance along a segment and free-flight sampling, in doubles and
 * in duals from one source (medium_generic.h, compiled twice by medium.c).
 *
 * A homogeneous medium has per-channel absorption sigma_a and scattering
 * sigma_s coefficients (per unit length, Mitsuba's `scale` applied),
 * extinction sigma_t = sigma_a + sigma_s, and a phase function (phase.h).
 * Along a segment of length t the transmittance is exp(-sigma_t t) per
 * channel.
 *
 * Free flight (Mitsuba's "balance" strategy): u_ch picks one of the three
 * channels c uniformly, u_t the distance t = -log(1 - u_t) / sigma_t[c]
 * (exponential in that channel). A distance below t_max is a scattering
 * event inside the segment; else the flight reaches t_max. The densities
 * are the channels' average (one-sample MIS over the channels):
 *   scattering at t   p(t) = (1/3) sum_c sigma_t[c] exp(-sigma_t[c] t),
 *   reaching t_max    P    = (1/3) sum_c exp(-sigma_t[c] t_max),
 * and the sample's weight is the transmittance exp(-sigma_t t), times
 * sigma_s, over p(t) (scattering), or over P (reaching t_max). A channel
 * with sigma_t 0 never scatters (its distance is infinite). The inverse
 * gives numbers (u_ch, u_t) with which the sampler makes a given event,
 * the channel picked by its share of the density.
 */
#ifndef LMC_RENDER_MEDIUM_H
#define LMC_RENDER_MEDIUM_H

#include "ad/dual.h"
#include "render/error.h"
#include "render/media/phase.h"
#include "render/plugin.h"
#include "render/rgb_ad.h"
#include "render/spectrum.h"

typedef struct medium {
  rgb sigma_a, sigma_s; /* per unit length (scale applied) */
  rgb sigma_t;          /* sigma_a + sigma_s (medium_set) */
  phase_fn ph;
  char id[64];          /* the XML id, for messages */
  char file[256];       /* where it was declared (the XML element), for messages */
  int line;
} medium;

/* A free flight's outcome. */
typedef struct medium_flight {
  int scattered; /* 1: a scattering event at t < t_max; 0: the flight reached t_max */
  double t;      /* the event's distance (t_max when it reached it) */
  rgb weight;    /* transmittance (times sigma_s when scattered) over the density */
  double pdf;    /* p(t) (scattered) or P (reached t_max) */
} medium_flight;

/* In duals: the distance and the weight move with u_t (and with the
 * segment's length when it reached t_max). */
typedef struct medium_flight_ad {
  int scattered;
  ad t;
  adrgb weight;
  ad pdf;
} medium_flight_ad;

/* A free flight across a segment made of pieces in different media (the
 * ray crossing index-matched boundaries): the channel c picked by u_ch
 * and the optical depth tau = -log(1 - u_t) still to travel in it. Each
 * piece of length len in medium m (NULL: vacuum) either spends sigma_t[c]
 * len of tau, or scatters where tau runs out; T is the transmittance so
 * far, per channel. A single piece is medium_sample_flight's flight; over
 * several the densities are the same means over the channels of the
 * accumulated transmittance (medium_track_pdf). */
typedef struct medium_track {
  int c;
  double tau;
  rgb T;
} medium_track;

typedef struct medium_track_ad {
  int c;
  ad tau;
  adrgb T;
} medium_track_ad;

/* Sets m's coefficients (sigma_t from them) and an isotropic phase function. */
void medium_set(medium *m, rgb sigma_a, rgb sigma_s);
/* Mitsuba 0.6's homogeneous medium's parameters (its phase function is
 * read apart, from the nested <phase>): `material`, a preset by name (case
 * ignored; Mitsuba's default Skin1), or sigmaA and sigmaS, or sigmaT and
 * albedo (each pair starting from the preset's values; mixing the pairs,
 * or a preset with either, is an error), g (the preset's scattering
 * anisotropy, by which sigma_s is reduced to sigma_s (1 - g), as Mitsuba
 * does), and `scale` applied to the coefficients. Negative or non-finite
 * coefficients are errors at their line. */
lmc_status medium_read(medium *m, plugin_props *p);
/* A preset of Mitsuba's (Jensen et al. 2001; Narasimhan et al. 2006):
 * sigma_s, sigma_a (per metre: Mitsuba's tables times 100) and g; 0 when
 * `name` is none of them. */
int medium_material(const char *name, rgb *OUT_sigma_s, rgb *OUT_sigma_a, rgb *OUT_g);

/* exp(-sigma_t t). */
rgb medium_transmittance(const medium *m, double t);
adrgb medium_transmittance_ad(ad_arena *A, const medium *m, ad t);
/* A free flight over a segment of length t_max (INFINITY: unbounded) from
 * (u_ch, u_t); 0 when nothing can happen (a medium that does not
 * extinguish, unbounded). */
int medium_sample_flight(const medium *m, double t_max, double u_ch, double u_t,
                         medium_flight *OUT);
int medium_sample_flight_ad(ad_arena *A, const medium *m, ad t_max, ad u_ch, ad u_t,
                            medium_flight_ad *OUT);
/* The density of a flight's outcome: p(t) for scattering at t, P for
 * reaching t_max (scattered = 0, t = t_max). */
double medium_flight_pdf(const medium *m, int scattered, double t);
ad medium_flight_pdf_ad(ad_arena *A, const medium *m, int scattered, ad t);
/* A track's start from (u_ch, u_t); its next piece (1: it scatters there,
 * at *OUT_t from the piece's start); the density of its outcome from the
 * transmittance T it gathered: scattering in m (scattered 1), or passing
 * every piece (0; m unused). */
void medium_track_begin(double u_ch, double u_t, medium_track *k);
void medium_track_begin_ad(ad_arena *A, ad u_ch, ad u_t, medium_track_ad *k);
int medium_track_piece(const medium *m, double len, medium_track *k, double *OUT_t);
int medium_track_piece_ad(ad_arena *A, const medium *m, ad len, medium_track_ad *k, ad *OUT_t);
double medium_track_pdf(const medium *m, int scattered, rgb T);
ad medium_track_pdf_ad(ad_arena *A, const medium *m, int scattered, adrgb T);
/* The inverse of medium_sample_flight from two uniform numbers r: (u_ch,
 * u_t) making the outcome (scattered at t, or reaching t = t_max); 0 when
 * the sampler cannot make it. */
int medium_invert_flight(const medium *m, int scattered, double t, const double r[2],
                         double OUT_u[2]);

#endif
