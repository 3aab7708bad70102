/*
 * light_generic.h: the emitters' sampling routines and densities (light.c's
 * models), written once in render/real.h's vocabulary and compiled twice by
 * light.c: in doubles (light_sample_li, light_pdf_li, light_sample_le and
 * the direction density of light_pdf_le, light.h) and in duals (the same
 * names with _ad, light_ad.h) for the differentiable path. Not a header: no
 * include guard.
 *
 * The plain form computes exactly what light.c always has. The dual form's
 * values equal the plain ones to rounding; where a quotient's value is kept
 * bit for bit (LIGHT__EXACT) it is the plain division's. What only the duals
 * need is in #if R_DUAL blocks: a number reused inside a discrete choice
 * (a triangle of the light, a pixel of the map) moves with its number at
 * the choice's scale (light__remap), and the choices are reported (tri,
 * cell) for the dual path's topology.
 */

#undef LIGHT__EXACT
#undef LIGHT__CLAMP
#if R_DUAL
/* x's value as the plain division computes it. */
#define LIGHT__EXACT(x, value) ((x).v = (value))
#define LIGHT__CLAMP(x, lo, hi) ad_clamp(A, (x), (lo), (hi))
#else
#define LIGHT__EXACT(x, value) ((void)0)
#define LIGHT__CLAMP(x, lo, hi) fmin((hi), fmax((lo), (x)))
#endif

/* c s for a constant vector c. */
static REAL3 R_FN(light__cscale)(R_CTX vec3 c, REAL s) {
  return R3_MAKE(R_MUL_S(s, c.x), R_MUL_S(s, c.y), R_MUL_S(s, c.z));
}

/* c - a and a + c for a constant vector c. */
static REAL3 R_FN(light__csub)(R_CTX vec3 c, REAL3 a) {
  return R3_MAKE(R_S_SUB(c.x, a.x), R_S_SUB(c.y, a.y), R_S_SUB(c.z, a.z));
}
static REAL3 R_FN(light__cadd)(R_CTX REAL3 a, vec3 c) {
  return R3_MAKE(R_ADD_S(a.x, c.x), R_ADD_S(a.y, c.y), R_ADD_S(a.z, c.z));
}

/* A constant colour c times s. */
static RRGB R_FN(light__rgb_cscale)(R_CTX rgb c, REAL s) {
#if R_DUAL
  return (adrgb){ad_mul_s(A, s, c.r), ad_mul_s(A, s, c.g), ad_mul_s(A, s, c.b)};
#else
  return rgb_scale(c, s);
#endif
}

/* frame_to_world for a constant frame: s x + t y + n z. */
static REAL3 R_FN(light__to_world_c)(R_CTX const frame *f, REAL3 v) {
#if R_DUAL
  adv3 r;
  r.x = ad_add(A, ad_lincomb(A, f->s.x, v.x, f->t.x, v.y), ad_mul_s(A, v.z, f->n.x));
  r.y = ad_add(A, ad_lincomb(A, f->s.y, v.x, f->t.y, v.y), ad_mul_s(A, v.z, f->n.y));
  r.z = ad_add(A, ad_lincomb(A, f->s.z, v.x, f->t.z, v.y), ad_mul_s(A, v.z, f->n.z));
  return r;
#else
  return frame_to_world(f, v);
#endif
}

/* A constant matrix (the rotation part of m) times v. */
static REAL3 R_FN(light__mat_vec)(R_CTX const double (*m)[4], REAL3 v) {
#if R_DUAL
  adv3 r;
  r.x = ad_add(A, ad_lincomb(A, m[0][0], v.x, m[0][1], v.y), ad_mul_s(A, v.z, m[0][2]));
  r.y = ad_add(A, ad_lincomb(A, m[1][0], v.x, m[1][1], v.y), ad_mul_s(A, v.z, m[1][2]));
  r.z = ad_add(A, ad_lincomb(A, m[2][0], v.x, m[2][1], v.y), ad_mul_s(A, v.z, m[2][2]));
  return r;
#else
  return v3(m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
            m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z);
#endif
}

/* A number u reused inside a discrete choice: its remapped value `value`,
 * moving with u at `scale` (the inverse width of the choice's cell). */
static REAL R_FN(light__remap)(R_CTX double value, double scale, REAL u) {
#if R_DUAL
  ad r = ad_mul_s(A, u, scale);
  r.v = value;
  return r;
#else
  (void)scale, (void)u;
  return value;
#endif
}

