/*
 * manifold.h: the manifold walk of manifold exploration (Jakob and
 * Marschner 2012, "Manifold Exploration: A Markov Chain Monte Carlo
 * Technique for Rendering Scenes with Difficult Specular Transport",
 * section 4 and its appendix; Jakob's thesis, chapter 4): a specular (or
 * glossy-treated-as-specular) chain of a light path held on its constraint
 * manifold while its end moves, and the generalized geometry term of the
 * chain. MEMLT's manifold perturbation and HSLT build on it.
 *
 * The chain. x_0 is a fixed start (mf_start): a point (a point light, a
 * pinhole, or a surface point whose normal n0 enters the geometry term's
 * cosine) or a direction (a light at infinity: an environment map,
 * sunsky, a directional light). A direction start is x_0 at infinity: d
 * is the unit direction of the first segment, the way it travels from x_0
 * to x_1 (for a light, the way its light travels: pathspace.h's v.dir of
 * an `inf` endpoint), so that wi at x_1 is -d; x_1 may lie anywhere on
 * the line through it along d. x_1 .. x_k (1 <= k <= MF_MAX_CHAIN) are specular vertices, each a
 * reflection or a refraction chosen by the caller; x_{k+1} is the end, on
 * a non-specular surface. A surface vertex is (mesh, triangle,
 * barycentrics (b1, b2)); it moves with (b1, b2) on the plane of its
 * triangle: p = b0 p0 + b1 p1 + b2 p2 (b0 = 1 - b1 - b2) and its shading
 * normal ns = normalize(b0 n0 + b1 n1 + b2 n2) (the mesh's vertex normals
 * as mesh_hit_normals interpolates them; the winding normal where the mesh
 * has none or sets face_normals). Bump maps and anisotropic frames
 * (bsdf_needs_tangents) are not followed: the frame is frame_from_z(ns).
 *
 * The constraints. With wi = normalize(x_{i-1} - x_i) (at x_1 after a
 * direction start, wi = -d) and wo = normalize(x_{i+1} - x_i) (directions
 * away from the surface), the
 * generalized half vector of vertex i is
 *   h_i = normalize(wi + eta_r wo), turned so that h_i . ns >= 0,
 * where eta_r = 1 for a reflection and, for a refraction, the ratio of the
 * index on wo's side to the index on wi's side: eta_r = eta when wi . ns > 0
 * (wi outside, the side ns points to) and 1 / eta otherwise, eta = intIOR /
 * extIOR of the surface (bsdf.eta). (Multiplying by the index on wi's
 * side, this is Jakob's eta_i wi + eta_o wo.) Its constraint is
 *   c_i = (h_i . s_i, h_i . t_i) - target_i,
 * (s_i, t_i, ns_i) = frame_from_z(ns_i), the shading frame: the projection
 * of the half vector on the tangent plane of the SHADING normal. target_i
 * is (0, 0) for a smooth surface; a glossy vertex treated as specular keeps
 * its current value (mf_half_vector) as its target, as HSLT needs.
 *
 * The Jacobian. c_i depends on the barycentrics of x_{i-1}, x_i and
 * x_{i+1} only, so dc / db over x_1 .. x_k is block tridiagonal with 2 x 2
 * blocks A_i = dc_i / db_{i-1} (zero for i = 1: x_0 is fixed, and a
 * direction start's c_1 does not depend on any position of x_0), B_i =
 * dc_i / db_i and C_i = dc_i / db_{i+1} (C_k: the end's). lmc's forward
 * mode AD (src/ad) computes them (mf_jacobian); mf_solve solves
 *   A_i d_{i-1} + B_i d_i + C_i d_{i+1} = r_i,  i = 1 .. k,
 * d_0 = 0, d_{k+1} given, by block Gaussian elimination (the block Thomas
 * algorithm, O(k)).
 *
 * The walk (mf_walk). Given a chain on its manifold and a target point on
 * the end's surface, each Newton step asks for the change d_{k+1} of the
 * end's barycentrics that moves it (on the plane of its triangle) onto the
 * target, solves for d_1 (the change of x_1, that is, of the first
 * segment's direction), moves x_1 by beta d_1 on its triangle's plane and
 * PROJECTS back onto the surfaces: a ray from x_0 through the moved x_1
 * (after a direction start, the ray along d through the moved x_1, from
 * outside the scene's bounding sphere: mf_start_ray), followed through every chain vertex by specular reflection or refraction
 * about the actual shading normal of each new hit (about the microfacet
 * normal whose projection is the vertex's target, for a non-zero target),
 * to a new end (mf_trace). A step whose projection fails or does not bring
 * the end nearer halves beta and retries from the same chain; a step that
 * does is taken and beta doubles again (at most 1), as Jakob does. The
 * walk succeeds when the end is within tol of the target. It fails, with
 * its status, when a projection leaves the manifold and halving cannot
 * help (beta below min_beta), or after max_traces projections.
 *
 * Leaving the manifold (mf_trace's statuses): a ray that misses
 * (MF_EMISS); a vertex on another mesh (MF_ESHAPE; another triangle of the
 * same mesh is fine: a smooth mesh is one surface; after a direction
 * start, x_1 is the first hit of the ray from outside the scene, so a
 * ray that meets another mesh first fails so); total internal
 * reflection at a refraction vertex (MF_ETIR); a direction on the wrong
 * side of a vertex (a reflection through its surface or a refraction that
 * does not cross it, by the shading or the geometric normal: MF_ESIDE).
 *
 * The generalized geometry term (mf_geometry_term). For the chain
 * x_0 .. x_{k+1}, the density a connection through it needs, defined as
 * the ordinary G when k = 0:
 *   G(x_0 <-> x_{k+1}) = |cos theta_0| dw_0 / dA_{k+1}
 *     = G(x_0, x_1) |det(dx_1 / dx_{k+1})|
 *     = G(x_0, x_1) / |det(dx_{k+1} / dx_1)|,
 *   G(x_0, x_1) = |cos theta_0| |cos theta_1| / |x_1 - x_0|^2,
 * with w_0 the direction out of x_0 (solid angle), A the area measure on
 * the surfaces (each triangle's own area), cos theta_0 = n0 . w_0 (1 when
 * n0 is zero: a point) and cos theta_1 by the GEOMETRIC normal of x_1's
 * triangle (the one the area measure and the ray's foreshortening see).
 * dx_1 / dx_{k+1} is the 2 x 2 block of the inverse constraint Jacobian
 * that the walk uses (x_0 held fixed): in barycentrics M = d b_1 / d b_{k+1}
 * = the solution d_1 of mf_solve for d_{k+1} = e_1, e_2 and r = 0, and in
 * area |det(dx_1 / dx_{k+1})| = |det M| J_1 / J_{k+1}, J = |e1 x e2| the
 * area of a unit of barycentrics (twice the triangle's area). This is
 * Mitsuba's SpecularManifold::G (the area of x_1's tangent map times
 * G(x_0, x_1)), with lmc's geometric-normal cosine at x_1 (pathspace.h).
 *
 * After a direction start, x_0's free measure is not a solid angle at a
 * point but the area A_perp of the plane perpendicular to d that the
 * parallel rays cross (d fixed: a light at infinity has solid-angle
 * measure in its direction, and the rays of one direction are told apart
 * by where they cross that plane). The generalized geometry term is the
 * Jacobian of that area per unit area at the end:
 *   G(d <-> x_{k+1}) = dA_perp / dA_{k+1}
 *     = (dA_perp / dA_1) (dA_1 / dA_{k+1})
 *     = |cos theta_1| |det(dx_1 / dx_{k+1})|,
 * cos theta_1 = d . ng_1 (a patch dA_1 of x_1's triangle casts |cos
 * theta_1| dA_1 on the perpendicular plane), dx_1 / dx_{k+1} the same
 * block as above with d held fixed (c_1 does not depend on x_0). For
 * k = 0 it is |cos theta_1|, pathspace.h's G of an edge to infinity; the
 * light's radiance times G dA_{k+1} dsigma(d) is the power the chain
 * carries from the solid angle dsigma(d) onto dA_{k+1}.
 *
 * Memory and threads: every function works on caller-owned structs and
 * the stack (the AD arena of one constraint, 16 KB); nothing allocates.
 * The scene is read only. Not supported yet: a moving x_0 (a free start;
 * x_0 is pinned, as a position or as a direction), media vertices,
 * bump-mapped or anisotropic shading frames, thindielectric; see
 * docs/manifold.md.
 *
 * Chains of path-space paths (mf_chain_from_path, mf_chain_to_path). A
 * ps_path's vertices x_a .. x_b (a < b) make a chain when x_a and x_b are
 * endpoints or non-specular surfaces and every vertex between them is a
 * specular surface: ps_vertex.delta set, or a glossy vertex (ps_glossy)
 * when the caller treats those as specular (MF_PATH_GLOSSY: the target is
 * its current half vector, HSLT's case). The chain runs from x_a to x_b,
 * or from x_b to x_a (MF_PATH_FROM_B); an endpoint at infinity (`inf`) is
 * always its start, a direction start with d = v.dir. Each chain vertex
 * reads (mesh, triangle, barycentrics) from its record's hit; its kind is
 * the geometry's: a reflection when the directions to its two path
 * neighbours (ps_dir) lie on the same side of its geometric normal, else
 * a refraction, whose eta is its BSDF's (dielectric, roughdielectric).
 * The start: the pinhole is a point whose n0 is the optical axis
 * (pathspace.h's cosine there), a point or spot light a point (n0 = 0),
 * an area light endpoint or a surface a point with its geometric normal.
 * The end is a surface record (type BDPT_VERTEX_SURFACE).
 */
