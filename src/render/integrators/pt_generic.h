/*
 * pt_generic.h: the unidirectional estimator's walk (path tracing with
 * next-event estimation and MIS, integrator_pt.c's opening comment), written
 * once in render/real.h's vocabulary: pt_li runs it in doubles on the
 * sampler and Embree (integrator_pt.c), path.c in duals on its recorded
 * numbers and hits, for the gradient and Hessian of the same formula. Not a
 * header: no include guard; each of the two files includes it once.
 *
 * The includer defines, besides R_DUAL and render/real.h:
 *   PT_CTX          its context parameter, named c (PT_SCENE, PT_RS: its
 *                   scene and settings; PT_ARENA: the statement naming the
 *                   arena A, or nothing);
 *   PT_HIT, PT_LI   its surface hit and light-sample types;
 *   PT_INTERSECT(org, dir, tmin, h), PT_BLOCKED(p, wi, lp, dist): the
 *                   closest hit and the shadow ray;
 *   PT_DRAW(diff)   the next number (diff: it is continuous);
 *   PT_TOPO(x)      notes a branch taken (the dual path's topology);
 *   PT_LE_INFINITE(l, dir, pdf), PT_PDF_INFINITE(l, dir, ref, pdf): an
 *                   infinite light's radiance along dir and its direct-
 *                   sampling density from ref (the plain side computes both
 *                   at once and keeps the density in pdf);
 *   PT_PDF_LI(l, ref, w, p, n), PT_SAMPLE_LI(l, ref, u1, u2, ls): light.c's
 *                   direct sampling and its density;
 *   PT_MIS(a, b), PT_SCALE_C(c, w): the power heuristic and a constant
 *                   colour times a number;
 *   PT_ADD(L, beta, contrib, emit, lobes, length): L += beta contrib (the
 *                   dual side also notes the emitter, lobes and length);
 *   PT_RR_Q(beta, eta): Russian roulette's survival probability;
 *   PT_LOBE(flags): the dual path's lobe flag of a BSDF sample (plain: 0);
 *   PT_FOOTPRINT(h, depth, org): the hit h of the ray from org at depth
 *                   reads its textures over its footprint (plain: the
 *                   camera hit with ray differentials; duals: nothing);
 *   PT_MEDIA_CODE   1: the walk through participating media is compiled
 *                   (plain side: integrator_pt_media.c; duals: path.c), used
 *                   when PT_MEDIA_ON; with it PT_FLY(org, dir, tmin, med,
 *                   u_ch, u_t, h, vp, fw) (render_fly: the free flight
 *                   across boundaries to a surface, 1, in h, or a
 *                   scattering point, 2, at vp; its weight in fw),
 *                   PT_TRANSMIT(p, wi, ls, med, T) (the shadow ray's
 *                   transmittance to the light sample ls, 0 when blocked)
 *                   and PT_MEDIUM_AFTER(h, cur, dir) (scene_medium_after).
 *                   0: the walk without media (integrator_pt.c).
 */

static int pt__counts(const render_settings *rs, int length) {
  return rs->mindepth <= 0 || length >= rs->mindepth;
}

/* What the walk carries from vertex to vertex. */
typedef struct pt__state {
  RRGB beta;      /* the throughput */
  int prev_delta; /* the previous vertex was the camera or a delta lobe */
  REAL prev_pdf;  /* solid-angle density of the previous BSDF (phase) sample */
  REAL3 prev_p;   /* the previous vertex */
  unsigned lobes; /* lobes sampled so far (the dual path's flags) */
} pt__state;

/* L += the infinite lights along dir, where the path of `depth` segments
 * escaped (MIS against the previous sample). */
static void pt__escape(PT_CTX, const pt__state *w, REAL3 dir, int depth, RRGB *L) {
  PT_ARENA
  (void)depth;
  const scene *s = PT_SCENE;
  for (int k = 0; k < s->n_infinite; k++) {
    int li = s->infinite_lights[k];
    const light *l = &s->lights[li];
    double pdf_inf = 0.0;
    rgb le = PT_LE_INFINITE(l, dir, &pdf_inf);
    if (rgb_is_black(le)) continue;
    REAL mis = R_C(1.0);
    if (!w->prev_delta) {
      REAL pdf_l = R_MUL_S(PT_PDF_INFINITE(l, dir, w->prev_p, pdf_inf), scene_light_pmf(s, li));
      mis = PT_MIS(w->prev_pdf, pdf_l);
    }
    PT_ADD(*L, w->beta, PT_SCALE_C(le, mis), path__emit_flag(l), w->lobes, depth);
  }
}

