// Host side of the reference path tracer: light tables, buffers, launches, read-back.
#include "reference/path_tracer.h"

#include <algorithm>
#include <cmath>

#include "cl/kernel_sources.h"
#include "util/error.h"
#include "util/hash.h"

namespace gi {

namespace {
constexpr const char* kProgram = "kernels/reference/path_tracer.cl";
}

const char* referenceModeName(ReferenceMode m) {
  switch (m) {
    case ReferenceMode::Full: return "full";
    case ReferenceMode::Direct: return "direct";
    case ReferenceMode::Indirect: return "indirect";
    case ReferenceMode::OneBounce: return "one-bounce";
  }
  return "?";
}

ReferenceMode parseReferenceMode(const std::string& n) {
  if (n == "full") return ReferenceMode::Full;
  if (n == "direct") return ReferenceMode::Direct;
  if (n == "indirect") return ReferenceMode::Indirect;
  if (n == "one-bounce") return ReferenceMode::OneBounce;
  throw Error("--mode '" + n + "': expected full, direct, indirect or one-bounce");
}

uint64_t pathTracerCodeHash() { return fnv1a64(cl::expandKernelIncludes(kProgram)); }

PathTracer::PathTracer(cl::Context& ctx, const Scene& scene, const GiView& view, const PathTracerOptions& options)
    : ctx_(ctx), opt_(options), view_(view) {
  if (opt_.width <= 0 || opt_.height <= 0) throw Error("path tracer: image size must be positive");
  if (opt_.maxBounces < 0 || opt_.maxBounces > 1000) throw Error("path tracer: max bounces must be in 0..1000");
  view_.width = opt_.width;
  view_.height = opt_.height;

  scene_ = std::make_unique<DeviceScene>(ctx, scene);
  bvh_ = std::make_unique<DeviceBvh>(ctx, scene, *scene_);

  // Punctual lights, without the stand-ins for emissive geometry (sampled as triangles here).
  std::vector<GiLight> lights;
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    bool standIn = i < scene.lightNames.size() && scene.lightNames[i].rfind("emitter:", 0) == 0;
    if (!standIn) lights.push_back(scene.lights[i]);
  }
  lightCount_ = uint32_t(lights.size());
  lights_ = ctx.upload(lights, "path tracer lights");

  // Emissive triangles: power = luminance(emissive factor) × area (textures not integrated: a
  // textured emitter is sampled by its factor, which changes the variance, not the mean).
  std::vector<uint32_t> emitTri;
  std::vector<double> power;
  std::vector<float> triPmf(scene.triangleCount(), 0.0f);
  for (size_t t = 0; t < scene.triangleCount(); ++t) {
    const GiMaterial& m = scene.materials[scene.triangleMaterial[t]];
    double lum = 0.2126 * m.emissive[0] + 0.7152 * m.emissive[1] + 0.0722 * m.emissive[2];
    if (!(lum > 0.0)) continue;
    glm::vec3 p0 = scene.positions[scene.triangles[t][0]];
    double area = 0.5 * glm::length(glm::cross(scene.positions[scene.triangles[t][1]] - p0,
                                               scene.positions[scene.triangles[t][2]] - p0));
    if (!(area > 0.0)) continue;
    emitTri.push_back(uint32_t(t));
    power.push_back(lum * area);
  }
  double total = 0.0;
  for (double p : power) total += p;
  std::vector<float> cdf(power.size());
  double run = 0.0;
  for (size_t i = 0; i < power.size(); ++i) {
    run += power[i];
    cdf[i] = float(run / total);
    triPmf[emitTri[i]] = float(power[i] / total);
  }
  if (!cdf.empty()) cdf.back() = 1.0f;
  emitCount_ = uint32_t(emitTri.size());
  emitTri_ = ctx.upload(emitTri, "emissive triangles");
  emitCdf_ = ctx.upload(cdf, "emissive triangle CDF");
  triPmf_ = ctx.upload(triPmf, "triangle light pmf");

  switch (opt_.mode) {
    case ReferenceMode::Full: kMin_ = 0; kMax_ = uint32_t(opt_.maxBounces); break;
    case ReferenceMode::Direct: kMin_ = 0; kMax_ = std::min(1u, uint32_t(opt_.maxBounces)); break;
    case ReferenceMode::Indirect: kMin_ = 2; kMax_ = uint32_t(opt_.maxBounces); break;
    case ReferenceMode::OneBounce: kMin_ = 2; kMax_ = 2; break;
  }