/* Shirley and Chiu's concentric map of the square to the disk. */
static void R_FN(light__concentric)(R_CTX REAL u1, REAL u2, REAL *OUT_x, REAL *OUT_y) {
  REAL a = R_SUB_S(R_MUL_S(u1, 2.0), 1.0), b = R_SUB_S(R_MUL_S(u2, 2.0), 1.0);
  if (R_V(a) == 0.0 && R_V(b) == 0.0) {
    *OUT_x = *OUT_y = R_C(0.0);
    return;
  }
  REAL r, phi;
  if (fabs(R_V(a)) > fabs(R_V(b))) {
    r = a;
    phi = R_MUL_S(R_DIV(b, a), M_PI / 4.0); /* (pi/4) b/a */
  } else {
    r = b;
    phi = R_S_SUB(M_PI / 2.0, R_MUL_S(R_DIV(a, b), M_PI / 4.0)); /* pi/2 - (pi/4) a/b */
  }
  *OUT_x = R_MUL(r, R_COS(phi));
  *OUT_y = R_MUL(r, R_SIN(phi));
}

/* The direction of cosine z about +z at azimuth 2 pi u (the sphere and
 * cone warps). */
static REAL3 R_FN(light__z_phi)(R_CTX REAL z, REAL u) {
  REAL r = R_SAFE_SQRT(R_S_SUB(1.0, R_SQR(z)));
  REAL phi = R_MUL_S(u, 2.0 * M_PI);
  LIGHT__EXACT(phi, 2.0 * M_PI * R_V(u));
  return R3_MAKE(R_MUL(r, R_COS(phi)), R_MUL(r, R_SIN(phi)), z);
}

/* light_disk_point: the point for (u1, u2) of the disk of radius r facing
 * the unit dir, centred at center - dir r. */
static REAL3 R_FN(light__disk_point)(R_CTX const struct scene *s, REAL3 dir, REAL u1, REAL u2) {
  REAL x, y;
  R_FN(light__concentric)(R_ARG u1, u2, &x, &y);
  RFRAME f = R3_FRAME_FROM_Z(dir);
  REAL3 offset = R3_ADD(R3_SCALE(f.s, x), R3_SCALE(f.t, y));
  REAL3 q = R3_SCALE_S(R3_SUB(offset, dir), s->radius);
  return R_FN(light__cadd)(R_ARG q, s->center);
}

/* Mitsuba's spot falloff of the cosine to the axis: 1 inside the beam, 0
 * beyond the cutoff, linear in the angle between. */
static REAL R_FN(light__spot_falloff)(R_CTX const light *l, REAL cos_theta) {
  if (R_V(cos_theta) <= l->cos_cutoff) return R_C(0.0);
  if (R_V(cos_theta) >= l->cos_beam) return R_C(1.0);
  double width = l->cutoff - l->beam_width;
  if (!(width > 0.0)) return R_C(1.0);
  /* (cutoff - theta) / (cutoff - beam_width), theta = acos(cos_theta) */
  REAL theta = R_ACOS(LIGHT__CLAMP(cos_theta, -1.0, 1.0));
  REAL f = R_DIV_S(R_S_SUB(l->cutoff, theta), width);
  LIGHT__EXACT(f, (l->cutoff - R_V(theta)) / width);
  return LIGHT__CLAMP(f, 0.0, 1.0);
}

/* A point of an area light uniform by area from (u1, u2): a triangle by
 * its area with u1, u1 reused inside its cell, a uniform point on it (b1 =
 * 1 - sqrt(u1'), b2 = u2 sqrt(u1')); *OUT_n the emitting side's normal (a
 * hit's geometric normal there). Returns the triangle. */
