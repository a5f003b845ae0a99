// `ssao`: screen-space ambient occlusion (Chapman 2011; seed 003 §3.5.1) and screen-space
// one-bounce colour bleeding (seed 003 eq. 3.5). docs/techniques/ssao.md.
//
// A modifier of the indirect term (Technique::modifiesIndirect): in a chain such as `lpv+ssao` it
// multiplies the indirect radiance of the techniques before it by (1 − occlusion), as seed 003
// applied SSAO to the LPV/VCT indirect term. Alone (`ssao`) there is no indirect term to occlude,
// and the technique's output is its own one-bounce colour bleeding. `ssao.bleeding=auto` turns
// the bleeding on only when ssao is first in the chain (after a technique that already computes
// the first bounce it would count it twice).
#pragma once
#include <array>
#include <vector>

#include "gi/technique.h"

namespace gi {

TechniqueInfo ssaoTechniqueInfo();

struct SsaoSettings {
  int samples = 16;
  float radius = 0.0f;  // metres
  float bias = 0.0f;    // metres
  float blurTau = 0.05f;
  bool bleeding = false;
  // 1: occlusion (and bleeding) per camera pixel; 2: per pixel of a half-resolution grid (camera
  // pixels (2u, 2v)), then blurred per camera pixel over the grid, depth-aware.
  int downsample = 1;
};

// The hemisphere kernel: `samples` tangent-space vectors (x, y, z along the normal, w = 0) with
// directions uniform over the hemisphere (Halton 2, 3) and lengths lerp(0.1, 1, (i/N)²).
std::vector<float> ssaoKernelVectors(int samples);
// The 4×4 rotation tile: 16 (cos, sin) pairs, angle 2π·rank/16 with the rank of a 4×4 Bayer matrix.
std::vector<float> ssaoRotations();
// The camera's projection as the kernels use it, (fx, fy, cx, cy): a camera-space point (x, y, depth)
// projects to pixel coordinates (cx + fx·x/depth, cy − fy·y/depth). Throws for a view that is not a
// perspective projection looking down −z.
std::array<float, 4> ssaoProjection(const GiView& view);
// Reads the ssao.* parameters; radius and bias 0 = automatic from the scene bounds.
SsaoSettings ssaoSettings(const ParamSet& params, const Bounds& sceneBounds, bool upstreamIndirect);

class SsaoTechnique : public Technique {
public:
  std::string name() const override { return "ssao"; }
  bool modifiesIndirect() const override { return true; }
  void setup(const FrameResources& frame) override;
  void render(const FrameResources& frame, cl::Buffer& indirect) override;

  // The two passes, separately (tests): raw per-pixel occlusion and irradiance E from the
  // G-buffer, then the depth-aware blur and the composition into `indirect`.
  void occlusionPass(const FrameResources& frame, const SsaoSettings& s);
  void blurComposePass(const FrameResources& frame, const SsaoSettings& s, bool upstreamIndirect,
                       cl::Buffer& indirect);

  // float per grid pixel (occluded fraction), float4 per grid pixel (irradiance E, W/m²) — the grid
  // is the camera image unless downsample = 2; blurred occlusion per camera pixel.
  cl::Buffer& rawOcclusion() { return rawOcclusion_; }
  cl::Buffer& rawIrradiance() { return rawIrradiance_; }
  const cl::Buffer& occlusion() const { return occlusion_; }
  // uint per grid pixel: the 4-byte depth-plane records the occlusion pass samples
  // (kernels/gi/ssao/ssao.cl, ssao_encode_record).
  const cl::Buffer& depthPlaneRecords() const { return records_; }

private:
  cl::Program program_, blurProgram_;
  cl::Kernel occlusionKernel_, blurKernel_, planesKernel_;
  cl::Buffer kernelVectors_, rotations_, rawOcclusion_, rawIrradiance_, occlusion_, records_;
  // downsample = 2: the grid pixels' depth, geometric normal, and planes (1/depth and its slopes).
  cl::Buffer gridDepth_, gridNormal_, gridInvDepth_, gridSlopeX_, gridSlopeY_;
  int programSamples_ = 0, programDownsample_ = 0, programBleeding_ = -1;
};

}  // namespace gi
