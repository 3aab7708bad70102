/*
 * bdpt_generic.h: the steps of BDPT that the plain integrator
 * (integrator_bdpt.c) and the differentiable strategy (path_bdpt.c) share,
 * written once in render/real.h's vocabulary: the vertex queries, the
 * direction between vertices, f cos at a vertex with Mitsuba's side rule
 * and Veach's shading-normal correction, the densities of the MIS walk
 * (pbrt's Vertex::ConvertDensity, Pdf, PdfLight, PdfLightOrigin) and the
 * power-heuristic MIS weight (pbrt's MISWeight), the connections, and
 * (bdpt_walk.h, through media bdpt_media.h) the walks. integrator_bdpt.c's
 * opening comment states the rules. Not a header: no include guard; each of
 * the two files includes it once, its statics are its own.
 *
 * The includer defines, besides R_DUAL and render/real.h:
 *   BDPT_VERTEX       its vertex type (bdpt_vertex, path__bdv), with the
 *                     fields type, delta, light, pdf_fwd, pdf_rev, p, n,
 *                     dir, wo and hit (sh, ng, tu, tv, bsdf);
 *   BDPT_HIT          the type of its hit field;
 *   BDPT_CTX, BDPT_C  the context parameter and argument (the scene, or
 *                     path.c's evaluation context), BDPT_SC its scene and
 *                     BDPT_ARENA the statement that names the arena A (or
 *                     nothing);
 *   BDPT_CAM_PDF_DIR(w), BDPT_PDF_LE_DIR(l, p, n, w), BDPT_PDF_LI(l, ref,
 *                     w, p, n): the camera's direction density and the
 *                     emitters' emission and direct-sampling densities in
 *                     its arithmetic (camera.c's and light.c's);
 *   BDPT_MEDIA_CODE   1: the walk and the connections through participating
 *                     media are compiled (the plain side, used when its
 *                     walker's and joiner's `media` is set: medium
 *                     vertices, free flights across index-matched
 *                     boundaries, the flights' densities in pdf_fwd and
 *                     pdf_rev, the connections' transmittance); 0: the
 *                     dual side, which has no media yet.
 */

/* ---- Vertex queries -------------------------------------------------------- */

static REAL bdpt__remap0(R_CTX REAL x) { return R_V(x) != 0.0 ? x : R_C(1.0); }

/* The light a vertex acts as when it is a path's light endpoint, or -1. */
static int bdpt__light_index(const BDPT_VERTEX *v) {
  return v->type == BDPT_VERTEX_LIGHT || v->type == BDPT_VERTEX_SURFACE ? v->light : -1;
}

/* Light endpoint standing for the infinite lights (escaped ray, constant, envmap). */
static int bdpt__is_infinite(const scene *sc, const BDPT_VERTEX *v) {
  if (v->type != BDPT_VERTEX_LIGHT) return 0;
  return v->light < 0 || light_is_infinite(&sc->lights[v->light]);
}

/* Light endpoint whose position is at infinity (infinite or directional). */
static int bdpt__at_infinity(const scene *sc, const BDPT_VERTEX *v) {
  if (v->type != BDPT_VERTEX_LIGHT) return 0;
  return bdpt__is_infinite(sc, v) || sc->lights[v->light].type == LIGHT_DIRECTIONAL;
}

static int bdpt__is_delta_light(const scene *sc, const BDPT_VERTEX *v) {
  return v->type == BDPT_VERTEX_LIGHT && v->light >= 0 && light_is_delta(&sc->lights[v->light]);
}

static int bdpt__has_normal(const BDPT_VERTEX *v) { return v3_len2(v->n) > 0.0; }

/* Scattering vertex whose BSDF has a non-delta part (can be connected). */
static int bdpt__connectible(const BDPT_VERTEX *v) {
  return (v->type == BDPT_VERTEX_SURFACE && !bsdf_is_delta(v->hit.bsdf)) ||
         v->type == BDPT_VERTEX_MEDIUM;
}