static int64_t R_FN(light__area_point)(R_CTX const light *l, const struct scene *s, REAL u1,
                                       REAL u2, REAL3 *OUT_p, vec3 *OUT_n) {
  const mesh *m = &s->meshes[l->mesh];
  double u1r;
  int tri = distrib1d_sample_discrete(&l->tri_dist, R_V(u1), NULL, &u1r);
  double width = l->tri_dist.cdf[tri + 1] - l->tri_dist.cdf[tri];
  REAL ur = R_FN(light__remap)(R_ARG u1r, width > 0.0 ? 1.0 / width : 0.0, u1);
  REAL sq = R_SAFE_SQRT(ur);
  REAL b1 = R_S_SUB(1.0, sq), b2 = R_MUL(u2, sq);
  REAL b0 = R_SUB(R_S_SUB(1.0, b1), b2);
  const uint32_t *idx = m->idx + 3 * tri;
  vec3 a = mesh_position(m, idx[0]), b = mesh_position(m, idx[1]), c = mesh_position(m, idx[2]);
  /* b0 a + b1 b + b2 c */
  *OUT_p = R3_ADD(R3_ADD(R_FN(light__cscale)(R_ARG a, b0), R_FN(light__cscale)(R_ARG b, b1)),
                  R_FN(light__cscale)(R_ARG c, b2));
  *OUT_n = mesh_hit_normals(m, tri, a, b, c, R_V(b1), R_V(b2), NULL);
  return tri;
}

/* Lat-long (u, v) to a world direction towards the environment, and
 * sin(theta): phi = 2 pi u, theta = pi v, d = (sin phi sin theta,
 * cos theta, -cos phi sin theta) in the map's frame. */
static REAL3 R_FN(light__env_uv_to_dir)(R_CTX const light *l, REAL u, REAL v, REAL *OUT_sin) {
  REAL phi = R_MUL_S(u, 2.0 * M_PI), theta = R_MUL_S(v, M_PI);
  LIGHT__EXACT(phi, 2.0 * M_PI * R_V(u));
  LIGHT__EXACT(theta, M_PI * R_V(v));
  REAL st = R_SIN(theta), ct = R_COS(theta);
  *OUT_sin = st;
  REAL3 d = R3_MAKE(R_MUL(R_SIN(phi), st), ct, R_NEG(R_MUL(R_COS(phi), st)));
  return R3_NORMALIZE(R_FN(light__mat_vec)(R_ARG(const double(*)[4]) l->to_world.m, d));
}

/* Importance sampling of the map's pixels from (u1, u2): (u, v) and its
 * density in (u, v); the point moves with the numbers inside its pixel
 * (the row chosen by u2, the column by u1: distrib2d_sample). OUT_cell:
 * the pixel's row and column. */
static void R_FN(light__env_sample)(R_CTX const light *l, REAL u1, REAL u2, REAL *OUT_u,
                                    REAL *OUT_v, double uv[2], double *OUT_pdf_uv,
                                    int64_t OUT_cell[2]) {
  const distrib2d *d2 = &l->env_dist;
  distrib2d_sample(d2, R_V(u1), R_V(u2), uv, OUT_pdf_uv);
#if R_DUAL
  double pdf_v;
  int row, col;
  distrib1d_sample_cont(&d2->marginal, u2.v, &pdf_v, &row);
  distrib1d_sample_cont(&d2->conditional[row], u1.v, NULL, &col);
  const distrib1d *mv = &d2->marginal, *cu = &d2->conditional[row];
  double wv = mv->cdf[row + 1] - mv->cdf[row], wu = cu->cdf[col + 1] - cu->cdf[col];
  *OUT_v = R_FN(light__remap)(R_ARG uv[1], wv > 0.0 ? 1.0 / (wv * mv->n) : 0.0, u2);
  *OUT_u = R_FN(light__remap)(R_ARG uv[0], wu > 0.0 ? 1.0 / (wu * cu->n) : 0.0, u1);
  OUT_cell[0] = row;
  OUT_cell[1] = col;
#else
  *OUT_u = uv[0];
  *OUT_v = uv[1];
  OUT_cell[0] = OUT_cell[1] = -1;
#endif
}

/* The direction towards the environment for (u1, u2) by the map's
 * importance sampling, its radiance and its solid-angle density: the
 * density in (u, v) over the Jacobian 2 pi^2 sin(theta). 0 where nothing
 * can be sampled (the poles, a black map). */
static int R_FN(light__env_dir)(R_CTX const light *l, REAL u1, REAL u2, REAL3 *OUT_w,
                                rgb *OUT_le, REAL *OUT_pdf, int64_t cell[2]) {
  REAL uu, vv, st;
  double uv[2], pdf_uv;
  R_FN(light__env_sample)(R_ARG l, u1, u2, &uu, &vv, uv, &pdf_uv, cell);
  *OUT_w = R_FN(light__env_uv_to_dir)(R_ARG l, uu, vv, &st);
  if (!(R_V(st) > 0.0) || !(pdf_uv > 0.0)) return 0;
  *OUT_le = light__env_eval_uv(l, uv[0], uv[1]);
  *OUT_pdf = R_S_DIV(pdf_uv, R_MUL_S(st, 2.0 * M_PI * M_PI));
  LIGHT__EXACT(*OUT_pdf, pdf_uv / (2.0 * M_PI * M_PI * R_V(st)));
  return 1;
}

