// One frame, as data flowing down one line (ARCHITECTURE.md):
//   shadow maps -> camera G-buffer -> RSMs (if the technique wants them) -> direct lighting
//   -> technique (indirect) -> compose -> [host] display transform -> image
// The renderer owns the device scene, the raster passes and the technique; `gi render`,
// the tests and the benchmarks all drive frames through it.
#pragma once
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "cl/runtime.h"
#include "gi/technique.h"
#include "image/image.h"
#include "raster/gbuffer.h"
#include "scene/device_scene.h"
#include "scene/scene.h"
#include "util/params.h"

namespace gi {

struct RenderSettings {
  int width = 0, height = 0;       // 0 = the scene's default size
  std::string camera;              // name or index; "" = the scene's default camera
  std::string technique = "direct";  // a technique or a chain "source+modifier+..." (lpv+ssao)
  std::vector<std::string> sets;   // "name=value" parameter assignments
};

// The renderer's own parameters (shadow and RSM resolutions) plus those of every technique.
ParamSet declareAllParams();

using PassTimes = std::vector<std::pair<std::string, double>>;  // name, device ms (first-launch order)

class Renderer {
public:
  Renderer(cl::Context& ctx, const Scene& scene, const RenderSettings& settings);
  ~Renderer();

  // Renders one frame; returns the device time of every named kernel launch.
  PassTimes renderFrame();

  int width() const { return width_; }
  int height() const { return height_; }
  const Camera& camera() const { return camera_; }
  const ParamSet& params() const { return params_; }
  uint64_t deviceBytes() const;  // scene + frame buffers

  Image radiance();        // final linear radiance, RGB
  Image directRadiance();  // direct lighting only (incl. emission)
  Image indirectRadiance();  // the technique's output (zero for "direct")
  // Every technique of the chain's statistics about the last frame (reads the device back).
  std::vector<TechniqueStatistic> techniqueStatistics();

  // Writes the G-buffer planes and every RSM as EXR files into `dir`; returns the paths.
  std::vector<std::string> writeAovs(const std::string& dir);

  const GBuffer& gbuffer() const { return gbuffer_; }
  const std::vector<ReflectiveShadowMap>& rsms() const { return rsms_; }
  const ShadowMapSet& shadowMaps() const { return shadowMaps_; }
  const DeviceScene& deviceScene() const { return *deviceScene_; }
  const cl::Buffer& directBuffer() const { return direct_; }
  // The resources a technique sees in this frame (tests drive single passes with them).
  FrameResources frameResources(bool upstreamIndirect) const;

private:
  Image readFloat4(const cl::Buffer& b, int w, int h, int channels);

  cl::Context& ctx_;
  Scene scene_;  // own copy: lights get shadow-map indices
  ParamSet params_;
  int width_ = 0, height_ = 0;
  Camera camera_;
  GiView cameraView_{};
  std::unique_ptr<DeviceScene> deviceScene_;
  std::unique_ptr<RasterPasses> raster_;
  std::vector<std::unique_ptr<Technique>> chain_;  // empty for "direct"
  GBuffer gbuffer_;
  ShadowMapSet shadowMaps_;
  std::vector<ReflectiveShadowMap> rsms_;
  cl::Program lightingProgram_;
  cl::Kernel directKernel_, composeKernel_;
  cl::Buffer direct_, indirect_, final_;
  bool wantRsm_ = false;
  bool staticShadows_ = false;  // shadow.static: render the shadow maps once, reuse them
  bool shadowsRendered_ = false;
};

// Splits a technique chain "a+b+c" and checks it: known names, no repeats, and only the first may
// be a source (a technique that overwrites the indirect term); throws gi::Error naming the problem.
std::vector<const TechniqueInfo*> parseTechniqueChain(const std::string& chain);

// Picks a camera by name or index ("" = default); throws gi::Error listing the cameras.
const Camera& selectCamera(const Scene& scene, const std::string& nameOrIndex);

}  // namespace gi