/* Unit direction from vertex a towards vertex b (either may be at infinity). */
static REAL3 bdpt__dir_to(BDPT_CTX, const BDPT_VERTEX *a, const BDPT_VERTEX *b) {
  BDPT_ARENA
  if (bdpt__at_infinity(BDPT_SC, b)) return R3_NEG(b->dir);
  if (bdpt__at_infinity(BDPT_SC, a)) return a->dir;
  return R3_NORMALIZE(R3_SUB(b->p, a->p));
}

/* ---- f cos at a surface vertex ----------------------------------------------- */

/* Local direction of w at a surface, and whether w lies on the same side
 * of the geometric and the shading surface (Mitsuba's rule). */
static int bdpt__side_ok(R_CTX const BDPT_HIT *h, REAL3 w, REAL3 *OUT_local) {
  *OUT_local = R3_TO_LOCAL(&h->sh, w);
  return v3_dot(R3_V(w), h->ng) * R_V(OUT_local->z) > 0.0;
}

/* Veach's shading-normal correction for importance transport:
 *   |wo . ns| |wi . ng| / (|wo . ng| |wi . ns|). */
static REAL bdpt__shading_correction(R_CTX const BDPT_HIT *h, REAL3 wo, REAL3 wi) {
  REAL num = R_MUL(R_FABS(R3_DOT(wo, h->sh.n)), R_FABS(R3_DOT_C(h->ng, wi)));
  REAL den = R_MUL(R_FABS(R3_DOT_C(h->ng, wo)), R_FABS(R3_DOT(wi, h->sh.n)));
  return R_V(den) > 0.0 ? R_DIV(num, den) : R_C(0.0);
}

/* f(wo, wi) |wi . n_s| at a surface vertex, towards the unit direction wi,
 * with the correction above in importance mode; 0 when a direction breaks
 * the side rule. */
static RRGB bdpt__f_cos(R_CTX const BDPT_VERTEX *v, REAL3 wi, transport_mode mode) {
#if BDPT_MEDIA_CODE
  if (v->type == BDPT_VERTEX_MEDIUM) {
    REAL ph = R_FN(phase_eval)(R_ARG v->ph, v->wo, wi);
    return RRGB_MAKE(ph, ph, ph);
  }
#endif
  const BDPT_HIT *h = &v->hit;
  REAL3 wo_l, wi_l;
  if (!bdpt__side_ok(R_ARG h, v->wo, &wo_l) || !bdpt__side_ok(R_ARG h, wi, &wi_l))
    return RRGB_ZERO();
  RRGB f = R_FN(bsdf_eval)(R_ARG h->bsdf, h->tu, h->tv, wo_l, wi_l, mode);
  REAL cs = R_FABS(wi_l.z);
  if (mode == TRANSPORT_IMPORTANCE) cs = R_MUL(cs, bdpt__shading_correction(R_ARG h, v->wo, wi));
  return RRGB_SCALE(f, cs);
}

/* ---- Densities ------------------------------------------------------------------ */

/* Solid-angle density at `from` of the direction to `to`, as a density of
 * `to`: per unit area (times |cos| at `to` over the squared distance), or
 * unchanged when `to` is at infinity. */
static REAL bdpt__convert(BDPT_CTX, REAL pdf_sa, const BDPT_VERTEX *from, const BDPT_VERTEX *to) {
  BDPT_ARENA
  if (bdpt__at_infinity(BDPT_SC, to)) return pdf_sa;
  REAL3 d = R3_SUB(to->p, from->p);
  REAL d2 = R3_LEN2(d);
  if (!(R_V(d2) > 0.0)) return R_C(0.0);
  REAL pdf = R_DIV(pdf_sa, d2);
  if (bdpt__has_normal(to)) pdf = R_MUL(pdf, R_DIV(R_FABS(R3_DOT_C(to->n, d)), R_SQRT(d2)));
  return pdf;
}

