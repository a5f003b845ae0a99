// The `splat` technique (splatting indirect illumination as tiled VPL culling), for the registry.
// docs/techniques/splat.md.
#pragma once
#include "gi/technique.h"

namespace gi {
TechniqueInfo splatTechniqueInfo();
}  // namespace gi