#ifndef LMC_PATH_MANIFOLD_H
#define LMC_PATH_MANIFOLD_H

#include <stdint.h>

#include "lmc/path/pathspace.h"
#include "render/scene.h"

#define MF_MAX_CHAIN 16 /* largest number k of specular vertices */

/* The status table: name, value, description. */
#define MF_STATUS_MAP(X)                                                      \
  X(OK, 0, "success")                                                         \
  X(EINVAL, -1, "invalid chain")                                              \
  X(EMISS, -2, "a ray of the projection hit nothing")                         \
  X(ESHAPE, -3, "a vertex landed on another shape")                           \
  X(ETIR, -4, "total internal reflection at a refraction vertex")             \
  X(ESIDE, -5, "a direction on the wrong side of a vertex's surface")         \
  X(EBSDF, -6, "a refraction vertex on a surface that does not refract")     \
  X(ESINGULAR, -7, "the constraint Jacobian is singular")                     \
  X(ENOCONV, -8, "the walk did not reach its target")

typedef enum mf_status {
#define MF__STATUS_ENUM(name, value, text) MF_##name = value,
  MF_STATUS_MAP(MF__STATUS_ENUM)
#undef MF__STATUS_ENUM
} mf_status;

/* Text for a status ("total internal reflection at a refraction vertex"). */
const char *mf_status_str(int status);

