// The instant-radiosity techniques of issue 4 (docs/techniques/{vpl,igi}.md), for the registry.
#pragma once
#include "gi/technique.h"

namespace gi {
TechniqueInfo vplTechniqueInfo();  // all-pairs VPL gather
TechniqueInfo igiTechniqueInfo();  // interleaved VPL gather + discontinuity filter
}  // namespace gi
