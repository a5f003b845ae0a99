// The `rsm` technique (RSM gather), for the registry. docs/techniques/rsm.md.
#pragma once
#include "gi/technique.h"

namespace gi {
TechniqueInfo rsmTechniqueInfo();
}  // namespace gi