/* What a chain vertex does to the ray. */
typedef enum mf_kind { MF_REFLECT = 0, MF_REFRACT = 1 } mf_kind;

/* A surface vertex. (mesh, prim, b1, b2) is the state; p, ns and ng are
 * derived from it (mf_vertex_set, mf_trace) for the caller's use: every
 * computation below recomputes them from the barycentrics. */
typedef struct mf_vertex {
  int mesh;          /* index into scene->meshes (mf_trace's prototype: -1 = any) */
  int64_t prim;      /* triangle of the mesh */
  double b1, b2;     /* barycentrics on it */
  mf_kind kind;      /* chain vertices: reflection or refraction (the end: unused) */
  double eta;        /* refraction: intIOR / extIOR of the surface (mf_trace fills it) */
  double target[2];  /* the half vector's target (0, 0: smooth; chain vertices) */
  vec3 p;            /* derived: position */
  vec3 ns;           /* derived: unit shading normal */
  vec3 ng;           /* derived: unit geometric normal, on ns's side (mesh_hit_normals) */
} mf_vertex;

/* What the fixed start x_0 is. */
typedef enum mf_start {
  MF_START_POINT = 0,    /* a point x0 (normal n0) */
  MF_START_DIRECTION = 1 /* a point at infinity: the first segment runs along d */
} mf_start;

