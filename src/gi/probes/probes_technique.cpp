// `probes`: a frame = [update the probes] -> shade every camera pixel from them.
// Updates: probes.update=dynamic traces probes.rays rays per probe every frame and blends them in
// with hysteresis (lights may move); static rebuilds the field completely on the first frame
// (probes.rebuild_updates updates, a running mean, each one more bounce) and then only shades.
// Both start with relocation passes (probes.relocate) that move probes out of geometry.
// probes.update_budget (dynamic only): each frame updates that many probes round-robin instead of
// all; the first frame updates every probe (a whole round in budget-sized launches), so that the
// field starts complete.
#include "gi/probes/probes_technique.h"

#include <memory>

namespace gi {

ProbeSettings probeSettings(const ParamSet& p) {
  ProbeSettings s;
  s.counts = glm::ivec3(p.getInt("probes.grid_x"), p.getInt("probes.grid_y"), p.getInt("probes.grid_z"));
  s.irradianceRes = p.getInt("probes.irradiance_res");
  s.distanceRes = p.getInt("probes.distance_res");
  s.rays = p.getInt("probes.rays");
  // The static rebuild happens once and updates every probe: a budget would only split it into
  // more launches (and make the later ones see the earlier ones' new maps), so it gets none and
  // its ray results hold all probes.
  s.updateBudget = p.getChoice("probes.update") == "dynamic" ? p.getInt("probes.update_budget") : 0;
  int exponent = std::stoi(p.getChoice("probes.distance_exponent"));
  s.distanceExponentLog2 = 0;
  while ((1 << s.distanceExponentLog2) < exponent) ++s.distanceExponentLog2;
  s.chebyshevPower = p.getInt("probes.chebyshev_power");
  s.multiBounce = p.getBool("probes.multibounce");
  s.backfaceFloor = p.getFloat("probes.backface_floor");
  s.smoothBackface = p.getChoice("probes.backface") == "smooth";
  s.crushThreshold = p.getFloat("probes.crush");
  s.perceptualBlend = p.getBool("probes.perceptual_blend");
  s.normalBias = p.getFloat("probes.normal_bias");
  s.viewBias = p.getFloat("probes.view_bias");
  s.maxDistance = p.getFloat("probes.max_distance");
  s.relocate = p.getBool("probes.relocate");
  s.backfaceFraction = p.getFloat("probes.backface_fraction");
  s.minFrontface = p.getFloat("probes.min_frontface");
  s.downsample = p.getInt("probes.downsample");
  s.tauZ = p.getFloat("probes.tau_z");
  s.tauNDegrees = p.getFloat("probes.tau_n");
  return s;
}

namespace {

class ProbesTechnique : public Technique {
public:
  std::string name() const override { return "probes"; }

  void setup(const FrameResources& f) override {
    field_ = std::make_unique<ProbeField>(f.ctx, f.scene, f.deviceScene, probeSettings(f.params));
  }

