/*
 * model_twice.h: compiles a model file's body (the `#else` part of the
 * file MODEL_BODY names: a BSDF of bsdf/models/, a phase function of
 * media/models/) twice, in doubles and then in duals (render/real.h), so
 * that a model is one file. With the vocabulary, each pass defines what
 * the BSDF bodies share per form: BSDF_R_REV(p) and BSDF_R_SET_REV(out,
 * rev), the reverse density that only the plain samplers compute in the
 * same pass (the dual sample record has none). Included once by a model
 * file, after its includes; not a header.
 */
#define R_DUAL 0
#include "render/real.h"
#define BSDF_R_REV(p) (p)
#define BSDF_R_SET_REV(out, rev) ((out)->pdf_rev = (rev), (out)->has_pdf_rev = 1)
#include MODEL_BODY
#undef BSDF_R_REV
#undef BSDF_R_SET_REV
#undef R_DUAL

#define R_DUAL 1
#include "render/real.h"
#define BSDF_R_REV(p) NULL
#define BSDF_R_SET_REV(out, rev) (void)(rev)
#include MODEL_BODY
#undef BSDF_R_REV
#undef BSDF_R_SET_REV
#undef R_DUAL
