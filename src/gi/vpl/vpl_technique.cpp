// `vpl`: all-pairs VPL gathering (docs/techniques/vpl.md).
// `igi`: the same gather with interleaved sampling + discontinuity filter (docs/techniques/igi.md).
// Both without visibility unless `vpl.visibility=rays` (gi/vpl/vpl_visibility.h).
#include <memory>

#include "gi/filters/discontinuity_filter.h"
#include "gi/vpl/techniques.h"
#include "gi/vpl/vpl_lights.h"

namespace gi {

namespace {

class VplTechnique : public Technique {
public:
  std::string name() const override { return "vpl"; }
  bool needsRsm() const override { return true; }
  void setup(const FrameResources& f) override {
    generator_ = std::make_unique<VplGenerator>(f.ctx, "vpl");
    gather_ = std::make_unique<InterleavedGather>(f.ctx, "vpl");
  }
  void render(const FrameResources& f, cl::Buffer& indirect) override {
    generator_->generate(f.rsms, f.params.getInt("vpl.count"), f.params.getFloat("vpl.d_min"), vpls_,
                         visibility_.bounces(f));
    visibility_.update(f);
    if (f.params.getBool("vpl.specular")) {
      brdfGather(f, indirect);
      return;
    }
    gather_->resize(f.gbuffer.width, f.gbuffer.height, 1, 1);
    gather_->shadeCameraOrder(f.gbuffer, vpls_, &visibility_, true, indirect);
  }

private:
  // vpl.specular: kernels/gi/vpl/vpl_brdf_gather.cl, the same all-pairs sum with the receivers' full
  // BRDF (Lambert + GGX), one shadow ray per facing pair for both terms.
  void brdfGather(const FrameResources& f, cl::Buffer& indirect) {
    bool rays = visibility_.enabled();
    cl::Kernel& k = rays ? brdfVisible_ : brdf_;
    if (!k.get()) {
      cl::Program& program = rays ? brdfVisibleProgram_ : brdfProgram_;
      program = f.ctx.buildProgram("kernels/gi/vpl/vpl_brdf_gather.cl", visibility_.defines());
      k = program.kernel("vpl_brdf_gather");
    }
    const GBuffer& g = f.gbuffer;
    int pixels = g.width * g.height;
    k.args(pixels, g.view, g.position, g.normal, g.albedo, g.specular, vpls_.vpls, vpls_.count, indirect);
    visibility_.setArgs(k, 9);
    size_t items = (size_t(pixels) + f.ctx.vectorWidth() - 1) / f.ctx.vectorWidth();
    f.ctx.launch(k, cl::NDRange::d1(cl::roundUp(items, 16), 16), rays ? "vpl: shade brdf + rays" : "vpl: shade brdf");
  }

