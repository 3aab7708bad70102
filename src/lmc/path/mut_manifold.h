/*
 * mut_manifold.h: the manifold perturbation of manifold exploration
 * (Jakob and Marschner 2012, section 5; Jakob's thesis, chapter 4) on
 * pathspace.h's states: the image point moves as the lens perturbation
 * moves it, the camera's specular chain is retraced to a new first
 * diffuse vertex, and the specular chain behind that vertex, which no ray
 * from it can retrace (its far end is pinned), follows by the manifold
 * walk (lmc/path/manifold.h). Chain vertices are S (delta surfaces) or G
 * (glossy, ps_glossy), which the move treats as specular with their half
 * vectors held (Jakob's offset manifolds; Kaplanyan et al. 2014's
 * half-vector coordinates).
 *
 * Form. x_1 .. x_{b-1} are S or G (none when b = 1), x_b is neither (a D
 * surface), x_{b+1} .. x_{c-1} are S or G (at least one: with none the lens
 * perturbation applies), and x_c is fixed: a D surface or the emitter end
 * x_k (a point, spot or area light's point, or a direction at infinity).
 * No other perturbation moves this form when x_c is at infinity (a caustic
 * of an environment seen on a diffuse surface, E D S+ L, or the LMC
 * paper's torus, E G+ D G+ L), and the lens and multi-chain perturbations
 * move it only apart when both sides of x_b are specular.
 *
 * The sky form. x_1 .. x_{k-1} are S or G and x_k is a direction at
 * infinity that a ray can meet (an environment, a constant or sunsky
 * emitter; not a directional light), or a point on an area light: the
 * camera's chain reaches the sky (a glass cube seen against the sky, the
 * torus's other paths, E G+ L) or the light (a lamp seen in a mirror or
 * through glass). mut_manifold_form gives b = c = k. The camera ray
 * through the moved image point is traced through x_1 .. x_{k-1} about
 * their held half vectors (mf_scatter) and must leave the scene (y_k is
 * its direction) or meet x_k's area light (y_k is that point). There is
 * no walk: the trace is its own inverse.
 *
 * The move. The raster point moves by the lens perturbation's offset
 * (mut_perturb.h: length with density proportional to 1/r on [r1, r2],
 * uniform angle); the camera ray through it is traced through x_1 ..
 * x_{b-1} (mf_trace of the chain x_0 .. x_b), each S vertex through its
 * lobe, each G vertex about the microfacet normal that keeps its half
 * vector (in its shading frame) x's, to a new y_b on x_b's mesh. The chain
 * x_c, x_{c-1}, .., x_{b+1}, x_b (x_c its fixed start, G vertices' half
 * vectors held) then walks (mf_walk) until its end reaches y_b; its
 * vertices are y's y_{c-1} .. y_{b+1}, and y_b joins y_{b+1} (a shadow
 * ray). The walk is deterministic, so the move is reversible only if the
 * walk from y's chain back to x_b returns to x's chain: it is computed, and
 * a y whose reverse walk fails or lands elsewhere (by more than 1e-6 of the
 * scene's radius at any vertex) is refused (T(y -> x) = 0).
 *
 * Transition density. The move keeps every G vertex's half vector h_i and
 * moves the rest, so it is a move in the coordinates (raster point, h_i,
 * the S vertices' reduced Diracs), in which the path's density is f times
 * the Jacobian from the path measure (pathspace.h's: area, delta vertices'
 * Diracs reduced) to them; as a density in the path measure of the
 * changed vertices y_1 .. y_{c-1}:
 *   T(x -> y) = p_r(|dr|) / (2 pi |dr|) * W H * pdf_cam(y_1)
 *               * prod_{i=1..b-1} K_i(y)                        (the camera's chain)
 *               * Phi(y) / G(y)                                 (the chain behind y_b)
 * K_i, the density of y_{i+1} through y_i: for an S vertex |cos y_{i+1}| /
 * |y_{i+1} - y_i|^2 (its forced direction), for a G vertex |det dc_i /
 * dA_{i+1}| (c_i its projected half vector, manifold.h; mf_jacobian's C_i
 * over the area of a unit of barycentrics): the camera's chain is traced
 * one vertex after the other, so its Jacobian is triangular. Phi is the
 * density the chain behind y_b would have if it were traced from x_c with
 * a solid-angle density of one (after a direction start: a density of one
 * on the plane perpendicular to it): |cos y_{c-1}| / |y_{c-1} - x_c|^2 (a
 * direction start: |cos y_{c-1}|) times, at each further vertex, the
 * factor above through the chain vertex before it (ps_forced_density from
 * the light side for an S vertex); G is the generalized geometry term of
 * that chain with its G vertices' half vectors held and without x_c's
 * cosine (mf_geometry_term: d omega_c / dA_b, or dA_perp / dA_b): y_b is
 * drawn with the camera's density, and the chain is a function of y_b
 * and the held half vectors, so its direction at x_c has the density of
 * y_b over G. For a chain without S or G vertices Phi / G = 1. The
 * half-vector measure is the same at x and y (the held h_i are equal), so
 * it cancels in the acceptance f(y) T(y -> x) / (f(x) T(x -> y)), as do
 * the offsets' densities.
 *
 * The sky form's density: p_r(|dr|) / (2 pi |dr|) W H pdf_cam(y_1)
 * prod_{i=1..k-1} K_i, with K_i as above for i < k - 1 and, for the
 * direction y_k, 1 after an S vertex (its Dirac reduced) and |det d h_{k-1}
 * / d omega| (mf_half_vector_dir_jacobian) after a G vertex; a G vertex's
 * K_i before a surface (an area light's y_k too) is the same determinant
 * times |cos y_{i+1}| / d^2, an S vertex's |cos y_{i+1}| / d^2.
 *
 * HSLT's half-vector perturbation (Kaplanyan, Hanika and Dachsbacher 2014;
 * mut_manifold_init_hslt). The same move over the whole path: x_b is the
 * camera's first vertex that is not S (x_1 .. x_{b-1} are S), x_c = x_k
 * the emitter end, and every vertex between them (at least one) is a
 * chain vertex, S or not: a D vertex too is held at a half vector, its
 * target (MF_PATH_ANY). The move draws the raster offset as above and a
 * new half vector for every chain vertex that is not S, h'_j = h_j +
 * sigma_j z (z a standard normal pair, in the projected half vector's
 * coordinates of manifold.h; sigma_j = hslt_step times the vertex's
 * width, mut_manifold_hslt_width; a draw with |h'_j| >= 1 makes no
 * proposal), projects x's chain onto the manifold of those targets (a
 * trace from x_k through x_{k-1} about them: mf_trace_through) and walks
 * it to y_b, which the retraced camera ray gives. The chain is then a
 * function of y_b and the h', so
 *   T(x -> y) = p_r(|dr|) / (2 pi |dr|) * W H * pdf_cam(y_1)
 *               * prod_{i=1..b-1} K_i(y) * Phi(y) / G(y) * prod_j q(h'_j | h_j),
 * Phi and G as above with every non-S chain vertex's factor |det dc_i /
 * dA_{i+1}| (the density per unit of its half vector's measure), q the
 * normal density of the draw. q is symmetric, so the ratio keeps f,
 * Phi / G and the camera's Jacobians. The reverse walk from y, with x's
 * half vectors as targets, must return to x, as above. The light's end
 * x_k stays: a point on a light, or a light's direction at infinity
 * (other moves change it).
 */