/* Density of `next` when emitted from the light endpoint v. */
static REAL bdpt__pdf_light(BDPT_CTX, const BDPT_VERTEX *v, const BDPT_VERTEX *next) {
  BDPT_ARENA
  const scene *sc = BDPT_SC;
  int li = bdpt__light_index(v);
  if (bdpt__at_infinity(sc, v)) {
    /* Planar density of light_sample_le's disk: 1/(pi r^2) |cos|. */
    double pdf = 1.0 / (M_PI * sc->radius * sc->radius);
    if (!bdpt__has_normal(next)) return R_C(pdf);
    return R_MUL_S(R_FABS(R3_DOT_C(next->n, v->dir)), pdf);
  }
  if (li < 0) return R_C(0.0);
  REAL3 d = R3_SUB(next->p, v->p);
  REAL d2 = R3_LEN2(d);
  if (!(R_V(d2) > 0.0)) return R_C(0.0);
  REAL3 w = R3_SCALE(d, R_INV(R_SQRT(d2)));
  REAL pdf = R_DIV(BDPT_PDF_LE_DIR(&sc->lights[li], v->p, v->n, w), d2);
  if (bdpt__has_normal(next)) pdf = R_MUL(pdf, R_FABS(R3_DOT_C(next->n, w)));
  return pdf;
}

/* Density of choosing v as the light endpoint (with the light selection
 * probability); `next` is the vertex it connects to. Infinite lights: the
 * solid-angle density summed over all infinite lights. Delta positions
 * and directional lights: the selection probability alone; area lights:
 * times the position density (1 / area, whatever the direction). */
static REAL bdpt__pdf_light_origin(BDPT_CTX, const BDPT_VERTEX *v, const BDPT_VERTEX *next) {
  BDPT_ARENA
  const scene *sc = BDPT_SC;
  if (bdpt__is_infinite(sc, v)) {
    REAL3 w_env = R3_NEG(v->dir);
    REAL pdf = R_C(0.0);
    for (int k = 0; k < sc->n_infinite; k++) {
      int li = sc->infinite_lights[k];
      REAL p = BDPT_PDF_LI(&sc->lights[li], next->p, w_env, next->p, next->n);
      pdf = R_ADD(pdf, R_MUL_S(p, scene_light_pmf(sc, li)));
    }
    return pdf;
  }
  int li = bdpt__light_index(v);
  if (li < 0) return R_C(0.0);
  const light *l = &sc->lights[li];
  double pmf = scene_light_pmf(sc, li);
  if (light_is_delta(l)) return R_C(pmf);
  double pdf_pos, pdf_dir;
  light_pdf_le(l, sc, R3_V(v->p), v->n, v3(0.0, 0.0, 1.0), &pdf_pos, &pdf_dir);
  return R_C(pmf * pdf_pos);
}

/* Density of `next` when sampled at v, which was reached from `prev`
 * (pbrt's Vertex::Pdf). Light endpoints use bdpt__pdf_light. */
static REAL bdpt__pdf(BDPT_CTX, const BDPT_VERTEX *v, const BDPT_VERTEX *prev,
                      const BDPT_VERTEX *next) {
  BDPT_ARENA
  if (v->type == BDPT_VERTEX_LIGHT) return bdpt__pdf_light(BDPT_C, v, next);
  REAL3 wi = bdpt__dir_to(BDPT_C, v, next);
  REAL pdf_sa;
  if (v->type == BDPT_VERTEX_CAMERA) {
    pdf_sa = BDPT_CAM_PDF_DIR(wi);
#if BDPT_MEDIA_CODE
  } else if (v->type == BDPT_VERTEX_MEDIUM) {
    if (!prev) return R_C(0.0);
    pdf_sa = R_FN(phase_eval)(R_ARG v->ph, bdpt__dir_to(BDPT_C, v, prev), wi);
#endif
  } else {
    if (!prev) return R_C(0.0);
    const BDPT_HIT *h = &v->hit;
    REAL3 wo = bdpt__dir_to(BDPT_C, v, prev);
    pdf_sa = R_FN(bsdf_pdf)(R_ARG h->bsdf, h->tu, h->tv, R3_TO_LOCAL(&h->sh, wo),
                            R3_TO_LOCAL(&h->sh, wi));
  }
  return bdpt__convert(BDPT_C, pdf_sa, v, next);
}

