// The rasterized views of a frame built on the Rasterizer:
//   GBuffer             camera G-buffer planes (ALGORITHMS.md §1), structure of arrays;
//   ShadowMapSet        every light's shadow maps in one depth buffer + view table;
//   ReflectiveShadowMap one light's RSM: position, normal, reflected flux per texel.
// Each has a pass that renders it (kernels/raster/raster.cl + gbuffer.cl).
#pragma once
#include <string>
#include <vector>

#include "cl/runtime.h"
#include "raster/rasterizer.h"
#include "scene/device_scene.h"
#include "scene/scene.h"

namespace gi {

struct GBuffer {
  int width = 0, height = 0;
  GiView view{};
  VisibilityBuffer visibility;  // triangle id + linear view depth (the "depth" plane)
  cl::Buffer position;          // float4: world position, w = 1 on surfaces, 0 on background
  cl::Buffer geoNormal;         // float4: face normal towards the camera
  cl::Buffer normal;            // float4: shading normal (normal map applied)
  cl::Buffer albedo;            // float4: diffuse albedo ρ, w = metallic
  cl::Buffer specular;          // float4: specular F0, w = roughness
  cl::Buffer emission;          // float4: emitted radiance
  cl::Buffer instance;          // uint: instance id, GI_INVALID_ID on background
  void allocate(cl::Context& ctx, int w, int h);
};

struct ShadowMapSet {
  std::vector<GiView> views;      // every face of every light, in light order
  std::vector<uint32_t> offsets;  // first depth of each view
  cl::Buffer viewTable, offsetTable, depths;
};

struct ReflectiveShadowMap {
  int light = -1;
  GiView view{};
  VisibilityBuffer visibility;
  cl::Buffer position, normal, flux;  // float4 each; flux in W per texel
};

struct ShadowSettings {
  int resolution = 2048;      // directional and narrow spot lights
  int cubeResolution = 1024;  // per face, point and wide spot lights
};

// Views of the light: one for directional and narrow spot lights, six cube faces for point and
// wide spot lights (cone wider than GI_SPOT_CUBE_COS). The faces are slightly wider than 90° so
// PCF near a face border still reads inside the face.
std::vector<GiView> shadowViewsForLight(const GiLight& light, const Bounds& bounds, const ShadowSettings& settings);

// RSM view of a light (single view; wide cones are capped at 160°, losing the flux beyond 80°
// off-axis: 3 % for the cosine-lobe stand-ins of emissive surfaces).
GiView rsmViewForLight(const GiLight& light, const Bounds& bounds, int resolution);

class RasterPasses {
public:
  explicit RasterPasses(cl::Context& ctx);
  Rasterizer& rasterizer() { return rasterizer_; }

  void renderGBuffer(const DeviceScene& scene, const GiView& camera, GBuffer& out);

  // Assigns lights[i].shadow_map (the caller uploads the lights afterwards) and allocates `out`.
  void planShadowMaps(std::vector<GiLight>& lights, const Bounds& bounds, const ShadowSettings& settings,
                      ShadowMapSet& out);
  void renderShadowMaps(const DeviceScene& scene, ShadowMapSet& maps);

  void renderRsm(const DeviceScene& scene, const Scene& host, int light, int resolution, ReflectiveShadowMap& out);

private:
  cl::Context& ctx_;
  Rasterizer rasterizer_;
  cl::Program program_;
  cl::Kernel gbufferResolve_, rsmResolve_;
  VisibilityBuffer shadowScratch_;
};

}  // namespace gi
