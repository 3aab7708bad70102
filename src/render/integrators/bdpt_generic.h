/*
 * bdpt_generic.h: the steps of BDPT that the plain integrator
 * (integrator_bdpt.c) and the differentiable strategy (path_bdpt.c) share,
 * written once in render/real.h's vocabulary: the vertex queries, the
 * direction between vertices, f cos at a vertex with Mitsuba's side rule
 * and Veach's shading-normal correction, the densities of the MIS walk
 * (pbrt's Vertex::ConvertDensity, Pdf, PdfLight, PdfLightOrigin) and the
 * power-heuristic MIS weight (pbrt's MISWeight). integrator_bdpt.c's
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

#if BDPT_MEDIA_CODE
/* The free-flight density with which a segment of transmittance T ends at
 * x: scattering there (a medium vertex, in its medium), or passing on to it
 * (medium.h's track). */
static double bdpt__flight(const scene *sc, const bdpt_vertex *x, rgb T) {
  int scat = x->type == BDPT_VERTEX_MEDIUM;
  return medium_track_pdf(scat ? scene_medium(sc, x->med) : NULL, scat, T);
}

/* The medium a ray from x along d starts in. */
static int bdpt__medium_toward(const scene *sc, const bdpt_vertex *x, vec3 d) {
  return x->type == BDPT_VERTEX_SURFACE ? scene_medium_after(sc, &x->hit, x->med, d) : x->med;
}
#endif

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

/* ---- The random walk ------------------------------------------------------------ */

/* Extends path (n vertices) from org along dir, bdpt's walk for both
 * subpaths: pdf_dir is the density of dir at the last vertex (solid angle,
 * or planar for lights at infinity); each surface vertex takes its four
 * numbers (lobe, direction, roulette), samples the BSDF (or reads an
 * absolute direction at a rough vertex, integrator.h's bdpt_param), keeps
 * its forward density and its predecessor's reverse one, and survives
 * Russian roulette from rrdepth segments on (on light subpaths relative to
 * the throughput at y_1). Returns the new vertex count.
 *
 * The includer defines, for the walk: BDPT_WALK_CTX (its walker parameter,
 * named w, with the fields sc and rs) and BDPT_WALK_PROLOGUE (what names
 * BDPT_C and the arena A from it), BDPT_W_INTERSECT(org, dir, tmin, hit),
 * BDPT_W_DRAW(diff), BDPT_W_TOPO(x), BDPT_W_FAR_POINT(org, dir) (the
 * vertex of an escaped ray), BDPT_W_ROUGH(h) and BDPT_W_ABSOLUTE(rough, n)
 * (whether the direction at vertex n - 1 is absolute), BDPT_W_SPHERE_DIR(u1,
 * u2, J), BDPT_W_PDF_REV(bs, h, wo_l) (the reverse density of a BSDF
 * sample), BDPT_W_RR_Q(mode, beta, beta1, eta) and BDPT_W_SET_LOBE(v,
 * flags). */
