// `gi render`: load a scene, render frames with a technique, write the image (PNG: display
// transform applied; EXR: linear radiance), optionally the AOVs, a timing table and JSON.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "app/common_options.h"
#include "image/image.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "util/file_io.h"

namespace gi::app {

namespace {

struct RenderArgs {
  std::string scene;
  std::string out = "out/render.png";
  std::string jsonPath, aovDir;
  int frames = 1;
  bool timings = false, listParams = false;
  RenderSettings settings;
  CommonOptions common;
};

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void checkOutputPath(const std::string& out) {
  std::string ext = std::filesystem::path(out).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  if (ext != ".png" && ext != ".exr")
    throw Error("--out '" + out + "': unsupported extension (use .png or .exr)");
}

void run(RenderArgs& a) {
  if (a.listParams) {
    std::printf("parameters (set with --set name=value):\n%s", declareAllParams().describe().c_str());
    return;
  }
  checkOutputPath(a.out);
  if (a.frames < 1 || a.frames > 100000) throw Error("--frames must be in 1..100000");
  // Validate parameters before any expensive work.
  {
    ParamSet p = declareAllParams();
    for (const std::string& s : a.settings.sets) p.set(s);
  }
  auto t0 = std::chrono::steady_clock::now();
  Scene scene = loadScene(a.scene, a.common.media);
  double loadSeconds = secondsSince(t0);

  auto t1 = std::chrono::steady_clock::now();
  cl::Context ctx(cl::selectDevice(a.common.device));
  Renderer renderer(ctx, scene, a.settings);
  double setupSeconds = secondsSince(t1);

  // Per-kernel times per frame; the reported value is the median over frames.
  std::map<std::string, std::vector<double>> perPass;
  std::vector<std::string> order;
  std::vector<double> frameMs;
  for (int f = 0; f < a.frames; ++f) {
    auto tf = std::chrono::steady_clock::now();
    PassTimes times = renderer.renderFrame();
    frameMs.push_back(secondsSince(tf) * 1e3);
    for (auto& [name, ms] : times) {
      if (!perPass.count(name)) order.push_back(name);
      perPass[name].push_back(ms);
    }
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
  };

  Image linear = renderer.radiance();
  std::string ext = std::filesystem::path(a.out).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  writeImage(a.out, ext == ".exr" ? linear : displayTransform(linear, scene.exposure));
  std::vector<std::string> aovs;
  if (!a.aovDir.empty()) aovs = renderer.writeAovs(a.aovDir);

  double totalMs = 0;
  for (auto& n : order) totalMs += median(perPass[n]);
  if (a.timings) {
    std::printf("%s on %s, %dx%d, technique %s, %d frame(s), median device times:\n", scene.name.c_str(),
                ctx.device().name.c_str(), renderer.width(), renderer.height(), a.settings.technique.c_str(), a.frames);
    for (auto& n : order) std::printf("  %-28s %9.3f ms\n", n.c_str(), median(perPass[n]));
    std::printf("  %-28s %9.3f ms\n", "sum of passes", totalMs);
    std::printf("  %-28s %9.3f ms\n", "frame (wall)", median(frameMs));
    std::printf("  %-28s %9.3f s\n", "scene load", loadSeconds);
    std::printf("  %-28s %9.3f s\n", "device setup", setupSeconds);
  }
  std::printf("wrote %s\n", a.out.c_str());
  for (auto& p : aovs) std::printf("wrote %s\n", p.c_str());

  if (!a.jsonPath.empty()) {
    nlohmann::json j;
    j["scene"] = scene.name;
    j["device"] = ctx.device().name;
    j["driver"] = ctx.device().driverVersion;
    j["width"] = renderer.width();
    j["height"] = renderer.height();
    j["technique"] = a.settings.technique;
    j["camera"] = renderer.camera().name;
    j["frames"] = a.frames;
    for (auto& [name, p] : renderer.params().all()) j["params"][name] = renderer.params().valueString(name);
    for (auto& n : order) j["passes_ms"][n] = median(perPass[n]);
    j["frame_wall_ms"] = median(frameMs);
    j["scene_load_s"] = loadSeconds;
    j["device_setup_s"] = setupSeconds;
    j["device_bytes"] = renderer.deviceBytes();
    j["output"] = a.out;
    writeAtomically(a.jsonPath, [&](const std::filesystem::path& tmp) {
      std::ofstream o(tmp);
      o << j.dump(2) << "\n";
      if (!o) throw Error("cannot write " + a.jsonPath);
    });
  }
}

}  // namespace

void registerRenderCommand(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  auto* cmd = app.add_subcommand("render", "Render a scene with a technique and write the image");
  addRenderSettingsOptions(cmd, args->scene, args->settings);
  cmd->add_option("--out", args->out, "output image: .png (display-transformed, 8-bit sRGB) or .exr (linear)");
  cmd->add_flag("--list-params", args->listParams, "print every parameter with its default and range, then exit");
  cmd->add_flag("--timings", args->timings, "print per-kernel device milliseconds");
  cmd->add_option("--json", args->jsonPath, "write timings, settings and device as JSON to this file");
  cmd->add_option("--aov", args->aovDir, "write G-buffer planes, direct/indirect radiance and RSMs as EXR into this folder");
  cmd->add_option("--frames", args->frames, "frames to render (timings are medians over frames)");
  addCommonOptions(cmd, args->common);
  cmd->callback([args] { run(*args); });
}

}  // namespace gi::app
