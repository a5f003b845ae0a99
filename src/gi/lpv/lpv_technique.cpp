// `lpv`: light propagation volumes (Kaplanyan 2009; Kaplanyan & Dachsbacher 2010; seeds 003, 004)
// in the conventions of ALGORITHMS.md §4: RSM injection, geometry volume from RSM and camera
// surfels, gather propagation, trilinear lookup, cascades. The passes are in lpv_volume.h, the
// kernels in kernels/gi/lpv/lpv.cl, the choices and measurements in docs/techniques/lpv.md.
//
// Parameters (`--set lpv.*`): resolution (cells per axis, 16..128), cascades (0 = one grid over the
// scene bounds, 1..4 camera-centred levels, default 3), extent (metres of the finest cascade;
// 0 = so that the coarsest covers the scene from the first frame's camera), iterations (0 = the resolution), rsm_size (RSM merged to
// this size before injection), occlusion (geometry-volume blocking), injection_bias (VPL shift in
// cells along its normal), lookup_storage (auto / buffer / image), bounces (blocked light reflected by the blockers: orders >= 3),
// damping (Kaplanyan 2009: irradiance decreasing along the normal is damped).
// Handles diffuse transport only; one bounce (the RSM's) unless lpv.bounces.
#include "gi/lpv/lpv_technique.h"

#include <algorithm>
#include <memory>

#include "gi/lpv/lpv_volume.h"

namespace gi {
namespace {

class LpvTechnique : public Technique {
public:
  std::string name() const override { return "lpv"; }
  bool needsRsm() const override { return true; }

  void setup(const FrameResources& f) override {
    const ParamSet& p = f.params;
    int rsmResolution = p.getInt("rsm.resolution"), rsmSize = p.getInt("lpv.rsm_size");
    if (rsmSize > rsmResolution || rsmResolution % rsmSize != 0)
      throw Error("lpv.rsm_size=" + std::to_string(rsmSize) + " must divide rsm.resolution=" +
                  std::to_string(rsmResolution));
    block_ = rsmResolution / rsmSize;
    cascades_ = p.getInt("lpv.cascades");
    volume_ = std::make_unique<LpvVolume>(f.ctx, p.getInt("lpv.resolution"), std::max(cascades_, 1),
                                          lookupStorage(p.getChoice("lpv.lookup_storage"), f.ctx.device(),
                                                        p.getInt("lpv.resolution"), std::max(cascades_, 1)),
                                          p.getBool("lpv.bounces") && p.getBool("lpv.occlusion"));
  }

  void render(const FrameResources& f, cl::Buffer& indirect) override {
    const ParamSet& p = f.params;
    const Scene& scene = f.scene;
    glm::vec3 camera(f.gbuffer.view.eye[0], f.gbuffer.view.eye[1], f.gbuffer.view.eye[2]);
    int n = volume_->resolution();
    if (extent0_ <= 0.0f) extent0_ = finestExtent(p.getFloat("lpv.extent"), scene.bounds, camera, n);
    bool occlusion = p.getBool("lpv.occlusion");
    int iterations = p.getInt("lpv.iterations");
    if (iterations == 0) iterations = n;

    volume_->begin(lpvCascadeLayout(scene.bounds, camera, n, cascades_, extent0_), lpvInjectionFixedScale(scene, f.rsms));
    for (const ReflectiveShadowMap& r : f.rsms) {
      volume_->inject(r.position, r.normal, r.flux, r.view.width, block_, p.getFloat("lpv.injection_bias"));
      if (occlusion) volume_->addGeometryRsm(r.view, r.position, r.normal, r.view.width);
    }
    if (occlusion) volume_->addGeometryCamera(f.gbuffer);
    volume_->resolve(occlusion);
    volume_->propagate(iterations, occlusion);
    volume_->lookup(f.gbuffer, cascades_ > 0, indirect, p.getBool("lpv.damping"));
  }

private:
  // "auto": a 3D image on GPUs that hold one of n × n × 3·n·cascades (hardware trilinear
  // filtering), a buffer elsewhere (PoCL filters images in software, slower than the kernel's own
  // interpolation).
  static LpvLookupStorage lookupStorage(const std::string& choice, const cl::DeviceInfo& device, int n, int cascades) {
    if (choice == "image") return LpvLookupStorage::Image;  // LpvImage names what the device lacks
    if (choice != "auto" || !device.isGpu || !device.imageSupport) return LpvLookupStorage::Buffer;
    size_t depth = 0;  // OpenCL 1.2 guarantees 2048; 128³ × 3 channels × 4 cascades needs 1536
    clGetDeviceInfo(device.id, CL_DEVICE_IMAGE3D_MAX_DEPTH, sizeof(depth), &depth, nullptr);
    return size_t(n) * 3 * cascades <= depth ? LpvLookupStorage::Image : LpvLookupStorage::Buffer;
  }

