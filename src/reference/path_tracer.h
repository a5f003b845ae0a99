// Host side of the reference path tracer (kernels/reference/path_tracer.cl documents the light
// transport, the bounce-order definition of the modes and what is not handled).
//
// Usage: PathTracer pt(ctx, scene, view, options); while (pt.samplesDone() < spp) pt.addSamples(n);
// then image() (mean radiance, linear RGB) and variance() (per-pixel variance of that mean).
// Results are bit-identical for the same scene, view, options and sample count, however the
// samples were split into addSamples() calls.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "cl/runtime.h"
#include "image/image.h"
#include "reference/bvh.h"
#include "scene/device_scene.h"
#include "scene/scene.h"

namespace gi {

// Which light paths a sample adds, by order k = number of surface reflections of the light
// before the camera (the visible surface included; emission seen directly is k = 0).
enum class ReferenceMode {
  Full,       // 0 <= k <= maxBounces
  Direct,     // k in {0, 1}: emission seen + one reflection of every light
  Indirect,   // 2 <= k <= maxBounces: everything but Direct
  OneBounce,  // k = 2 exactly: light -> surface -> visible surface -> camera
};
const char* referenceModeName(ReferenceMode m);
ReferenceMode parseReferenceMode(const std::string& name);  // full|direct|indirect|one-bounce

struct PathTracerOptions {
  int width = 640, height = 360;
  int maxBounces = 8;        // largest order k added (Full, Indirect)
  ReferenceMode mode = ReferenceMode::Full;
  bool diffuseOnly = false;  // specular lobe off, f = ρ/π
  uint32_t seed = 0;
};

class PathTracer {
public:
  // Builds the BVH, the emissive-triangle CDF and uploads the scene.
  PathTracer(cl::Context& ctx, const Scene& scene, const GiView& view, const PathTracerOptions& options);
  ~PathTracer();

  // Enqueues `count` more samples per pixel and waits for them.
  void addSamples(int count);
  int samplesDone() const { return samples_; }

  // The running sums (float4 per pixel: Σ L and Σ L²) and their sample count, for checkpoints.
  // Restoring them and adding more samples gives the same bits as never stopping: each pixel's
  // samples are added in sample order whatever the launches were.
  struct Accumulation {
    std::vector<float> sum, sumSq;
    int samples = 0;
  };
  Accumulation accumulation() const;
  void restore(const Accumulation& a);  // throws gi::Error if the sizes do not match

  Image image() const;     // mean radiance per pixel, RGB, linear
  Image variance() const;  // variance of that mean per pixel and channel (0 below 2 samples)

  const BvhStats& bvhStats() const { return bvh_->stats(); }
  uint32_t emissiveTriangles() const { return emitCount_; }
  uint32_t punctualLights() const { return lightCount_; }

private:
  void download(std::vector<float>& s, std::vector<float>& s2) const;

  cl::Context& ctx_;
  PathTracerOptions opt_;
  GiView view_;
  std::unique_ptr<DeviceScene> scene_;
  std::unique_ptr<DeviceBvh> bvh_;
  cl::Program program_;
  mutable cl::Kernel kernel_;
  cl::Buffer lights_, emitTri_, emitCdf_, triPmf_, sum_, sumSq_;
  uint32_t lightCount_ = 0, emitCount_ = 0;
  uint32_t kMin_ = 0, kMax_ = 0;
  int samples_ = 0;
};

// Kernel source version for cache keys: a hash of the expanded path-tracer program text.
uint64_t pathTracerCodeHash();

}  // namespace gi
