/*
 * mut_perturb.h: the perturbations of path-space MLT (Veach 1997, section
 * 11.4.3; Veach and Guibas 1997) on pathspace.h's states: small moves of a
 * path that keep its form, each with its exact transition density.
 *
 * Forms. A surface vertex is S (scattering through a delta lobe), G
 * (glossy: ps_glossy, a narrow lobe of a rough conductor or dielectric,
 * phong or ward) or D (the rest). Seen from the camera, x splits into chains: x_1 .. x_{e_0} is a
 * run of S and G vertices (none or more) ending at a D vertex x_{e_0};
 * while the vertex after a chain's end is not connectible (an S vertex), a
 * further chain (S|G)+ D follows, up to e_{n-1}, whose successor is
 * connectible (a D or G surface or the emitter end). A path whose camera
 * walk reaches the emitter end through S and G vertices alone has no
 * chains. (G vertices are connectible; the chains retrace them rather than
 * join through them, because a narrow lobe rejects nearly every join.)
 *
 *  - Lens perturbation (one chain: E S* D (D|L)): the raster point moves by
 *    an offset of length r with density proportional to 1/r on [r1, r2] and
 *    uniform angle; the camera ray through it is retraced through the chain,
 *    each S vertex keeping its lobe (reflection or transmission, the delta
 *    lobe of a mixed BSDF), each G vertex leaving along a new direction
 *    (below; not Veach's: his perturbations know only S and D), to a new D
 *    end, which joins x_{e_0 + 1}.
 *  - Multi-chain perturbation (two chains or more: E S* D (S+ D)+ (D|L)):
 *    the lens perturbation through the first chain; at each further chain's
 *    start the direction leaving the D vertex is x's direction there turned
 *    by an angle theta with density proportional to 1/theta on
 *    [mc_theta1, mc_theta2] and uniform azimuth; the last end joins its
 *    successor.
 *  - Caustic perturbation (E (D|G) (S|G)* (D|L)): x_1 is connectible; m > 1
 *    is the next D vertex or the emitter end (x_2 .. x_{m-1} are S or G);
 *    x_m is a surface or a finite emitter (not a direction at infinity).
 *    The direction leaving x_m towards x_{m-1} turns by theta with density proportional to 1/theta
 *    on [theta1 s, theta2 s], uniform azimuth, where s = |x_1 - x_0| /
 *    (|x_1 x_2| + ... + |x_{m-1} x_m|) (Veach p. 354: an image-plane move
 *    like the lens perturbation's), capped so that theta2 s <= pi / 2 (a
 *    turn must stay below pi for its density to hold; a path whose x_1
 *    nearly touches x_2 would ask for more), depends on the path: the move is not
 *    symmetric and both directions' ranges enter the ratio. The chain is
 *    retraced towards the camera to a new x_1, each S vertex keeping its
 *    lobe, each G vertex leaving along a new direction (below, importance
 *    transport), and x_1 joins the pinhole (its raster point must lie on
 *    the film).
 * A retraced G vertex's direction: with probability 1/2 a sample of its
 * BSDF, else x's direction at that vertex turned by an angle with density
 * proportional to 1/theta on [theta1, theta2] and uniform azimuth (a
 * local move: a fresh sample of a narrow lobe scatters the rest of the
 * path, which loses a small lit region; the turn keeps it near x's).
 * Each kept vertex's lobe flag stays; a retraced vertex must have the same
 * kind (S, G or D) as x's, or there is no proposal (the chain stays).
 *
 * Transition densities, in the path measure of the changed vertices
 * (pathspace.h: area, delta vertices' Diracs reduced):
 *   lens, multi-chain: T(x -> y) = p_r(|dr|) / (2 pi |dr|) * W H *
 *       pdf_cam(y_1) prod_{i=2..e} J_i *
 *       prod_{chains j > 0} p_theta(theta_j) / (2 pi sin theta_j),
 *     dr the raster offset, W H the film's area in pixels (pdf_cam(y_1)
 *     W H is the raster-to-area Jacobian), e the last chain's end, J_i =
 *     (pdf_cam(y_i) + p_turn(y_i)) / 2 after a G vertex (the BSDF's sampling
 *     density and the turn's, p_theta(theta) / (2 pi sin theta) times
 *     |cos y_i| / |y_i - y_{i-1}|^2, theta the angle between x's and y's
 *     directions there), else |cos y_i| / |y_i - y_{i-1}|^2;
 *   caustic: T(x -> y) = p_theta,x(theta) / (2 pi sin theta) *
 *       |cos y_{m-1}| / |y_{m-1} - x_m|^2 *
 *       prod_{i=1..m-2} K_i, K_i = ps_forced_density(y_i through y_{i+1})
 *       when y_{i+1} is S, (pdf_light(y_i) + p_turn(y_i)) / 2 when G,
 *     p_theta,x on x's range;
 * and the acceptance f(y) T(y -> x) / (f(x) T(x -> y)): for the lens and
 * multi-chain perturbations the offsets' densities are symmetric and
 * cancel, leaving the Jacobians and the G vertices' sampling densities.
 */
