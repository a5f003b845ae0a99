#include "gi/vpl/vpl_visibility.h"

#include <cmath>

namespace gi {

void declareVplVisibilityParams(ParamSet& p) {
  p.addChoice("vpl.visibility", "none", {"none", "rays"},
              "VPL visibility for every VPL technique: none = every VPL lights every receiver it faces; "
              "rays = one shadow ray per receiver-VPL pair through the reference BVH (exact, slow on a CPU)");
  p.addFloat("vpl.ray_epsilon", 1e-3, 0.0, 1.0,
             "visibility rays: metres kept off the receiver and the VPL surfaces (rasterized positions)");
  p.addInt("vpl.bounces", 0, 0, 8,
           "further VPL generations traced from the RSM's VPLs through the scene (Keller's instant radiosity): "
           "0 = one-bounce indirect light only, B = light of up to B+1 bounces (vpl, igi, splat, sh-igi)");
  p.addFloat("vpl.bounce_fraction", 0.5, 0.01, 1.0,
             "share of each VPL generation that continues to the next (N_{g+1} = ceil(fraction N_g) per light; "
             "flux scaled by N_g/N_{g+1}, so any value is unbiased)");
}

std::vector<int> vplGenerationSizes(int perLight, const VplBounces& b) {
  std::vector<int> sizes{perLight};
  for (int g = 0; g < b.generations; ++g)
    sizes.push_back(int(std::ceil(double(b.fraction) * double(sizes.back()) - 1e-4)));
  return sizes;
}

VplBounces VplVisibility::bounces(const FrameResources& f) {
  VplBounces b;
  b.generations = f.params.getInt("vpl.bounces");
  b.fraction = f.params.getFloat("vpl.bounce_fraction");
  b.rayEpsilon = f.params.getFloat("vpl.ray_epsilon");
  if (b.generations == 0) return b;
  if (!bvh_) bvh_ = std::make_unique<DeviceBvh>(f.ctx, f.scene, f.deviceScene);
  b.scene = &f.deviceScene;
  b.bvh = bvh_.get();
  return b;
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