/* L += the emission of the area light at h, reached along dir. */
static void pt__emitted(PT_CTX, const pt__state *w, const PT_HIT *h, REAL3 dir, int depth,
                        RRGB *L) {
  PT_ARENA
  (void)depth;
  const scene *s = PT_SCENE;
  const light *l = &s->lights[h->light];
  rgb le = light_le_area(l, h->ng, v3_neg(R3_V(dir)));
  if (rgb_is_black(le)) return;
  REAL mis = R_C(1.0);
  if (!w->prev_delta) {
    REAL pdf_l = R_MUL_S(PT_PDF_LI(l, w->prev_p, dir, h->p, h->ng), scene_light_pmf(s, h->light));
    mis = PT_MIS(w->prev_pdf, pdf_l);
  }
  PT_ADD(*L, w->beta, PT_SCALE_C(le, mis), PATH_EMIT_AREA, w->lobes, depth);
}

/* A vertex of the walk: a surface hit h, or a scattering point (medv) in
 * the medium med; p its position, wo (wo_l: in the shading frame) towards
 * the previous vertex, b its BSDF. */
typedef struct pt__vertex {
  const PT_HIT *h;
  REAL3 p, wo, wo_l;
  const bsdf *b;
  int medv, med;
} pt__vertex;

/* Next-event estimation at v from the numbers (u_light, ul1, ul2): L +=
 * the light it finds, times the transmittance through media, MIS-weighted
 * against v's own sample. Returns how far it got (part of the dual path's
 * topology: each step is a branch). */
static int pt__nee(PT_CTX, const pt__vertex *v, const pt__state *w, REAL u_light, REAL ul1,
                   REAL ul2, int depth, RRGB *L) {
  PT_ARENA
  const scene *s = PT_SCENE;
  const PT_HIT *h = v->h;
  int nee = 0;
  double pmf, u_rem;
  int li = scene_sample_light(s, R_V(u_light), &pmf, &u_rem);
  PT_TOPO(li);
  PT_LI ls;
  if (!(li >= 0 && pmf > 0.0 && PT_SAMPLE_LI(&s->lights[li], v->p, ul1, ul2, &ls) &&
        R_V(ls.pdf) > 0.0 && !RRGB_IS_BLACK(ls.li)))
    return nee;
  nee = 1;
  REAL3 wi_l = ls.wi;
  REAL pdf_b; /* the BSDF's (phase function's) density of wi, for the MIS weight */
  RRGB f;
#if PT_MEDIA_CODE
  if (v->medv) {
    pdf_b = R_FN(phase_eval)(R_ARG &scene_medium(s, v->med)->ph, v->wo, ls.wi);
    f = RRGB_MAKE(pdf_b, pdf_b, pdf_b);
  } else
#endif
  {
    wi_l = R3_TO_LOCAL(&h->sh, ls.wi);
    if (!(v3_dot(R3_V(ls.wi), h->ng) * R_V(wi_l.z) > 0.0)) return nee;
    f = R_FN(bsdf_eval_pdf)(R_ARG v->b, h->tu, h->tv, v->wo_l, wi_l, TRANSPORT_RADIANCE, &pdf_b);
  }
  nee = 2;
  if (RRGB_IS_BLACK(f)) return nee;
  nee = 3;
  int clear;
#if PT_MEDIA_CODE
  RRGB tr = RRGB_CONST(rgb_gray(1.0));
  if (PT_MEDIA_ON) {
    int med_l = v->medv ? v->med : PT_MEDIUM_AFTER(h, v->med, R3_V(ls.wi));
    clear = PT_TRANSMIT(v->p, ls.wi, ls, med_l, &tr) && !RRGB_IS_BLACK(tr);
    PT_TOPO(clear);
    if (clear) f = RRGB_MUL(f, tr);
  } else
#endif
    clear = !PT_BLOCKED(v->p, ls.wi, ls.p, ls.dist);
  if (!clear) return nee;
  REAL pdf_l = R_MUL_S(ls.pdf, pmf);
  REAL mis = ls.delta ? R_C(1.0) : PT_MIS(pdf_l, pdf_b);
  REAL sc = R_DIV(v->medv ? mis : R_MUL(R_FABS(wi_l.z), mis), pdf_l);
  PT_ADD(*L, w->beta, RRGB_SCALE(RRGB_MUL(f, ls.li), sc), path__emit_flag(&s->lights[li]),
         w->lobes | (v->medv ? 0u : (unsigned)PT_LOBE(bsdf_flags(v->b) & ~BSDF_DELTA)), depth + 1);
  (void)depth;
  return nee;
}