  // The finest cascade's edge: the parameter, or else (fixed at the first frame, so the cells keep
  // their size when the camera moves) the size at which the coarsest cascade, centred on the
  // camera, covers the whole scene with a cell to spare for the snapping.
  float finestExtent(float parameter, const Bounds& b, const glm::vec3& camera, int n) const {
    if (parameter > 0.0f) return parameter;
    float reach = 0.0f;  // largest per-axis distance from the camera to a corner of the bounds
    for (int c = 0; c < 8; ++c) {
      glm::vec3 corner((c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 4) ? b.hi.z : b.lo.z);
      glm::vec3 d = glm::abs(corner - camera);
      reach = std::max({reach, d.x, d.y, d.z});
    }
    float coarsest = 2.0f * reach * float(n) / float(n - 2);
    return std::max(coarsest / float(1 << (std::max(cascades_, 1) - 1)), 1e-6f);
  }

  std::unique_ptr<LpvVolume> volume_;
  float extent0_ = 0.0f;
  int block_ = 1, cascades_ = 0;
};

}  // namespace

TechniqueInfo lpvTechniqueInfo() {
  return {"lpv", "light propagation volumes: RSM injection, geometry-volume blocking, SH gather propagation, cascades",
          [](ParamSet& p) {
            p.addInt("lpv.resolution", 32, 16, 128, "grid cells per axis (each cascade)");
            p.addInt("lpv.cascades", 3, 0, 4,
                     "0 = one grid over the scene bounds; 1..4 = camera-centred cascades, each twice the previous");
            p.addFloat("lpv.extent", 0.0, 0.0, 1e6,
                       "edge of the finest cascade in metres; 0 = the coarsest covers the scene from the first frame's camera");
            p.addInt("lpv.iterations", 0, 0, 1024, "propagation steps; 0 = the grid resolution");
            p.addInt("lpv.rsm_size", 256, 16, 4096, "RSM texels per side after merging for injection; must divide rsm.resolution");
            p.addBool("lpv.occlusion", true, "geometry-volume blocking (from RSM and camera surfels)");
            p.addBool("lpv.bounces", false,
                      "multiple bounces (Kaplanyan & Dachsbacher 2010): light the geometry volume blocks is reflected "
                      "diffusely with the camera surfels' albedo and propagates on; needs lpv.occlusion");
            p.addBool("lpv.damping", false,
                      "Kaplanyan 2009's self-illumination damping: irradiance that decreases along the normal (light "
                      "flowing away from the surface) is limited to the irradiance one cell further out");
            p.addFloat("lpv.injection_bias", 0.5, 0.0, 2.0, "VPL shift along its normal before injection, in cells");
            p.addChoice("lpv.lookup_storage", "auto", {"auto", "buffer", "image"},
                        "grid the lookup reads: a 3D image (hardware trilinear filtering) or a buffer; auto = image on GPUs");
          },
          [] { return std::make_unique<LpvTechnique>(); }};
}

}  // namespace gi
