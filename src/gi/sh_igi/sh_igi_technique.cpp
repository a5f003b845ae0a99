// `sh-igi` on the instant-radiosity machinery: VPLs from VplGenerator, the de-interleaved
// sub-images of InterleavedGather (with geometric normals), optional visibility rays
// (VplVisibility); its own passes project the incoming radiance into SH, re-interleave the 27
// coefficients and filter + shade them (kernels/gi/sh_igi/sh_igi.cl).
#include "gi/sh_igi/sh_igi_technique.h"

#include <cmath>
#include <map>
#include <memory>

#include "gi/vpl/vpl_lights.h"
#include "gi/vpl/vpl_visibility.h"

namespace gi {

namespace {

constexpr size_t kPad = 64;     // SH_PAD in the kernel
constexpr size_t kPlanes = 32;  // SH_PLANES: 27 coefficients, depth, geometric normal, instance id

class ShIgiTechnique : public Technique {
public:
  std::string name() const override { return "sh-igi"; }
  bool needsRsm() const override { return true; }
  bool deliversDirectLight(const ParamSet& p) const override { return p.getChoice("sh-igi.direct") == "vpl"; }
  void setup(const FrameResources& f) override {
    generator_ = std::make_unique<VplGenerator>(f.ctx, "sh-igi: vpl");
    gather_ = std::make_unique<InterleavedGather>(f.ctx, "sh-igi");
  }
  void render(const FrameResources& f, cl::Buffer& indirect) override {
    const ParamSet& p = f.params;
    const GBuffer& g = f.gbuffer;
    int n = p.getInt("sh-igi.n"), m = p.getInt("sh-igi.m");
    int fx = p.getInt("sh-igi.filter_x"), fy = p.getInt("sh-igi.filter_y");
    fx = fx > 0 ? fx : n;
    fy = fy > 0 ? fy : m;
    if (fx < n || fy < m)
      throw Error("sh-igi.filter_x/filter_y (" + std::to_string(fx) + "x" + std::to_string(fy) +
                  ") must be at least the pattern " + std::to_string(n) + "x" + std::to_string(m));
    generator_->generate(f.rsms, p.getInt("sh-igi.count"), p.getFloat("sh-igi.d_min"), vpls_, visibility_.bounces(f));
    gather_->resize(g.width, g.height, n, m);
    visibility_.update(f);
    Programs& prog = programs(f, fx, fy);

    size_t coeffBytes = gather_->slots() * 27 * 4;
    if (!coeffs_ || coeffs_.bytes() != coeffBytes) {
      coeffs_ = cl::Buffer(f.ctx, coeffBytes, CL_MEM_READ_WRITE, "sh-igi sub-image SH coefficients");
      f.ctx.fill(coeffs_, 0.0f);
    }
    size_t P = size_t(g.width) * g.height + 2 * kPad;
    if (!planes_ || planes_.bytes() != P * kPlanes * 4) {
      planes_ = cl::Buffer(f.ctx, P * kPlanes * 4, CL_MEM_READ_WRITE, "sh-igi filter planes");
      f.ctx.fill(planes_, 0.0f);  // margins: never read by an accepted neighbour (x/y masks)
    }

    gather_->deinterleave(g, /*geometricNormal=*/true);
    int direct = deliversDirectLight(p) ? 1 : 0;
    cl::Kernel& project = visibility_.enabled() ? prog.projectVisible : prog.project;
    project.args(gather_->planes(), n * m, gather_->stride(), vpls_.vpls, vpls_.count, direct, f.deviceScene.lights,
                 int(f.scene.lights.size()), f.shadowMaps.viewTable, f.shadowMaps.offsetTable, f.shadowMaps.depths,
                 coeffs_);
    visibility_.setArgs(project, 12);
    size_t items = gather_->slots() / size_t(f.ctx.vectorWidth());
    size_t local = f.ctx.vectorWidth() > 1 ? 4 : 64;
    f.ctx.launch(project, cl::NDRange::d1(cl::roundUp(items, local), local),
                 visibility_.enabled() ? "sh-igi: project + rays" : "sh-igi: project");

    prog.prepare.args(g.width, g.height, n, m, gather_->subWidth(), gather_->stride(), coeffs_, g.visibility.depth,
                      g.geoNormal, g.instance, planes_);
    f.ctx.launch(prog.prepare, cl::NDRange::d2(cl::roundUp(g.width, 16), cl::roundUp(g.height, 16), 16, 16),
                 "sh-igi: re-interleave");

    float cosTauN = std::cos(p.getFloat("sh-igi.tau_n") * 3.14159265f / 180.0f);
    prog.filter.args(g.width, g.height, planes_, g.position, g.normal, g.albedo, g.specular, g.view,
                     p.getFloat("sh-igi.tau_z"), cosTauN, int(p.getBool("sh-igi.same_instance")),
                     int(p.getBool("sh-igi.glossy")), indirect);
    int vw = f.ctx.vectorWidth();
    size_t gx = (size_t(g.width) + vw - 1) / vw;
    if (vw == 1)
      f.ctx.launch(prog.filter, cl::NDRange::d2(cl::roundUp(gx, 16), cl::roundUp(g.height, 16), 16, 16),
                   "sh-igi: filter + shade");
    else
      f.ctx.launch(prog.filter, cl::NDRange::d2(gx, cl::roundUp(g.height, 8), 1, 8), "sh-igi: filter + shade");
  }

private:
  struct Programs {
    cl::Program program, visibleProgram;
    cl::Kernel project, projectVisible, prepare, filter;
  };
  // One program per filter window (compile-time GI_FX, GI_FY); the visibility variant of the
  // projection is built the first time rays are asked for.
  Programs& programs(const FrameResources& f, int fx, int fy) {
    auto key = std::make_pair(fx, fy);
    auto it = programs_.find(key);
    if (it == programs_.end()) {
      Programs p;
      p.program = f.ctx.buildProgram("kernels/gi/sh_igi/sh_igi.cl",
                                     {{"GI_FX", std::to_string(fx)}, {"GI_FY", std::to_string(fy)}});
      p.project = p.program.kernel("sh_igi_project");
      p.prepare = p.program.kernel("sh_igi_prepare");
      p.filter = p.program.kernel("sh_igi_filter_shade");
      it = programs_.emplace(key, std::move(p)).first;
    }
    Programs& p = it->second;
    if (visibility_.enabled() && !p.projectVisible.get()) {
      cl::Defines d = visibility_.defines();
      d.push_back({"GI_FX", std::to_string(fx)});
      d.push_back({"GI_FY", std::to_string(fy)});
      p.visibleProgram = f.ctx.buildProgram("kernels/gi/sh_igi/sh_igi.cl", d);
      p.projectVisible = p.visibleProgram.kernel("sh_igi_project");
    }
    return p;
  }

