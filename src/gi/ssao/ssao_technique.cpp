// `ssao`: screen-space ambient occlusion and colour bleeding (kernels/gi/ssao/ssao.cl).
//
// Choices where Chapman's tutorial and seed 003 are silent (docs/techniques/ssao.md):
// - kernel directions from the Halton (2, 3) sequence, uniform over the hemisphere (z = ξ1), not
//   Chapman's random box samples, so the expected occlusion of a corner is known in closed form;
// - rotation noise as a 4×4 ordered (Bayer-ranked) tile of 16 evenly spaced angles instead of
//   random vectors: deterministic, and every 4×4 blur window averages all 16 rotations;
// - occlusion tested against the tangent plane of the visible surface (exact for planes) instead
//   of its depth at the pixel centre;
// - radius 0 = 5 % of the scene's bounding-box diagonal; bias 0 = 1 % of the radius.
#include "gi/ssao/ssao_technique.h"
#include "util/halton.h"
#include "cl/gather_width.h"

#include <glm/gtc/type_ptr.hpp>

#include <cmath>
#include <memory>

#include "util/error.h"

namespace gi {

namespace {

// The kernels take `vw` adjacent pixels of a row of a width × height image per work-item.
cl::NDRange pixelGroups(int vw, int width, int height) {
  int groups = (width + vw - 1) / vw;
  return cl::NDRange::d2(cl::roundUp(groups, 8), cl::roundUp(height, 8), 8, 8);
}

}  // namespace

std::array<float, 4> ssaoProjection(const GiView& view) {
  if (view.orthographic) throw Error("ssao: needs a perspective camera (this view is orthographic)");
  glm::mat4 viewProj = glm::make_mat4(view.view_proj), viewMatrix = glm::make_mat4(view.view);
  glm::mat4 proj = viewProj * glm::inverse(viewMatrix);
  // glm::perspective (possibly off-centre): clip = (P00·x + P20·z, P11·y + P21·z, ., −z).
  auto near = [](float a, float b) { return std::fabs(a - b) <= 1e-5f * std::max(1.0f, std::fabs(b)); };
  if (!near(proj[1][0], 0) || !near(proj[0][1], 0) || !near(proj[3][0], 0) || !near(proj[3][1], 0) ||
      !near(proj[2][3], -1) || !near(proj[3][3], 0) || !near(proj[0][3], 0) || !near(proj[1][3], 0))
    throw Error("ssao: the camera's projection is not a perspective projection looking down -z");
  float W = float(view.width), H = float(view.height);
  return {0.5f * W * proj[0][0], 0.5f * H * proj[1][1], 0.5f * W * (1.0f - proj[2][0]), 0.5f * H * (1.0f + proj[2][1])};
}

std::vector<float> ssaoKernelVectors(int samples) {
  std::vector<float> v(size_t(samples) * 4);
  for (int i = 0; i < samples; ++i) {
    float z = radicalInverse(uint32_t(i) + 1, 2);  // uniform in [0, 1): uniform over the hemisphere
    float phi = 6.2831853f * radicalInverse(uint32_t(i) + 1, 3);
    float h = std::sqrt(std::max(0.0f, 1.0f - z * z));
    float t = float(i) / float(samples);
    float scale = 0.1f + 0.9f * t * t;  // Chapman's accelerating lerp(0.1, 1, (i/N)²)
    v[4 * i + 0] = scale * h * std::cos(phi);
    v[4 * i + 1] = scale * h * std::sin(phi);
    v[4 * i + 2] = scale * z;
    v[4 * i + 3] = 0.0f;
  }
  return v;
}

std::vector<float> ssaoRotations() {
  static const int bayer[16] = {0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5};
  std::vector<float> r(32);
  for (int k = 0; k < 16; ++k) {
    float a = 6.2831853f * float(bayer[k]) / 16.0f;
    r[2 * k] = std::cos(a);
    r[2 * k + 1] = std::sin(a);
  }
  return r;
}

SsaoSettings ssaoSettings(const ParamSet& p, const Bounds& bounds, bool upstreamIndirect) {
  SsaoSettings s;
  s.samples = p.getInt("ssao.samples");
  s.radius = p.getFloat("ssao.radius");
  if (s.radius <= 0.0f) s.radius = 0.05f * glm::length(bounds.extent());
  s.bias = p.getFloat("ssao.bias");
  if (s.bias <= 0.0f) s.bias = 0.01f * s.radius;
  s.blurTau = p.getFloat("ssao.blur_tau");
  std::string b = p.getChoice("ssao.bleeding");
  s.bleeding = b == "on" || (b == "auto" && !upstreamIndirect);
  s.downsample = p.getInt("ssao.downsample");
  return s;
}

void SsaoTechnique::setup(const FrameResources& f) {
  size_t n = size_t(f.gbuffer.width) * f.gbuffer.height;
  rawOcclusion_ = cl::Buffer(f.ctx, n * 4, CL_MEM_READ_WRITE, "ssao raw occlusion");
  records_ = cl::Buffer(f.ctx, n * 4, CL_MEM_READ_WRITE, "ssao depth-plane records");
  rawIrradiance_ = cl::Buffer(f.ctx, n * 16, CL_MEM_READ_WRITE, "ssao raw bleeding irradiance");
  occlusion_ = cl::Buffer(f.ctx, n * 4, CL_MEM_READ_WRITE, "ssao occlusion");
  rotations_ = f.ctx.upload(ssaoRotations(), "ssao rotations");
}

void SsaoTechnique::occlusionPass(const FrameResources& f, const SsaoSettings& s) {
  if (s.downsample != 1 && s.downsample != 2)
    throw Error("ssao.downsample = " + std::to_string(s.downsample) + ": expected 1 or 2");
  if (s.samples != programSamples_ || s.downsample != programDownsample_ || int(s.bleeding) != programBleeding_) {
    program_ = f.ctx.buildProgram("kernels/gi/ssao/ssao.cl", {{"GI_SSAO_SAMPLES", std::to_string(s.samples)},
                                                              {"GI_SSAO_DOWN", std::to_string(s.downsample)},
                                                              {"GI_SSAO_BLEEDING", s.bleeding ? "1" : "0"}});
    occlusionKernel_ = program_.kernel("ssao_occlusion");
    if (s.downsample == 1) {
      blurKernel_ = program_.kernel("ssao_blur_compose");
    } else {
      // The native vector width (8 lanes with AVX2): its two sets of 16-wide accumulators (even
      // and odd pixels) spill the 16 AVX2 registers (docs/PERFORMANCE.md).
      blurProgram_ = f.ctx.buildProgram("kernels/gi/ssao/ssao.cl",
                                        cl::withGatherWidth(f.ctx, {{"GI_SSAO_SAMPLES", std::to_string(s.samples)},
                                                                    {"GI_SSAO_DOWN", "2"}}));
      blurKernel_ = blurProgram_.kernel("ssao_upsample_blur_compose");
    }
    planesKernel_ = program_.kernel("ssao_depth_planes");
    kernelVectors_ = f.ctx.upload(ssaoKernelVectors(s.samples), "ssao kernel vectors");
    programSamples_ = s.samples;
    programDownsample_ = s.downsample;
    programBleeding_ = int(s.bleeding);
  }
  const GBuffer& g = f.gbuffer;
  std::array<float, 4> p = ssaoProjection(g.view);
  cl_float4 projection{{p[0], p[1], p[2], p[3]}};
  const int d = s.downsample, gw = (g.width + d - 1) / d, gh = (g.height + d - 1) / d;
  if (d == 2 && !gridDepth_) {
    gridDepth_ = cl::Buffer(f.ctx, size_t(gw) * gh * 4, CL_MEM_READ_WRITE, "ssao grid depth");
    gridNormal_ = cl::Buffer(f.ctx, size_t(gw) * gh * 16, CL_MEM_READ_WRITE, "ssao grid geometric normal");
    gridInvDepth_ = cl::Buffer(f.ctx, size_t(gw) * gh * 4, CL_MEM_READ_WRITE, "ssao grid 1/depth");
    gridSlopeX_ = cl::Buffer(f.ctx, size_t(gw) * gh * 4, CL_MEM_READ_WRITE, "ssao grid 1/depth slope x");
    gridSlopeY_ = cl::Buffer(f.ctx, size_t(gw) * gh * 4, CL_MEM_READ_WRITE, "ssao grid 1/depth slope y");
  }
  // At full resolution the grid is the G-buffer itself (the grid planes are not written: any buffer
  // stands in for them).
  const cl::Buffer& depth = d == 1 ? g.visibility.depth : gridDepth_;
  const cl::Buffer& normal = d == 1 ? g.geoNormal : gridNormal_;
  const cl::Buffer& invDepth = d == 1 ? records_ : gridInvDepth_;
  const cl::Buffer& slopeX = d == 1 ? records_ : gridSlopeX_;
  const cl::Buffer& slopeY = d == 1 ? records_ : gridSlopeY_;
  planesKernel_.args(gw, gh, g.width, g.view, projection, g.visibility.depth, g.geoNormal, records_, depth, normal,
                     invDepth, slopeX, slopeY);
  f.ctx.launch(planesKernel_, pixelGroups(f.ctx.vectorWidth(), gw, gh), "ssao: depth planes");
  occlusionKernel_.args(gw, gh, g.width, g.view, projection, depth, normal, records_, kernelVectors_, rotations_,
                        s.radius, s.bias, g.position, g.normal, f.direct, rawOcclusion_,
                        rawIrradiance_);
  f.ctx.launch(occlusionKernel_, pixelGroups(f.ctx.vectorWidth(), gw, gh), "ssao: occlusion");
}

void SsaoTechnique::blurComposePass(const FrameResources& f, const SsaoSettings& s, bool upstream,
                                    cl::Buffer& indirect) {
  const GBuffer& g = f.gbuffer;
  if (programDownsample_ == 1) {
    blurKernel_.args(g.width, g.height, g.visibility.depth, g.albedo, rawOcclusion_, rawIrradiance_, s.blurTau,
                     int(upstream), int(s.bleeding), occlusion_, indirect);
    f.ctx.launch(blurKernel_, pixelGroups(f.ctx.vectorWidth(), g.width, g.height), "ssao: blur + compose");
  } else {
    const int gw = (g.width + 1) / 2, gh = (g.height + 1) / 2;
    blurKernel_.args(g.width, g.height, gw, gh, g.visibility.depth, g.albedo, gridInvDepth_, gridSlopeX_,
                     gridSlopeY_, rawOcclusion_, rawIrradiance_, s.blurTau, int(upstream), int(s.bleeding), occlusion_,
                     indirect);
    // 2·vw camera pixels per work-item (the even and the odd ones).
    f.ctx.launch(blurKernel_, pixelGroups(2 * cl::gatherVectorWidth(f.ctx), g.width, g.height),
                 "ssao: upsample, blur + compose");
  }
}

void SsaoTechnique::render(const FrameResources& f, cl::Buffer& indirect) {
  SsaoSettings s = ssaoSettings(f.params, f.scene.bounds, f.upstreamIndirect);
  occlusionPass(f, s);
  blurComposePass(f, s, f.upstreamIndirect, indirect);
}

TechniqueInfo ssaoTechniqueInfo() {
  return {"ssao",
          "screen-space ambient occlusion (Chapman) on the indirect term of the techniques before it "
          "(lpv+ssao) and screen-space one-bounce colour bleeding (seed 003 eq. 3.5)",
          [](ParamSet& p) {
            p.addInt("ssao.samples", 16, 1, 256, "hemisphere samples per pixel");
            p.addFloat("ssao.radius", 0.0, 0.0, 1000.0, "hemisphere radius R in metres; 0 = 5 % of the scene diagonal");
            p.addFloat("ssao.bias", 0.0, 0.0, 1000.0,
                       "a sample is occluded only this far (metres) behind the visible surface; 0 = 1 % of R");
            p.addFloat("ssao.blur_tau", 0.05, 0.0, 10.0,
                       "4x4 blur: neighbours whose view depth differs by more than this fraction are skipped");
            p.addInt("ssao.downsample", 1, 1, 2,
                     "1: occlusion per pixel; 2: on a half-resolution grid, then a depth-aware 4x4 blur per pixel");
            p.addChoice("ssao.bleeding", "auto", {"auto", "on", "off"},
                        "screen-space one-bounce colour bleeding (eq. 3.5); auto = on only when ssao is first in "
                        "the technique chain");
          },
          [] { return std::make_unique<SsaoTechnique>(); }};
}

}  // namespace gi
