/*
 * bdpt_media.h: bdpt_generic.h's steps through participating media, on
 * the plain side only (integrator_bdpt.c, BDPT_MEDIA_CODE 1): the free
 * flight's density at a vertex, the medium a ray leaves a vertex in, the
 * walk's free flight and its scattering vertex. Not a header: bdpt_generic.h includes it
 * once, after the densities, in its includer's vocabulary (BDPT_VERTEX,
 * BDPT_C, the walker's BDPT_WALK_CTX and BDPT_W_* macros).
 */

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

/* The walk's free flight from org along dir (tmin on), in medium *med
 * across index-matched boundaries (render_fly; the medium reached into
 * *med and v->med): 1 to a surface (its hit in v), 2 to a scattering point
 * (at *OUT_p), 0 nowhere; -1 ends the walk (the crossings exhausted, or
 * the weight black). The flight's weight multiplies *beta, its density
 * into *OUT_flight, its transmittance into v->tseg. */
static int bdpt__fly(BDPT_WALK_CTX, vec3 org, vec3 dir, double tmin, int *med, BDPT_VERTEX *v,
                     vec3 *OUT_p, double *OUT_flight, rgb *beta) {
  double u_ch = BDPT_W_DRAW(0), u_t = BDPT_W_DRAW(1);
  rgb fw;
  int found = render_fly(w->sc, w->cnt, org, dir, tmin, med, u_ch, u_t, &v->hit, OUT_p, &v->tseg,
                         OUT_flight, &fw);
  if (found < 0) return -1;
  v->med = *med;
  *beta = rgb_mul(*beta, fw);
  return rgb_is_black(*beta) ? -1 : found;
}

/* The walk's scattering point at mp in medium med (found by a flight of
 * density `flight`): path[*n] becomes a medium vertex, its density from
 * path[*n - 1] (no normal: 1 / d^2, or the planar density of a light at
 * infinity) times the flight's; it takes its four numbers, samples the
 * phase function (weight 1; symmetric, so the reverse density is the
 * same) and survives Russian roulette. The next segment's org, dir and
 * density into *org, *dir, *pdf_dir (*planar cleared); 0: the walk ends
 * (the vertex counted). */
static int bdpt__medium_vertex(BDPT_WALK_CTX, transport_mode mode, BDPT_VERTEX *path, int *n,
                               int max_vertices, vec3 mp, int med, double flight, double eta_scale,
                               rgb *beta, vec3 *org, vec3 *dir, double *pdf_dir, int *planar) {
  BDPT_WALK_PROLOGUE
  const scene *sc = w->sc;
  BDPT_VERTEX *prev = &path[*n - 1], *v = &path[*n];
  v->type = BDPT_VERTEX_MEDIUM;
  v->light = -1;
  v->p = mp;
  v->wo = v3_neg(*dir);
  v->ph = &scene_medium(sc, med)->ph;
  v->pdf_fwd = (*planar ? *pdf_dir : bdpt__convert(BDPT_C, *pdf_dir, prev, v)) * flight;
  (*n)++;
  int live = *n < max_vertices;
  double u_lobe = BDPT_W_DRAW(0), u1 = BDPT_W_DRAW(live), u2 = BDPT_W_DRAW(live);
  double u_rr = BDPT_W_DRAW(0);
  (void)u_lobe;
  if (!live) return 0;
  vec3 wi;
  double pdf;
  if (!phase_sample(v->ph, v->wo, u1, u2, &wi, &pdf)) return 0;
  prev->pdf_rev = bdpt__convert(BDPT_C, pdf, v, prev) * bdpt__flight(sc, prev, v->tseg);
  if (*n - 1 >= w->rs->rrdepth) {
    double q = BDPT_W_RR_Q(mode, *beta, path[1].beta, eta_scale);
    if (!(u_rr < q)) return 0;
    *beta = rgb_scale(*beta, 1.0 / q);
  }
  *org = mp;
  *dir = wi;
  *pdf_dir = pdf;
  *planar = 0;
  return 1;
}
