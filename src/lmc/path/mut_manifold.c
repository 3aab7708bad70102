/*
 * mut_manifold.c: the manifold perturbation on smooth specular chains
 * (mut_manifold.h states the move and its density). Mitsuba 0.6's
 * manifold perturbation (src/libbidir/mut_manifold.cpp) was read for the
 * method's facts (a walk of the chain behind the perturbed vertex towards
 * its new position, the reverse walk computed and a move whose reverse
 * does not return refused); the code here is lmc's own, on the walk of
 * manifold.h and the caches of pathspace.h.
 */
#include "lmc/path/mut_manifold.h"

#include <math.h>
#include <string.h>

#define MM_PI 3.14159265358979323846

void mut_manifold_init(mut_manifold *mm, const ps_context *ctx, const mut_perturb *mp) {
  memset(mm, 0, sizeof *mm);
  mm->ctx = ctx;
  mm->mp = mp;
  mf_options_default(ctx->sc, &mm->walk);
  /* Tighter than the default: the walk converges quadratically near its
   * end, and the reverse move must land on x to within back_tol. */
  mm->walk.tol = 1e-10 * ctx->sc->radius;
  mm->back_tol = 1e-6 * ctx->sc->radius;
  mm->test_jac_power = 1.0;
}

int mut_manifold_form(const mut_manifold *mm, const ps_path *x, int *OUT_b, int *OUT_c) {
  const ps_context *ctx = mm->ctx;
  int k = x->k, b = 1;
  while (b < k && x->x[b].delta) b++;
  if (b + 1 >= k || ps_glossy(ctx, x, b) || !x->x[b + 1].delta) return 0;
  int c = b + 1;
  while (c < k && x->x[c].delta) c++;
  if (c - b - 1 > MF_MAX_CHAIN) return 0;
  /* x_c is fixed: a non-delta surface (glossy or not) or the emitter end. */
  mf_chain ch;
  if (mf_chain_from_path(ctx, x, b, c, MF_PATH_FROM_B, &ch) != MF_OK) return 0;
  *OUT_b = b, *OUT_c = c;
  return 1;
}

/* The walk of chain `from` (x_c .. x_b of a path) towards `target`. */
static int mm__walk(const mut_manifold *mm, const mf_chain *from, vec3 target, mf_chain *OUT,
                    int64_t *rays, mut_manifold_tally *tally) {
  mf_walk_info info;
  memset(&info, 0, sizeof info);
  int st = mf_walk(mm->ctx->sc, from, target, &mm->walk, OUT, &info);
  if (rays) *rays += info.traces;
  if (tally) {
    tally->walks++;
    tally->traces += info.traces;
    tally->walked += st == MF_OK;
  }
  return st == MF_OK;
}

int mut_manifold_generate(const mut_manifold *mm, const ps_path *x, double rx, double ry,
                          ps_path *OUT_y, int64_t *rays, mut_manifold_tally *tally) {
  const ps_context *ctx = mm->ctx;
  const scene *sc = ctx->sc;
  int b, c;
  if (!mut_manifold_form(mm, x, &b, &c)) return 0;
  if (!(rx >= 0.0 && rx < sc->cam.width && ry >= 0.0 && ry < sc->cam.height)) return 0;
  ps_path *y = OUT_y;
  *y = *x;
  y->rays = 0;
  /* The camera's chain retraced to a new y_b. */
  if (!mut_perturb_first_hit(ctx, rx, ry, &y->x[0].v, &y->x[1].v, rays)) return 0;
  for (int i = 1; i < b; i++) {
    vec3 wo = v3_normalize(v3_sub(y->x[i - 1].v.p, y->x[i].v.p)), dir;
    if (!mut_perturb_forced_dir(&y->x[i].v, wo, mut_perturb_transmits(x, i), TRANSPORT_RADIANCE,
                                &dir))
      return 0;
    y->x[i].v.delta = 1;
    if (!mut_perturb_trace(ctx, &y->x[i].v, dir, TRANSPORT_RADIANCE, &y->x[i + 1].v, rays)) return 0;
  }
  y->x[b].v.delta = 0;
  /* The chain behind x_b walked to it, its end on y_b's surface. */
  mf_chain cx, cy;
  if (mf_chain_from_path(ctx, x, b, c, MF_PATH_FROM_B, &cx) != MF_OK) return 0;
  if (y->x[b].v.hit.mesh != cx.v[cx.k + 1].mesh) return 0;
  if (!mm__walk(mm, &cx, y->x[b].v.p, &cy, rays, tally)) return 0;
  bdpt_vertex yb = y->x[b].v;
  if (mf_chain_to_path(sc, &cy, b, c, MF_PATH_FROM_B, y) != MF_OK) return 0;
  y->x[b].v = yb; /* the retraced vertex, which the walk's end reached within its tolerance */
  ps_update(ctx, y, 0, c + 1 > y->k ? y->k : c + 1);
  /* x's form: the kinds of every changed vertex. */
  for (int i = 1; i < c; i++)
    if (y->x[i].delta != x->x[i].delta || ps_glossy(ctx, y, i) != ps_glossy(ctx, x, i)) return 0;
  /* y_b joins y_{b+1}; the walk traced the rest of the chain. */
  if (rays) (*rays)++;
  if (ps_edge_blocked(ctx, y, b)) {
    y->f = rgb_zero();
    y->lum = 0.0;
    return 1;
  }
  ps_total(y);
  return 1;
}

