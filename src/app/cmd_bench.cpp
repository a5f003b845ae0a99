// `gi bench`: time a technique on a scene over many frames and write what a researcher needs to
// trust the numbers: per-kernel and per-pass device times (median, min, max over the timed frames,
// from OpenCL profiling events), whole-frame wall time, the device and driver, the resolution,
// every parameter's value and the git revision of the build. Optionally the quality of the final
// frame against a reference EXR (SSIM, ten Brug's grade, LDR-FLIP, relative MSE, PSNR).
//
// Warm-up: building the programs happens while the renderer is set up (reported as setup_s), and
// --warmup frames are rendered and thrown away before timing, so that the first launch of every
// (kernel, work-group size) pair — 48–100 ms on PoCL, PERFORMANCE_FACTS.md — is not timed.
//
// A kernel is a labelled launch ("gbuffer: tiles"); its pass is the label up to the first ':'
// ("gbuffer"). A kernel launched several times in a frame counts with the sum of its launches;
// a pass's time in a frame is the sum of its kernels; statistics are then taken over frames.
// `gi sweep` runs this command once per configuration (docs/SWEEPS.md).
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "app/common_options.h"
#include "image/image.h"
#include "metrics/metrics.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "util/build_info.h"
#include "util/file_io.h"

namespace gi::app {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

struct BenchArgs {
  std::string scene, jsonPath, imagePath, referencePath, heatmapPath;
  int frames = 10, warmup = 2;
  RenderSettings settings;
  CommonOptions common;
};

std::string lowerExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// Median (mean of the two middle values for an even count), minimum and maximum.
Json summarize(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  double median = n == 0 ? 0.0 : (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
  return Json{{"median_ms", median}, {"min_ms", n ? v.front() : 0.0}, {"max_ms", n ? v.back() : 0.0}};
}

std::string passOf(const std::string& kernel) { return kernel.substr(0, kernel.find(':')); }

Json number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

// Quality of the final frame against a linear reference EXR, both through the scene's display
// transform for the display-domain metrics (docs/METRICS.md).
Json measureQuality(const Image& linear, float exposure, const std::string& referencePath, Image* flipMap) {
  Image reference = metrics::toRgb(readImage(referencePath));
  if (reference.width != linear.width || reference.height != linear.height)
    throw Error("bench: reference '" + referencePath + "' is " + std::to_string(reference.width) + "x" +
                std::to_string(reference.height) + ", the frame is " + std::to_string(linear.width) + "x" +
                std::to_string(linear.height));
  Image refDisplay = displayTransform(reference, exposure), testDisplay = displayTransform(linear, exposure);
  Json q{{"reference", referencePath}};
  if (linear.width >= metrics::kSsimMinSize && linear.height >= metrics::kSsimMinSize) {
    metrics::SsimResult s = metrics::ssim(refDisplay, testDisplay);
    q["ssim"] = s.mean;
    q["grade"] = metrics::tenBrugGrade(refDisplay, testDisplay, s).grade;
    q["grade255"] = metrics::tenBrugGrade(refDisplay, testDisplay,
                                          metrics::ssim(refDisplay, testDisplay, metrics::kSsimDataRange8Bit)).grade;
  }
  metrics::FlipResult f = metrics::flip(refDisplay, testDisplay);
  q["flip"] = f.mean;
  q["relmse"] = number(metrics::relMse(reference, linear));
  q["psnr_db"] = number(metrics::psnr(refDisplay, testDisplay));
  if (flipMap) *flipMap = std::move(f.map);
  return q;
}

void writeJson(const std::string& path, const Json& j) {
  writeAtomically(path, [&](const fs::path& tmp) {
    std::ofstream o(tmp);
    o << j.dump(2) << "\n";
    o.close();
    if (!o) throw Error("cannot write " + path);
  });
}

void run(BenchArgs& a) {
  // Everything the user can get wrong is checked before the expensive work.
  if (a.frames < 1 || a.frames > 100000) throw Error("bench: --frames must be in 1..100000");
  if (a.warmup < 0 || a.warmup > 10000) throw Error("bench: --warmup must be in 0..10000");
  if (!a.imagePath.empty() && lowerExtension(a.imagePath) != ".png" && lowerExtension(a.imagePath) != ".exr")
    throw Error("bench: --image '" + a.imagePath + "': use .png (display-transformed) or .exr (linear)");
  if (!a.heatmapPath.empty() && lowerExtension(a.heatmapPath) != ".png")
    throw Error("bench: --heatmap '" + a.heatmapPath + "' must end in .png");
  if (!a.heatmapPath.empty() && a.referencePath.empty()) throw Error("bench: --heatmap needs --reference");
  if (!a.referencePath.empty() && !fs::exists(a.referencePath))
    throw Error("bench: reference '" + a.referencePath + "' does not exist");
  {
    ParamSet p = declareAllParams();
    for (const std::string& s : a.settings.sets) p.set(s);
  }

  auto seconds = [](auto t0) { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  auto t0 = std::chrono::steady_clock::now();
  Scene scene = loadScene(a.scene, a.common.media);
  double loadSeconds = seconds(t0);
  auto t1 = std::chrono::steady_clock::now();
  cl::Context ctx(cl::selectDevice(a.common.device));
  Renderer renderer(ctx, scene, a.settings);
  double setupSeconds = seconds(t1);

  for (int f = 0; f < a.warmup; ++f) renderer.renderFrame();

  std::vector<std::string> kernelOrder, passOrder;
  std::map<std::string, std::vector<double>> kernelMs, passMs;
  std::vector<double> wallMs, deviceMs;
  for (int f = 0; f < a.frames; ++f) {
    auto tf = std::chrono::steady_clock::now();
    PassTimes times = renderer.renderFrame();
    wallMs.push_back(seconds(tf) * 1e3);
    std::map<std::string, double> passThisFrame;
    double total = 0;
    for (auto& [name, ms] : times) {
      if (!kernelMs.count(name)) kernelOrder.push_back(name);
      kernelMs[name].push_back(ms);
      std::string pass = passOf(name);
      if (std::find(passOrder.begin(), passOrder.end(), pass) == passOrder.end()) passOrder.push_back(pass);
      passThisFrame[pass] += ms;
      total += ms;
    }
    for (auto& [pass, ms] : passThisFrame) passMs[pass].push_back(ms);
    deviceMs.push_back(total);
  }

  Image linear = renderer.radiance();
  const std::vector<TechniqueStatistic> statistics = renderer.techniqueStatistics();
  Image flipMap;
  Json quality;
  if (!a.referencePath.empty())
    quality = measureQuality(linear, scene.exposure, a.referencePath, a.heatmapPath.empty() ? nullptr : &flipMap);

  const cl::DeviceInfo& dev = ctx.device();
  Json j;
  j["tool"] = "gi bench";
  j["git_revision"] = kGitRevision;
  j["scene"] = scene.name;
  j["scene_path"] = a.scene;
  j["camera"] = renderer.camera().name;
  j["width"] = renderer.width();
  j["height"] = renderer.height();
  j["exposure"] = scene.exposure;
  j["technique"] = a.settings.technique;
  j["sets"] = a.settings.sets;
  for (auto& [name, p] : renderer.params().all()) j["params"][name] = renderer.params().valueString(name);
  j["device"] = {{"name", dev.name},       {"vendor", dev.vendor},
                 {"platform", dev.platformName + " " + dev.platformVersion},
                 {"version", dev.deviceVersion}, {"driver", dev.driverVersion},
                 {"type", dev.isGpu ? "gpu" : dev.isCpu ? "cpu" : "other"}, {"vector_width", ctx.vectorWidth()}};
  j["frames"] = a.frames;
  j["warmup"] = a.warmup;
  j["kernels"] = Json::array();
  auto named = [](const std::string& name, const Json& stats) {
    Json e{{"name", name}};
    e.update(stats);
    return e;
  };
  for (auto& k : kernelOrder) j["kernels"].push_back(named(k, summarize(kernelMs[k])));
  j["passes"] = Json::array();
  for (auto& p : passOrder) j["passes"].push_back(named(p, summarize(passMs[p])));
  j["device_total_ms"] = summarize(deviceMs);
  j["frame_wall_ms"] = summarize(wallMs);
  j["scene_load_s"] = loadSeconds;
  j["setup_s"] = setupSeconds;
  j["device_bytes"] = renderer.deviceBytes();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  j["host_peak_rss_bytes"] = uint64_t(usage.ru_maxrss) * 1024;  // Linux reports KiB
  if (!statistics.empty()) {
    j["statistics"] = Json::object();
    for (auto& st : statistics) j["statistics"][st.name] = st.value;
  }
  if (!a.imagePath.empty()) j["image"] = a.imagePath;
  if (!quality.is_null()) {
    if (!a.heatmapPath.empty()) quality["heatmap"] = a.heatmapPath;
    j["quality"] = quality;
  }

  std::printf("%s, camera %s, %dx%d, technique %s on %s (%s)\n", scene.name.c_str(), renderer.camera().name.c_str(),
              renderer.width(), renderer.height(), a.settings.technique.c_str(), dev.name.c_str(),
              dev.driverVersion.c_str());
  std::printf("%d timed frame(s) after %d warm-up frame(s); device ms        median        min        max\n",
              a.frames, a.warmup);
  auto row = [](const std::string& name, const Json& s) {
    std::printf("  %-40s %10.3f %10.3f %10.3f\n", name.c_str(), s["median_ms"].get<double>(), s["min_ms"].get<double>(),
                s["max_ms"].get<double>());
  };
  for (auto& k : j["kernels"]) row(k["name"].get<std::string>(), k);
  for (auto& p : j["passes"]) row("pass " + p["name"].get<std::string>(), p);
  row("sum of kernels", j["device_total_ms"]);
  row("frame (wall)", j["frame_wall_ms"]);
  if (!statistics.empty()) std::printf("last frame:\n");
  for (auto& st : statistics) std::printf("  %-40s %12.6g   %s\n", st.name.c_str(), st.value, st.meaning.c_str());
  if (!quality.is_null())
    std::printf("quality vs %s: ssim %.4f  flip %.4f  grade %.3f  relmse %.4g\n", a.referencePath.c_str(),
                quality.value("ssim", NAN), quality.value("flip", NAN), quality.value("grade", NAN),
                quality["relmse"].is_null() ? NAN : quality["relmse"].get<double>());

  // Outputs last, so that a failure above leaves none of them.
  if (!a.imagePath.empty())
    writeImage(a.imagePath, lowerExtension(a.imagePath) == ".exr" ? linear : displayTransform(linear, scene.exposure));
  if (!a.heatmapPath.empty()) writeImage(a.heatmapPath, metrics::magmaHeatmap(flipMap));
  if (!a.jsonPath.empty()) {
    writeJson(a.jsonPath, j);
    std::printf("wrote %s\n", a.jsonPath.c_str());
  }
}

}  // namespace

void registerBenchCommand(CLI::App& app) {
  auto args = std::make_shared<BenchArgs>();
  auto* cmd = app.add_subcommand("bench", "Time a technique over many frames (per-kernel/per-pass statistics, JSON)");
  addRenderSettingsOptions(cmd, args->scene, args->settings);
  cmd->add_option("--frames", args->frames, "timed frames (default 10)");
  cmd->add_option("--warmup", args->warmup, "frames rendered and discarded before timing (default 2)");
  cmd->add_option("--json", args->jsonPath, "write the results as JSON to this file");
  cmd->add_option("--image", args->imagePath, "write the final frame: .png (display-transformed) or .exr (linear)");
  cmd->add_option("--reference", args->referencePath, "linear reference EXR (gi reference): adds SSIM, grade, FLIP, relMSE");
  cmd->add_option("--heatmap", args->heatmapPath, "write the FLIP error map against --reference as a magma .png");
  addCommonOptions(cmd, args->common);
  cmd->callback([args] { run(*args); });
}

}  // namespace gi::app
