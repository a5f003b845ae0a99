#include "raster/gbuffer.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "cl/gather_width.h"
#include "render/views.h"

namespace gi {

void GBuffer::allocate(cl::Context& ctx, int w, int h) {
  if (w == width && h == height && position) return;
  width = w;
  height = h;
  size_t n = size_t(w) * h;
  position = cl::Buffer(ctx, n * 16, CL_MEM_READ_WRITE, "G-buffer positions");
  geoNormal = cl::Buffer(ctx, n * 16, CL_MEM_READ_WRITE, "G-buffer geometric normals");
  normal = cl::Buffer(ctx, n * 16, CL_MEM_READ_WRITE, "G-buffer shading normals");
  albedo = cl::Buffer(ctx, n * 16, CL_MEM_READ_WRITE, "G-buffer albedo");
  specular = cl::Buffer(ctx, n * 16, CL_MEM_READ_WRITE, "G-buffer specular");
  emission = cl::Buffer(ctx, n * 16, CL_MEM_READ_WRITE, "G-buffer emission");
  instance = cl::Buffer(ctx, n * 4, CL_MEM_READ_WRITE, "G-buffer instance ids");
}

namespace {
glm::vec3 vec3Of(const float* v) { return glm::vec3(v[0], v[1], v[2]); }
bool usesCube(const GiLight& l) {
  return l.type == GI_LIGHT_POINT || (l.type == GI_LIGHT_SPOT && l.cos_outer < GI_SPOT_CUBE_COS);
}
}  // namespace

std::vector<GiView> shadowViewsForLight(const GiLight& l, const Bounds& bounds, const ShadowSettings& s) {
  if (l.type == GI_LIGHT_DIRECTIONAL) return {makeDirectionalShadowView(vec3Of(l.direction), bounds, s.resolution)};
  glm::vec3 pos = vec3Of(l.position);
  if (!usesCube(l)) {
    float fov = 2.0f * std::acos(std::clamp(l.cos_outer, -1.0f, 1.0f)) * 1.05f;
    return {makePerspectiveLightView(pos, vec3Of(l.direction), std::min(fov, 3.0f), bounds, s.resolution)};
  }
  // Face order matches shadow_cube_face(): +x, -x, +y, -y, +z, -z. Two texels of margin.
  float fov = 2.0f * std::atan(1.0f + 4.0f / float(s.cubeResolution));
  const glm::vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<GiView> views;
  for (const glm::vec3& a : axes) views.push_back(makePerspectiveLightView(pos, a, fov, bounds, s.cubeResolution));
  return views;
}

GiView rsmViewForLight(const GiLight& l, const Bounds& bounds, int resolution) {
  if (l.type == GI_LIGHT_DIRECTIONAL) return makeDirectionalLightView(vec3Of(l.direction), bounds, resolution);
  float halfAngle = l.type == GI_LIGHT_POINT ? 1.396f : std::acos(std::clamp(l.cos_outer, -1.0f, 1.0f));
  float fov = std::min(2.0f * halfAngle * 1.02f, 2.0f * 1.3962634f);  // at most 160°
  glm::vec3 dir = l.type == GI_LIGHT_POINT ? glm::vec3(0, -1, 0) : vec3Of(l.direction);
  return makePerspectiveLightView(vec3Of(l.position), dir, fov, bounds, resolution);
}

RasterPasses::RasterPasses(cl::Context& ctx) : ctx_(ctx), rasterizer_(ctx) {
  program_ = ctx.buildProgram("kernels/raster/gbuffer.cl", cl::withGatherWidth(ctx));
  gbufferResolve_ = program_.kernel("gbuffer_resolve");
  rsmResolve_ = program_.kernel("rsm_resolve");
}

void RasterPasses::renderGBuffer(const DeviceScene& scene, const GiView& camera, GBuffer& out) {
  out.allocate(ctx_, camera.width, camera.height);
  out.view = camera;
  rasterizer_.render(scene, camera, out.visibility, "gbuffer");
  gbufferResolve_.args(camera, out.visibility.triangle, scene.positions, scene.normals, scene.tangents, scene.uvs,
                       scene.triangles, scene.triangleInstance, scene.materials, scene.textures, scene.texels,
                       out.position, out.geoNormal, out.normal, out.albedo, out.specular, out.emission, out.instance);
  // One work-item per GI_VW pixels of a row (16 on CPU devices, 1 on GPUs).
  const int vw = cl::gatherVectorWidth(ctx_);
  const size_t lx = vw == 1 ? 16 : 1, ly = vw == 1 ? 16 : 8;
  ctx_.launch(gbufferResolve_, cl::NDRange::d2((camera.width + vw - 1) / vw, camera.height, lx, ly),
              "gbuffer: resolve");
}

void RasterPasses::planShadowMaps(std::vector<GiLight>& lights, const Bounds& bounds, const ShadowSettings& settings,
                                  ShadowMapSet& out) {
  out.views.clear();
  out.offsets.clear();
  uint64_t total = 0;
  for (GiLight& l : lights) {
    l.shadow_map = int(out.views.size());
    for (const GiView& v : shadowViewsForLight(l, bounds, settings)) {
      out.views.push_back(v);
      out.offsets.push_back(uint32_t(total));
      total += uint64_t(v.width) * v.height;
    }
  }
  if (total > 0xFFFFFFFFull) throw Error("shadow maps need more than 2^32 texels; lower shadow resolution");
  out.viewTable = ctx_.upload(out.views, "shadow view table");
  out.offsetTable = ctx_.upload(out.offsets, "shadow offset table");
  out.depths = cl::Buffer(ctx_, std::max<uint64_t>(total, 1) * sizeof(float), CL_MEM_READ_WRITE, "shadow maps");
}

void RasterPasses::renderShadowMaps(const DeviceScene& scene, ShadowMapSet& maps) {
  for (size_t v = 0; v < maps.views.size(); ++v) {
    GiView view = maps.views[v];
    view.cull_backfaces = 0;  // both sides cast shadows (open meshes, double-sided foliage)
    rasterizer_.render(scene, view, shadowScratch_, "shadow maps");
    size_t bytes = size_t(view.width) * view.height * sizeof(float);
    ctx_.copy(shadowScratch_.depth, maps.depths, bytes, 0, size_t(maps.offsets[v]) * sizeof(float));
  }
}

void RasterPasses::renderRsm(const DeviceScene& scene, const Scene& host, int light, int resolution,
                             ReflectiveShadowMap& out) {
  GiView view = rsmViewForLight(host.lights[light], host.bounds, resolution);
  view.cull_backfaces = 1;
  out.light = light;
  out.view = view;
  size_t n = size_t(resolution) * resolution;
  if (!out.position || out.position.bytes() != n * 16) {
    out.position = cl::Buffer(ctx_, n * 16, CL_MEM_READ_WRITE, "RSM positions");
    out.normal = cl::Buffer(ctx_, n * 16, CL_MEM_READ_WRITE, "RSM normals");
    out.flux = cl::Buffer(ctx_, n * 16, CL_MEM_READ_WRITE, "RSM flux");
  }
  rasterizer_.render(scene, view, out.visibility, "rsm");
  rsmResolve_.args(view, scene.lights, light, out.visibility.triangle, scene.positions, scene.normals, scene.tangents,
                   scene.uvs, scene.triangles, scene.materials, scene.textures, scene.texels, out.position, out.normal,
                   out.flux);
  const int vw = cl::gatherVectorWidth(ctx_);
  const size_t lx = vw == 1 ? 16 : 1, ly = vw == 1 ? 16 : 8;
  ctx_.launch(rsmResolve_, cl::NDRange::d2((resolution + vw - 1) / vw, resolution, lx, ly), "rsm: resolve");
}

}  // namespace gi