#if BDPT_MEDIA_CODE
#include "render/integrators/bdpt_media.h"
#endif

/* ---- The MIS weight ------------------------------------------------------------- */

/* The power-heuristic weight of strategy (s, t) over every strategy of the
 * same path (pbrt's ratio walk; integrator_bdpt.c). sampled: the light
 * vertex of an s = 1 connection (NULL: lp[0]); t_conn: through media, the
 * connection's transmittance (NULL: no media). */
static REAL bdpt__mis_weight(BDPT_CTX, const BDPT_VERTEX *cam, int t, const BDPT_VERTEX *lp,
                             int s, const BDPT_VERTEX *sampled, const rgb *t_conn) {
  BDPT_ARENA
  const scene *sc = BDPT_SC;
  if (t < 1 || s + t < 2) return R_C(0.0);
  /* The connection vertices and their predecessors. */
  const BDPT_VERTEX *qs = s > 0 ? ((s == 1 && sampled) ? sampled : &lp[s - 1]) : NULL;
  const BDPT_VERTEX *pt = &cam[t - 1];
  const BDPT_VERTEX *qsm = s > 1 ? &lp[s - 2] : NULL;
  const BDPT_VERTEX *ptm = t > 1 ? &cam[t - 2] : NULL;

  /* Reverse densities of the joined path next to the connection. */
  REAL pt_rev =
      s > 0 ? bdpt__pdf(BDPT_C, qs, qsm, pt) : bdpt__pdf_light_origin(BDPT_C, pt, ptm);
  REAL ptm_rev = R_C(0.0), qs_rev = R_C(0.0), qsm_rev = R_C(0.0);
  if (ptm) ptm_rev = s > 0 ? bdpt__pdf(BDPT_C, pt, qs, ptm) : bdpt__pdf_light(BDPT_C, pt, ptm);
  if (qs) qs_rev = bdpt__pdf(BDPT_C, pt, ptm, qs);
  if (qsm) qsm_rev = bdpt__pdf(BDPT_C, qs, pt, qsm);
#if BDPT_MEDIA_CODE
  /* Each density with its segment's free flight: the connection's for pt
   * and qs, their own subpaths' for ptm and qsm. */
  if (t_conn) {
    if (s > 0) pt_rev = R_MUL_S(pt_rev, bdpt__flight(sc, pt, *t_conn));
    if (ptm) ptm_rev = R_MUL_S(ptm_rev, bdpt__flight(sc, ptm, pt->tseg));
    if (qs) qs_rev = R_MUL_S(qs_rev, bdpt__flight(sc, qs, *t_conn));
    if (qsm) qsm_rev = R_MUL_S(qsm_rev, bdpt__flight(sc, qsm, qs->tseg));
  }
#else
  (void)t_conn;
#endif

  REAL sum = R_C(0.0);

  /* Walking the camera subpath towards the camera, vertex i moves to the
   * light side: strategy (s + t - i, i) joins cam[i-1] and cam[i]. */
  REAL ri = R_C(1.0);
  for (int i = t - 1; i >= 1; i--) {
    REAL rev = i == t - 1 ? pt_rev : (i == t - 2 ? ptm_rev : cam[i].pdf_rev);
    ri = R_MUL(ri, R_DIV(bdpt__remap0(R_ARG rev), bdpt__remap0(R_ARG cam[i].pdf_fwd)));
    int delta_i = i == t - 1 ? 0 : cam[i].delta;
    int ok = !delta_i && !cam[i - 1].delta;
    if (i == 1 && s + t - 1 < 2) ok = 0; /* (s', t') = (1, 1) is not used */
    if (ok) sum = R_ADD(sum, R_SQR(ri));
  }

  /* Walking the light subpath towards the light, vertex i moves to the
   * camera side: strategy (i, s + t - i) joins lp[i-1] and lp[i]. */
  ri = R_C(1.0);
  for (int i = s - 1; i >= 0; i--) {
    const BDPT_VERTEX *v = i == s - 1 ? qs : &lp[i];
    REAL rev = i == s - 1 ? qs_rev : (i == s - 2 ? qsm_rev : lp[i].pdf_rev);
    ri = R_MUL(ri, R_DIV(bdpt__remap0(R_ARG rev), bdpt__remap0(R_ARG v->pdf_fwd)));
    int delta_i = i == s - 1 ? 0 : lp[i].delta;
    int delta_prev = i > 0 ? lp[i - 1].delta : bdpt__is_delta_light(sc, s == 1 ? qs : &lp[0]);
    if (!delta_i && !delta_prev) sum = R_ADD(sum, R_SQR(ri));
  }
  return R_S_DIV(1.0, R_ADD_S(sum, 1.0));
}

