// The `lpv` technique (light propagation volumes), for the registry. docs/techniques/lpv.md.
#pragma once
#include "gi/technique.h"

namespace gi {
TechniqueInfo lpvTechniqueInfo();
}  // namespace gi