#ifndef LMC_PATH_MUT_PERTURB_H
#define LMC_PATH_MUT_PERTURB_H

#include "lmc/path/pathspace.h"
#include "render/rng.h"

/* The most chains a multi-chain perturbation follows. */
#define MUT_PERTURB_MAX_CHAINS PS_MAX_VERTICES

typedef enum mut_perturb_kind {
  MUT_PERTURB_LENS = 0,
  MUT_PERTURB_MULTICHAIN,
  MUT_PERTURB_CAUSTIC
} mut_perturb_kind;

/* The perturbations' sizes (mut_perturb_init: Mitsuba 0.6's defaults). */
typedef struct mut_perturb {
  const ps_context *ctx;    /* borrowed */
  double r1, r2;            /* lens: the raster offset's length range, pixels (0.1 and
                               sqrt(0.05 W H / pi), Veach p. 354) */
  double theta1, theta2;    /* caustic: the angle range seen from the camera that r1, r2
                               pixels span (radians) */
  double mc_theta1, mc_theta2; /* multi-chain: the direction's angle range (0.0001 and
                                  0.1 degrees, radians) */
  double test_jac_power;    /* tests only: the densities' Jacobians raised to this wrong
                               power (1: right) */
} mut_perturb;

void mut_perturb_init(mut_perturb *mp, const ps_context *ctx);

/* Whether vertex i of x is G (the opening comment). */
int mut_perturb_glossy(const mut_perturb *mp, const ps_path *x, int i);
/* The camera-side chains of x: their ends e_0 < e_1 < ... into OUT_ends
 * (room for MUT_PERTURB_MAX_CHAINS); returns their number (0: none). */
int mut_perturb_chains(const mut_perturb *mp, const ps_path *x, int *OUT_ends);
/* The caustic perturbation's m for x, or 0 when it does not apply. */
int mut_perturb_caustic_m(const mut_perturb *mp, const ps_path *x);
/* The caustic perturbation's scale s of x's turn (the opening comment). */
double mut_perturb_caustic_scale(const mut_perturb *mp, const ps_path *x, int m);
/* Whether perturbation `kind` applies to x. */
int mut_perturb_applies(const mut_perturb *mp, mut_perturb_kind kind, const ps_path *x);

/* y from x by the lens or multi-chain perturbation with its choices given:
 * the new raster point (rx, ry) and, for the chains after the first, the
 * directions dirs[0 .. n - 2] leaving their starting D vertices; G
 * vertices sample their BSDFs from r (NULL: a path with G vertices makes
 * no proposal). Returns 1 with y evaluated (f(y) may be 0: blocked, off
 * the lobes' support), 0 when y has not x's form (the chain stays). rays
 * (may be NULL) adds the rays traced. */
int mut_perturb_lens_generate(const mut_perturb *mp, const ps_path *x, double rx, double ry,
                              const vec3 *dirs, rng *r, ps_path *OUT_y, int64_t *rays);
