// `splat`: splatting indirect illumination (Dachsbacher & Stamminger 2006; ALGORITHMS.md §2.4)
// as tiled VPL culling — kernels/gi/splat/splat.cl. docs/techniques/splat.md.
#include <memory>

#include "gi/filters/discontinuity_filter.h"
#include "gi/splat/splat_technique.h"
#include "gi/vpl/vpl_lights.h"
#include "gi/vpl/vpl_visibility.h"

namespace gi {

namespace {

constexpr int kTile = 16;

class SplatTechnique : public Technique {
public:
  std::string name() const override { return "splat"; }
  bool needsRsm() const override { return true; }
  void setup(const FrameResources& f) override {
    generator_ = std::make_unique<VplGenerator>(f.ctx, "splat: vpl");
    program_ = f.ctx.buildProgram("kernels/gi/splat/splat.cl");
    bounds_ = program_.kernel("splat_bounds");
    bin_ = program_.kernel("splat_bin");
    shade_ = program_.kernel("splat_shade");
    filter_ = std::make_unique<DiscontinuityFilter>(f.ctx, "splat: discontinuity filter");
  }
  void render(const FrameResources& f, cl::Buffer& indirect) override {
    const ParamSet& p = f.params;
    float eps = p.getFloat("splat.epsilon");
    generator_->generate(f.rsms, p.getInt("splat.count"), p.getFloat("splat.d_min"), vpls_, visibility_.bounces(f));
    const GBuffer& g = f.gbuffer;
    int n = p.getInt("splat.n"), m = p.getInt("splat.m"), sets = n * m;
    int ordering = p.getChoice("splat.ordering") == "stride" ? 0 : 1;
    bool interleaved = sets > 1;
    // Interleaved: tiles 16n pixels wide, so that a work-item's GI_VW lanes of one pixel class
    // (x stride n) stay in one tile (kernels/gi/splat/splat.cl).
    int tileWidth = kTile * n;
    int tilesX = (g.width + tileWidth - 1) / tileWidth, tilesY = (g.height + kTile - 1) / kTile;
    int count = std::max(vpls_.count, 1), perSet = (count + sets - 1) / sets;
    size_t listEntries = size_t(tilesX) * tilesY * sets * perSet;
    if (listEntries != listEntries_ || count != capacity_ || size_t(tilesX) * tilesY * sets != tileSets_) {
      rects_ = cl::Buffer(f.ctx, size_t(count) * 16, CL_MEM_READ_WRITE, "splat VPL tile rectangles");
      lists_ = cl::Buffer(f.ctx, listEntries * 4, CL_MEM_READ_WRITE, "splat (tile, set) lists");
      counts_ = cl::Buffer(f.ctx, size_t(tilesX) * tilesY * sets * 4, CL_MEM_READ_WRITE, "splat (tile, set) counts");
      capacity_ = count;
      listEntries_ = listEntries;
      tileSets_ = size_t(tilesX) * tilesY * sets;
    }
    if (vpls_.count == 0) {
      f.ctx.fill(indirect, 0.0f);
      return;
    }
    bounds_.args(g.view, vpls_.vpls, vpls_.count, eps, tileWidth, tilesX, tilesY, rects_);
    f.ctx.launch(bounds_, cl::NDRange::d1(cl::roundUp(vpls_.count, 64), 64), "splat: bounds");
    bin_.args(rects_, vpls_.count, tilesX, tilesY, sets, ordering, perSet, lists_, counts_);
    f.ctx.launch(bin_, cl::NDRange::d1(cl::roundUp(tileSets_, 16), 16), "splat: bin");
    int vw = f.ctx.vectorWidth();
    size_t bytes = size_t(g.width) * g.height * 16;
    if (interleaved && (!irradiance_ || irradiance_.bytes() != bytes))
      irradiance_ = cl::Buffer(f.ctx, bytes, CL_MEM_READ_WRITE, "splat irradiance");
    visibility_.update(f);
    if (visibility_.enabled() && !visibleShade_.get()) {
      visibleProgram_ = f.ctx.buildProgram("kernels/gi/splat/splat.cl", visibility_.defines());
      visibleShade_ = visibleProgram_.kernel("splat_shade");
    }
    cl::Kernel& shade = visibility_.enabled() ? visibleShade_ : shade_;
    shade.args(g.width, g.height, tilesX, g.position, g.normal, g.albedo, vpls_.vpls, eps, lists_,
               counts_, n, m, perSet, interleaved ? irradiance_ : indirect);
    visibility_.setArgs(shade, 14);
    size_t gx = size_t(tilesX) * n * (kTile / vw);  // per tile row: n pixel classes × kTile/vw lane chunks
    size_t lx = vw == 1 ? 16 : 1;
    f.ctx.launch(shade, cl::NDRange::d2(gx, size_t(tilesY) * kTile, lx, 16),
                 visibility_.enabled() ? "splat: shade + rays" : "splat: shade");
    if (interleaved) {
      GeometryTest t;
      t.tauZ = p.getFloat("splat.tau_z");
      t.tauNDegrees = p.getFloat("splat.tau_n");
      filter_->run(g, irradiance_, n, m, t, indirect, filterShapeFromName(p.getChoice("splat.filter")));
    }
  }

private:
  std::unique_ptr<VplGenerator> generator_;
  cl::Program program_;
  cl::Kernel bounds_, bin_, shade_;
  cl::Program visibleProgram_;  // splat_shade with visibility rays, built when first asked for
  cl::Kernel visibleShade_;
  VplVisibility visibility_;
  cl::Buffer rects_, lists_, counts_, irradiance_;
  std::unique_ptr<DiscontinuityFilter> filter_;
  VplSet vpls_;
  int capacity_ = 0;
  size_t listEntries_ = 0, tileSets_ = 0;
};

}  // namespace

TechniqueInfo splatTechniqueInfo() {
  return {"splat", "splatting indirect illumination as tiled VPL culling (influence radius d_min/sqrt(eps)), visibility per vpl.visibility",
          [](ParamSet& p) {
            p.addInt("splat.count", 256, 1, 4096, "VPLs per light");
            p.addFloat("splat.epsilon", 1.0 / 256.0, 1e-12, 1.0,
                       "cut-off: a VPL is dropped where E_p < epsilon x its value at d_min (radius d_min/sqrt(eps))");
            p.addFloat("splat.d_min", 0.0, 0.0, 100.0, "distance clamp in metres; 0 = 0.5 x RSM texel footprint");
            p.addInt("splat.n", 1, 1, 8, "interleave pattern width (1 x 1 = not interleaved)");
            p.addInt("splat.m", 1, 1, 8, "interleave pattern height");
            p.addChoice("splat.ordering", "stride", {"stride", "contiguous"},
                        "VPL-to-set assignment: stride = k mod n*m (Halton order), contiguous = consecutive blocks");
            p.addChoice("splat.filter", "box", {"box", "separable"},
                        "discontinuity filter (interleaved): box = 2D window; separable = row pass then column pass");
            p.addFloat("splat.tau_z", 0.05, 0.0, 10.0, "filter (interleaved): relative view-depth tolerance");
            p.addFloat("splat.tau_n", 25.0, 0.0, 180.0, "filter (interleaved): geometric-normal tolerance in degrees");
          },
          [] { return std::make_unique<SplatTechnique>(); }};
}

}  // namespace gi
