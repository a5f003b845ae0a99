#include "gi/emitter_flags.h"

#include <algorithm>
#include <set>
#include <string>

#include "scene/lights.h"

namespace gi {

std::vector<uint32_t> instanceEmissionFlags(const Scene& scene) {
  std::set<std::string> standIns;
  for (const std::string& n : scene.lightNames)
    if (n.rfind(kEmitterLightPrefix, 0) == 0) standIns.insert(n.substr(std::string(kEmitterLightPrefix).size()));
  uint32_t instances = 1;
  for (uint32_t i : scene.triangleInstance) instances = std::max(instances, i + 1);
  std::vector<uint32_t> flags(instances, 1);
  for (uint32_t i = 0; i < instances; ++i) {
    std::string name = i < scene.instanceNames.size() && !scene.instanceNames[i].empty() ? scene.instanceNames[i]
                                                                                         : "instance" + std::to_string(i);
    if (standIns.count(name)) flags[i] = 0;
  }
  return flags;
}

}  // namespace gi