/* The next direction wi from v's BSDF (phase function) by (u_lobe, ub1,
 * ub2): w takes the sample's weight, density and lobe, eta_scale the
 * radiance scaling of a refraction. 0: the walk ends here. */
static int pt__scatter(PT_CTX, const pt__vertex *v, REAL u_lobe, REAL ub1, REAL ub2, pt__state *w,
                       double *eta_scale, REAL3 *OUT_wi) {
  PT_ARENA
  const PT_HIT *h = v->h;
  (void)c;
#if PT_MEDIA_CODE
  if (v->medv) {
    /* (the phase function's sample has weight 1) */
    (void)u_lobe;
    w->prev_delta = 0;
    return R_FN(phase_sample)(R_ARG &scene_medium(PT_SCENE, v->med)->ph, v->wo, ub1, ub2, OUT_wi,
                              &w->prev_pdf);
  }
#endif
  R_FN(bsdf_sample) bs;
  int sampled = R_FN(bsdf_sample_f)(R_ARG v->b, h->tu, h->tv, v->wo_l, u_lobe, ub1, ub2,
                                    TRANSPORT_RADIANCE, &bs);
  PT_TOPO(sampled ? bs.flags : -1);
  if (!sampled) return 0;
  *OUT_wi = R3_TO_WORLD(&h->sh, bs.wi);
  int side_ok = !(v3_dot(R3_V(*OUT_wi), h->ng) * R_V(bs.wi.z) <= 0.0);
  PT_TOPO(side_ok);
  if (!side_ok) return 0;
  w->beta = RRGB_MUL(w->beta, bs.weight);
  if (RRGB_IS_BLACK(w->beta)) return 0;
  w->lobes |= PT_LOBE(bs.flags);
  w->prev_delta = (bs.flags & BSDF_DELTA) != 0;
  w->prev_pdf = bs.pdf;
  if (bs.flags & BSDF_TRANSMISSION) *eta_scale *= bs.eta * bs.eta;
  return 1;
}

/* Radiance along the ray (org, dir) from the camera; keep_rx, keep_ry are
 * the dual path's film position, kept across its bounces (NULL: none). */
