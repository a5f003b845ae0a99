// Lane count for the gather-heavy per-pixel kernels (G-buffer and RSM resolve, RSM gather): their
// cost is per-lane loads of scattered records and many long-lived values.
#pragma once
#include "cl/runtime.h"

namespace gi::cl {

// GI_VW for those kernels: on CPU devices the native float vector width, 16 with AVX-512 and 8
// with AVX2, where 16-wide code spills its 16 ymm registers (measured on an AVX2 EPYC: the
// G-buffer resolve took 1.7x the CPU time at 16 lanes); 1 on GPUs. $GI_VECTOR_WIDTH overrides it
// as it overrides Context::vectorWidth(). Results do not depend on the lane count.
int gatherVectorWidth(const Context& ctx);

// `defines` plus GI_VW = gatherVectorWidth(ctx), for Context::buildProgram (a GI_VW in the
// defines replaces the context's default width).
Defines withGatherWidth(const Context& ctx, Defines defines = {});

}  // namespace gi::cl
