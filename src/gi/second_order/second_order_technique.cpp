#include <algorithm>
#include <cmath>
#include <memory>
#include <cstring>
#include <random>

#include "gi/filters/discontinuity_filter.h"
#include "gi/second_order/second_order.h"

namespace gi {

namespace {

constexpr float kInvPi = 0.31830988618379067154f;
constexpr double kTwoPi = 6.28318530717958647692;

// Uniform random directions in the cone z ≥ cosAccept (the "without Halton placement" variant of the
// flicker measurement): a fresh set every frame.
std::vector<glm::vec4> randomConeDirections(float cosAccept, int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<glm::vec4> out(count);
  for (glm::vec4& d : out) {
    double z = 1.0 - u(rng) * (1.0 - double(cosAccept)), phi = kTwoPi * u(rng);
    double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    d = glm::vec4(float(std::sin(phi) * r), float(std::cos(phi) * r), float(z), 0.0f);
  }
  return out;
}

std::vector<glm::vec4> randomSquarePoints(int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<glm::vec4> out(count);
  for (glm::vec4& p : out) p = glm::vec4(u(rng), u(rng), 0.0f, 0.0f);
  return out;
}

}  // namespace

void SecondOrderTechnique::setup(const FrameResources& f) {
  program_ = f.ctx.buildProgram("kernels/gi/second_order/second_order.cl");
  place_ = program_.kernel("so_place_indirect");
  flag_ = program_.kernel("so_flag");
  rowCounts_ = program_.kernel("so_row_counts");
  scanRows_ = program_.kernel("so_scan_rows");
  pickNegative_ = program_.kernel("so_pick_negative");
  negative_ = program_.kernel("so_negative_lights");
  shadeLow_ = program_.kernel("so_shade_low");
  compact_ = program_.kernel("so_compact");
  refine_ = program_.kernel("so_refine");
  upsampler_ = std::make_unique<GeometryAwareUpsampler>(f.ctx, "second-order: upsample");
  counters_ = cl::Buffer(f.ctx, 4 * sizeof(int), CL_MEM_READ_WRITE, "second-order counters");
  f.ctx.fill(counters_, 0);
}

void SecondOrderTechnique::render(const FrameResources& f, cl::Buffer& indirect) {
  const ParamSet& p = f.params;
  cl::Context& ctx = f.ctx;
  const GBuffer& g = f.gbuffer;
  // GI_VW = the context's lane count: 16 on a CPU, also with AVX2, where the light loops ran
  // ≈ 12 % faster in CPU time than with 8 lanes (two independent vector chains per operation).
  const int W = g.width, H = g.height, vw = ctx.vectorWidth();
  const int N = p.getInt("second-order.count");
  int M = p.getInt("second-order.negative");
  if (M < 0) M = N / 2;
  // vpl.visibility=rays: every pair gets a shadow ray, E_s is already the occluded I_c and there
  // is nothing left for negative lights to remove.
  visibility_.update(f);
  const bool rays = visibility_.enabled();
  if (rays) M = 0;
  negativeAsked_ = M;
  const std::string placement = p.getChoice("second-order.placement");
  const float dmin = p.getFloat("second-order.d_min");
  const bool multires = p.getBool("second-order.multires");
  const float tauD = p.getFloat("second-order.tau_d"), tauN = p.getFloat("second-order.tau_n");
  const float cosTauN = std::cos(tauN * 3.14159265f / 180.0f);
  const uint32_t seed = uint32_t(p.getInt("second-order.seed")) * 7919u + uint32_t(frame_++);

  // Indirect lights, N per light.
  const int L = int(f.rsms.size()), positive = N * L, lightCount = positive + M;
  if (!lights_.vpls || lights_.vpls.bytes() != size_t(std::max(lightCount, 1)) * 48) {
    lights_.vpls = cl::Buffer(ctx, size_t(std::max(lightCount, 1)) * 48, CL_MEM_READ_WRITE, "second-order lights");
    ctx.fill(lights_.vpls, 0.0f);
  }
  lights_.count = lightCount;
  lights_.perLight = N;
  if (placement == "flux") {
    if (!fluxGenerator_) fluxGenerator_ = std::make_unique<VplGenerator>(ctx, "second-order: flux placement");
    fluxGenerator_->generate(f.rsms, N, dmin, fluxLights_);
    if (positive > 0) ctx.copy(fluxLights_.vpls, lights_.vpls, size_t(positive) * 48);
  } else {
    samples_.resize(f.rsms.size());
    for (int l = 0; l < L; ++l) {
      const ReflectiveShadowMap& rsm = f.rsms[l];
      const GiLight& light = f.scene.lights.at(rsm.light);
      const int res = rsm.view.width;
      const bool ortho = rsm.view.orthographic != 0;
      const float cosAccept = ortho ? 0.0f : acceptedConeCos(light, rsm.view);
      const float weight = ortho ? float(res) * float(res) / float(N) : coneSolidAngle(cosAccept) / float(N);
      Samples& s = samples_[l];
      if (placement == "random" || s.count != N || s.orthographic != ortho || s.cosAccept != cosAccept) {
        std::vector<glm::vec4> pts;
        if (placement == "random") pts = ortho ? randomSquarePoints(N, seed + 104729u * l) : randomConeDirections(cosAccept, N, seed + 104729u * l);
        else pts = ortho ? haltonSquarePoints(N) : haltonConeDirections(cosAccept, N);
        s.buffer = ctx.upload(pts, "second-order light samples");
        s.count = placement == "random" ? -1 : N;  // random: new points next frame
        s.orthographic = ortho;
        s.cosAccept = cosAccept;
      }
      place_.args(rsm.view, s.buffer, N, weight, rsm.position, rsm.normal, rsm.flux, dmin, l * N, lights_.vpls);
      ctx.launch(place_, cl::NDRange::d1(cl::roundUp(N, 64), 64), "second-order: place indirect lights");
    }
  }

  // Pixel classes and counts (full resolution), then the negative lights.
  const size_t pixels = size_t(W) * H;
  const int capacity = int(cl::roundUp(pixels, size_t(vw)));
  if (W != width_ || H != height_) {
    flags_ = cl::Buffer(ctx, pixels, CL_MEM_READ_WRITE, "second-order pixel flags");
    rowCountsBuf_ = cl::Buffer(ctx, size_t(H) * 2 * sizeof(int), CL_MEM_READ_WRITE, "second-order row counts");
    rowOffsets_ = cl::Buffer(ctx, size_t(H) * sizeof(int), CL_MEM_READ_WRITE, "second-order row offsets");
    list_ = cl::Buffer(ctx, size_t(capacity) * sizeof(int), CL_MEM_READ_WRITE, "second-order re-shade list");
    planes_ = cl::Buffer(ctx, size_t(capacity) * 6 * sizeof(float), CL_MEM_READ_WRITE, "second-order re-shade planes");
    ctx.fill(planes_, 0.0f);
    lowW_ = (W + 1) / 2;
    lowH_ = (H + 1) / 2;
    lowIrradiance_ = cl::Buffer(ctx, size_t(lowW_) * lowH_ * 16, CL_MEM_READ_WRITE, "second-order half-res irradiance");
    width_ = W;
    height_ = H;
    candidatesFor_ = -1;
  }
  flag_.args(W, H, g.visibility.depth, g.normal, g.instance, tauD, cosTauN, int(!multires), flags_);
  // Row-wise work-groups (blocks of one row, streamed) took 2/3 of the CPU time of 1 x 8 groups.
  ctx.launch(flag_, cl::NDRange::d2(cl::roundUp((W + vw - 1) / vw, 8), H, 8, 1), "second-order: flag pixels");
  rowCounts_.args(W, H, flags_, rowCountsBuf_);
  ctx.launch(rowCounts_, cl::NDRange::d1(cl::roundUp(H, 8), 8), "second-order: row counts");
  scanRows_.args(H, rowCountsBuf_, rowOffsets_, counters_);
  ctx.launch(scanRows_, cl::NDRange::d1(1, 1), "second-order: scan rows");

  if (M > 0) {
    if (candidatesFor_ != M) {
      int candidates = int(std::min<size_t>(pixels, size_t(std::max(64 * M, 4096))));
      candidates_ = ctx.upload(haltonScreenPixels(W, H, candidates), "second-order screen Halton pixels");
      candidateCount_ = candidates;
      picked_ = cl::Buffer(ctx, size_t(M) * sizeof(int), CL_MEM_READ_WRITE, "second-order negative pixels");
      candidatesFor_ = M;
    }
    pickNegative_.args(candidates_, candidateCount_, flags_, M, picked_, counters_);
    ctx.launch(pickNegative_, cl::NDRange::d1(1, 1), "second-order: negative lights");
    negative_.args(g.view, picked_, counters_, M, g.position, g.geoNormal, g.visibility.depth, dmin, positive,
                   lights_.vpls);
    ctx.launch(negative_, cl::NDRange::d1(cl::roundUp(M, 16), 16), "second-order: negative lights");
  }

  // Half resolution over every pixel, upsampled; or nothing (every surface pixel is re-shaded).
  if (multires) {
    if (rays && !visibleShadeLow_.get()) buildVisibilityKernels(ctx);
    cl::Kernel& shadeLow = rays ? visibleShadeLow_ : shadeLow_;
    shadeLow.args(W, H, lowW_, lowH_, g.position, g.normal, lights_.vpls, lightCount, lowIrradiance_);
    visibility_.setArgs(shadeLow, 9);
    ctx.launch(shadeLow, cl::NDRange::d2((lowW_ + vw - 1) / vw, cl::roundUp(lowH_, 8), 1, 8),
               rays ? "second-order: half resolution: shade + rays" : "second-order: half resolution: shade");
    GeometryTest t;
    t.tauZ = tauD;
    t.tauNDegrees = tauN;
    upsampler_->run(g, lowIrradiance_, 2, t, indirect);
  } else {
    ctx.fill(indirect, 0.0f);
  }

  // Full-resolution re-shading of the listed pixels.
  compact_.args(W, H, flags_, rowOffsets_, g.position, g.normal, capacity, list_, planes_);
  ctx.launch(compact_, cl::NDRange::d1(cl::roundUp(H, 8), 8), "second-order: re-shade list");
  if (rays && !visibleRefine_.get()) buildVisibilityKernels(ctx);
  cl::Kernel& refine = rays ? visibleRefine_ : refine_;
  refine.args(counters_, list_, planes_, capacity, lights_.vpls, lightCount, g.albedo, indirect);
  visibility_.setArgs(refine, 8);
  size_t items = size_t(capacity) / size_t(vw), local = vw > 1 ? 16 : 64;
  ctx.launch(refine, cl::NDRange::d1(cl::roundUp(items, local), local),
             rays ? "second-order: full-resolution shade + rays" : "second-order: full-resolution shade");
}

std::vector<TechniqueStatistic> SecondOrderTechnique::statistics(cl::Context& ctx) const {
  if (!counters_.get()) return {};
  std::vector<int> c = ctx.download<int>(counters_);
  const double surface = double(c[1]);
  return {{"second-order.reshaded_fraction", surface > 0 ? c[0] / surface : 0.0,
           "share of the surface pixels shaded at full resolution (1 without multi-resolution)"},
          {"second-order.reshaded_pixels", double(c[0]), "pixels shaded at full resolution"},
          {"second-order.negative_lights", negativeAsked_ > 0 ? double(c[2]) : 0.0, "negative lights placed (back-facing surface pixels found)"}};
}

void SecondOrderTechnique::buildVisibilityKernels(cl::Context& ctx) {
  visibleProgram_ = ctx.buildProgram("kernels/gi/second_order/second_order.cl", visibility_.defines());
  visibleRefine_ = visibleProgram_.kernel("so_refine");
  visibleShadeLow_ = visibleProgram_.kernel("so_shade_low");
}

std::vector<glm::vec4> haltonConeDirections(float cosAccept, int count) {
  std::vector<glm::vec4> out;
  out.reserve(count);
  for (uint32_t i = 1; int(out.size()) < count; ++i) {
    if (i > (1u << 22))
      throw Error("second-order: the light's cone (cos " + std::to_string(cosAccept) + ") is too narrow for " +
                  std::to_string(count) + " Halton points on the sphere; lower second-order.count");
    float z = 2.0f * radicalInverse(i, 3) - 1.0f;
    if (z < cosAccept) continue;
    float phi = float(kTwoPi) * radicalInverse(i, 2), r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    out.emplace_back(std::sin(phi) * r, std::cos(phi) * r, z, 0.0f);
  }
  return out;
}

std::vector<glm::vec4> haltonSquarePoints(int count) {
  std::vector<glm::vec4> out(count);
  for (int i = 0; i < count; ++i) out[i] = glm::vec4(radicalInverse(i + 1, 2), radicalInverse(i + 1, 3), 0.0f, 0.0f);
  return out;
}

std::vector<int> haltonScreenPixels(int width, int height, int count) {
  std::vector<int> out(count);
  for (int i = 0; i < count; ++i) {
    int x = std::min(int(radicalInverse(i + 1, 2) * float(width)), width - 1);
    int y = std::min(int(radicalInverse(i + 1, 3) * float(height)), height - 1);
    out[i] = y * width + x;
  }
  return out;
}

float acceptedConeCos(const GiLight& light, const GiView& rsmView) {
  float halfFov = std::atan(rsmView.texel_world_size * float(rsmView.height) * 0.5f);
  float c = std::cos(halfFov);
  return light.type == GI_LIGHT_SPOT ? std::max(light.cos_outer, c) : c;
}

std::vector<HostVpl> hostPlaceIndirectLights(const GiView& view, const std::vector<glm::vec4>& samples, float weight,
                                             const std::vector<glm::vec4>& position, const std::vector<glm::vec4>& normal,
                                             const std::vector<glm::vec4>& flux, float dminOverride) {
  const int res = view.width;
  const glm::vec3 eye(view.eye[0], view.eye[1], view.eye[2]);
  const glm::vec3 axis = -glm::vec3(view.view[2], view.view[6], view.view[10]);
  const glm::vec3 right(view.view[0], view.view[4], view.view[8]), up(view.view[1], view.view[5], view.view[9]);
  glm::mat4 viewProj;
  std::memcpy(&viewProj[0][0], view.view_proj, sizeof(viewProj));
  std::vector<HostVpl> out(samples.size());
  for (size_t k = 0; k < samples.size(); ++k) {
    glm::vec4 s = samples[k];
    int tx, ty;
    if (view.orthographic) {
      tx = std::clamp(int(s.x * float(res)), 0, res - 1);
      ty = std::clamp(int(s.y * float(res)), 0, res - 1);
    } else {
      glm::vec4 c = viewProj * glm::vec4(eye + s.x * right + s.y * up + s.z * axis, 1.0f);
      tx = std::clamp(int(std::floor((c.x / c.w * 0.5f + 0.5f) * float(res))), 0, res - 1);
      ty = std::clamp(int(std::floor((0.5f - c.y / c.w * 0.5f) * float(res))), 0, res - 1);
    }
    size_t t = size_t(ty) * res + tx;
    HostVpl& v = out[k];
    if (!(position[t].w > 0.0f)) {
      v.dmin2 = 1.0f;
      continue;
    }
    v.position = glm::vec3(position[t]);
    v.normal = glm::vec3(normal[t]);
    float scale = weight, footprint = view.texel_world_size;
    if (!view.orthographic) {
      glm::vec3 w = v.position - eye;
      float depth = glm::dot(w, axis), c = depth / glm::length(w);
      float omega = view.texel_world_size * view.texel_world_size * c * c * c;
      scale = omega > 0.0f ? weight / omega : 0.0f;
      footprint *= std::abs(depth);
    }
    v.flux = glm::vec3(flux[t]) * scale;
    float d = dminOverride > 0.0f ? dminOverride : 0.5f * footprint;
    v.dmin2 = d * d;
  }
  return out;
}

HostVpl hostNegativeLight(const std::vector<HostVpl>& positive, glm::vec3 x, glm::vec3 n, float z, const GiView& camera,
                          int surfacePixels, int found, float dminOverride) {
  glm::vec3 e(0.0f), dir(0.0f);
  for (const HostVpl& p : positive) {
    glm::vec3 v = x - p.position;
    float d2 = glm::dot(v, v);
    float g = std::max(glm::dot(p.normal, v), 0.0f) * std::max(glm::dot(n, v), 0.0f) /
              (std::max(d2, 1e-20f) * std::max(d2, p.dmin2));
    glm::vec3 c = p.flux * g;
    e += c;
    dir += (c.x * 0.2126f + c.y * 0.7152f + c.z * 0.0722f) * v / std::sqrt(std::max(d2, 1e-20f));
  }
  e *= kInvPi;
  glm::vec3 toEye = glm::vec3(camera.eye[0], camera.eye[1], camera.eye[2]) - x;
  float r = glm::length(toEye), s = camera.texel_world_size;
  float cosSurface = std::max(std::abs(glm::dot(n, toEye)) / r, 0.05f);
  float area = s * s * z * z * (z / r) / cosSurface;
  float len = glm::length(dir);
  HostVpl out;
  out.position = x;
  float d = dminOverride > 0.0f ? dminOverride : 0.5f * s * z;
  out.dmin2 = d * d;
  out.normal = len > 0.0f ? dir / len : glm::vec3(0.0f);
  out.flux = len > 0.0f ? -e * (area * float(surfacePixels) / float(found)) : glm::vec3(0.0f);
  return out;
}

TechniqueInfo secondOrderTechniqueInfo() {
  return {"second-order",
          "Cochran & Steele: Halton-placed indirect lights from the spot's RSM, negative lights for indirect occlusion, "
          "half-resolution shading with full-resolution re-shading at normal/depth discontinuities; visibility per vpl.visibility",
          [](ParamSet& p) {
            p.addInt("second-order.count", 256, 1, 4096, "indirect lights N per light (Halton points in the light's cone)");
            p.addInt("second-order.negative", -1, -1, 4096,
                     "negative lights M (Halton pixels over the screen); -1 = N/2, 0 = none (simple indirect "
                     "illumination); always 0 with vpl.visibility=rays");
            p.addChoice("second-order.placement", "halton", {"halton", "random", "flux"},
                        "indirect-light placement: halton (the paper), random (new uniform points every frame), "
                        "flux (the VPL generator's flux-importance sampling)");
            p.addInt("second-order.seed", 1, 0, 1000000, "seed of the random placement");
            p.addFloat("second-order.d_min", 0.0, 0.0, 100.0,
                       "distance clamp in metres; 0 = 0.5 x the RSM texel (indirect) or pixel (negative) footprint");
            p.addBool("second-order.multires", true, "half-resolution shading with full-resolution re-shading");
            p.addFloat("second-order.tau_n", 25.0, 0.0, 180.0, "re-shade when the shading normal differs by more (degrees)");
            p.addFloat("second-order.tau_d", 0.02, 0.0, 10.0, "re-shade when the view depth differs by more (relative)");
          },
          [] { return std::make_unique<SecondOrderTechnique>(); }};
}

}  // namespace gi
