// `rsm`: RSM gather (Dachsbacher & Stamminger 2005; ALGORITHMS.md §2.1) at reduced resolution
// with geometry-aware upsampling (§3). docs/techniques/rsm.md.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <tuple>

#include "cl/gather_width.h"
#include "cl/tile_groups.h"
#include "util/halton.h"
#include "gi/filters/discontinuity_filter.h"
#include "gi/rsm/rsm_technique.h"

namespace gi {

namespace {

constexpr int kRowsPerItem = 4;       // GI_RSM_ROWS of kernels/gi/rsm/rsm_gather.cl
constexpr int kBlockWidth = 8;        // GI_RSM_BLOCK_W: a sample-centre block is 8 × kRowsPerItem low-res pixels
constexpr float kSampleBand = 8.0f;  // texels: band height of the sample order (see render())

class RsmTechnique : public Technique {
public:
  std::string name() const override { return "rsm"; }
  bool needsRsm() const override { return true; }
  void setup(const FrameResources& f) override {
    upsampler_ = std::make_unique<GeometryAwareUpsampler>(f.ctx, "rsm: upsample");
  }
  void render(const FrameResources& f, cl::Buffer& indirect) override {
    const ParamSet& p = f.params;
    int down = p.getInt("rsm.downsample");
    int samples = p.getInt("rsm.samples");
    float radius = p.getFloat("rsm.radius");
    bool xi2 = p.getChoice("rsm.weights") == "xi2";
    bool block = p.getChoice("rsm.sample_centre") == "block";
    int tolerance = p.getInt("rsm.block_tolerance");
    if (down != down_) {
      cl::Defines defs = {{"GI_DOWN", std::to_string(down)}, {"GI_RSM_ROWS", std::to_string(kRowsPerItem)},
                          {"GI_RSM_BLOCK_W", std::to_string(kBlockWidth)}};
      program_ = f.ctx.buildProgram("kernels/gi/rsm/rsm_gather.cl", cl::withGatherWidth(f.ctx, defs));
      pack_ = program_.kernel("rsm_pack");
      gatherOrtho_ = program_.kernel("rsm_gather_ortho");
      gatherPerspective_ = program_.kernel("rsm_gather_perspective");
      down_ = down;
    }
    if (block && blockDown_ != down) {
      // Block centres: a work-item's lanes lie in one block, so at most kBlockWidth lanes (8 on
      // AVX-512 CPUs, whose gather width is 16).
      blockWidthLanes_ = std::min(cl::gatherVectorWidth(f.ctx), kBlockWidth);
      cl::Defines defs = {{"GI_DOWN", std::to_string(down)}, {"GI_RSM_ROWS", std::to_string(kRowsPerItem)},
                          {"GI_RSM_BLOCK_W", std::to_string(kBlockWidth)}, {"GI_VW", std::to_string(blockWidthLanes_)}};
      blockProgram_ = f.ctx.buildProgram("kernels/gi/rsm/rsm_gather.cl", defs);
      blockOrtho_ = blockProgram_.kernel("rsm_gather_block_ortho");
      blockPerspective_ = blockProgram_.kernel("rsm_gather_block_perspective");
      blockDown_ = down;
    }
    const GBuffer& g = f.gbuffer;
    int lw = (g.width + down - 1) / down, lh = (g.height + down - 1) / down;
    if (!low_ || low_.bytes() != size_t(lw) * lh * 16) low_ = cl::Buffer(f.ctx, size_t(lw) * lh * 16, CL_MEM_READ_WRITE, "rsm low-res irradiance");
    if (f.rsms.empty()) {
      f.ctx.fill(indirect, 0.0f);
      return;
    }
    int res = f.rsms[0].view.width;
    float inner = block ? p.getFloat("rsm.block_inner") : 0.0f;
    if (samples != samples_ || radius != radius_ || res != res_ || xi2 != xi2_ || inner != inner_) {
      std::vector<float> offsets(size_t(samples) * 2), weights(samples);
      float rmax = radius * float(res);
      for (int i = 0; i < samples; ++i) {
        float x1 = radicalInverse(uint32_t(i) + 1, 2), x2 = radicalInverse(uint32_t(i) + 1, 3);
        offsets[2 * i] = rmax * x1 * std::sin(6.2831853f * x2);
        offsets[2 * i + 1] = rmax * x1 * std::cos(6.2831853f * x2);
        weights[i] = xi2 ? 3.14159265f * rmax * rmax * 3.0f * x1 * x1 / float(samples)
                         : 6.2831853f * rmax * rmax * x1 / float(samples);
      }
      // Sample order (the sum does not depend on it): serpentine over bands kSampleBand texels
      // high, so consecutive samples read nearby texels and a work-item's 32 pixels find part of
      // the next sample's records still in L1 (−12 % gather time on Sponza, docs/PERFORMANCE.md).
      std::vector<int> order(samples);
      for (int i = 0; i < samples; ++i) order[i] = i;
      // Block centres: the samples of radius < rsm.block_inner × r_max (ξ1 < block_inner) come
      // first, each group in that order; they stay around every pixel's own projection.
      auto key = [&](int i) {
        int band = int(std::floor(offsets[2 * i + 1] / kSampleBand));
        bool outer = radicalInverse(uint32_t(i) + 1, 2) >= inner;
        return std::tuple<bool, int, float>(outer, band, (band & 1) ? -offsets[2 * i] : offsets[2 * i]);
      };
      std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return key(a) < key(b); });
      std::vector<float> sortedOffsets(offsets.size()), sortedWeights(weights.size());
      // Block centres: the pattern around the centre texel's middle, texel c + floor(o + ½).
      std::vector<int32_t> blockOffsets(offsets.size());
      for (int i = 0; i < samples; ++i) {
        sortedOffsets[2 * i] = offsets[2 * order[i]];
        sortedOffsets[2 * i + 1] = offsets[2 * order[i] + 1];
        sortedWeights[i] = weights[order[i]];
        blockOffsets[2 * i] = int32_t(std::floor(sortedOffsets[2 * i] + 0.5f));
        blockOffsets[2 * i + 1] = int32_t(std::floor(sortedOffsets[2 * i + 1] + 0.5f));
      }
      offsets.swap(sortedOffsets);
      weights.swap(sortedWeights);
      offsets_ = f.ctx.upload(offsets, "rsm sample offsets");
      weights_ = f.ctx.upload(weights, "rsm sample weights");
      blockOffsets_ = f.ctx.upload(blockOffsets, "rsm block sample offsets");
      samples_ = samples;
      radius_ = radius;
      res_ = res;
      xi2_ = xi2;
      inner_ = inner;
      innerSamples_ = 0;
      for (int i = 0; i < samples; ++i) innerSamples_ += radicalInverse(uint32_t(i) + 1, 2) < inner;
      // The largest offset component: receivers this far inside the RSM need no texel clamps.
      sampleReach_ = 0.0f;
      for (float o : offsets) sampleReach_ = std::max(sampleReach_, std::fabs(o));
    }
    int vw = cl::gatherVectorWidth(f.ctx);
    for (size_t l = 0; l < f.rsms.size(); ++l) {
      const ReflectiveShadowMap& r = f.rsms[l];
      size_t gy = (size_t(lh) + kRowsPerItem - 1) / kRowsPerItem;
      // The RSM as 16-byte records with a one-texel border (kernels/gi/rsm/rsm_gather.cl).
      size_t res = size_t(r.view.width), pitch = res + 2;
      if (!records_ || records_.bytes() != pitch * pitch * 16) {
        records_ = cl::Buffer(f.ctx, pitch * pitch * 16, CL_MEM_READ_WRITE, "rsm packed records");
        // The border keeps these (depth 1, zero flux and normal); rsm_pack writes the interior.
        const float one = 1.0f;
        uint32_t border[4] = {0, 0, 0, 0};
        std::memcpy(&border[0], &one, 4);
        f.ctx.fill(records_, border, sizeof(border));
      }
      pack_.args(r.view, r.position, r.normal, r.flux, records_);
      // Work-groups along a row: PoCL runs a group's work-items one after another, so the three
      // RSM planes are read as one stream each.
      const size_t lx = 16, ly = vw == 1 ? 16 : 1;
      f.ctx.launch(pack_, cl::NDRange::d2(cl::roundUp((res + vw - 1) / vw, lx), cl::roundUp(res, ly), lx, ly), "rsm: pack");
      cl::Kernel& gather = block ? (r.view.orthographic ? blockOrtho_ : blockPerspective_)
                                 : (r.view.orthographic ? gatherOrtho_ : gatherPerspective_);
      gather.args(g.width, g.height, lw, lh, g.position, g.normal, r.view, records_, samples, offsets_, weights_,
                  blockOffsets_, tolerance, innerSamples_, p.getFloat("rsm.d_min"), sampleReach_, int(l > 0), low_);
      size_t gx = (size_t(lw) + (block ? blockWidthLanes_ : vw) - 1) / (block ? blockWidthLanes_ : vw);
      // 4 × 4 work-items per group, fewer where PoCL's threads could not share the groups evenly
      // (half of 640 × 360 on 2 threads: 60 or 120 groups of 4 × 4, now 2 × 1 or 2 × 2; cl/tile_groups.h).
      f.ctx.launch(gather, cl::balancedTileGroups(f.ctx.device(), gx, gy, 4, 4), "rsm: gather");
    }
    GeometryTest t;
    t.tauZ = p.getFloat("rsm.tau_z");
    t.tauNDegrees = p.getFloat("rsm.tau_n");
    upsampler_->run(g, low_, down, t, indirect);
  }

private:
  std::unique_ptr<GeometryAwareUpsampler> upsampler_;
  cl::Program program_, blockProgram_;
  cl::Kernel pack_, gatherOrtho_, gatherPerspective_, blockOrtho_, blockPerspective_;
  cl::Buffer low_, offsets_, weights_, blockOffsets_, records_;
  int down_ = 0, blockDown_ = 0, samples_ = 0, res_ = 0, blockWidthLanes_ = 0;
  float radius_ = 0, inner_ = -1;
  int innerSamples_ = 0;
  float sampleReach_ = 0.0f;
  bool xi2_ = false;
};

}  // namespace

