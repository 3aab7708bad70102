/*
 * phase_model_file.h: what a phase function's model file (media/models/)
 * includes: the record (phase.h), the dual numbers, the frames and warps.
 * Not API.
 */
#ifndef LMC_RENDER_PHASE_MODEL_FILE_H
#define LMC_RENDER_PHASE_MODEL_FILE_H

#include <math.h>

#include "ad/dual.h"
#include "ad/dual_math.h"
#include "ad/dual_vec3.h"
#include "render/frame.h"
#include "render/media/phase.h"
#include "render/plugin.h"
#include "render/warp.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#endif