  void render(const FrameResources& f, cl::Buffer& indirect) override {
    const ParamSet& p = f.params;
    bool dynamic = p.getChoice("probes.update") == "dynamic";
    if (field_->updates() == 0) field_->relocate(f.deviceScene, kFirstRelocationPasses);
    if (dynamic) {
      // First frame: a whole round, ⌈N/budget⌉ updates (one without a budget).
      int probes = field_->probeCount(), perUpdate = field_->probesPerUpdate();
      int updates = field_->updates() == 0 ? (probes + perUpdate - 1) / perUpdate : 1;
      for (int i = 0; i < updates; ++i) field_->update(f.deviceScene, p.getFloat("probes.hysteresis"));
    } else if (field_->updates() == 0) {
      // Update i adds a bounce (multi-bounce) and averages noise. A running mean over all n would
      // keep the first updates' fewer bounces (with albedo 0.5, 80 % of the converged indirect light
      // after 8 updates); restarting it at updates 1, 2, 4, 8, … ends with the mean of the last
      // half, whose bounces have converged geometrically (97 % in the same example). At the
      // positions found above (classification only).
      int n = p.getInt("probes.rebuild_updates");
      for (int i = 0; i < n; ++i) {
        if (i > 0 && (i & (i - 1)) == 0) field_->restartMean();
        field_->update(f.deviceScene, 1.0f, false);
      }
    }
    field_->shade(f.gbuffer, indirect);
  }

private:
  // Before the first update, relocation passes (distances only) move the probes out of geometry:
  // the first takes a probe out through the nearest back face, the next ones settle it at the
  // minimum front-face distance.
  static constexpr int kFirstRelocationPasses = 4;
  std::unique_ptr<ProbeField> field_;
};

}  // namespace

TechniqueInfo probesTechniqueInfo() {
  return {"probes",
          "light-field probes (McGuire et al. 2017, seed 004): octahedral irradiance and filtered-distance maps on a "
          "probe grid, Chebyshev visibility, updated by ray tracing (DDGI style); diffuse indirect only",
          [](ParamSet& p) {
            p.addInt("probes.grid_x", 0, 0, 64, "probes along x; 0 = automatic (8 along the two longest axes, 4 along the shortest)");
            p.addInt("probes.grid_y", 0, 0, 64, "probes along y; 0 = automatic");
            p.addInt("probes.grid_z", 0, 0, 64, "probes along z; 0 = automatic");
            p.addInt("probes.irradiance_res", 8, 2, 64, "interior texels per side of each probe's octahedral irradiance map");
            p.addInt("probes.distance_res", 16, 2, 128, "interior texels per side of each probe's octahedral distance map");
            p.addInt("probes.rays", 64, 1, 4096, "rays per probe per update");
            p.addChoice("probes.update", "dynamic", {"dynamic", "static"},
                        "dynamic: one update per frame blended with hysteresis; static: a full rebuild on the first frame only");
            p.addFloat("probes.hysteresis", 0.97, 0.0, 1.0,
                       "weight of the previous value in a dynamic update of a probe (DDGI; per update of that probe)");
            p.addInt("probes.update_budget", 0, 0, 64 * 64 * 64,
                     "dynamic: probes updated per frame, round-robin in an order spread over the grid (the first frame updates all); "
                     "0 or more than the grid's probes = all (read at setup)");
            p.addInt("probes.rebuild_updates", 32, 1, 4096, "static: updates averaged in the full rebuild (each adds a bounce)");
            p.addBool("probes.multibounce", true, "ray hits gather the probes' own irradiance (infinite bounces over updates)");
            p.addChoice("probes.distance_exponent", "64", {"1", "2", "4", "8", "16", "32", "64"},
                        "distance filter: ray weight max(0, cos)^this");
            p.addInt("probes.chebyshev_power", 3, 0, 8, "the Chebyshev visibility bound is raised to this power");
            p.addChoice("probes.backface", "smooth", {"eq7", "smooth"},
                        "backface weight: eq7 = max(backface_floor, n . direction to the probe) (seed 004 eq. 7); "
                        "smooth = ((n . direction + 1)/2)^2 + 0.2 (DDGI)");
            p.addFloat("probes.backface_floor", 0.05, 0.0, 1.0,
                        "eq7: smallest backface weight max(floor, n . direction to the probe) (seed 004 eq. 7 has 0)");
            p.addFloat("probes.crush", 0.2, 0.0, 1.0,
                       "DDGI: backface x visibility weights w below this become w^3/crush^2 (DDGI 0.2); 0 = off");
            p.addBool("probes.perceptual_blend", false, "blend the probes' irradiance as its square root, square the sum (DDGI)");
            p.addFloat("probes.normal_bias", 0.045, 0.0, 1.0, "visibility test point offset along the normal, fraction of the smallest probe spacing");
            p.addFloat("probes.view_bias", 0.18, 0.0, 1.0, "visibility test point offset towards the viewer, fraction of the smallest probe spacing");
            p.addInt("probes.downsample", 1, 1, 4, "shade at 1/downsample resolution, then upsample geometry-aware");
            p.addFloat("probes.tau_z", 0.05, 0.0, 10.0, "upsampling: relative view-depth tolerance");
            p.addFloat("probes.tau_n", 25.0, 0.0, 180.0, "upsampling: geometric-normal tolerance in degrees");
            p.addFloat("probes.max_distance", 0.0, 0.0, 1e6, "probe ray length in metres; 0 = the scene's bounding-box diagonal");
            p.addBool("probes.relocate", true,
                      "DDGI relocation and classification: probes inside geometry move out or are switched off");
            p.addFloat("probes.backface_fraction", 0.25, 0.0, 1.0,
                       "a probe with more than this fraction of its rays on back faces is inside geometry");
            p.addFloat("probes.min_frontface", 0.1, 0.0, 0.45,
                       "relocation keeps probes this far from surfaces, fraction of the smallest probe spacing");
          },
          [] { return std::make_unique<ProbesTechnique>(); }};
}

}  // namespace gi
