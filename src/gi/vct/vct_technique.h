#pragma once
#include "gi/technique.h"

namespace gi {
TechniqueInfo vctTechniqueInfo();

// vct_diffuse and vct_specular trace a tile of `lanes` (GI_VW) pixels per work-item, this many
// wide and lanes / width high (VCT_TILE_W in kernels/gi/vct/cone_trace.cl).
inline int vctLaneTileWidth(int lanes) { return lanes >= 8 ? 4 : 1; }
}