/* A chain x_0 .. x_{k+1}: v[i] is x_i for i = 1 .. k + 1 (v[0] unused). */
typedef struct mf_chain {
  int k;                        /* specular vertices, 1 .. MF_MAX_CHAIN */
  mf_start start;               /* x_0 a point (x0, n0) or a direction (d) */
  vec3 x0;                      /* MF_START_POINT: the fixed start */
  vec3 n0;                      /* its unit normal, or (0, 0, 0) for a point (cos theta_0 = 1) */
  vec3 d;                       /* MF_START_DIRECTION: unit direction from x_0 towards x_1
                                   (the light's travel; wi at x_1 is -d) */
  mf_vertex v[MF_MAX_CHAIN + 2]; /* x_1 .. x_k specular, x_{k+1} the end */
} mf_chain;

/* The constraints and their Jacobian blocks (row: the constraint's s or t
 * component; column: b1 or b2 of the vertex), indexed by i = 1 .. k. */
typedef struct mf_jac {
  int k;
  double c[MF_MAX_CHAIN + 1][2];       /* c_i (half vector minus target) */
  double A[MF_MAX_CHAIN + 1][2][2];    /* dc_i / db_{i-1} (A_1 = 0) */
  double B[MF_MAX_CHAIN + 1][2][2];    /* dc_i / db_i */
  double C[MF_MAX_CHAIN + 1][2][2];    /* dc_i / db_{i+1} */
} mf_jac;

/* The walk's settings. */
typedef struct mf_options {
  double tol;      /* success: |end - target| <= tol (default 1e-7 scene->radius) */
  int max_traces;  /* projections (accepted or not) before MF_ENOCONV (default 64) */
  double min_beta; /* step size below which a failing step ends the walk (default 2^-20) */
  int off_start;   /* 1: the chain may start off its manifold (new targets): its first
                      successful projection is taken whatever its end's distance (default 0) */
} mf_options;

/* What a walk did. */
typedef struct mf_walk_info {
  int steps;        /* Newton steps taken (accepted projections) */
  int traces;       /* projections traced (taken and refused) */
  double dist;      /* final |end - target| */
  int last_fail;    /* status of the last refused projection (MF_OK: none) */
} mf_walk_info;

/* Default options for scene sc. */
void mf_options_default(const scene *sc, mf_options *OUT);

/* Sets v's state (mesh, prim, b1, b2) and its derived p, ns, ng; leaves
 * kind, eta and target alone. Returns MF_EINVAL for a bad mesh or triangle. */
int mf_vertex_set(const scene *sc, mf_vertex *v, int mi, int64_t prim, double b1, double b2);

/* The projected half vector of chain vertex i (1 .. k) before the target
 * is subtracted: (h_i . s_i, h_i . t_i). A glossy vertex treated as
 * specular takes it as its target. Plain arithmetic. */
int mf_half_vector(const scene *sc, const mf_chain *c, int i, double OUT[2]);

/* The same for a vertex v (its kind, eta and shading normal ns) and unit
 * directions wi, wo away from it: h = normalize(wi + eta_r wo) turned to
 * ns's side, projected on frame_from_z(ns). */
void mf_half_vector_dirs(const mf_vertex *v, vec3 wi, vec3 wo, double OUT[2]);
/* |det d(mf_half_vector_dirs) / d wo| per unit solid angle of wo, wi and
 * the vertex held: the density a direction leaving v about a held half
 * vector has per unit of the projected half vector's measure. */
