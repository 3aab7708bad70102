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
 *                   camera hit with ray differentials; duals: nothing).
 */

static int pt__counts(const render_settings *rs, int length) {
  return rs->mindepth <= 0 || length >= rs->mindepth;
}

/* Radiance along the ray (org, dir) from the camera; keep_rx, keep_ry are
 * the dual path's film position, kept across its bounces (NULL: none). */
static RRGB pt__walk(PT_CTX, REAL3 org, REAL3 dir, REAL *keep_rx, REAL *keep_ry) {
  PT_ARENA
  const scene *s = PT_SCENE;
  const render_settings *rs = PT_RS;
  RRGB L = RRGB_ZERO(), beta = RRGB_CONST(rgb_gray(1.0));
  int prev_delta = 1;        /* the previous vertex was the camera or a delta lobe */
  REAL prev_pdf = R_C(0.0);  /* solid-angle density of the previous BSDF sample */
  REAL3 prev_p = org;
  double tmin = 0.0, eta_scale = 1.0;
  unsigned lobes = 0; /* lobes sampled so far (the dual path's flags) */
#if R_DUAL
  size_t mark = ad_arena_mark(A);
#else
  (void)keep_rx, (void)keep_ry;
#endif

  for (int depth = 1;; depth++) {
    /* Find the next vertex; on a miss, add the infinite lights. */
    PT_HIT h;
    if (!PT_INTERSECT(org, dir, tmin, &h)) {
      if (!pt__counts(rs, depth)) break;
      for (int k = 0; k < s->n_infinite; k++) {
        int li = s->infinite_lights[k];
        const light *l = &s->lights[li];
        double pdf_inf = 0.0;
        rgb le = PT_LE_INFINITE(l, dir, &pdf_inf);
        if (rgb_is_black(le)) continue;
        REAL w = R_C(1.0);
        if (!prev_delta) {
          REAL pdf_l = R_MUL_S(PT_PDF_INFINITE(l, dir, prev_p, pdf_inf), scene_light_pmf(s, li));
          w = PT_MIS(prev_pdf, pdf_l);
        }
        PT_ADD(L, beta, PT_SCALE_C(le, w), path__emit_flag(l), lobes, depth);
      }
      break;
    }
    PT_FOOTPRINT(h, depth, org);
    REAL3 wo = R3_NEG(dir);

    /* Emission of an area light that the path hit. */
    if (h.light >= 0 && pt__counts(rs, depth)) {
      const light *l = &s->lights[h.light];
      rgb le = light_le_area(l, h.ng, R3_V(wo));
      if (!rgb_is_black(le)) {
        REAL w = R_C(1.0);
        if (!prev_delta) {
          REAL pdf_l = R_MUL_S(PT_PDF_LI(l, prev_p, dir, h.p, h.ng), scene_light_pmf(s, h.light));
          w = PT_MIS(prev_pdf, pdf_l);
        }
        PT_ADD(L, beta, PT_SCALE_C(le, w), PATH_EMIT_AREA, lobes, depth);
      }
    }

    /* Take this bounce's numbers (fixed layout; differentiated only when
     * the path goes on to use them), then stop if too long. */
    int live = !(rs->maxdepth >= 0 && depth >= rs->maxdepth);
    REAL u_light = PT_DRAW(0), ul1 = PT_DRAW(live), ul2 = PT_DRAW(live);
    REAL u_lobe = PT_DRAW(0), ub1 = PT_DRAW(live), ub2 = PT_DRAW(live);
    REAL u_rr = PT_DRAW(0);
    if (!live) break;

    const bsdf *b = h.bsdf;
    REAL3 wo_l = R3_TO_LOCAL(&h.sh, wo);
    /* Shading and geometry must agree (a NaN carries on, as it always has). */
    int wo_ok = !(v3_dot(R3_V(wo), h.ng) * R_V(wo_l.z) <= 0.0);
    PT_TOPO(wo_ok);
    if (!wo_ok) break;

    /* Next-event estimation: sample a light, weight by MIS. `nee` counts how
     * far it got (part of the dual path's topology: each step is a branch). */
    int nee = 0;
    if (!bsdf_is_delta(b) && s->n_lights > 0 && pt__counts(rs, depth + 1)) {
      double pmf, u_rem;
      int li = scene_sample_light(s, R_V(u_light), &pmf, &u_rem);
      PT_TOPO(li);
      PT_LI ls;
      if (li >= 0 && pmf > 0.0 && PT_SAMPLE_LI(&s->lights[li], h.p, ul1, ul2, &ls) &&
          R_V(ls.pdf) > 0.0 && !RRGB_IS_BLACK(ls.li)) {
        nee = 1;
        REAL3 wi_l = R3_TO_LOCAL(&h.sh, ls.wi);
        if (v3_dot(R3_V(ls.wi), h.ng) * R_V(wi_l.z) > 0.0) {
          nee = 2;
          REAL pdf_b; /* the BSDF's density of wi, for the MIS weight */
          RRGB f = R_FN(bsdf_eval_pdf)(R_ARG b, h.tu, h.tv, wo_l, wi_l, TRANSPORT_RADIANCE, &pdf_b);
          if (!RRGB_IS_BLACK(f)) {
            nee = 3;
            if (!PT_BLOCKED(h.p, ls.wi, ls.p, ls.dist)) {
              REAL pdf_l = R_MUL_S(ls.pdf, pmf);
              REAL w = ls.delta ? R_C(1.0) : PT_MIS(pdf_l, pdf_b);
              REAL sc = R_DIV(R_MUL(R_FABS(wi_l.z), w), pdf_l);
              PT_ADD(L, beta, RRGB_SCALE(RRGB_MUL(f, ls.li), sc),
                     path__emit_flag(&s->lights[li]),
                     lobes | path__lobe_flag(bsdf_flags(b) & ~BSDF_DELTA), depth + 1);
            }
          }
        }
      }
    }
    PT_TOPO(nee);
    (void)nee;

    /* Sample the BSDF for the next direction. */
    R_FN(bsdf_sample) bs;
    int sampled =
        R_FN(bsdf_sample_f)(R_ARG b, h.tu, h.tv, wo_l, u_lobe, ub1, ub2, TRANSPORT_RADIANCE, &bs);
    PT_TOPO(sampled ? bs.flags : -1);
    if (!sampled) break;
    REAL3 wi = R3_TO_WORLD(&h.sh, bs.wi);
    int side_ok = !(v3_dot(R3_V(wi), h.ng) * R_V(bs.wi.z) <= 0.0);
    PT_TOPO(side_ok);
    if (!side_ok) break;
    beta = RRGB_MUL(beta, bs.weight);
    if (RRGB_IS_BLACK(beta)) break;
    lobes |= PT_LOBE(bs.flags);
    prev_delta = (bs.flags & BSDF_DELTA) != 0;
    prev_pdf = bs.pdf;
    prev_p = h.p;
    if (bs.flags & BSDF_TRANSMISSION) eta_scale *= bs.eta * bs.eta;

    /* Russian roulette on the throughput (without the radiance scaling of
     * refraction, which would otherwise end paths inside glass); q is a
     * dual on the dual path since the estimator divides by it. */
    if (depth >= rs->rrdepth) {
      REAL q = PT_RR_Q(beta, eta_scale);
      PT_TOPO(R_V(u_rr) < R_V(q));
      if (!(R_V(u_rr) < R_V(q))) break;
      beta = RRGB_SCALE(beta, R_INV(q));
    }
    org = h.p;
    dir = wi;
    tmin = scene_ray_eps(s, R3_V(h.p));
#if R_DUAL
    /* Keep what the next bounce needs and drop the rest of this one. */
    ad *keep[] = {&L.r,      &L.g,      &L.b,      &beta.r,   &beta.g, &beta.b,
                  &prev_pdf, &prev_p.x, &prev_p.y, &prev_p.z, &org.x,  &org.y,
                  &org.z,    &dir.x,    &dir.y,    &dir.z,    keep_rx, keep_ry};
    path__keep(c, mark, keep, (int)(sizeof keep / sizeof keep[0]));
#endif
  }
  (void)lobes;
  return L;
}