/* y from x by the caustic perturbation with x_m's new direction towards
 * y_{m-1} given (as above). */
int mut_perturb_caustic_generate(const mut_perturb *mp, const ps_path *x, vec3 dir, rng *r,
                                 ps_path *OUT_y, int64_t *rays);
/* Whether x's vertex i scatters through a transmission (its neighbours
 * on opposite sides of its geometric normal). */
int mut_perturb_transmits(const ps_path *x, int i);
/* The direction leaving surface vertex v, reached from along wo (unit,
 * towards the vertex before it), through a delta lobe that transmits
 * (trans) or reflects, into *OUT_dir; 0 when v has no such lobe there. */
int mut_perturb_forced_dir(const bdpt_vertex *v, vec3 wo, int trans, transport_mode mode,
                           vec3 *OUT_dir);
/* A direction sampled from the BSDF of surface vertex v reached from along
 * wo (unit, towards the vertex before it) in transport mode `mode`, not
 * through a delta lobe, on the sides Mitsuba's rule allows; 0 when there is
 * none (or r is NULL). */
int mut_perturb_sample_dir(const bdpt_vertex *v, vec3 wo, transport_mode mode, rng *r,
                           vec3 *OUT_dir);

/* T(x -> y) of perturbation `kind` (the opening comment), 0 when y cannot
 * come from x by it. */
double mut_perturb_density(const mut_perturb *mp, mut_perturb_kind kind, const ps_path *x,
                           const ps_path *y);

/* A proposal's random choices (for tests). */
typedef struct mut_perturb_choice {
  double size, phi;      /* lens, multi-chain: the raster offset's length (pixels) and angle;
                            caustic: the turn's angle and azimuth (the frame frame_from_z of
                            x_m's direction towards x_{m-1}) */
  double turn, turn_phi; /* multi-chain: the first further chain's turn and azimuth */
} mut_perturb_choice;

/* Proposes y from x by perturbation `kind` (which must apply to x): draws
 * its choices from r, generates y and writes f(y) T(y -> x) / (f(x)
 * T(x -> y)) to *OUT_ratio. Returns 0 when there is no proposal (ratio 0;
 * the chain stays). rays as above; OUT_choice (may be NULL) gets the
 * choices drawn, whether or not they made a proposal. */
int mut_perturb_propose(const mut_perturb *mp, mut_perturb_kind kind, rng *r, const ps_path *x,
                        ps_path *OUT_y, double *OUT_ratio, int64_t *rays,
                        mut_perturb_choice *OUT_choice);

/* Retracing, one vertex at a time (also the lens subpath mutation's):
 * the surface hit from vertex `from` along the unit direction dir, as
 * bdpt's walk records it (delta flag clear); and the pinhole and the
 * surface its ray through raster point (rx, ry) hits. Return 0 when the
 * ray hits no surface. rays (may be NULL) adds the rays traced. */
int mut_perturb_trace(const ps_context *ctx, const bdpt_vertex *from, vec3 dir,
                      transport_mode mode, bdpt_vertex *OUT, int64_t *rays);
int mut_perturb_first_hit(const ps_context *ctx, double rx, double ry, bdpt_vertex *OUT_pinhole,
                          bdpt_vertex *OUT_hit, int64_t *rays);
/* The escape of a camera-side ray from `from` along dir to the infinite
 * lights: the endpoint at infinity bdpt's walk records (light -1); 0 when
 * the ray hits a surface or the scene has no infinite light. */
int mut_perturb_trace_sky(const ps_context *ctx, const bdpt_vertex *from, vec3 dir,
                          bdpt_vertex *OUT, int64_t *rays);

/* The offset distributions: a length on [lo, hi] with density 1 / (t
 * ln(hi / lo)) from u in [0, 1), and that density (0 outside). */
double mut_perturb_log_sample(double lo, double hi, double u);
double mut_perturb_log_pdf(double lo, double hi, double t);

#endif