double mf_half_vector_dir_jacobian(const mf_vertex *v, vec3 wi, vec3 wo);
/* The direction leaving chain vertex v (p, ns, ng, kind, eta, target)
 * reached along -wi (wi unit, away from v): reflected or refracted about ns,
 * or about the microfacet normal whose projection is v's target when it is
 * not zero; MF_ESIDE or MF_ETIR as mf_trace says. */
int mf_scatter(const mf_vertex *v, vec3 wi, vec3 *OUT_wo);

/* The constraint c_i (1 .. k): mf_half_vector minus target_i. Plain
 * arithmetic, written apart from the dual form (the tests compare them). */
int mf_constraint(const scene *sc, const mf_chain *c, int i, double OUT[2]);

/* Every constraint and its Jacobian blocks, by forward-mode AD: for each
 * i, the barycentrics of x_{i-1}, x_i, x_{i+1} are the six variables. */
int mf_jacobian(const scene *sc, const mf_chain *c, mf_jac *OUT);

/* Solves A_i d_{i-1} + B_i d_i + C_i d_{i+1} = r_i (i = 1 .. k) for
 * d_1 .. d_k, with d_0 = 0 and d_{k+1} = d_end. Vectors are flat pairs:
 * r_i = (r[2 i], r[2 i + 1]) (r may be NULL: zero), d_i likewise into
 * OUT_d (2 (k + 1) doubles; OUT_d[0], OUT_d[1] are set to 0). Block
 * Thomas. MF_ESINGULAR when a pivot block is singular. */
int mf_solve(const mf_jac *J, const double *r, const double d_end[2], double *OUT_d);

/* The ray of a chain's first segment that passes through the point x1:
 * from x0 along normalize(x1 - x0) for a point start; for a direction
 * start along d from *OUT_org = x1 - s d, s = (x1 - center) . d + 2
 * radius (scene->center, scene->radius: the origin lies outside the
 * bounding sphere, and x1 at distance s along the ray). *OUT_dir is unit.
 * Returns MF_EINVAL for a bad start (a direction that is not finite or
 * zero, x1 = x0). */
int mf_start_ray(const scene *sc, const mf_chain *c, vec3 x1, vec3 *OUT_org, vec3 *OUT_dir);

/* Traces a chain: from proto->x0 along the unit direction dir, through
 * proto->k specular vertices whose kinds and targets proto gives (and
 * their meshes, unless -1), to an end on any surface (on proto's end mesh
 * unless it is -1). Each vertex scatters about its new hit's shading
 * normal (its target's microfacet normal when the target is not zero);
 * a refraction vertex takes eta from its BSDF (dielectric or
 * roughdielectric, else MF_EBSDF). Writes the whole chain (x0, n0, kinds,
 * targets copied) to *OUT. A failing trace's status says why (above).
 * Point starts only (MF_EINVAL for a direction start: mf_trace_through). */
int mf_trace(const scene *sc, const mf_chain *proto, vec3 dir, mf_chain *OUT);

/* mf_trace along the ray of mf_start_ray through x1: for a point start
 * mf_trace towards x1; for a direction start the ray along d whose first
 * hit is x_1 (on proto's x_1 mesh unless -1: another mesh first is
 * MF_ESHAPE, nothing MF_EMISS). What mf_walk projects with. */
int mf_trace_through(const scene *sc, const mf_chain *proto, vec3 x1, mf_chain *OUT);

/* The manifold walk: moves chain c (on its manifold: as mf_trace made it;
 * under o->off_start it may be off it, its targets new) so that its end
 * reaches `target` (a point on the end's surface), x_0 fixed. On MF_OK, *OUT is the chain whose end is within o->tol of the
 * target; on failure *OUT is the last chain reached (on the manifold) and
 * the status says why. info may be NULL. OUT may be c. */
int mf_walk(const scene *sc, const mf_chain *c, vec3 target, const mf_options *o, mf_chain *OUT,
            mf_walk_info *info);

/* The generalized geometry term G(x_0 <-> x_{k+1}) of chain c (definition
 * above; after a direction start G(d <-> x_{k+1})) into *OUT_G.
 * MF_ESINGULAR when the chain's Jacobian is singular. */
