#pragma once
#include "gi/technique.h"

namespace gi {
TechniqueInfo vctTechniqueInfo();
}