  std::unique_ptr<VplGenerator> generator_;
  std::unique_ptr<InterleavedGather> gather_;
  VplVisibility visibility_;
  VplSet vpls_;
  cl::Program brdfProgram_, brdfVisibleProgram_;
  cl::Kernel brdf_, brdfVisible_;
};

class IgiTechnique : public Technique {
public:
  std::string name() const override { return "igi"; }
  bool needsRsm() const override { return true; }
  void setup(const FrameResources& f) override {
    generator_ = std::make_unique<VplGenerator>(f.ctx, "igi: vpl");
    gather_ = std::make_unique<InterleavedGather>(f.ctx, "igi");
    filter_ = std::make_unique<DiscontinuityFilter>(f.ctx, "igi: discontinuity filter");
  }
  void render(const FrameResources& f, cl::Buffer& indirect) override {
    const ParamSet& p = f.params;
    int n = p.getInt("igi.n"), m = p.getInt("igi.m");
    int fx = p.getInt("igi.filter_x"), fy = p.getInt("igi.filter_y");
    fx = fx > 0 ? fx : n;
    fy = fy > 0 ? fy : m;
    if (fx < n || fy < m)
      throw Error("igi.filter_x/filter_y (" + std::to_string(fx) + "x" + std::to_string(fy) +
                  ") must be at least the pattern " + std::to_string(n) + "x" + std::to_string(m));
    generator_->generate(f.rsms, p.getInt("igi.count"), p.getFloat("igi.d_min"), vpls_, visibility_.bounces(f));
    gather_->resize(f.gbuffer.width, f.gbuffer.height, n, m);
    size_t bytes = size_t(f.gbuffer.width) * f.gbuffer.height * 16;
    if (!irradiance_ || irradiance_.bytes() != bytes)
      irradiance_ = cl::Buffer(f.ctx, bytes, CL_MEM_READ_WRITE, "igi irradiance");
    visibility_.update(f);
    gather_->shadeCameraOrder(f.gbuffer, vpls_, &visibility_, false, irradiance_);
    GeometryTest t;
    t.tauZ = p.getFloat("igi.tau_z");
    t.tauNDegrees = p.getFloat("igi.tau_n");
    t.sameInstance = p.getBool("igi.same_instance");
    filter_->run(f.gbuffer, irradiance_, fx, fy, t, indirect, filterShapeFromName(p.getChoice("igi.filter")));
  }

private:
  std::unique_ptr<VplGenerator> generator_;
  std::unique_ptr<InterleavedGather> gather_;
  std::unique_ptr<DiscontinuityFilter> filter_;
  VplVisibility visibility_;
  VplSet vpls_;
  cl::Buffer irradiance_;
};

}  // namespace

TechniqueInfo vplTechniqueInfo() {
  return {"vpl", "all-pairs VPL gathering from flux-sampled RSM texels, visibility per vpl.visibility (instant radiosity)",
          [](ParamSet& p) {
            declareVplVisibilityParams(p);
            p.addInt("vpl.count", 256, 1, 4096, "VPLs per light (Halton-stratified, flux-importance-sampled)");
            p.addFloat("vpl.d_min", 0.0, 0.0, 100.0,
                       "distance clamp of the 1/d² term in metres; 0 = 0.5 x the RSM texel footprint at each VPL");
            p.addBool("vpl.specular", false,
                      "gather with the receivers' full BRDF, Lambert + GGX lobe (kernels/gi/vpl/vpl_brdf_gather.cl); "
                      "false = the diffuse gather of ALGORITHMS.md §2");
          },
          [] { return std::make_unique<VplTechnique>(); }};
}

TechniqueInfo igiTechniqueInfo() {
  return {"igi", "interleaved VPL gathering (n x m VPL sets on de-interleaved sub-images) + discontinuity filter, visibility per vpl.visibility",
          [](ParamSet& p) {
            p.addInt("igi.count", 256, 1, 4096, "VPLs per light, split into n*m sets (VPL k -> set k mod n*m)");
            p.addFloat("igi.d_min", 0.0, 0.0, 100.0, "distance clamp in metres; 0 = 0.5 x RSM texel footprint");
            p.addInt("igi.n", 4, 1, 8, "interleave pattern width");
            p.addInt("igi.m", 4, 1, 8, "interleave pattern height");
            p.addInt("igi.filter_x", 0, 0, 16, "discontinuity filter window width; 0 = n (must be >= n)");
            p.addInt("igi.filter_y", 0, 0, 16, "discontinuity filter window height; 0 = m (must be >= m)");
            p.addChoice("igi.filter", "box", {"box", "separable"},
                        "discontinuity filter: box = the 2D window in one pass (Segovia); separable = a row pass "
                        "then a column pass (the thesis's separable blur; filter_x + filter_y taps)");
            p.addFloat("igi.tau_z", 0.05, 0.0, 10.0, "filter: relative view-depth tolerance");
            p.addFloat("igi.tau_n", 25.0, 0.0, 180.0, "filter: geometric-normal tolerance in degrees");
            p.addBool("igi.same_instance", false, "filter: neighbours must share the instance id");
          },
          [] { return std::make_unique<IgiTechnique>(); }};
}

}  // namespace gi