  cl::Defines defs;
  if (opt_.diffuseOnly) defs.push_back({"PT_DIFFUSE_ONLY", "1"});
  program_ = ctx.buildProgram(kProgram, defs);
  kernel_ = program_.kernel("pt_render");

  size_t pixels = size_t(opt_.width) * opt_.height;
  ctx.requireAllocation(pixels * 16, "path tracer accumulation");
  sum_ = cl::Buffer(ctx, pixels * 16, CL_MEM_READ_WRITE, "path tracer sum");
  sumSq_ = cl::Buffer(ctx, pixels * 16, CL_MEM_READ_WRITE, "path tracer sum of squares");
  ctx.fill(sum_, glm::vec4(0.0f));
  ctx.fill(sumSq_, glm::vec4(0.0f));
}

PathTracer::~PathTracer() = default;

void PathTracer::addSamples(int count) {
  if (count <= 0) return;
  // Empty range: a sample with nothing to add (e.g. one-bounce with max bounces < 2).
  bool nothing = kMin_ > kMax_;
  if (!nothing) {
    unsigned a = bvh_->setArgs(kernel_, 0);
    uint32_t pixels = uint32_t(opt_.width) * uint32_t(opt_.height);
    kernel_.setArg(a++, scene_->positions);
    kernel_.setArg(a++, scene_->normals);
    kernel_.setArg(a++, scene_->tangents);
    kernel_.setArg(a++, lights_);
    kernel_.setArg(a++, lightCount_);
    kernel_.setArg(a++, emitTri_);
    kernel_.setArg(a++, emitCdf_);
    kernel_.setArg(a++, emitCount_);
    kernel_.setArg(a++, triPmf_);
    kernel_.setArg(a++, view_);
    kernel_.setArg(a++, uint32_t(opt_.width));
    kernel_.setArg(a++, uint32_t(opt_.height));
    kernel_.setArg(a++, uint32_t(samples_));
    kernel_.setArg(a++, uint32_t(count));
    kernel_.setArg(a++, opt_.seed);
    kernel_.setArg(a++, kMin_);
    kernel_.setArg(a++, kMax_);
    kernel_.setArg(a++, sum_);
    kernel_.setArg(a++, sumSq_);
    // 64 pixels of one row per work-group: coherent camera rays, thousands of groups.
    ctx_.launch(kernel_, cl::NDRange::d1(pixels, 64), "path trace");
    ctx_.finish();
    ctx_.profiler().discard();
  }
  samples_ += count;
}

void PathTracer::download(std::vector<float>& s, std::vector<float>& s2) const {
  s = ctx_.download<float>(sum_);
  s2 = ctx_.download<float>(sumSq_);
}

PathTracer::Accumulation PathTracer::accumulation() const {
  Accumulation a;
  download(a.sum, a.sumSq);
  a.samples = samples_;
  return a;
}

void PathTracer::restore(const Accumulation& a) {
  const size_t floats = size_t(opt_.width) * opt_.height * 4;
  if (a.sum.size() != floats || a.sumSq.size() != floats || a.samples < 0)
    throw Error("path tracer: a checkpoint of " + std::to_string(a.sum.size() / 4) + " pixels does not fit a " +
                std::to_string(opt_.width) + "x" + std::to_string(opt_.height) + " image");
  ctx_.write(sum_, a.sum.data(), floats * sizeof(float));
  ctx_.write(sumSq_, a.sumSq.data(), floats * sizeof(float));
  samples_ = a.samples;
}

Image PathTracer::image() const {
  std::vector<float> s, s2;
  download(s, s2);
  Image img(opt_.width, opt_.height, 3);
  float inv = samples_ > 0 ? 1.0f / float(samples_) : 0.0f;
  for (size_t i = 0; i < img.pixelCount(); ++i)
    for (int c = 0; c < 3; ++c) img.pixels[3 * i + c] = s[4 * i + c] * inv;
  return img;
}

Image PathTracer::variance() const {
  std::vector<float> s, s2;
  download(s, s2);
  Image img(opt_.width, opt_.height, 3);
  if (samples_ < 2) return img;
  double n = samples_;
  for (size_t i = 0; i < img.pixelCount(); ++i)
    for (int c = 0; c < 3; ++c) {
      double mean = s[4 * i + c] / n;
      double var = std::max(0.0, (double(s2[4 * i + c]) - n * mean * mean) / (n - 1.0));
      img.pixels[3 * i + c] = float(var / n);
    }
  return img;
}

}  // namespace gi
