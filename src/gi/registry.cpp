// The list of GI techniques. Add one line per technique.
#include "gi/technique.h"

namespace gi {

const std::vector<TechniqueInfo>& techniqueRegistry() {
  static const std::vector<TechniqueInfo> registry = {
  };
  return registry;
}

const TechniqueInfo* findTechnique(const std::string& name) {
  for (const TechniqueInfo& t : techniqueRegistry())
    if (t.name == name) return &t;
  return nullptr;
}

}  // namespace gi
