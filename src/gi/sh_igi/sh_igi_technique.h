// `sh-igi`: SH-filtered instant global illumination (Segovia & Wald, seed 001; ALGORITHMS.md §2.5;
// kernels/gi/sh_igi/sh_igi.cl; docs/techniques/sh-igi.md).
#pragma once
#include "gi/technique.h"

namespace gi {
TechniqueInfo shIgiTechniqueInfo();
}  // namespace gi