/* ---- Direct sampling from a receiver ----------------------------------------- */

int R_FN(light_sample_li)(R_CTX const light *l, const struct scene *s, REAL3 ref, REAL u1,
                          REAL u2, R_FN(light_li_sample) *out) {
#if R_DUAL
  out->delta = 0;
  out->n = v3(0.0, 0.0, 0.0);
  int64_t *cell = out->cell;
#else
  memset(out, 0, sizeof *out);
  int64_t cell[2];
#endif
  cell[0] = cell[1] = -1;
  out->tri = -1;
  switch (l->type) {
  case LIGHT_AREA: {
    /* A point by area; its density 1/A in solid angle: d^2 / (A cos_l). */
    REAL3 p;
    vec3 n;
    out->tri = R_FN(light__area_point)(R_ARG l, s, u1, u2, &p, &n);
    REAL3 d = R3_SUB(p, ref);
    REAL dist2 = R3_LEN2(d);
    if (!(R_V(dist2) > 0.0)) return 0;
    REAL dist = R_SQRT(dist2);
    REAL3 wi = R3_SCALE(d, R_INV(dist));
    REAL cos_l = R_NEG(R3_DOT_C(n, wi));
    if (!(R_V(cos_l) > 0.0)) return 0; /* ref is behind the emitting side */
    out->wi = wi;
    out->dist = R_V(dist);
    out->p = R3_V(p);
#if R_DUAL
    out->pd = p;
#endif
    out->n = n;
    out->li = RRGB_CONST(l->value);
    out->pdf = R_DIV(dist2, R_MUL_S(cos_l, l->area));
    LIGHT__EXACT(out->pdf, R_V(dist2) / (R_V(cos_l) * l->area));
    out->delta = 0;
    return isfinite(R_V(out->pdf)) && R_V(out->pdf) > 0.0;
  }
  case LIGHT_POINT:
  case LIGHT_SPOT: {
    REAL3 d = R_FN(light__csub)(R_ARG l->pos, ref);
    REAL dist2 = R3_LEN2(d);
    if (!(R_V(dist2) > 0.0)) return 0;
    REAL dist = R_SQRT(dist2);
    REAL3 wi = R3_SCALE(d, R_INV(dist));
    REAL falloff = R_C(1.0);
    if (l->type == LIGHT_SPOT) {
      falloff = R_FN(light__spot_falloff)(R_ARG l, R_NEG(R3_DOT_C(l->frm.n, wi)));
      if (!(R_V(falloff) > 0.0)) return 0;
    }
    REAL sc = R_DIV(falloff, dist2);
    LIGHT__EXACT(sc, R_V(falloff) / R_V(dist2));
    out->wi = wi;
    out->dist = R_V(dist);
    out->p = l->pos;
    out->li = R_FN(light__rgb_cscale)(R_ARG l->value, sc);
    out->pdf = R_C(1.0);
    out->delta = 1;
    break;
  }
  case LIGHT_DIRECTIONAL:
    out->wi = R3_CONST(-l->frm.n.x, -l->frm.n.y, -l->frm.n.z);
    out->dist = INFINITY;
    out->p = v3_fma(R3_V(ref), R3_V(out->wi), 2.0 * s->radius);
    out->li = RRGB_CONST(l->value);
    out->pdf = R_C(1.0);
    out->delta = 1;
    break;
  case LIGHT_CONSTANT:
    /* Uniform on the sphere: z = 1 - 2 u1, phi = 2 pi u2. */
    out->wi = R_FN(light__z_phi)(R_ARG R_S_SUB(1.0, R_MUL_S(u1, 2.0)), u2);
    out->dist = INFINITY;
    out->p = v3_fma(R3_V(ref), R3_V(out->wi), 2.0 * s->radius);
    out->li = RRGB_CONST(l->value);
    out->pdf = R_C(1.0 / (4.0 * M_PI));
    out->delta = 0;
    break;
  case LIGHT_ENVMAP: {
    /* (u, v) in proportion to luminance * sin(theta), mapped to the sphere. */
    rgb le;
    if (!R_FN(light__env_dir)(R_ARG l, u1, u2, &out->wi, &le, &out->pdf, cell)) return 0;
    out->dist = INFINITY;
    out->p = v3_fma(R3_V(ref), R3_V(out->wi), 2.0 * s->radius);
    out->li = RRGB_CONST(le);
    out->delta = 0;
    if (!isfinite(R_V(out->pdf))) return 0;
    break;
  }
  default:
    return 0;
  }
#if R_DUAL
  out->pd = R3_CONST(out->p.x, out->p.y, out->p.z);
#endif
  return 1;
}

