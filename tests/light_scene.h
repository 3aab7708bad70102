/*
 * light_scene.h: the scene of one light of each kind that test_light.c and
 * test_light_invert.c share (cmocka group setup and teardown, g_scene).
 */
#ifndef LMC_TESTS_LIGHT_SCENE_H
#define LMC_TESTS_LIGHT_SCENE_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/lights/light.h"
#include "render/scene.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ---------------------------------------------------------------------------
 * The test scene: a unit square [-0.5, 0.5]^2 at height H, split into four
 * triangles of areas 0.1, 0.15, 0.4, 0.35 around the inner vertex
 * (0.2, -0.3); wound to face +z, flip_normals makes it emit downwards.
 * The lights are added in this order.
 */
#define H 1.0
enum { L_AREA, L_POINT, L_SPOT, L_DIR, L_CONST, L_ENV, L_ENV_ID, L_ENV_ONE, N_LIGHTS };
#define ENV_W 32
#define ENV_H 16

static const rgb area_L = {2.0, 1.0, 0.5};
static const rgb point_I = {3.0, 2.0, 1.0};
static const rgb spot_I = {5.0, 4.0, 3.0};
static const rgb dir_E = {1.5, 1.0, 0.5};
static const rgb const_L = {0.5, 1.0, 2.0};
#define SPOT_CUTOFF (30.0 * M_PI / 180.0)
#define SPOT_BEAM (20.0 * M_PI / 180.0)

static scene *g_scene;

/* Envmap pixels: a smooth background, a bright spot and a dim region. */
static inline void env_fill_test(lmc_image *img) {
  for (int y = 0; y < ENV_H; y++)
    for (int x = 0; x < ENV_W; x++) {
      float *p = img->data + 3 * (y * ENV_W + x);
      p[0] = (float)(0.2 + 0.3 * x / ENV_W);
      p[1] = (float)(0.3 + 0.2 * y / ENV_H);
      p[2] = 0.25f;
      if (x == 20 && y == 5) p[0] = p[1] = p[2] = 6.0f;
      if (x >= 4 && x < 8 && y >= 10) p[0] = p[1] = p[2] = 0.0f;
    }
}

/* Envmap whose red channel encodes the pixel: r = x + 100 y. */
static inline void env_fill_index(lmc_image *img) {
  for (int y = 0; y < ENV_H; y++)
    for (int x = 0; x < ENV_W; x++) {
      float *p = img->data + 3 * (y * ENV_W + x);
      p[0] = (float)(x + 100 * y);
      p[1] = p[2] = 1.0f;
    }
}

static inline int setup(void **state) {
  (void)state;
  lmc_error err;
  scene *s;
  if (scene_create(&s, &err) != LMC_OK) return -1;

  /* The square's mesh. */
  mesh m;
  memset(&m, 0, sizeof m);
  if (mesh_alloc(&m, 5, 4, 0, 0, &err) != LMC_OK) return -1;
  const float pos[15] = {-0.5f, -0.5f, (float)H, 0.5f, -0.5f, (float)H, 0.5f, 0.5f, (float)H,
                         -0.5f, 0.5f,  (float)H, 0.2f, -0.3f, (float)H};
  const uint32_t idx[12] = {4, 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0};
  memcpy(m.p, pos, sizeof pos);
  memcpy(m.idx, idx, sizeof idx);
  m.flip_normals = 1;
  m.light = L_AREA;
  m.bsdf = 0;
  snprintf(m.name, sizeof m.name, "square");
  bsdf b;
  memset(&b, 0, sizeof b);
  if (scene_add_bsdf(s, &b, &err) < 0) return -1;
  int mi = scene_add_mesh(s, &m, &err);
  if (mi < 0) return -1;

  light l;
  /* Area. */
  memset(&l, 0, sizeof l);
  l.type = LIGHT_AREA;
  l.mesh = mi;
  l.value = area_L;
  if (scene_add_light(s, &l, &err) != L_AREA) return -1;
  /* Point. */
  memset(&l, 0, sizeof l);
  l.type = LIGHT_POINT;
  l.pos = v3(0.3, -0.2, 0.4);
  l.value = point_I;
  if (scene_add_light(s, &l, &err) != L_POINT) return -1;
  /* Spot, tilted axis. */
  memset(&l, 0, sizeof l);
  l.type = LIGHT_SPOT;
  l.pos = v3(1.0, 2.0, 3.0);
  l.frm = frame_from_z(v3_normalize(v3(1.0, -1.0, 2.0)));
  l.cutoff = SPOT_CUTOFF;
  l.beam_width = SPOT_BEAM;
  l.value = spot_I;
  if (scene_add_light(s, &l, &err) != L_SPOT) return -1;
  /* Directional (direction deliberately not normalised). */
  memset(&l, 0, sizeof l);
  l.type = LIGHT_DIRECTIONAL;
  l.frm.n = v3(0.3, -1.0, 0.2);
  l.value = dir_E;
  if (scene_add_light(s, &l, &err) != L_DIR) return -1;
  /* Constant. */
  memset(&l, 0, sizeof l);
  l.type = LIGHT_CONSTANT;
  l.value = const_L;
  if (scene_add_light(s, &l, &err) != L_CONST) return -1;
  /* Envmaps: rotated test map, identity index map, single-pixel map. */
  for (int k = 0; k < 3; k++) {
    memset(&l, 0, sizeof l);
    l.type = LIGHT_ENVMAP;
    l.scale = k == 0 ? 1.5 : 1.0;
    l.to_world = k == 0 ? xform_rotate(v3(0.3, 1.0, 0.2), 40.0) : xform_identity();
    l.image.width = ENV_W;
    l.image.height = ENV_H;
    l.image.channels = 3;
    l.image.data = calloc(3 * ENV_W * ENV_H, sizeof(float));
    if (!l.image.data) return -1;
    if (k == 0) env_fill_test(&l.image);
    if (k == 1) env_fill_index(&l.image);
    if (k == 2) {
      float *p = l.image.data + 3 * (3 * ENV_W + 11); /* pixel (11, 3) */
      p[0] = p[1] = p[2] = 1.0f;
    }
    if (scene_add_light(s, &l, &err) != L_ENV + k) return -1;
  }
  if (scene_finalize(s, &err) != LMC_OK) {
    char buf[1200];
    lmc_error_format(&err, buf, sizeof buf);
    fprintf(stderr, "scene_finalize: %s\n", buf);
    return -1;
  }
  g_scene = s;
  return 0;
}

static inline int teardown(void **state) {
  (void)state;
  scene_destroy(g_scene);
  return 0;
}

static inline const light *L(int i) { return &g_scene->lights[i]; }

#endif
