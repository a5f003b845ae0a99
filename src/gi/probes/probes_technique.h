// `probes`: light-field probes (McGuire et al. 2017 as seed 004 used them) updated by ray tracing
// (DDGI style). gi/probes/probe_field.h; docs/techniques/probes.md.
#pragma once
#include "gi/probes/probe_field.h"
#include "gi/technique.h"

namespace gi {

TechniqueInfo probesTechniqueInfo();

// The probes.* parameters that shape the grid and its maps (read once, at setup).
ProbeSettings probeSettings(const ParamSet& params);

}  // namespace gi