static RRGB pt__walk(PT_CTX, REAL3 org, REAL3 dir, REAL *keep_rx, REAL *keep_ry) {
  PT_ARENA
  const scene *s = PT_SCENE;
  const render_settings *rs = PT_RS;
  RRGB L = RRGB_ZERO();
  pt__state w = {RRGB_CONST(rgb_gray(1.0)), 1, R_C(0.0), org, 0};
  double tmin = 0.0, eta_scale = 1.0;
#if PT_MEDIA_CODE
  int med = PT_MEDIA_ON ? s->cam.medium : 0; /* the medium the ray travels in */
#endif
#if R_DUAL
  size_t mark = ad_arena_mark(A);
#else
  (void)keep_rx, (void)keep_ry;
#endif

  for (int depth = 1;; depth++) {
    /* Find the next vertex (through media: a surface or a scattering
     * point, medv); on a miss, add the infinite lights. */
    PT_HIT h;
    int found, medv = 0;
    REAL3 vp; /* the vertex */
#if PT_MEDIA_CODE
    if (PT_MEDIA_ON) {
      REAL u_ch = PT_DRAW(0), u_t = PT_DRAW(1);
      RRGB fw;
      found = PT_FLY(org, dir, tmin, &med, u_ch, u_t, &h, &vp, &fw);
      PT_TOPO(found);
      if (found < 0) break;
      w.beta = RRGB_MUL(w.beta, fw);
      if (RRGB_IS_BLACK(w.beta)) break;
      medv = found == 2;
    } else
#endif
      found = PT_INTERSECT(org, dir, tmin, &h);
    if (!found) {
      if (pt__counts(rs, depth)) pt__escape(c, &w, dir, depth, &L);
      break;
    }
    if (!medv) {
      PT_FOOTPRINT(h, depth, org);
      vp = h.p;
    }
    REAL3 wo = R3_NEG(dir);

    /* Emission of an area light that the path hit. */
    if (!medv && h.light >= 0 && pt__counts(rs, depth)) pt__emitted(c, &w, &h, dir, depth, &L);

    /* Take this bounce's numbers (fixed layout; differentiated only when
     * the path goes on to use them), then stop if too long. */
    int live = !(rs->maxdepth >= 0 && depth >= rs->maxdepth);
    REAL u_light = PT_DRAW(0), ul1 = PT_DRAW(live), ul2 = PT_DRAW(live);
    REAL u_lobe = PT_DRAW(0), ub1 = PT_DRAW(live), ub2 = PT_DRAW(live);
    REAL u_rr = PT_DRAW(0);
    if (!live) break;

    const bsdf *b = NULL;
    REAL3 wo_l = wo;
    if (!medv) {
      b = h.bsdf;
      wo_l = R3_TO_LOCAL(&h.sh, wo);
      /* Shading and geometry must agree (a NaN carries on, as it always has). */
      int wo_ok = !(v3_dot(R3_V(wo), h.ng) * R_V(wo_l.z) <= 0.0);
      PT_TOPO(wo_ok);
      if (!wo_ok) break;
    }

    /* Next-event estimation: sample a light, weight by MIS. */
    pt__vertex v = {&h, vp, wo, wo_l, b, medv, 0};
#if PT_MEDIA_CODE
    v.med = med;
#endif
    int nee = 0;
    if ((medv || !bsdf_is_delta(b)) && s->n_lights > 0 && pt__counts(rs, depth + 1))
      nee = pt__nee(c, &v, &w, u_light, ul1, ul2, depth, &L);
    PT_TOPO(nee);
    (void)nee;

    /* Sample the BSDF (the phase function) for the next direction. */
    REAL3 wi;
    if (!pt__scatter(c, &v, u_lobe, ub1, ub2, &w, &eta_scale, &wi)) break;
#if PT_MEDIA_CODE
    if (PT_MEDIA_ON && !medv) med = PT_MEDIUM_AFTER(&h, med, R3_V(wi));
#endif
    w.prev_p = vp;

    /* Russian roulette on the throughput (without the radiance scaling of
     * refraction, which would otherwise end paths inside glass); q is a
     * dual on the dual path since the estimator divides by it. */
    if (depth >= rs->rrdepth) {
      REAL q = PT_RR_Q(w.beta, eta_scale);
      PT_TOPO(R_V(u_rr) < R_V(q));
      if (!(R_V(u_rr) < R_V(q))) break;
      w.beta = RRGB_SCALE(w.beta, R_INV(q));
    }
    org = vp;
    dir = wi;
    tmin = medv ? 0.0 : scene_ray_eps(s, R3_V(vp));
#if R_DUAL
    /* Keep what the next bounce needs and drop the rest of this one. */
    ad *keep[] = {&L.r,        &L.g,        &L.b,        &w.beta.r,   &w.beta.g, &w.beta.b,
                  &w.prev_pdf, &w.prev_p.x, &w.prev_p.y, &w.prev_p.z, &org.x,    &org.y,
                  &org.z,      &dir.x,      &dir.y,      &dir.z,      keep_rx,   keep_ry};
    path__keep(c, mark, keep, (int)(sizeof keep / sizeof keep[0]));
#endif
  }
  (void)w.lobes;
  return L;
}