static int bdpt__walk(BDPT_WALK_CTX, transport_mode mode, REAL3 org, REAL3 dir, double tmin,
                      RRGB beta, REAL pdf_dir, int planar, BDPT_VERTEX *path, int n,
                      int max_vertices) {
  BDPT_WALK_PROLOGUE
  const scene *sc = w->sc;
  double eta_scale = 1.0; /* radiance compression undone for Russian roulette */
#if BDPT_MEDIA_CODE
  int med = w->med; /* the medium the walk travels in */
#endif
  while (n < max_vertices) {
    BDPT_VERTEX *prev = &path[n - 1];
    BDPT_VERTEX *v = &path[n];
#if R_DUAL
    size_t mark = ad_arena_mark(A);
#endif
    memset(v, 0, sizeof *v);
    v->pdf_rev = R_C(0.0);
    v->jac = R_C(1.0);

    /* Find the next vertex (through media: a surface or a scattering
     * point, with the flight's weight and density); a camera ray that
     * escapes ends on the infinite lights. */
    int found;
#if BDPT_MEDIA_CODE
    vec3 mp;
    double flight = 1.0; /* the flight's density */
    if (w->media) {
      double u_ch = BDPT_W_DRAW(0), u_t = BDPT_W_DRAW(1);
      rgb fw;
      found = render_fly(sc, w->cnt, org, dir, tmin, &med, u_ch, u_t, &v->hit, &mp, &v->tseg, &flight,
                         &fw);
      if (found < 0) break;
      v->med = med;
      beta = rgb_mul(beta, fw);
      if (rgb_is_black(beta)) break;
    } else
#endif
      found = BDPT_W_INTERSECT(org, dir, tmin, &v->hit);
    v->beta = beta;
    if (!found) {
      if (mode == TRANSPORT_RADIANCE && sc->n_infinite > 0) {
        v->type = BDPT_VERTEX_LIGHT;
        v->light = -1;
        v->dir = R3_NEG(dir);
        v->p = BDPT_W_FAR_POINT(org, dir);
        v->pdf_fwd = pdf_dir; /* solid angle: the vertex is at infinity */
#if BDPT_MEDIA_CODE
        v->pdf_fwd *= flight;
#endif
        n++;
      }
      break;
    }
#if BDPT_MEDIA_CODE
    if (found == 2) {
      /* A scattering point: its density from prev (no normal: 1 / d^2, or
       * the planar density of a light at infinity) times the flight's. */
      v->type = BDPT_VERTEX_MEDIUM;
      v->light = -1;
      v->p = mp;
      v->wo = v3_neg(dir);
      v->ph = &scene_medium(sc, med)->ph;
      v->pdf_fwd = (planar ? pdf_dir : bdpt__convert(BDPT_C, pdf_dir, prev, v)) * flight;
      n++;
      int live = n < max_vertices;
      double u_lobe = BDPT_W_DRAW(0), u1 = BDPT_W_DRAW(live), u2 = BDPT_W_DRAW(live);
      double u_rr = BDPT_W_DRAW(0);
      (void)u_lobe;
      if (!live) break;
      /* The phase function's sample (weight 1; symmetric: the reverse
       * density is the same). */
      vec3 wi;
      double pdf;
      if (!phase_sample(v->ph, v->wo, u1, u2, &wi, &pdf)) break;
      prev->pdf_rev = bdpt__convert(BDPT_C, pdf, v, prev) * bdpt__flight(sc, prev, v->tseg);
      if (n - 1 >= w->rs->rrdepth) {
        double q = BDPT_W_RR_Q(mode, beta, path[1].beta, eta_scale);
        if (!(u_rr < q)) break;
        beta = rgb_scale(beta, 1.0 / q);
      }
      org = mp;
      dir = wi;
      tmin = 0.0;
      pdf_dir = pdf;
      planar = 0;
      continue;
    }
#endif
    v->type = BDPT_VERTEX_SURFACE;
    v->light = v->hit.light;
    v->p = v->hit.p;
    v->n = v->hit.ng;
    v->wo = R3_NEG(dir);
    if (planar)
      v->pdf_fwd = R_MUL(pdf_dir, R_FABS(R3_DOT_C(v->n, dir)));
    else
      v->pdf_fwd = bdpt__convert(BDPT_C, pdf_dir, prev, v);
#if BDPT_MEDIA_CODE
    v->pdf_fwd *= flight;
#endif
    n++;

    /* This vertex's numbers (always taken, differentiated only when a
     * next direction uses them), then stop if long enough. */
    int live = n < max_vertices;
    REAL u_lobe = BDPT_W_DRAW(0), u1 = BDPT_W_DRAW(live), u2 = BDPT_W_DRAW(live);
    REAL u_rr = BDPT_W_DRAW(0);
    if (!live) break;

    /* Sample the BSDF for the next direction, or read it (absolute). */
    const BDPT_HIT *h = &v->hit;
    REAL3 wo_l, wi_l;
    int ok = bdpt__side_ok(R_ARG h, v->wo, &wo_l);
    BDPT_W_TOPO(ok);
    if (!ok) break;
    int rough = BDPT_W_ROUGH(h);
#if !R_DUAL
    v->rough = rough;
#endif
    R_FN(bsdf_sample) bs;
    REAL3 wi;
    if (BDPT_W_ABSOLUTE(rough, n)) {
      /* The direction's spherical coordinates; the BSDF's value and
       * density there make the same sample weight f cos / pdf. */
      REAL J;
      wi = BDPT_W_SPHERE_DIR(u1, u2, &J);
      ok = bdpt__side_ok(R_ARG h, wi, &wi_l);
      BDPT_W_TOPO(ok);
      if (!ok) break;
      REAL pdf;
      RRGB f = R_FN(bsdf_eval_pdf)(R_ARG h->bsdf, h->tu, h->tv, wo_l, wi_l, mode, &pdf);
      int trans = R_V(wi_l.z) * R_V(wo_l.z) < 0.0;
      ok = R_V(pdf) > 0.0 && isfinite(R_V(pdf));
      RRGB weight = ok ? RRGB_SCALE(f, R_DIV(R_FABS(wi_l.z), pdf)) : RRGB_ZERO();
      ok = ok && RRGB_IS_FINITE(weight) && !RRGB_IS_BLACK(weight);
      BDPT_W_TOPO(ok ? 1 + trans : -1);
      if (!ok) break;
      bs.wi = wi_l, bs.f = f, bs.pdf = pdf, bs.weight = weight;
      bs.eta = !trans ? 1.0 : R_V(wi_l.z) < 0.0 ? h->bsdf->eta : 1.0 / h->bsdf->eta;
      bs.flags = (trans ? BSDF_TRANSMISSION : BSDF_REFLECTION) | BSDF_GLOSSY;
#if !R_DUAL
      bs.has_pdf_rev = 0;
      v->sph[0] = u1, v->sph[1] = u2;
#endif
      v->jac = R_MUL(pdf, J);
      (void)u_lobe;
    } else {
      ok = R_FN(bsdf_sample_f)(R_ARG h->bsdf, h->tu, h->tv, wo_l, u_lobe, u1, u2, mode, &bs);
      BDPT_W_TOPO(ok ? bs.flags : -1);
      if (!ok) break;
      wi = R3_TO_WORLD(&h->sh, bs.wi);
      ok = bdpt__side_ok(R_ARG h, wi, &wi_l);
      BDPT_W_TOPO(ok);
      if (!ok) break;
#if !R_DUAL
      if (rough) {
        /* Where this direction lies in the absolute parametrization. */
        double J;
        bdpt_sphere_coords(wi, &v->sph[0], &v->sph[1], &J);
        v->jac = bsdf_pdf(h->bsdf, h->tu, h->tv, wo_l, wi_l) * J;
      }
#endif
    }
    REAL pdf_fwd_sa = bs.pdf;
    REAL pdf_rev_sa = BDPT_W_PDF_REV(bs, h, wo_l);
    BDPT_W_SET_LOBE(v, bs.flags);
    if (bs.flags & BSDF_DELTA) {
      /* Delta lobes: densities read as one in the MIS walk (remap0). */
      v->delta = 1;
      pdf_fwd_sa = pdf_rev_sa = R_C(0.0);
    }
    RRGB weight = bs.weight;
    if (mode == TRANSPORT_IMPORTANCE)
      weight = RRGB_SCALE(weight, bdpt__shading_correction(R_ARG h, v->wo, wi));
    beta = RRGB_MUL(beta, weight);
    if (mode == TRANSPORT_RADIANCE && (bs.flags & BSDF_TRANSMISSION)) eta_scale *= bs.eta * bs.eta;
    prev->pdf_rev = bdpt__convert(BDPT_C, pdf_rev_sa, v, prev);
#if BDPT_MEDIA_CODE
    if (w->media) {
      prev->pdf_rev *= bdpt__flight(sc, prev, v->tseg);
      med = scene_medium_after(sc, &v->hit, med, wi);
    }
#endif
    if (RRGB_IS_BLACK(beta)) break;

    /* Russian roulette on the scattering throughput (n - 1 segments so
     * far); on light subpaths relative to the throughput at y_1. In duals
     * the divisor q carries its derivatives. */
    if (n - 1 >= w->rs->rrdepth) {
      REAL q = BDPT_W_RR_Q(mode, beta, path[1].beta, eta_scale);
      BDPT_W_TOPO(R_V(u_rr) < R_V(q));
      if (!(R_V(u_rr) < R_V(q))) break;
      beta = RRGB_SCALE(beta, R_INV(q));
    }
    dir = wi;
    tmin = scene_ray_eps(sc, R3_V(v->p));
    pdf_dir = pdf_fwd_sa;
    planar = 0;
#if R_DUAL
    /* Keep this vertex and what the next step needs; drop the rest. */
    BDPT_HIT *vh = &v->hit;
    ad *keep[] = {&v->beta.r,   &v->beta.g,   &v->beta.b,     &v->pdf_fwd, &v->p.x,
                  &v->p.y,      &v->p.z,      &v->wo.x,       &v->wo.y,    &v->wo.z,
                  &vh->sh.s.x,  &vh->sh.s.y,  &vh->sh.s.z,    &vh->sh.t.x, &vh->sh.t.y,
                  &vh->sh.t.z,  &vh->sh.n.x,  &vh->sh.n.y,    &vh->sh.n.z, &vh->tu,
                  &vh->tv,      &prev->pdf_rev, &beta.r,      &beta.g,     &beta.b,
                  &dir.x,       &dir.y,       &dir.z,         &pdf_dir,    &v->jac};
    path__keep(w, mark, keep, (int)(sizeof keep / sizeof keep[0]));
    vh->p = v->p;
    v->pdf_rev = ad_const(A, 0.0);
#endif
    org = v->p;
  }
  return n;
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

/* ---- The light subpath ---------------------------------------------------------- */

/* The light subpath y_0 .. y_{n-1} (at most max_vertices): the emitter's
 * five numbers (always taken: light choice, position, direction), the light
 * endpoint with its density (selection times position for area lights,
 * selection alone for delta positions and directional lights, the summed
 * solid-angle density for infinite lights), then the walk from y_1 on, per
 * solid angle or with the planar disk density for lights at infinity. The
 * includer defines BDPT_W_LE, its emission-sample type, and
 * BDPT_W_SAMPLE_LE(l, u1, u2, u3, u4, les). Returns the vertex count. */
static int bdpt__light_walk(BDPT_WALK_CTX, int max_vertices, BDPT_VERTEX *path) {
  BDPT_WALK_PROLOGUE
  const scene *sc = w->sc;
  REAL u_light = BDPT_W_DRAW(0);
  REAL u1 = BDPT_W_DRAW(1), u2 = BDPT_W_DRAW(1), u3 = BDPT_W_DRAW(1), u4 = BDPT_W_DRAW(1);
  if (max_vertices > BDPT_MAX_VERTICES) max_vertices = BDPT_MAX_VERTICES;
  if (max_vertices < 1 || sc->n_lights == 0) return 0;

  /* Choose a light and an emitted ray. */
  double pmf, u_remap;
  int li = scene_sample_light(sc, R_V(u_light), &pmf, &u_remap);
  BDPT_W_TOPO(li);
  if (li < 0 || !(pmf > 0.0)) return 0;
  const light *l = &sc->lights[li];
  BDPT_W_LE les;
  int ok = BDPT_W_SAMPLE_LE(l, u1, u2, u3, u4, &les) && les.pdf_pos > 0.0 &&
           R_V(les.pdf_dir) > 0.0 && !RRGB_IS_BLACK(les.le);
  BDPT_W_TOPO(ok);
  if (!ok) return 0;

  /* The light endpoint y_0. */
  BDPT_VERTEX *y0 = &path[0];
  memset(y0, 0, sizeof *y0);
  y0->type = BDPT_VERTEX_LIGHT;
  y0->light = li;
  y0->p = les.p;
  int far = light_is_infinite(l) || l->type == LIGHT_DIRECTIONAL;
  y0->n = l->type == LIGHT_AREA ? les.n : v3(0.0, 0.0, 0.0);
  y0->dir = les.dir;
  y0->wo = R3_CONST(0.0, 0.0, 0.0);
  y0->beta = RRGB_SCALE_S(les.le, 1.0 / (pmf * les.pdf_pos));
  y0->pdf_rev = R_C(0.0);
#if !R_DUAL
  /* Where on an area light (its inverse, bdpt_invert_light_subpath, needs the triangle). */
  y0->hit.mesh = l->type == LIGHT_AREA ? l->mesh : -1;
  y0->hit.prim = les.tri;
#endif

  /* beta = Le cos0 / (pmf pdf_pos pdf_dir). */
  REAL cos0 = l->type == LIGHT_AREA ? R_FABS(R3_DOT_C(les.n, les.dir)) : R_C(1.0);
  RRGB beta = RRGB_SCALE(les.le, R_DIV(cos0, R_MUL_S(les.pdf_dir, pmf * les.pdf_pos)));
  REAL pdf_next;
  if (far) {
    BDPT_VERTEX tmp;
    memset(&tmp, 0, sizeof tmp);
    tmp.type = BDPT_VERTEX_SURFACE;
    tmp.p = R3_ADD(les.p, les.dir);
    y0->pdf_fwd = light_is_infinite(l) ? bdpt__pdf_light_origin(BDPT_C, y0, &tmp) : R_C(pmf);
    pdf_next = R_C(les.pdf_pos);
  } else {
    y0->pdf_fwd = R_C(light_is_delta(l) ? pmf : pmf * les.pdf_pos);
    pdf_next = les.pdf_dir;
  }
  double tmin = l->type == LIGHT_AREA ? scene_ray_eps(sc, R3_V(les.p)) : 0.0;
#if BDPT_MEDIA_CODE
  /* The medium the light sits in (at infinity: the ambient one). */
  if (w->media) {
    w->med = y0->med =
        far ? sc->ambient_medium
            : render_medium_at(sc, l->type == LIGHT_AREA ? l->mesh : -1, les.p, les.n, les.dir);
    /* From infinity through the ambient medium: only its clear channels. */
    if (far && sc->ambient_medium)
      beta = rgb_mul(beta, medium_transmittance(scene_medium(sc, sc->ambient_medium), INFINITY));
  }
#endif
  return bdpt__walk(w, TRANSPORT_IMPORTANCE, les.p, les.dir, tmin, beta, pdf_next, far, path, 1,
                    max_vertices);
}

/* ---- The camera subpath ---------------------------------------------------------- */

/* The camera endpoint z_0: the pinhole, throughput 1, density 1. */
static void bdpt__camera_vertex(BDPT_WALK_CTX, BDPT_VERTEX *z0) {
  BDPT_WALK_PROLOGUE
  memset(z0, 0, sizeof *z0);
  z0->type = BDPT_VERTEX_CAMERA;
  z0->light = -1;
  z0->p = R3_CONST(w->sc->cam.pos.x, w->sc->cam.pos.y, w->sc->cam.pos.z);
  z0->beta = RRGB_CONST(rgb_gray(1.0));
  z0->pdf_fwd = R_C(1.0);
  z0->pdf_rev = R_C(0.0);
  z0->dir = z0->wo = R3_CONST(0.0, 0.0, 0.0);
#if BDPT_MEDIA_CODE
  z0->med = w->media ? w->sc->cam.medium : 0;
#endif
}

/* The camera subpath from z_0 along the camera ray (org, dir). */
static int bdpt__camera_walk(BDPT_WALK_CTX, REAL3 org, REAL3 dir, int max_vertices,
                             BDPT_VERTEX *path) {
  BDPT_WALK_PROLOGUE
  REAL pdf_dir = BDPT_CAM_PDF_DIR(dir);
#if BDPT_MEDIA_CODE
  w->med = path[0].med;
#endif
  return bdpt__walk(w, TRANSPORT_RADIANCE, org, dir, 0.0, RRGB_CONST(rgb_gray(1.0)), pdf_dir, 0,
                    path, 1, max_vertices);
}
