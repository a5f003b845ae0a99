// The pass interface every GI technique implements (ARCHITECTURE.md, "The pass interface").
//
// A technique reads the frame's rasterized views (camera G-buffer, shadow maps, RSMs, the scene)
// and writes indirect radiance (float4 per camera pixel, linear, W/(m²·sr)) that the renderer
// adds to the direct lighting. It owns its parameters, declared under "<name>." and settable with
// `--set`, and launches only named kernels so the profiler prints one line per kernel.
//
// Adding a technique = a folder src/gi/<name>/ + kernels/gi/<name>/ + one line in registry.cpp.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cl/runtime.h"
#include "raster/gbuffer.h"
#include "scene/device_scene.h"
#include "scene/scene.h"
#include "util/params.h"

namespace gi {

// Everything a technique may read in a frame.
struct FrameResources {
  cl::Context& ctx;
  const Scene& scene;
  const DeviceScene& deviceScene;
  const GBuffer& gbuffer;
  const ShadowMapSet& shadowMaps;
  const std::vector<ReflectiveShadowMap>& rsms;  // one per light when the technique asks for them
  const ParamSet& params;
  const cl::Buffer& direct;  // direct radiance (emission included) per camera pixel, float4
  bool upstreamIndirect;     // an earlier technique of the chain has written the indirect buffer
};

// A number a technique reports about its last frame (`gi bench` writes them under "statistics",
// `gi sweep` into results.csv), e.g. the share of pixels second-order re-shaded at full resolution.
struct TechniqueStatistic {
  std::string name;     // "<technique>.<what>", e.g. "second-order.reshaded_fraction"
  double value = 0.0;
  std::string meaning;  // one line for the bench printout
};

class Technique {
public:
  virtual ~Technique() = default;
  virtual std::string name() const = 0;
  virtual bool needsRsm() const { return false; }
  // A modifier reads the indirect radiance the techniques before it in the chain wrote
  // (`--technique lpv+ssao`) and rewrites it in place; a source technique overwrites it and must
  // come first. See Renderer and docs/RENDERING.md ("Technique chains").
  virtual bool modifiesIndirect() const { return false; }
  // True when the technique's output already holds the direct light of the punctual lights
  // (sh-igi.direct=vpl): the renderer then adds only the surfaces' emission to it, not the
  // rasterized direct pass. Only the first technique of a chain is asked.
  virtual bool deliversDirectLight(const ParamSet& params) const { return false; }
  // Builds programs and allocates buffers; called once before the first frame.
  virtual void setup(const FrameResources& frame) {}
  // Writes indirect radiance for every camera pixel into `indirect` (float4 per pixel); a
  // modifier reads it first when frame.upstreamIndirect is set.
  virtual void render(const FrameResources& frame, cl::Buffer& indirect) = 0;
  // What the last frame did, read back from the device: called after timed frames, never inside.
  virtual std::vector<TechniqueStatistic> statistics(cl::Context& ctx) const { return {}; }
};

struct TechniqueInfo {
  std::string name;
  std::string description;
  std::function<void(ParamSet&)> declareParams;
  std::function<std::unique_ptr<Technique>()> create;
};

// All techniques, in the order `gi render --help` lists them. "direct" (no indirect light) is
// handled by the renderer itself and is not in this list.
const std::vector<TechniqueInfo>& techniqueRegistry();
const TechniqueInfo* findTechnique(const std::string& name);

}  // namespace gi
