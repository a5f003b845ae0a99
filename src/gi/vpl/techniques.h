// The instant-radiosity techniques of issue 4 (docs/techniques/{vpl,igi}.md), for the registry.
#pragma once
#include "gi/technique.h"

namespace gi {
TechniqueInfo vplTechniqueInfo();  // all-pairs VPL gather, no visibility
TechniqueInfo igiTechniqueInfo();  // interleaved VPL gather + discontinuity filter, no visibility
}  // namespace gi
