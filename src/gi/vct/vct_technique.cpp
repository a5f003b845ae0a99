// `vct`: voxel cone tracing (Crassin et al. 2011 as in seed 003 §3.4; ALGORITHMS.md §5).
// A frame: voxelize (every frame, or once with vct.static=1) -> inject direct light from the
// shadow maps -> isotropic or anisotropic mips -> [bounces 2..k: cone-trace every voxel, inject,
// re-mip] (-> SH voxels: project level 0 onto SH, mip the coefficients) -> diffuse cones per pixel (optionally at reduced resolution + geometry-aware upsampling)
// -> one specular cone per pixel. docs/techniques/vct.md.
#include "gi/vct/vct_technique.h"

#include <memory>

#include "cl/gather_width.h"
#include "cl/tile_groups.h"
#include "gi/filters/discontinuity_filter.h"
#include "gi/vct/voxel_scene.h"
#include "util/error.h"

namespace gi {

namespace {

VoxelScene::Directional directionalVoxels(const ParamSet& p) {
  const std::string& v = p.getChoice("vct.voxels");
  return v == "directional" ? VoxelScene::Directional::Plane
                            : v == "directional_slab" ? VoxelScene::Directional::Slab : VoxelScene::Directional::Off;
}

// Mirrors VctTraceParams in kernels/gi/vct/cone_trace.cl.
struct VctTraceParams {
  float startOffset, maxDistance, stepFactor, aoLambda;
  int32_t anisotropic, applyAo, footprintInFront, levelSteps, specularLevelSteps;
};
static_assert(sizeof(VctTraceParams) == 36, "VctTraceParams layout");

class VctTechnique : public Technique {
public:
  std::string name() const override { return "vct"; }

  void setup(const FrameResources& f) override {
    int res = f.params.getInt("vct.resolution");
    voxels_ = std::make_unique<VoxelScene>(f.ctx, f.scene, res, directionalVoxels(f.params));
    voxelized_ = emptySpaceBuilt_ = false;
    upsampler_ = std::make_unique<GeometryAwareUpsampler>(f.ctx, "vct: upsample");
  }

