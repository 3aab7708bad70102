/*
 * bsdf_model_file.h: what a BSDF model file (models/NAME.c) includes: the
 * record (bsdf_model.h), the helpers the models share in both forms
 * (bsdf_internal.h, bsdf_ad_internal.h), the microfacet distributions and
 * the property readers (render/plugin.h). Not API.
 */
#ifndef LMC_RENDER_BSDF_MODEL_FILE_H
#define LMC_RENDER_BSDF_MODEL_FILE_H

#include <math.h>
#include <stddef.h>

#include "render/bsdf/bsdf_ad_internal.h"
#include "render/bsdf/bsdf_internal.h"
#include "render/bsdf/bsdf_model.h"
#include "render/bsdf/microfacet.h"
#include "render/bsdf/microfacet_ad.h"
#include "render/frame.h"
#include "render/plugin.h"
#include "render/warp.h"

#endif