REAL R_FN(light_pdf_li)(R_CTX const light *l, const struct scene *s, REAL3 ref,
                                        REAL3 wi, REAL3 p, vec3 n) {
  (void)s;
  switch (l->type) {
  case LIGHT_AREA: {
    /* (1/A) d^2 / cos_l, zero when wi reaches the back of the light. */
    REAL dist2 = R3_LEN2(R3_SUB(p, ref));
    REAL cos_l = R_NEG(R3_DOT_C(n, wi));
    if (!(R_V(cos_l) > 0.0) || !(R_V(dist2) > 0.0) || !(l->area > 0.0)) return R_C(0.0);
    REAL r = R_DIV(dist2, R_MUL_S(cos_l, l->area));
    LIGHT__EXACT(r, R_V(dist2) / (R_V(cos_l) * l->area));
    return r;
  }
  case LIGHT_CONSTANT:
    return R_C(1.0 / (4.0 * M_PI));
  case LIGHT_ENVMAP: {
    double u, v, sin_theta;
    if (!light__env_dir_to_uv(l, R3_V(wi), &u, &v, &sin_theta)) return R_C(0.0);
    double pdf = light__env_pdf_uv(l, u, v, sin_theta);
#if R_DUAL
    /* Inside one pixel the density is C / sin(theta): its tangent through
     * sin(theta) of wi. */
    if (!(pdf > 0.0)) return ad_const(A, pdf);
    adv3 d = adv3_normalize(A, R_FN(light__mat_vec)(A, (const double(*)[4])l->to_world.inv, wi));
    ad st = ad_safe_sqrt(A, ad_s_sub(A, 1.0, ad_sqr(A, ad_clamp(A, d.y, -1.0, 1.0))));
    ad r = ad_mul_s(A, ad_s_div(A, st.v, st), pdf);
    r.v = pdf;
    return r;
#else
    return pdf;
#endif
  }
  default: /* delta lights */
    return R_C(0.0);
  }
}

/* ---- Emission ------------------------------------------------------------------ */

