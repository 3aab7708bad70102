/*
 * bdpt_walk.h: bdpt_generic.h's random walks: the walk that extends a
 * subpath (surface vertices by BSDF samples or absolute directions,
 * medium vertices on the plain side), and the light and camera subpaths
 * it makes. Not a header: bdpt_generic.h includes it once, at its end, in
 * its includer's vocabulary (the walker's BDPT_WALK_CTX and BDPT_W_*
 * macros, stated at bdpt__walk).
 */

/* ---- The random walk ------------------------------------------------------------ */


/* The walk's surface vertex v, found along dir from prev: its fields from
 * its hit, and its density from prev's pdf_dir (planar: a direction's
 * density on a plane, from a light at infinity). */
static void bdpt__surface_vertex(BDPT_WALK_CTX, BDPT_VERTEX *v, const BDPT_VERTEX *prev, REAL3 dir,
                                 REAL pdf_dir, int planar) {
  BDPT_WALK_PROLOGUE
  v->type = BDPT_VERTEX_SURFACE;
  v->light = v->hit.light;
  v->p = v->hit.p;
  v->n = v->hit.ng;
  v->wo = R3_NEG(dir);
  if (planar)
    v->pdf_fwd = R_MUL(pdf_dir, R_FABS(R3_DOT_C(v->n, dir)));
  else
    v->pdf_fwd = bdpt__convert(BDPT_C, pdf_dir, prev, v);
}

/* The next direction at the walk's surface vertex v (the n-th), from its
 * numbers u_lobe, u1, u2: a BSDF sample, or an absolute direction read
 * from them at a rough vertex (integrator.h's bdpt_param). The sample
 * (local) into *OUT_bs, the direction into *OUT_wi, wo in v's shading
 * frame into *OUT_wo_l; 0: the walk ends here. */
static int bdpt__next_dir(BDPT_WALK_CTX, transport_mode mode, BDPT_VERTEX *v, int n, REAL u_lobe,
                          REAL u1, REAL u2, R_FN(bsdf_sample) * OUT_bs, REAL3 *OUT_wi,
                          REAL3 *OUT_wo_l) {
  BDPT_WALK_PROLOGUE
  (void)n;
  const BDPT_HIT *h = &v->hit;
  REAL3 wo_l, wi_l;
  int ok = bdpt__side_ok(R_ARG h, v->wo, &wo_l);
  BDPT_W_TOPO(ok);
  if (!ok) return 0;
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
    if (!ok) return 0;
    REAL pdf;
    RRGB f = R_FN(bsdf_eval_pdf)(R_ARG h->bsdf, h->tu, h->tv, wo_l, wi_l, mode, &pdf);
    int trans = R_V(wi_l.z) * R_V(wo_l.z) < 0.0;
    ok = R_V(pdf) > 0.0 && isfinite(R_V(pdf));
    RRGB weight = ok ? RRGB_SCALE(f, R_DIV(R_FABS(wi_l.z), pdf)) : RRGB_ZERO();
    ok = ok && RRGB_IS_FINITE(weight) && !RRGB_IS_BLACK(weight);
    BDPT_W_TOPO(ok ? 1 + trans : -1);
    if (!ok) return 0;
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
    if (!ok) return 0;
    wi = R3_TO_WORLD(&h->sh, bs.wi);
    ok = bdpt__side_ok(R_ARG h, wi, &wi_l);
    BDPT_W_TOPO(ok);
    if (!ok) return 0;
#if !R_DUAL
    if (rough) {
      /* Where this direction lies in the absolute parametrization. */
      double J;
      bdpt_sphere_coords(wi, &v->sph[0], &v->sph[1], &J);
      v->jac = bsdf_pdf(h->bsdf, h->tu, h->tv, wo_l, wi_l) * J;
    }
#endif
  }
  *OUT_bs = bs;
  *OUT_wi = wi;
  *OUT_wo_l = wo_l;
  return 1;
}

#if R_DUAL
/* Keeps vertex v (after prev), the throughput and the next direction with
 * its density on the walk's arena from mark on, and drops the rest. */
static void bdpt__walk_keep(BDPT_WALK_CTX, size_t mark, BDPT_VERTEX *v, BDPT_VERTEX *prev,
                            RRGB *beta, REAL3 *dir, REAL *pdf_dir) {
  BDPT_WALK_PROLOGUE
  BDPT_HIT *vh = &v->hit;
  ad *keep[] = {&v->beta.r,   &v->beta.g,     &v->beta.b,  &v->pdf_fwd, &v->p.x,
                &v->p.y,      &v->p.z,        &v->wo.x,    &v->wo.y,    &v->wo.z,
                &vh->sh.s.x,  &vh->sh.s.y,    &vh->sh.s.z, &vh->sh.t.x, &vh->sh.t.y,
                &vh->sh.t.z,  &vh->sh.n.x,    &vh->sh.n.y, &vh->sh.n.z, &vh->tu,
                &vh->tv,      &prev->pdf_rev, &beta->r,    &beta->g,    &beta->b,
                &dir->x,      &dir->y,        &dir->z,     pdf_dir,     &v->jac};
  path__keep(w, mark, keep, (int)(sizeof keep / sizeof keep[0]));
  vh->p = v->p;
  v->pdf_rev = ad_const(A, 0.0);
}
#endif

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
      found = bdpt__fly(w, org, dir, tmin, &med, v, &mp, &flight, &beta);
      if (found < 0) break;
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
      if (!bdpt__medium_vertex(w, mode, path, &n, max_vertices, mp, med, flight, eta_scale, &beta,
                               &org, &dir, &pdf_dir, &planar))
        break;
      tmin = 0.0;
      continue;
    }
#endif
    bdpt__surface_vertex(w, v, prev, dir, pdf_dir, planar);
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
    R_FN(bsdf_sample) bs;
    REAL3 wi;
    REAL3 wo_l;
    if (!bdpt__next_dir(w, mode, v, n, u_lobe, u1, u2, &bs, &wi, &wo_l)) break;
    const BDPT_HIT *h = &v->hit;
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
    bdpt__walk_keep(w, mark, v, prev, &beta, &dir, &pdf_dir);
#endif
    org = v->p;
  }
  return n;
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
  z0->media = w->media;
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
