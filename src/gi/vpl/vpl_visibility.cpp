#include "gi/vpl/vpl_visibility.h"

namespace gi {

void declareVplVisibilityParams(ParamSet& p) {
  p.addChoice("vpl.visibility", "none", {"none", "rays"},
              "VPL visibility for every VPL technique: none = every VPL lights every receiver it faces; "
              "rays = one shadow ray per receiver-VPL pair through the reference BVH (exact, slow on a CPU)");
  p.addFloat("vpl.ray_epsilon", 1e-3, 0.0, 1.0,
             "visibility rays: metres kept off the receiver and the VPL surfaces (rasterized positions)");
}

void VplVisibility::update(const FrameResources& f) {
  rays_ = f.params.getChoice("vpl.visibility") == "rays";
  epsilon_ = f.params.getFloat("vpl.ray_epsilon");
  if (rays_ && !bvh_) bvh_ = std::make_unique<DeviceBvh>(f.ctx, f.scene, f.deviceScene);
}

cl::Defines VplVisibility::defines() const {
  if (!rays_) return {};
  return {{"GI_VPL_VISIBILITY", "1"}};
}

unsigned VplVisibility::setArgs(cl::Kernel& k, unsigned first) const {
  if (!rays_) return first;
  k.setArg(first++, epsilon_);
  return bvh_->setArgs(k, first);
}

}  // namespace gi
