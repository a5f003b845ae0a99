// VPL visibility for every VPL technique (`--set vpl.visibility=none|rays`, docs/techniques/vpl.md
// "Visibility"): with `rays` each receiver–VPL pair is tested by one shadow ray through the
// reference path tracer's BVH (src/reference/bvh.h; kernels/gi/vpl/vpl_visibility.h traces with
// its any-hit traversal). The BVH is built on the first frame that asks for rays.
//
// Use: a technique owns one VplVisibility; each frame `update(frame)`; when enabled() it builds its
// gather program with defines() and, after the kernel's own arguments, calls setArgs(). The same
// object hands VPL generation its multi-bounce settings and the BVH (`bounces(frame)`).
#pragma once
#include <memory>
#include <vector>

#include "cl/runtime.h"
#include "gi/technique.h"
#include "reference/bvh.h"
#include "util/params.h"

namespace gi {

// Declares vpl.visibility and vpl.ray_epsilon (shared by vpl, igi, splat, sh-igi, second-order)
// and vpl.bounces, vpl.bounce_fraction (vpl, igi, splat, sh-igi).
void declareVplVisibilityParams(ParamSet& p);

// Keller's further VPL generations (VplGenerator::generate; kernels/gi/vpl/vpl_bounce.cl), traced
// through the same BVH as the visibility rays.
struct VplBounces {
  int generations = 0;     // after the RSM's; 0 = one-bounce VPLs only
  float fraction = 0.5f;   // N_{g+1} = ceil(fraction · N_g) per light
  float rayEpsilon = 0.0f; // metres the rays start off the parent's surface
  const DeviceScene* scene = nullptr;
  const DeviceBvh* bvh = nullptr;
};
// VPLs per light of generation 0, 1, ..., b.generations.
std::vector<int> vplGenerationSizes(int perLight, const VplBounces& b);

class VplVisibility {
public:
  // Reads the parameters; builds the device BVH the first time rays are asked for.
  void update(const FrameResources& frame);
  bool enabled() const { return rays_; }
  // Program defines of the visibility variant of a gather (empty when disabled).
  cl::Defines defines() const;
  // Sets `float rayEpsilon` then the BVH arguments from index `first`; returns the next index.
  unsigned setArgs(cl::Kernel& kernel, unsigned first) const;
  const DeviceBvh* bvh() const { return bvh_.get(); }
  // The frame's vpl.bounces settings with this object's BVH (built here the first time bounces are
  // asked for).
  VplBounces bounces(const FrameResources& frame);

private:
  bool rays_ = false;
  float epsilon_ = 0.0f;
  std::unique_ptr<DeviceBvh> bvh_;
};

}  // namespace gi
