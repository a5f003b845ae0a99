// `sh-igi` on the instant-radiosity machinery: VPLs from VplGenerator, optional visibility rays
// (VplVisibility); its own passes project the incoming radiance into SH straight from the camera
// G-buffer (each lane's VPL set from a per-frame lane table) and filter + shade the 27 coefficients
// in camera order (kernels/gi/sh_igi/sh_igi.cl).
#include "gi/sh_igi/sh_igi_technique.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include "cl/gather_width.h"
#include "gi/vpl/vpl_lights.h"
#include "gi/vpl/vpl_visibility.h"

namespace gi {

namespace {

constexpr int kShIgiVplAttributes = 10;  // SH_VPL_ATTRS of the kernels' VPL lane table

class ShIgiTechnique : public Technique {
public:
  std::string name() const override { return "sh-igi"; }
  bool needsRsm() const override { return true; }
  bool deliversDirectLight(const ParamSet& p) const override { return p.getChoice("sh-igi.direct") == "vpl"; }
  void setup(const FrameResources& f) override {
    generator_ = std::make_unique<VplGenerator>(f.ctx, "sh-igi: vpl");
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
    visibility_.update(f);
    Programs& prog = programs(f, fx, fy);

    ShIgiPlanes layout(g.width, g.height);
    if (!planes_ || planes_.bytes() != layout.bytes()) {
      planes_ = cl::Buffer(f.ctx, layout.bytes(), CL_MEM_READ_WRITE, "sh-igi filter planes");
      f.ctx.fill(planes_, 0.0f);  // margins: only ever read by neighbours the x/y tests reject
    }

    // The VPL lane table: iteration k of lane phase ph holds VPL set_l + n·m·k of every lane l.
    const int sets = n * m, iterations = (vpls_.count + sets - 1) / sets;
    const size_t tableBytes = std::max<size_t>(1, size_t(sets) * iterations * kShIgiVplAttributes) *
                              size_t(shIgiVectorWidth(f.ctx)) * sizeof(float);
    if (!vplLanes_ || vplLanes_.bytes() < tableBytes)
      vplLanes_ = cl::Buffer(f.ctx, tableBytes, CL_MEM_READ_WRITE, "sh-igi vpl lanes");
    if (iterations > 0) {
      prog.vplLanes.args(n, m, vpls_.count, iterations, vpls_.vpls, vplLanes_);
      f.ctx.launch(prog.vplLanes, cl::NDRange::d1(cl::roundUp(size_t(sets) * iterations, 16), 16),
                   "sh-igi: vpl lanes");
    }

    int direct = deliversDirectLight(p) ? 1 : 0;
    cl::Kernel& project = visibility_.enabled() ? prog.projectVisible : prog.project;
    project.args(g.width, g.height, n, m, layout.pitch, layout.pad, g.position, g.geoNormal, g.visibility.depth,
                 g.instance, vplLanes_, iterations, direct, f.deviceScene.lights, int(f.scene.lights.size()),
                 f.shadowMaps.viewTable, f.shadowMaps.offsetTable, f.shadowMaps.depths, planes_);
    visibility_.setArgs(project, 19);
    f.ctx.launch(project, shIgiRange(f.ctx, layout),
                 visibility_.enabled() ? "sh-igi: project + rays" : "sh-igi: project");

    float cosTauN = std::cos(p.getFloat("sh-igi.tau_n") * 3.14159265f / 180.0f);
    const bool separable = p.getChoice("sh-igi.filter") == "separable";
    shIgiFilterShade(f.ctx, separable ? prog.filterSeparable : prog.filter, separable, layout, g, planes_,
                     p.getFloat("sh-igi.tau_z"), cosTauN, p.getBool("sh-igi.same_instance"), p.getBool("sh-igi.glossy"),
                     indirect);
  }

private:
  struct Programs {
    cl::Program program, visibleProgram, filterProgram, separableProgram;
    cl::Kernel vplLanes, project, projectVisible, filter, filterSeparable;
  };
  // One program per filter window (compile-time GI_FX, GI_FY); the visibility variant of the
  // projection is built the first time rays are asked for.
  Programs& programs(const FrameResources& f, int fx, int fy) {
    auto key = std::make_pair(fx, fy);
    auto it = programs_.find(key);
    if (it == programs_.end()) {
      Programs p;
      p.program = f.ctx.buildProgram("kernels/gi/sh_igi/sh_igi.cl",
                                     {{"GI_FX", std::to_string(fx)}, {"GI_FY", std::to_string(fy)}, {"GI_VW", std::to_string(shIgiVectorWidth(f.ctx))}});
      p.project = p.program.kernel("sh_igi_project");
      p.vplLanes = p.program.kernel("sh_igi_vpl_lanes");
      auto filterProgram = [&](bool separable) {
        return f.ctx.buildProgram("kernels/gi/sh_igi/sh_igi.cl",
                                  {{"GI_FX", std::to_string(fx)}, {"GI_FY", std::to_string(fy)},
                                   {"GI_VW", std::to_string(shIgiFilterVectorWidth(f.ctx, separable))}});
      };
      p.filterProgram = filterProgram(false);
      p.separableProgram = filterProgram(true);
      p.filter = p.filterProgram.kernel("sh_igi_filter_shade");
      p.filterSeparable = p.separableProgram.kernel("sh_igi_filter_shade_separable");
      it = programs_.emplace(key, std::move(p)).first;
    }
    Programs& p = it->second;
    if (visibility_.enabled() && !p.projectVisible.get()) {
      cl::Defines d = visibility_.defines();
      d.push_back({"GI_FX", std::to_string(fx)});
      d.push_back({"GI_FY", std::to_string(fy)});
      d.push_back({"GI_VW", std::to_string(shIgiVectorWidth(f.ctx))});
      p.visibleProgram = f.ctx.buildProgram("kernels/gi/sh_igi/sh_igi.cl", d);
      p.projectVisible = p.visibleProgram.kernel("sh_igi_project");
    }
    return p;
  }