int mut_manifold_reversible(const mut_manifold *mm, const ps_path *x, const ps_path *y,
                            int64_t *rays, mut_manifold_tally *tally) {
  int b, c;
  if (!mut_manifold_form(mm, x, &b, &c)) return 0;
  mf_chain cy, cz;
  if (mf_chain_from_path(mm->ctx, y, b, c, MF_PATH_FROM_B, &cy) != MF_OK) return 0;
  if (!mm__walk(mm, &cy, x->x[b].v.p, &cz, rays, tally)) return 0;
  /* Chain vertex i is x_{c - i}. */
  for (int i = 1; i <= cz.k; i++)
    if (!(v3_len(v3_sub(cz.v[i].p, x->x[c - i].v.p)) <= mm->back_tol)) return 0;
  return 1;
}

/* The chain's part of T(x -> y): Phi(y) / J(y) (mut_manifold.h). */
static double mm__chain_density(const mut_manifold *mm, const ps_path *y, int b, int c) {
  const ps_context *ctx = mm->ctx;
  double phi = y->x[c].inf ? fabs(v3_dot(ps_dir(y, c - 1, c), y->x[c - 1].v.n))
                           : ps_area_jacobian(ctx, y, c, c - 1);
  for (int j = b; j <= c - 2; j++) phi *= ps_forced_density(ctx, y, j + 1, j + 2, j, 1);
  mf_chain ch;
  if (!(phi > 0.0) || mf_chain_from_path(ctx, y, b, c, MF_PATH_FROM_B, &ch) != MF_OK) return 0.0;
  ch.n0 = v3(0.0, 0.0, 0.0); /* d omega at x_c, without its cosine */
  double J;
  if (mf_geometry_term(ctx->sc, &ch, &J) != MF_OK || !(J > 0.0) || !isfinite(J)) return 0.0;
  return phi / pow(J, mm->test_jac_power);
}

double mut_manifold_density(const mut_manifold *mm, const ps_path *x, const ps_path *y) {
  const ps_context *ctx = mm->ctx;
  const camera *cam = &ctx->sc->cam;
  int bx, cx, by, cy;
  if (y->k != x->k || !mut_manifold_form(mm, x, &bx, &cx) || !mut_manifold_form(mm, y, &by, &cy) ||
      by != bx || cy != cx)
    return 0.0;
  double dr = hypot(y->rx - x->rx, y->ry - x->ry);
  double p = mut_perturb_log_pdf(mm->mp->r1, mm->mp->r2, dr) / (2.0 * MM_PI * dr);
  if (!(p > 0.0)) return 0.0;
  double jac = (double)cam->width * cam->height * y->x[1].pdf_cam;
  for (int i = 2; i <= bx; i++) jac *= ps_area_jacobian(ctx, y, i - 1, i);
  return p * jac * mm__chain_density(mm, y, bx, cx);
}

int mut_manifold_propose(const mut_manifold *mm, rng *r, const ps_path *x, ps_path *OUT_y,
                         double *OUT_ratio, int64_t *rays, mut_manifold_tally *tally) {
  *OUT_ratio = 0.0;
  if (!mut_manifold_applies(mm, x)) return 0;
  double size = mut_perturb_log_sample(mm->mp->r1, mm->mp->r2, rng_uniform(r));
  double phi = 2.0 * MM_PI * rng_uniform(r);
  if (!mut_manifold_generate(mm, x, x->rx + size * cos(phi), x->ry + size * sin(phi), OUT_y, rays,
                             tally))
    return 0;
  double t_fwd = mut_manifold_density(mm, x, OUT_y);
  if (!(t_fwd > 0.0)) return 0;
  if (!(OUT_y->lum > 0.0) || !(x->lum > 0.0)) return 1;
  if (!mut_manifold_reversible(mm, x, OUT_y, rays, tally)) {
    if (tally) tally->irreversible++;
    return 1;
  }
  double t_rev = mut_manifold_density(mm, OUT_y, x);
  double ratio = OUT_y->lum * t_rev / (x->lum * t_fwd);
  *OUT_ratio = isfinite(ratio) ? ratio : 0.0;
  return 1;
}