/* ---- The connections ------------------------------------------------------------- */

/* What a connection found: its contribution before the MIS weight, how far
 * it got (part of the dual path's topology), the emitter and the connection
 * vertices' lobes (the dual path's flags), and for s = 1 the light vertex it
 * sampled.
 *
 * The includer defines, for the joins: BDPT_JOIN_CTX (its parameter, named
 * j, with the field sc) and BDPT_JOIN_PROLOGUE (what names BDPT_C and the
 * arena A from it), BDPT_J_SEGMENT_BLOCKED(a, dir, b) and BDPT_J_BLOCKED(p,
 * wi, lp, dist) (the shadow rays), BDPT_J_CAMERA_WE(dir, rx, ry),
 * BDPT_J_NUMBERS(t, u) (the s = 1 connection's three numbers into u[3];
 * 0 when there are none), BDPT_J_SAMPLE_LI(l, ref, u1, u2, ls) with its
 * type BDPT_J_LI and BDPT_J_LI_POINT(ls) (the sampled point), BDPT_J_TOPO(x),
 * BDPT_J_EMIT(l), BDPT_J_EMIT_AREA and BDPT_J_LOBES(v) (the dual path's
 * flags). */
typedef struct bdpt__join {
  RRGB L;
  int stage;
  unsigned emit, lobes;
  BDPT_VERTEX sampled;
  int has_sampled;
#if BDPT_MEDIA_CODE
  rgb tconn; /* through media: the connection's transmittance */
#endif
} bdpt__join;

#if BDPT_MEDIA_CODE
/* Through media, the shadow ray from x (at p) along d to lp (dist away,
 * INFINITY: towards a light at infinity): 1 when unblocked, the
 * connection's transmittance into J->tconn and J->L. */
static int bdpt__join_clear(BDPT_JOIN_CTX, const bdpt_vertex *x, vec3 p, vec3 d, vec3 lp,
                            double dist, bdpt__join *J) {
  const scene *sc = j->sc;
  if (!render_transmittance(sc, j->cnt, p, d, lp, dist, bdpt__medium_toward(sc, x, d), &J->tconn) ||
      rgb_is_black(J->tconn))
    return 0;
  J->L = rgb_mul(J->L, J->tconn);
  return 1;
}
#define BDPT__CLEAR(x, p, d, lp, dist, blocked) \
  (j->media ? bdpt__join_clear(j, (x), (p), (d), (lp), (dist), J) : !(blocked))
#else
#define BDPT__CLEAR(x, p, d, lp, dist, blocked) (!(blocked))
#endif