  std::unique_ptr<VplGenerator> generator_;
  std::unique_ptr<InterleavedGather> gather_;
  std::map<std::pair<int, int>, Programs> programs_;
  VplVisibility visibility_;
  VplSet vpls_;
  cl::Buffer coeffs_, planes_;
};

}  // namespace

TechniqueInfo shIgiTechniqueInfo() {
  return {"sh-igi",
          "interleaved VPL gathering of incoming radiance as 9 SH coefficients per channel, 27-channel discontinuity "
          "filter, Lambert + Phong zonal shading at the per-pixel (normal-mapped) normal; visibility per vpl.visibility",
          [](ParamSet& p) {
            p.addInt("sh-igi.count", 256, 1, 4096, "VPLs per light, split into n*m sets (VPL k -> set k mod n*m)");
            p.addFloat("sh-igi.d_min", 0.0, 0.0, 100.0, "distance clamp in metres; 0 = 0.5 x RSM texel footprint");
            p.addInt("sh-igi.n", 4, 1, 8, "interleave pattern width");
            p.addInt("sh-igi.m", 4, 1, 8, "interleave pattern height");
            p.addInt("sh-igi.filter_x", 0, 0, 16, "SH filter window width; 0 = n (must be >= n)");
            p.addInt("sh-igi.filter_y", 0, 0, 16, "SH filter window height; 0 = m (must be >= m)");
            p.addFloat("sh-igi.tau_z", 0.05, 0.0, 10.0, "filter: relative view-depth tolerance");
            p.addFloat("sh-igi.tau_n", 25.0, 0.0, 180.0, "filter: geometric-normal tolerance in degrees");
            p.addBool("sh-igi.same_instance", true, "filter: neighbours must share the instance id");
            p.addBool("sh-igi.glossy", true, "add the Phong-lobe (specular) term at the reflected view vector");
            p.addChoice("sh-igi.direct", "raster", {"raster", "vpl"},
                        "direct light: raster = the rasterized direct pass; vpl = every punctual light enters each "
                        "pixel's SH as one more source (shadow-mapped) and is filtered and shaded with the VPLs");
          },
          [] { return std::make_unique<ShIgiTechnique>(); }};
}

}  // namespace gi
