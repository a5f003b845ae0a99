#include "scene/scene.h"

namespace gi {

void Scene::computeBounds() {
  bounds = Bounds{};
  for (const glm::uvec3& t : triangles)
    for (int k = 0; k < 3; ++k) bounds.extend(positions[t[k]]);
}

}  // namespace gi
