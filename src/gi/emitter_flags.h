// Which instances' emission a technique must add itself (shared by vct and probes).
#pragma once
#include <cstdint>
#include <vector>

#include "scene/scene.h"

namespace gi {

// Per instance id: 1 when its emission belongs in a technique's gathered light. Emitters that have
// a spot/point stand-in (scene/lights.h) already light the scene through that light in the direct
// pass and in any direct irradiance a technique computes from the lights; gathering their emission
// as well would count the same light twice.
std::vector<uint32_t> instanceEmissionFlags(const Scene& scene);

}  // namespace gi
