#include "render/renderer.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "render/views.h"

namespace gi {

ParamSet declareAllParams() {
  ParamSet p;
  p.addInt("shadow.resolution", 2048, 64, 8192, "shadow map size (texels per side) for directional and spot lights");
  p.addInt("shadow.cube_resolution", 1024, 32, 4096, "shadow cube-face size for point lights and wide spot lights");
  p.addInt("rsm.resolution", 512, 16, 4096, "reflective shadow map size (texels per side)");
  p.addInt("shadow.static", 0, 0, 1,
           "1: render shadow maps on the first frame only and reuse them (lights and geometry are static); "
           "0: every frame");
  for (const TechniqueInfo& t : techniqueRegistry())
    if (t.declareParams) t.declareParams(p);
  return p;
}

const Camera& selectCamera(const Scene& scene, const std::string& sel) {
  if (scene.cameras.empty()) throw Error("scene '" + scene.name + "' has no camera");
  if (sel.empty()) return scene.cameras[std::clamp(scene.defaultCamera, 0, int(scene.cameras.size()) - 1)];
  for (const Camera& c : scene.cameras)
    if (c.name == sel) return c;
  if (std::all_of(sel.begin(), sel.end(), [](unsigned char ch) { return std::isdigit(ch); })) {
    size_t i = std::stoul(sel);
    if (i < scene.cameras.size()) return scene.cameras[i];
  }
  std::string names;
  for (size_t i = 0; i < scene.cameras.size(); ++i)
    names += (i ? ", " : "") + std::to_string(i) + ":" + (scene.cameras[i].name.empty() ? "(unnamed)" : scene.cameras[i].name);
  throw Error("camera '" + sel + "' not found in scene '" + scene.name + "' (cameras: " + names + ")");
}

Renderer::Renderer(cl::Context& ctx, const Scene& scene, const RenderSettings& settings)
    : ctx_(ctx), scene_(scene), params_(declareAllParams()) {
  for (const std::string& s : settings.sets) params_.set(s);
  width_ = settings.width > 0 ? settings.width : scene.defaultWidth;
  height_ = settings.height > 0 ? settings.height : scene.defaultHeight;
  if (width_ <= 0 || height_ <= 0 || width_ > 16384 || height_ > 16384)
    throw Error("image size " + std::to_string(width_) + "x" + std::to_string(height_) + " outside 1..16384");
  camera_ = selectCamera(scene_, settings.camera);
  cameraView_ = makeCameraView(camera_, width_, height_);

  if (settings.technique != "direct") {
    for (const TechniqueInfo* info : parseTechniqueChain(settings.technique)) {
      chain_.push_back(info->create());
      wantRsm_ = wantRsm_ || chain_.back()->needsRsm();
    }
  }

  raster_ = std::make_unique<RasterPasses>(ctx_);
  ShadowSettings shadow;
  shadow.resolution = params_.getInt("shadow.resolution");
  shadow.cubeResolution = params_.getInt("shadow.cube_resolution");
  raster_->planShadowMaps(scene_.lights, scene_.bounds, shadow, shadowMaps_);
  staticShadows_ = params_.getInt("shadow.static") != 0;
  deviceScene_ = std::make_unique<DeviceScene>(ctx_, scene_);

  lightingProgram_ = ctx_.buildProgram("kernels/render/direct_lighting.cl");
  directKernel_ = lightingProgram_.kernel("direct_lighting");
  composeKernel_ = lightingProgram_.kernel("compose");
  size_t n = size_t(width_) * height_;
  direct_ = cl::Buffer(ctx_, n * 16, CL_MEM_READ_WRITE, "direct radiance");
  indirect_ = cl::Buffer(ctx_, n * 16, CL_MEM_READ_WRITE, "indirect radiance");
  final_ = cl::Buffer(ctx_, n * 16, CL_MEM_READ_WRITE, "final radiance");
  ctx_.fill(indirect_, 0.0f);
  rsms_.resize(wantRsm_ ? scene_.lights.size() : 0);
  gbuffer_.allocate(ctx_, width_, height_);
  for (size_t i = 0; i < chain_.size(); ++i) chain_[i]->setup(frameResources(i > 0));
  ctx_.finish();
  ctx_.profiler().discard();
}

Renderer::~Renderer() = default;

FrameResources Renderer::frameResources(bool upstreamIndirect) const {
  return FrameResources{ctx_, scene_, *deviceScene_, gbuffer_, shadowMaps_, rsms_, params_, direct_, upstreamIndirect};
}

std::vector<const TechniqueInfo*> parseTechniqueChain(const std::string& chain) {
  std::vector<const TechniqueInfo*> out;
  size_t start = 0;
  for (;;) {
    size_t plus = chain.find('+', start);
    std::string name = chain.substr(start, plus == std::string::npos ? std::string::npos : plus - start);
    const TechniqueInfo* info = findTechnique(name);
    // "direct" is no technique object: the renderer runs it alone (direct light, no indirect
    // term), so there is nothing for a modifier to act on and nothing for it to follow.
    if (!info && name == "direct")
      throw Error("'direct' (direct light only, no indirect term) cannot be part of a chain, in '" + chain +
                  "': run it alone, or chain a modifier after a technique that computes indirect light, e.g. "
                  "lpv+ssao (ssao alone: --technique ssao)");
    if (!info) {
      std::string names = "direct";
      for (auto& t : techniqueRegistry()) names += ", " + t.name;
      throw Error("unknown technique '" + name + "' in '" + chain + "' (available: " + names +
                  "; chain them with '+', e.g. lpv+ssao)");
    }
    for (const TechniqueInfo* seen : out)
      if (seen == info) throw Error("technique '" + name + "' appears twice in '" + chain + "'");
    if (!out.empty() && !info->create()->modifiesIndirect())
      throw Error("technique '" + name + "' computes the indirect term itself and must come first in '" + chain +
                  "' (only modifiers such as ssao may follow another technique)");
    out.push_back(info);
    if (plus == std::string::npos) break;
    start = plus + 1;
  }
  return out;
}

PassTimes Renderer::renderFrame() {
  // Nothing in a scene moves yet, so with shadow.static the maps of the first frame stay valid.
  if (!staticShadows_ || !shadowsRendered_) {
    raster_->renderShadowMaps(*deviceScene_, shadowMaps_);
    shadowsRendered_ = true;
  }
  raster_->renderGBuffer(*deviceScene_, cameraView_, gbuffer_);
  for (size_t l = 0; l < rsms_.size(); ++l)
    raster_->renderRsm(*deviceScene_, scene_, int(l), params_.getInt("rsm.resolution"), rsms_[l]);

  directKernel_.args(cameraView_, gbuffer_.position, gbuffer_.geoNormal, gbuffer_.normal, gbuffer_.albedo,
                     gbuffer_.specular, gbuffer_.emission, deviceScene_->lights, int(scene_.lights.size()),
                     shadowMaps_.viewTable, shadowMaps_.offsetTable, shadowMaps_.depths, direct_);
  // One work-item per GI_VW pixels of a row (16 on CPU devices, 1 on GPUs).
  const int vw = ctx_.vectorWidth(), groupsX = (width_ + vw - 1) / vw;
  const size_t lx = vw == 1 ? 16 : 1, ly = vw == 1 ? 16 : 8;
  ctx_.launch(directKernel_, cl::NDRange::d2(cl::roundUp(groupsX, lx), cl::roundUp(height_, ly), lx, ly),
              "direct lighting");

  if (!chain_.empty()) {
    for (size_t i = 0; i < chain_.size(); ++i) chain_[i]->render(frameResources(i > 0), indirect_);
    uint32_t n = uint32_t(width_) * height_;
    // A technique delivering the direct light itself gets only the emission added (the
    // rasterized direct image stays available through directRadiance()).
    const cl::Buffer& base = chain_.front()->deliversDirectLight(params_) ? gbuffer_.emission : direct_;
    composeKernel_.args(base, indirect_, final_, n);
    ctx_.launch(composeKernel_, cl::NDRange::d1(n, 256), "compose");
  }
  return ctx_.profiler().collect();
}

uint64_t Renderer::deviceBytes() const {
  uint64_t b = deviceScene_->bytes + shadowMaps_.depths.bytes();
  b += 7 * size_t(width_) * height_ * 16;  // G-buffer planes + radiance buffers, roughly
  for (auto& r : rsms_) b += r.position.bytes() * 3;
  return b;
}

Image Renderer::readFloat4(const cl::Buffer& b, int w, int h, int channels) {
  std::vector<float> data(size_t(w) * h * 4);
  ctx_.read(b, data.data(), data.size() * sizeof(float));
  Image img(w, h, channels);
  for (size_t p = 0; p < size_t(w) * h; ++p)
    for (int c = 0; c < channels; ++c) img.pixels[p * channels + c] = data[p * 4 + c];
  return img;
}

std::vector<TechniqueStatistic> Renderer::techniqueStatistics() {
  std::vector<TechniqueStatistic> all;
  for (auto& t : chain_)
    for (TechniqueStatistic& s : t->statistics(ctx_)) all.push_back(std::move(s));
  return all;
}

Image Renderer::radiance() { return readFloat4(!chain_.empty() ? final_ : direct_, width_, height_, 3); }
Image Renderer::directRadiance() { return readFloat4(direct_, width_, height_, 3); }
Image Renderer::indirectRadiance() { return readFloat4(indirect_, width_, height_, 3); }

std::vector<std::string> Renderer::writeAovs(const std::string& dir) {
  namespace fs = std::filesystem;
  std::vector<std::string> written;
  auto save = [&](const std::string& name, const Image& img) {
    fs::path p = fs::path(dir) / (name + ".exr");
    writeImage(p, img);
    written.push_back(p.string());
  };
  std::vector<float> depth(size_t(width_) * height_);
  ctx_.read(gbuffer_.visibility.depth, depth.data(), depth.size() * sizeof(float));
  Image d(width_, height_, 1);
  d.pixels = depth;
  save("depth", d);
  save("position", readFloat4(gbuffer_.position, width_, height_, 4));
  save("geometric_normal", readFloat4(gbuffer_.geoNormal, width_, height_, 3));
  save("shading_normal", readFloat4(gbuffer_.normal, width_, height_, 3));
  save("albedo_metallic", readFloat4(gbuffer_.albedo, width_, height_, 4));
  save("specular_roughness", readFloat4(gbuffer_.specular, width_, height_, 4));
  save("emission", readFloat4(gbuffer_.emission, width_, height_, 3));
  std::vector<uint32_t> inst(size_t(width_) * height_);
  ctx_.read(gbuffer_.instance, inst.data(), inst.size() * sizeof(uint32_t));
  Image id(width_, height_, 1);
  for (size_t i = 0; i < inst.size(); ++i) id.pixels[i] = inst[i] == GI_INVALID_ID ? -1.0f : float(inst[i]);
  save("instance_id", id);
  save("direct", directRadiance());
  save("indirect", indirectRadiance());
  // RSMs: rendered here for every light if the technique did not need them.
  std::vector<ReflectiveShadowMap> extra;
  const std::vector<ReflectiveShadowMap>* rsms = &rsms_;
  if (rsms_.empty() && !scene_.lights.empty()) {
    extra.resize(scene_.lights.size());
    for (size_t l = 0; l < extra.size(); ++l)
      raster_->renderRsm(*deviceScene_, scene_, int(l), params_.getInt("rsm.resolution"), extra[l]);
    ctx_.profiler().discard();
    rsms = &extra;
  }
  for (size_t l = 0; l < rsms->size(); ++l) {
    const ReflectiveShadowMap& r = (*rsms)[l];
    int res = r.view.width;
    std::string prefix = "rsm" + std::to_string(l) + "_";
    save(prefix + "position", readFloat4(r.position, res, res, 4));
    save(prefix + "normal", readFloat4(r.normal, res, res, 3));
    save(prefix + "flux", readFloat4(r.flux, res, res, 3));
  }
  return written;
}

}  // namespace gi
