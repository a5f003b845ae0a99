// The VPL list (all generations) a VPL technique gathers for a rendered frame, downloaded for host
// sums: VplGenerator with `generations` further generations (vpl.ray_epsilon's default, fraction
// 0.5) through a BVH of `scene`. Shared by tests/vpl_bounce_test.cpp and tests/vpl_specular_test.cpp.
#pragma once
#include <vector>

#include "gi/vpl/vpl_lights.h"
#include "reference/bvh.h"
#include "render/renderer.h"
#include "scene/device_scene.h"

namespace gi::test {

inline std::vector<HostVpl> generatedVpls(cl::Context& ctx, const Scene& scene, const Renderer& frame, int perLight,
                                          int generations) {
  DeviceScene ds(ctx, scene);
  DeviceBvh bvh(ctx, scene, ds);
  VplBounces b;
  b.generations = generations;
  b.rayEpsilon = 1e-3f;
  b.scene = &ds;
  b.bvh = &bvh;
  VplGenerator gen(ctx);
  VplSet set;
  gen.generate(frame.rsms(), perLight, 0.0f, set, b);
  std::vector<glm::vec4> raw = ctx.download<glm::vec4>(set.vpls);
  std::vector<HostVpl> vpls(raw.size() / 3);
  for (size_t k = 0; k < vpls.size(); ++k)
    vpls[k] = {glm::vec3(raw[3 * k]), raw[3 * k].w, glm::vec3(raw[3 * k + 1]), glm::vec3(raw[3 * k + 2])};
  ctx.profiler().discard();
  return vpls;
}

}  // namespace gi::test