/* s = 0: the camera subpath ends on an emitter. */
static void bdpt__join_emitter(BDPT_JOIN_CTX, const BDPT_VERTEX *cam, int t, bdpt__join *J) {
  BDPT_JOIN_PROLOGUE
  const scene *sc = j->sc;
  const BDPT_VERTEX *pt = &cam[t - 1];
  if (pt->type == BDPT_VERTEX_SURFACE) {
    if (pt->light >= 0) {
      rgb le = light_le_area(&sc->lights[pt->light], pt->n, R3_V(pt->wo));
      J->stage = 1 + !rgb_is_black(le);
      J->L = RRGB_MUL(pt->beta, RRGB_CONST(le));
      J->emit = BDPT_J_EMIT_AREA;
    }
  } else if (pt->type == BDPT_VERTEX_LIGHT && pt->light < 0) {
    vec3 w_env = v3_neg(R3_V(pt->dir));
    rgb le = rgb_zero();
    for (int k = 0; k < sc->n_infinite; k++) {
      const light *l = &sc->lights[sc->infinite_lights[k]];
      rgb lk = light_le_infinite(l, w_env);
      if (l->type == LIGHT_ENVMAP) BDPT_J_TOPO((int64_t)(1e6 * rgb_luminance(lk))); /* the pixel */
      if (!rgb_is_black(lk)) J->emit |= BDPT_J_EMIT(l);
      le = rgb_add(le, lk);
    }
    J->stage = 3;
    J->L = RRGB_MUL(pt->beta, RRGB_CONST(le));
  }
}

/* t = 1: light tracing, y_{s-1} joined to the pinhole and splatted at its
 * raster point (*OUT_rx, *OUT_ry; may be NULL). */
static void bdpt__join_camera(BDPT_JOIN_CTX, const BDPT_VERTEX *cam, const BDPT_VERTEX *lp, int s,
                              bdpt__join *J, REAL *OUT_rx, REAL *OUT_ry) {
  BDPT_JOIN_PROLOGUE
  const scene *sc = j->sc;
  const BDPT_VERTEX *qs = &lp[s - 1];
  if (!bdpt__connectible(qs)) return;
  J->stage = 1;
  REAL3 d = R3_SUB(qs->p, cam[0].p);
  REAL d2 = R3_LEN2(d);
  if (!(R_V(d2) > 0.0)) return;
  REAL3 dir = R3_SCALE(d, R_INV(R_SQRT(d2)));
  REAL rx = R_C(0.0), ry = R_C(0.0);
  REAL we = BDPT_J_CAMERA_WE(dir, &rx, &ry);
  if (!(R_V(we) > 0.0)) return;
  J->stage = 2;
  REAL cos_cam = R3_DOT_C(sc->cam.forward, dir);
  RRGB f = bdpt__f_cos(R_ARG qs, R3_NEG(dir), TRANSPORT_IMPORTANCE);
  /* qs.beta f We cos_cam / d^2 */
  J->L = RRGB_SCALE(RRGB_MUL(qs->beta, f), R_DIV(R_MUL(we, cos_cam), d2));
  if (RRGB_IS_BLACK(J->L)) return;
  J->stage = 3;
  if (!BDPT__CLEAR(&cam[0], cam[0].p, dir, qs->p, sqrt(d2),
                   BDPT_J_SEGMENT_BLOCKED(cam[0].p, dir, qs->p))) {
    J->L = RRGB_ZERO();
    return;
  }
  J->stage = 4;
  if (OUT_rx) *OUT_rx = rx;
  if (OUT_ry) *OUT_ry = ry;
  J->emit = BDPT_J_EMIT(&sc->lights[lp[0].light]);
  J->lobes |= BDPT_J_LOBES(qs);
}