#ifndef LMC_PATH_MUT_MANIFOLD_H
#define LMC_PATH_MUT_MANIFOLD_H

#include "lmc/path/manifold.h"
#include "lmc/path/mut_perturb.h"

typedef struct mut_manifold {
  const ps_context *ctx; /* borrowed */
  const mut_perturb *mp; /* borrowed: the raster offset's range (r1, r2) */
  int hslt;              /* 1: HSLT's half-vector perturbation (above); 0: the manifold one */
  double hslt_step;      /* HSLT: sigma_j = hslt_step times the vertex's width */
  mf_options walk;        /* the walks' settings (mf_options_default) */
  double back_tol;        /* the reverse walk's chain against x's: 1e-6 scene radius */
  double test_jac_power;  /* tests only: G (and the sky form's area factor at an area light)
                             raised to this wrong power (1: right) */
  double test_glossy_power; /* tests only: the G vertices' factors likewise */
} mut_manifold;

/* What one proposal did (for the statistics line; may be summed). */
typedef struct mut_manifold_tally {
  int64_t walks;      /* walks begun (forward and reverse) */
  int64_t walked;     /* walks that reached their target */
  int64_t traces;     /* the walks' projections (rays through the chain) */
  int64_t irreversible; /* proposals refused because the reverse walk failed or went elsewhere */
} mut_manifold_tally;