int R_FN(light_sample_le)(R_CTX const light *l, const struct scene *s, REAL u1, REAL u2, REAL u3,
                          REAL u4, R_FN(light_le_sample) *out) {
#if R_DUAL
  out->n = v3(0.0, 0.0, 0.0);
  out->delta_pos = out->delta_dir = 0;
  int64_t *cell = out->cell;
#else
  memset(out, 0, sizeof *out);
  int64_t cell[2];
#endif
  cell[0] = cell[1] = -1;
  out->tri = -1;
  double disk_pdf = light_disk_pdf(s);
  switch (l->type) {
  case LIGHT_AREA: {
    /* Position by area (u1, u2), direction cosine-weighted (u3, u4). */
    out->tri = R_FN(light__area_point)(R_ARG l, s, u1, u2, &out->p, &out->n);
    REAL x, y;
    R_FN(light__concentric)(R_ARG u3, u4, &x, &y);
    REAL z = R_SAFE_SQRT(R_SUB(R_S_SUB(1.0, R_SQR(x)), R_SQR(y)));
    frame f = frame_from_z(out->n);
    out->dir = R3_NORMALIZE(R_FN(light__to_world_c)(R_ARG & f, R3_MAKE(x, y, z)));
    out->le = RRGB_CONST(l->value);
    out->pdf_pos = 1.0 / l->area;
    out->pdf_dir = R_C(0.0);
    if (!(R_V(z) > 0.0)) return 0;
    out->pdf_dir = R_DIV_S(z, M_PI);
    LIGHT__EXACT(out->pdf_dir, R_V(z) / M_PI);
    return 1;
  }
  case LIGHT_POINT:
    out->p = R3_CONST(l->pos.x, l->pos.y, l->pos.z);
    out->dir = R_FN(light__z_phi)(R_ARG R_S_SUB(1.0, R_MUL_S(u3, 2.0)), u4);
    out->le = RRGB_CONST(l->value);
    out->pdf_pos = 1.0;
    out->pdf_dir = R_C(1.0 / (4.0 * M_PI));
    out->delta_pos = 1;
    return 1;
  case LIGHT_SPOT: {
    /* Uniform in the cone cos theta >= cos_cutoff, times the falloff. */
    REAL3 local =
        R_FN(light__z_phi)(R_ARG R_S_SUB(1.0, R_MUL_S(u3, 1.0 - l->cos_cutoff)), u4);
    out->p = R3_CONST(l->pos.x, l->pos.y, l->pos.z);
    out->dir = R3_NORMALIZE(R_FN(light__to_world_c)(R_ARG & l->frm, local));
    out->le = R_FN(light__rgb_cscale)(R_ARG l->value, R_FN(light__spot_falloff)(R_ARG l, local.z));
    out->pdf_pos = 1.0;
    out->pdf_dir = R_C(1.0 / (2.0 * M_PI * (1.0 - l->cos_cutoff)));
    out->delta_pos = 1;
    return !RRGB_IS_BLACK(out->le);
  }
  case LIGHT_DIRECTIONAL:
    out->dir = R3_CONST(l->frm.n.x, l->frm.n.y, l->frm.n.z);
    out->p = R_FN(light__disk_point)(R_ARG s, out->dir, u1, u2);
    out->le = RRGB_CONST(l->value);
    out->pdf_pos = disk_pdf;
    out->pdf_dir = R_C(1.0);
    out->delta_dir = 1;
    break;
  case LIGHT_CONSTANT:
    /* Travel direction uniform (u3, u4); radiance arrives from -dir. */
    out->dir = R_FN(light__z_phi)(R_ARG R_S_SUB(1.0, R_MUL_S(u3, 2.0)), u4);
    out->p = R_FN(light__disk_point)(R_ARG s, out->dir, u1, u2);
    out->le = RRGB_CONST(l->value);
    out->pdf_pos = disk_pdf;
    out->pdf_dir = R_C(1.0 / (4.0 * M_PI));
    break;
  case LIGHT_ENVMAP: {
    /* The direction towards the environment by (u3, u4); the ray travels
     * the opposite way. */
    REAL3 w_env;
    rgb le;
    if (!R_FN(light__env_dir)(R_ARG l, u3, u4, &w_env, &le, &out->pdf_dir, cell)) return 0;
    out->dir = R3_NEG(w_env);
    out->p = R_FN(light__disk_point)(R_ARG s, out->dir, u1, u2);
    out->le = RRGB_CONST(le);
    out->pdf_pos = disk_pdf;
    if (!isfinite(R_V(out->pdf_dir))) return 0;
    break;
  }
  default:
    return 0;
  }
#if !R_DUAL
  out->n = out->dir; /* the disk's normal (the plain record's convention) */
#endif
  return 1;
}

/* The solid-angle density of light_sample_le emitting from p (normal n)
 * along the unit travel direction dir (light_pdf_le's pdf_dir). */
REAL R_FN(light_pdf_le_dir)(R_CTX const light *l, const struct scene *s, REAL3 p,
                                            vec3 n, REAL3 dir) {
  switch (l->type) {
  case LIGHT_AREA: {
    REAL cs = R3_DOT_C(n, dir);
    if (!(R_V(cs) > 0.0)) return R_C(0.0);
    REAL r = R_DIV_S(cs, M_PI);
    LIGHT__EXACT(r, R_V(cs) / M_PI);
    return r;
  }
  case LIGHT_POINT:
  case LIGHT_CONSTANT:
    return R_C(1.0 / (4.0 * M_PI));
  case LIGHT_SPOT:
    return R_C(v3_dot(R3_V(dir), l->frm.n) >= l->cos_cutoff
                   ? 1.0 / (2.0 * M_PI * (1.0 - l->cos_cutoff))
                   : 0.0);
  case LIGHT_DIRECTIONAL:
    return R_C(1.0);
  case LIGHT_ENVMAP:
    return R_FN(light_pdf_li)(R_ARG l, s, p, R3_NEG(dir), p, n);
  }
  return R_C(0.0);
}