  void render(const FrameResources& f, cl::Buffer& indirect) override {
    const ParamSet& p = f.params;
    bool anisotropic = p.getChoice("vct.mips") == "anisotropic";
    int cones = std::stoi(p.getChoice("vct.cones"));
    int down = p.getInt("vct.downsample");
    bool sh = p.getChoice("vct.voxels") == "sh";
    bool borderEdge = p.getChoice("vct.border") == "edge";
    VoxelScene::Directional kind = directionalVoxels(p);
    bool directional = kind != VoxelScene::Directional::Off;
    if (directional && !anisotropic)
      throw Error("vct.voxels=" + p.getChoice("vct.voxels") +
                  " needs vct.mips=anisotropic (the directional volumes are anisotropic mips)");
    if (kind != voxels_->directionalKind()) {  // parameters changed since setup
      voxels_ = std::make_unique<VoxelScene>(f.ctx, f.scene, voxels_->resolution(), kind);
      voxelized_ = false;
    }
    ShLobe lobe = p.getChoice("vct.sh_lobe") == "cosine" ? ShLobe::Cosine : ShLobe::Hemisphere;
    if (cones != cones_ || down != down_ || sh != sh_ || directional != directional_ ||
        borderEdge != borderEdge_) {
      program_ = f.ctx.buildProgram("kernels/gi/vct/cone_trace.cl",
                                    cl::withGatherWidth(f.ctx, {{"GI_VCT_CONES", std::to_string(cones)},
                                                                {"GI_DOWN", std::to_string(down)},
                                                                {"GI_VCT_SH", sh ? "1" : "0"},
                                                                {"GI_VCT_DIRECTIONAL", directional ? "1" : "0"},
                                                                {"GI_VCT_BORDER_EDGE", borderEdge ? "1" : "0"}}));
      lanes_ = cl::gatherVectorWidth(f.ctx);
      diffuse_ = program_.kernel("vct_diffuse");
      specular_ = program_.kernel("vct_specular");
      bounce_ = program_.kernel("vct_bounce");
      cones_ = cones;
      down_ = down;
      sh_ = sh;
      directional_ = directional;
      borderEdge_ = borderEdge;
    }
    const GiVoxelGrid& grid = voxels_->grid();
    float s = grid.voxel_size;
    VctTraceParams tp{};
    tp.startOffset = p.getFloat("vct.start_offset");
    tp.maxDistance = p.getFloat("vct.max_distance") * float(grid.resolution);
    tp.stepFactor = p.getFloat("vct.step_factor");
    tp.aoLambda = p.getFloat("vct.ao_lambda") * s;
    tp.anisotropic = anisotropic ? 1 : 0;
    tp.applyAo = p.getChoice("vct.ao") == "voxel" ? 1 : 0;
    tp.footprintInFront = p.getBool("vct.footprint_in_front") ? 1 : 0;
    tp.levelSteps = p.getChoice("vct.diffuse_steps") == "levels" ? 1 : 0;
    tp.specularLevelSteps = p.getChoice("vct.specular_steps") == "levels" ? 1 : 0;

    if (!voxelized_ || !p.getBool("vct.static")) {
      voxels_->voxelize(f.deviceScene);
      voxelized_ = true;
      emptySpaceBuilt_ = false;
    }
    voxels_->inject(f.deviceScene, f.shadowMaps);
    auto buildMips = [&] {
      voxels_->buildMips(anisotropic);
      if (sh) voxels_->buildShVoxels(anisotropic, lobe);
    };
    buildMips();
    // Chains the cone kernels do not read are passed as the isotropic one (any buffer will do).
    const cl::Buffer& aniso = anisotropic ? voxels_->aniso() : voxels_->iso();
    const cl::Buffer& shIso = sh ? voxels_->sh() : voxels_->iso();
    const cl::Buffer& shAniso = sh && anisotropic ? voxels_->shAniso() : shIso;
    int bounces = p.getInt("vct.bounces");
    if (bounces > 1) {
      size_t n = voxels_->voxelCount();
      if (!bounced_) {
        bounced_ = cl::Buffer(f.ctx, n * 16, CL_MEM_READ_WRITE, "vct multi-bounce level 0");
        direct_ = cl::Buffer(f.ctx, n * 16, CL_MEM_READ_WRITE, "vct injected direct level 0");
      }
      f.ctx.copy(voxels_->iso(), direct_, n * 16);
      VctTraceParams bp = tp;
      bp.applyAo = 0;
      for (int b = 2; b <= bounces; ++b) {
        bounce_.args(grid, bp, voxels_->accumulators(), direct_, voxels_->iso(), aniso, shIso, shAniso, bounced_);
        f.ctx.launch(bounce_, cl::NDRange::d1(cl::roundUp(n, 64), 64), "vct: bounce");
        f.ctx.copy(bounced_, voxels_->iso(), n * 16);
        buildMips();
      }
    }

    const GBuffer& g = f.gbuffer;
    int lw = (g.width + down - 1) / down, lh = (g.height + down - 1) / down;
    cl::Buffer* target = &indirect;
    if (down > 1) {
      if (!low_ || low_.bytes() != size_t(lw) * lh * 16)
        low_ = cl::Buffer(f.ctx, size_t(lw) * lh * 16, CL_MEM_READ_WRITE, "vct low-res irradiance");
      target = &low_;
    }
    diffuse_.args(grid, tp, voxels_->iso(), aniso, shIso, shAniso, g.width, g.height, lw, lh, g.position, g.normal, g.albedo, *target);
    // A tile of GI_VW traced pixels per work-item (VCT_TILE_W × VCT_TILE_H in cone_trace.cl).
    int tileW = vctLaneTileWidth(lanes_), tileH = lanes_ / tileW;
    int itemsX = (lw + tileW - 1) / tileW, itemsY = (lh + tileH - 1) / tileH;
    // 4 × 4 work-items per group, fewer where the launch would have too few groups for PoCL's
    // threads to share evenly (half resolution: 4 × 2; docs/PERFORMANCE.md, "Diffuse cones:
    // work-groups dealt evenly to PoCL's threads").
    f.ctx.launch(diffuse_, cl::balancedTileGroups(f.ctx.device(), itemsX, itemsY, 4, 4), "vct: diffuse cones");
    if (down > 1) {
      GeometryTest t;
      t.tauZ = p.getFloat("vct.tau_z");
      t.tauNDegrees = p.getFloat("vct.tau_n");
      upsampler_->run(g, low_, down, t, indirect);
    }
    if (p.getBool("vct.specular")) {
      // The continuous march with anisotropic mips steps over the lookups the empty-space map
      // shows empty (cone_lanes.h; the map depends on the occupancy bits only, voxel_scene.h).
      // With isotropic mips a lookup reads one volume, not three, and in the level-aligned march
      // one level, not two: there the stepping passes cost what the skipped lookups save
      // (docs/PERFORMANCE.md, *Specular cone: empty-space skip* and *Level-aligned specular
      // cone*): no map (a null buffer: the kernel skips nothing), and none is built.
      bool continuous = !tp.specularLevelSteps || tp.footprintInFront;
      bool skipEmpty = anisotropic && continuous;
      if (skipEmpty && !emptySpaceBuilt_) {
        voxels_->buildEmptySpace();
        emptySpaceBuilt_ = true;
      }
      specular_.args(grid, tp, voxels_->iso(), aniso, shIso, shAniso, skipEmpty ? voxels_->emptySpace() : noMap_,
                     g.view, g.position, g.normal, g.specular, indirect);
      int tileW = vctLaneTileWidth(lanes_), tileH = lanes_ / tileW;
      int itemsX = (g.width + tileW - 1) / tileW, itemsY = (g.height + tileH - 1) / tileH;
      f.ctx.launch(specular_, cl::NDRange::d2(cl::roundUp(itemsX, 8), cl::roundUp(itemsY, 8), 8, 8),
                   "vct: specular cone");
    }
  }

private:
  std::unique_ptr<VoxelScene> voxels_;
  std::unique_ptr<GeometryAwareUpsampler> upsampler_;
  cl::Program program_;
  cl::Kernel diffuse_, specular_, bounce_;
  bool emptySpaceBuilt_ = false;  // the empty-space map matches the current voxelization
  cl::Buffer noMap_;               // null: vct_specular without an empty-space map
  cl::Buffer low_, bounced_, direct_;
  int cones_ = 0, down_ = 0, lanes_ = 1;
  bool sh_ = false, directional_ = false, borderEdge_ = false, voxelized_ = false;
};

}  // namespace

TechniqueInfo vctTechniqueInfo() {
  return {"vct", "voxel cone tracing (Crassin et al. 2011): voxelized scene, injected direct light, mipmapped, diffuse + specular cones",
          [](ParamSet& p) {
            p.addInt("vct.resolution", 128, 32, 256, "voxel grid resolution N (N³ cubic voxels over the scene; power of two)");
            p.addChoice("vct.mips", "anisotropic", {"isotropic", "anisotropic"},
                        "mip filtering: isotropic (mean of 8 children) or anisotropic (6 directional volumes)");
            p.addChoice("vct.voxels", "isotropic", {"isotropic", "sh", "directional", "directional_slab"},
                        "voxel radiance: isotropic (one colour per voxel), l <= 1 spherical harmonics per colour "
                        "channel (seed 003 §3.4.5), evaluated against each cone's direction, or directional: level 0 "
                        "as 6 directional volumes from the surface normal, each voxel a thin plane seen only from "
                        "its front (directional: by projected coverage, transparent edge-on and to cones leaving it) "
                        "or a slab open only to cones leaving through its front (directional_slab); anisotropic mips "
                        "only; docs/techniques/vct.md, Accuracy point 8");
            p.addChoice("vct.sh_lobe", "hemisphere", {"hemisphere", "cosine"},
                        "SH voxels: a voxel shows its surface's radiance on its front hemisphere, or (ten Brug) a "
                        "clamped cosine lobe around its normal");
            p.addChoice("vct.cones", "6", {"6", "9"}, "diffuse cone set: 6 cones (ALGORITHMS §5) or ten Brug's 9 cones; 60° apertures");
            p.addFloat("vct.start_offset", 1.0, 0.0, 16.0, "cone origin offset along the normal, in voxels");
            p.addFloat("vct.step_factor", 0.5, 0.05, 4.0, "march step as a fraction of the cone diameter (at least ½ voxel)");
            p.addChoice("vct.diffuse_steps", "levels", {"levels", "continuous"},
                        "diffuse cones: samples where the diameter is a power of two, one mip level each (levels), "
                        "or steps of step_factor diameters with quadrilinear lookups (continuous; also used with "
                        "footprint_in_front)");
            p.addChoice("vct.specular_steps", "levels", {"levels", "continuous"},
                        "specular cone: steps of at most step_factor diameters that read one mip level each, the "
                        "cone's diameter rounded up to a power of two (levels), or quadrilinear lookups at the "
                        "cone's diameter (continuous; also used with footprint_in_front)");
            p.addChoice("vct.border", "zero", {"zero", "edge"},
                        "what a lookup reads past the grid's border: empty voxels (zero), so samples reaching past "
                        "it are diluted, or, ahead of the cone, the edge voxels (edge, a texture's clamp-to-edge in "
                        "the direction of travel), so a cone ending on a wall at the border sees it whole; edge gains "
                        "in closed scenes and leaks more; docs/techniques/vct.md, Accuracy point 9");
            p.addFloat("vct.max_distance", 1.0, 0.01, 2.0, "maximum cone length as a fraction of the grid edge");
            p.addBool("vct.specular", true, "trace one specular cone per pixel (aperture tan θ = GGX α)");
            p.addBool("vct.footprint_in_front", false,
                      "cap the sampled diameter (power of two <= (h - 1)/1.5 voxels, h = height above the surface, "
                      "nothing below h = 2.5) so cones never sample the surface they start from; "
                      "docs/techniques/vct.md has its measured effect");
            p.addChoice("vct.ao", "off", {"off", "voxel"}, "voxel ambient occlusion: multiply the diffuse indirect light by it");
            p.addFloat("vct.ao_lambda", 1.0, 0.0, 1000.0, "AO distance falloff 1/(1 + λ·d), λ per metre");
            p.addInt("vct.bounces", 1, 1, 8,
                     "light bounces in the voxels: 1 = injected direct light only; k = the cone-traced indirect "
                     "light injected back k - 1 times (one voxel cone-tracing pass each)");
            p.addInt("vct.downsample", 1, 1, 4, "trace the diffuse cones at 1/downsample resolution, then upsample geometry-aware");
            p.addFloat("vct.tau_z", 0.05, 0.0, 10.0, "upsampling: relative view-depth tolerance");
            p.addFloat("vct.tau_n", 25.0, 0.0, 180.0, "upsampling: geometric-normal tolerance in degrees");
            p.addBool("vct.static", false, "voxelize once and keep the voxels (static geometry); false: every frame");
          },
          [] { return std::make_unique<VctTechnique>(); }};
}

}  // namespace gi
