// VPL visibility for every VPL technique (`--set vpl.visibility=none|rays`, docs/techniques/vpl.md
// "Visibility"): with `rays` each receiver–VPL pair is tested by one shadow ray through the
// reference path tracer's BVH (src/reference/bvh.h; kernels/gi/vpl/vpl_visibility.h traces with
// its any-hit traversal). The BVH is built on the first frame that asks for rays.
//
// Use: a technique owns one VplVisibility; each frame `update(frame)`; when enabled() it builds its
// gather program with defines() and, after the kernel's own arguments, calls setArgs().
#pragma once
#include <memory>

#include "cl/runtime.h"
#include "gi/technique.h"
#include "reference/bvh.h"
#include "util/params.h"

namespace gi {

// Declares vpl.visibility and vpl.ray_epsilon (shared by vpl, igi, splat, sh-igi, second-order).
void declareVplVisibilityParams(ParamSet& p);

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

private:
  bool rays_ = false;
  float epsilon_ = 0.0f;
  std::unique_ptr<DeviceBvh> bvh_;
};

}  // namespace gi