int mf_geometry_term(const scene *sc, const mf_chain *c, double *OUT_G);

/* Flags of mf_chain_from_path and mf_chain_to_path. */
#define MF_PATH_GLOSSY 1u /* glossy inner vertices (ps_glossy) are specular, targets their half vectors */
#define MF_PATH_FROM_B 2u /* the chain starts at x_b (an endpoint at infinity is the start anyway) */
#define MF_PATH_ANY 4u    /* every inner vertex that is not delta (glossy or not, diffuse too) is a
                             chain vertex, its target its half vector (HSLT's whole-path chain) */

/* The chain of path p's vertices x_a .. x_b (above) into *OUT: x_0 the
 * start (x_a, or x_b under MF_PATH_FROM_B or when x_b is at infinity), the
 * vertices between as x_1 .. x_k in the chain's order, the other end as
 * x_{k+1}. The path's caches (ps_update: delta and inf flags) must be
 * current. MF_EINVAL when the vertices do not make a chain (an index out
 * of range, k = b - a - 1 outside 1 .. MF_MAX_CHAIN, an end that is
 * specular or (x_{k+1}) not a surface, an inner vertex that is neither
 * delta nor, under MF_PATH_GLOSSY, glossy (under MF_PATH_ANY, any inner
 * surface vertex qualifies), both ends at infinity);
 * MF_EBSDF for a chain vertex whose BSDF the chain cannot follow (a
 * refraction on a surface that is not a dielectric or roughdielectric
 * (thindielectric, a mask's pass-through), a bump-mapped or anisotropic
 * shading frame). Plain arithmetic; nothing traced. */
int mf_chain_from_path(const ps_context *ctx, const ps_path *p, int a, int b, unsigned flags,
                       mf_chain *OUT);

/* Whether path vertex j may be a chain vertex: delta, or glossy under
 * MF_PATH_GLOSSY, or any non-delta surface vertex under MF_PATH_ANY (else MF_EINVAL), on a BSDF the chain can follow (else
 * MF_EBSDF); its kind, a reflection or a refraction by the sides of the
 * geometric normal its path neighbours lie on, and a refraction's eta from
 * the BSDF, into *OUT_kind and *OUT_eta (left alone for a reflection). */
int mf_path_vertex(const ps_context *ctx, const ps_path *p, int j, unsigned flags,
                   mf_kind *OUT_kind, double *OUT_eta);

/* What mf_chain_from_path would return for the same arguments, without
 * reading the chain: its records' meshes and triangles are taken as valid,
 * and a glossy vertex whose half vector cannot be formed (which makes
 * mf_chain_from_path fail) is left to it. For forms checked at every step. */
int mf_path_chain_fits(const ps_context *ctx, const ps_path *p, int a, int b, unsigned flags);

/* The inverse: writes chain c's vertices x_1 .. x_{k+1} back into the
 * records of p's vertices x_a .. x_b they came from (the same a, b,
 * flags and path, so that the same vertex order follows). A record whose
 * (mesh, triangle, barycentrics) are the chain vertex's is left as it is,
 * bit for bit (so a chain written back unchanged leaves p unchanged);
 * any other gets what scene_intersect makes of a ray that hits that
 * point: hit (t, mesh, prim, b1, b2, p, ng, sh, tu, tv, bsdf, light), p =
 * hit.p, n = hit.ng, light = hit.light, and wo the unit direction to the
 * path neighbour its old wo pointed to (its own walk's side), t the
 * distance to it (from mf_start_ray's origin for a neighbour at
 * infinity). Type, delta flag, the walk's throughput and densities are
 * left: the caller re-evaluates the path (ps_update, ps_eval). MF_EINVAL
 * when c does not fit p's x_a .. x_b (k, a record that is not a surface);
 * p is then untouched. */
int mf_chain_to_path(const scene *sc, const mf_chain *c, int a, int b, unsigned flags,
                     ps_path *p);

#endif