TechniqueInfo rsmTechniqueInfo() {
  return {"rsm", "RSM gather (Dachsbacher & Stamminger 2005) at reduced resolution + geometry-aware upsampling, no visibility",
          [](ParamSet& p) {
            p.addInt("rsm.samples", 400, 1, 4096, "RSM samples per pixel (Halton 2,3 disc pattern, same for every pixel)");
            p.addFloat("rsm.radius", 0.1, 0.001, 1.0, "sampling disc radius r_max as a fraction of the RSM width");
            p.addInt("rsm.downsample", 2, 1, 8, "evaluate at 1/downsample resolution, then upsample geometry-aware");
            p.addFloat("rsm.d_min", 0.0, 0.0, 100.0, "distance clamp in metres; 0 = 0.5 x RSM texel footprint");
            p.addChoice("rsm.weights", "xi", {"xi", "xi2"},
                        "sample weights: xi = unbiased 2*pi*r^2*xi1/N; xi2 = the paper's xi1^2 (normalised, biased)");
            p.addChoice("rsm.sample_centre", "pixel", {"pixel", "block"},
                        "sampling-pattern centre: pixel = each pixel's own RSM projection (the paper); block = one "
                        "texel per 8 x 4 low-res pixels (one record per sample for all of them)");
            p.addInt("rsm.block_tolerance", 4, 0, 1000,
                     "block centres: pixels projecting more than this many texels (in x or y) from the block's "
                     "centre texel use their own centre");
            p.addFloat("rsm.block_inner", 0.0, 0.0, 1.0,
                       "block centres: samples of radius below this fraction of r_max stay around each pixel's "
                       "own projection");
            p.addFloat("rsm.tau_z", 0.05, 0.0, 10.0, "upsampling: relative view-depth tolerance");
            p.addFloat("rsm.tau_n", 25.0, 0.0, 180.0, "upsampling: geometric-normal tolerance in degrees");
          },
          [] { return std::make_unique<RsmTechnique>(); }};
}

}  // namespace gi