void mut_manifold_init(mut_manifold *mm, const ps_context *ctx, const mut_perturb *mp);
/* The same for HSLT's half-vector perturbation, its step factor `step` (> 0). */
void mut_manifold_init_hslt(mut_manifold *mm, const ps_context *ctx, const mut_perturb *mp,
                            double step);

/* HSLT: the width of vertex j's half-vector step before hslt_step: its
 * BSDF's roughness (bsdf_model.h; 1 for a diffuse surface), at most
 * MUT_HSLT_MAX_WIDTH. */
#define MUT_HSLT_MAX_WIDTH 0.25
/* HSLT: the projections a walk may trace before it fails (the manifold
 * perturbation's: mf_options_default's 64). */
#define MUT_HSLT_MAX_TRACES 8
double mut_manifold_hslt_width(const ps_context *ctx, const ps_path *x, int j);

/* The targets of the chain behind x_b as the move reads them from x: for
 * each path vertex j (b < j < c) that is not S, its projected half vector
 * (manifold.h) in OUT_h[2 j], OUT_h[2 j + 1]; the other entries 0. 1 on
 * success, 0 when the move does not apply or a chain cannot be read. */
int mut_manifold_half_vectors(const mut_manifold *mm, const ps_path *x,
                              double OUT_h[2 * PS_MAX_VERTICES]);

/* The form's indices of x (the opening comment): b and c, 1 when it
 * applies, else 0. */
int mut_manifold_form(const mut_manifold *mm, const ps_path *x, int *OUT_b, int *OUT_c);
static inline int mut_manifold_applies(const mut_manifold *mm, const ps_path *x) {
  int b, c;
  return mut_manifold_form(mm, x, &b, &c);
}

/* y from x through the image point (rx, ry): the retrace and the walk
 * (the opening comment), without the reverse walk; under HSLT, h gives
 * the chain's new targets as mut_manifold_half_vectors lays them out
 * (the manifold perturbation: NULL, x's own). Returns 1 with y evaluated
 * (f(y) may be 0: the join blocked), 0 when there is no y. rays (may be
 * NULL) adds the rays traced, tally (may be NULL) the walks. */
int mut_manifold_generate(const mut_manifold *mm, const ps_path *x, double rx, double ry,
                          const double *h, ps_path *OUT_y, int64_t *rays,
                          mut_manifold_tally *tally);

/* Whether the walk from y's chain to x's x_b (under HSLT with x's half
 * vectors as targets) returns to x's chain. */
int mut_manifold_reversible(const mut_manifold *mm, const ps_path *x, const ps_path *y,
                            int64_t *rays, mut_manifold_tally *tally);

/* T(x -> y) (the opening comment), 0 when y cannot come from x. */
double mut_manifold_density(const mut_manifold *mm, const ps_path *x, const ps_path *y);

/* Proposes y from x (to which the move must apply): draws the offset,
 * generates y, checks the reverse walk and writes f(y) T(y -> x) / (f(x)
 * T(x -> y)) to *OUT_ratio (0 for a refused y). Returns 0 when there is no
 * proposal. */
int mut_manifold_propose(const mut_manifold *mm, rng *r, const ps_path *x, ps_path *OUT_y,
                         double *OUT_ratio, int64_t *rays, mut_manifold_tally *tally);

#endif