/* s = 1: next-event estimation from z_{t-1} with a fresh light sample. */
static void bdpt__join_light(BDPT_JOIN_CTX, const BDPT_VERTEX *cam, int t, bdpt__join *J) {
  BDPT_JOIN_PROLOGUE
  const scene *sc = j->sc;
  const BDPT_VERTEX *pt = &cam[t - 1];
  REAL u[3] = {0}; /* (set when have) */
  int have = BDPT_J_NUMBERS(t, u);
  if (!bdpt__connectible(pt) || !have || sc->n_lights == 0) return;
  double pmf, u_remap;
  int li = scene_sample_light(sc, R_V(u[0]), &pmf, &u_remap);
  BDPT_J_TOPO(li);
  BDPT_J_LI ls;
  J->stage = 1;
  if (!(li >= 0 && pmf > 0.0 && BDPT_J_SAMPLE_LI(&sc->lights[li], pt->p, u[1], u[2], &ls) &&
        R_V(ls.pdf) > 0.0 && !RRGB_IS_BLACK(ls.li)))
    return;
  J->stage = 2;
  const light *l = &sc->lights[li];
  RRGB f = bdpt__f_cos(R_ARG pt, ls.wi, TRANSPORT_RADIANCE);
  /* pt.beta f Li / (pmf pdf) */
  REAL inv_pdf = R_INV(R_MUL_S(ls.pdf, pmf));
  J->L = RRGB_SCALE(RRGB_MUL(pt->beta, RRGB_MUL(f, ls.li)), inv_pdf);
  if (RRGB_IS_BLACK(J->L)) return;
  J->stage = 3;
  if (!BDPT__CLEAR(pt, pt->p, ls.wi, ls.p, ls.dist, BDPT_J_BLOCKED(pt->p, ls.wi, ls.p, ls.dist))) {
    J->L = RRGB_ZERO();
    return;
  }
  J->stage = 4;
  BDPT_VERTEX *v = &J->sampled;
  memset(v, 0, sizeof *v);
  v->type = BDPT_VERTEX_LIGHT;
  v->light = li;
  v->p = BDPT_J_LI_POINT(ls);
  v->n = l->type == LIGHT_AREA ? ls.n : v3(0.0, 0.0, 0.0);
  v->dir = R3_NEG(ls.wi);
  v->beta = RRGB_SCALE(ls.li, inv_pdf);
  v->pdf_rev = R_C(0.0);
  v->pdf_fwd = bdpt__pdf_light_origin(BDPT_C, v, pt);
#if !R_DUAL
  v->hit.mesh = l->type == LIGHT_AREA ? l->mesh : -1;
  v->hit.prim = ls.tri;
#endif
  J->has_sampled = 1;
  J->emit = BDPT_J_EMIT(l);
  J->lobes |= BDPT_J_LOBES(pt);
}

/* s, t >= 2: y_{s-1} and z_{t-1} joined by a shadow ray. */
static void bdpt__join_vertices(BDPT_JOIN_CTX, const BDPT_VERTEX *cam, int t,
                                const BDPT_VERTEX *lp, int s, bdpt__join *J) {
  BDPT_JOIN_PROLOGUE
  const scene *sc = j->sc;
  (void)sc; /* (the plain side notes no emitter) */
  const BDPT_VERTEX *qs = &lp[s - 1], *pt = &cam[t - 1];
  if (!bdpt__connectible(qs) || !bdpt__connectible(pt)) return;
  J->stage = 1;
  REAL3 d = R3_SUB(pt->p, qs->p);
  REAL d2 = R3_LEN2(d);
  if (!(R_V(d2) > 0.0)) return;
  J->stage = 2;
  REAL3 w = R3_SCALE(d, R_INV(R_SQRT(d2)));
  RRGB fq = bdpt__f_cos(R_ARG qs, w, TRANSPORT_IMPORTANCE);
  RRGB fp = bdpt__f_cos(R_ARG pt, R3_NEG(w), TRANSPORT_RADIANCE);
  /* beta_y f_y f_z beta_z / d^2 (the cosines are inside f_cos) */
  J->L = RRGB_SCALE(RRGB_MUL(RRGB_MUL(qs->beta, fq), RRGB_MUL(fp, pt->beta)), R_INV(d2));
  if (RRGB_IS_BLACK(J->L)) return;
  J->stage = 3;
  if (!BDPT__CLEAR(qs, qs->p, w, pt->p, sqrt(d2), BDPT_J_SEGMENT_BLOCKED(qs->p, w, pt->p))) {
    J->L = RRGB_ZERO();
    return;
  }
  J->stage = 4;
  J->emit = BDPT_J_EMIT(&sc->lights[lp[0].light]);
  J->lobes |= BDPT_J_LOBES(qs) | BDPT_J_LOBES(pt);
}

/* The walks that make the subpaths: bdpt_walk.h. */
#include "render/integrators/bdpt_walk.h"