  std::unique_ptr<VplGenerator> generator_;
  std::map<std::pair<int, int>, Programs> programs_;
  VplVisibility visibility_;
  VplSet vpls_;
  cl::Buffer planes_, vplLanes_;
};

}  // namespace

// The context's lane count (16 on a CPU): with 8 lanes on AVX2 the projection took ≈ 12 % more CPU
// time and the filter the same (perf samples, same load).
int shIgiVectorWidth(const cl::Context& ctx) { return ctx.vectorWidth(); }

// The separable filter with 8 lanes on a 16-lane CPU device: its CPU time fell to 0.6× on AVX2 (its
// private row pass, 11 rows × 27 planes, is half the size; the projection with 8 lanes took 2.2×
// its time, docs/PERFORMANCE.md, sh-igi, "Sixth round") and it is 0.75× on AVX-512. The box filter
// takes the width of the gathers (cl/gather_width.h: 16 lanes where the CPU's native float vector
// is 16 wide, i.e. AVX-512, else 8): the same CPU time at 8 and 16 lanes on AVX2, 0.85× with 16 on
// AVX-512 ("Eighth round"). $GI_VECTOR_WIDTH caps both.
int shIgiFilterVectorWidth(const cl::Context& ctx, bool separable) {
  return std::min(separable ? 8 : cl::gatherVectorWidth(ctx), ctx.vectorWidth());
}

cl::NDRange shIgiRange(const cl::Context& ctx, const ShIgiPlanes& l) {
  const size_t columns = size_t(l.width + shIgiVectorWidth(ctx) - 1) / size_t(shIgiVectorWidth(ctx));
  return cl::NDRange::d1(cl::roundUp(columns * size_t(l.height), 16), 16);
}

ShIgiPlanes::ShIgiPlanes(int width, int height) : width(width), height(height) {
  // Whole cache lines per plane row, and a margin of 16 floats after the last whole vector of 16:
  // window offsets reach at most 8 columns left (into the previous plane row's margin) or right.
  pitch = int(cl::roundUp(size_t(width), 16)) + 16;
  pad = 16;
  floats = size_t(pad) + size_t(height) * kPlanes * pitch + 16;
}

void shIgiFilterShade(cl::Context& ctx, cl::Kernel& filter, bool separable, const ShIgiPlanes& l, const GBuffer& g,
                      const cl::Buffer& planes, float tauZ, float cosTauN, bool sameInstance, bool glossy,
                      cl::Buffer& out, const std::string& label) {
  filter.args(l.width, l.height, l.pitch, l.pad, planes, g.normal, g.albedo, g.specular, g.view, tauZ,
              cosTauN, int(sameInstance), int(glossy), out);
  // GI_VW pixels of kShIgiFilterRows rows per work-item, row-major.
  const int lanes = shIgiFilterVectorWidth(ctx, separable);
  const size_t columns = size_t(l.width + lanes - 1) / size_t(lanes);
  const size_t blocks = size_t(l.height + kShIgiFilterRows - 1) / kShIgiFilterRows;
  ctx.launch(filter, cl::NDRange::d1(cl::roundUp(columns * blocks, 4), 4),
             label + (separable ? ": filter + shade (separable)" : ": filter + shade"));
}

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
            p.addChoice("sh-igi.filter", "box", {"box", "separable"},
                        "filter of the 27 coefficients: box = the fx x fy window; separable = an fx x 1 pass, then "
                        "1 x fy (the same mean without discontinuities, fx + fy taps)");
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
