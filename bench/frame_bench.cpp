// The foundation benchmark (issue: engine foundation, item 8): Sponza with its sun, direct
// lighting, per-kernel device milliseconds as medians over frames after warm-up; scene load time;
// warm start to the first Cornell box frame; peak memory at 1280×720. Prints a table that
// docs/PERFORMANCE.md records. Not a test: the machine is noisy, targets are checked by reading.
//
//   build/frame_bench [--scene scenes/sponza.json] [--frames 10] [--width 640 --height 360]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "cl/runtime.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"

using namespace gi;
using Clock = std::chrono::steady_clock;

namespace {

double seconds(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

long peakRssMiB() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::atol(line.c_str() + 6) / 1024;
  return -1;
}

struct Args {
  std::string scene = "scenes/sponza.json";
  int frames = 10, warmup = 2, width = 640, height = 360;
  std::string binary;  // gi binary for the warm-start measurement
};

void runFrames(cl::Context& ctx, const Scene& scene, const Args& a, int w, int h, bool print) {
  RenderSettings rs;
  rs.width = w;
  rs.height = h;
  Renderer r(ctx, scene, rs);
  for (int i = 0; i < a.warmup; ++i) r.renderFrame();  // program builds, first launches
  std::map<std::string, std::vector<double>> perPass;
  std::vector<std::string> order;
  std::vector<double> frames;
  for (int f = 0; f < a.frames; ++f) {
    auto t0 = Clock::now();
    PassTimes times = r.renderFrame();
    frames.push_back(seconds(t0) * 1e3);
    for (auto& [name, ms] : times) {
      if (!perPass.count(name)) order.push_back(name);
      perPass[name].push_back(ms);
    }
  }
  if (!print) return;
  std::printf("%dx%d, %d frames after %d warm-up, median (min .. max) device ms per kernel:\n", w, h, a.frames,
              a.warmup);
  double sum = 0;
  for (auto& n : order) {
    auto& v = perPass[n];
    sum += median(v);
    std::printf("  %-26s %8.2f  (%.2f .. %.2f)\n", n.c_str(), median(v), *std::min_element(v.begin(), v.end()),
                *std::max_element(v.begin(), v.end()));
  }
  std::printf("  %-26s %8.2f\n", "sum of kernels", sum);
  std::printf("  %-26s %8.2f  (%.2f .. %.2f)\n", "whole frame (wall)", median(frames),
              *std::min_element(frames.begin(), frames.end()), *std::max_element(frames.begin(), frames.end()));
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  a.binary = std::string(argv[0]);
  a.binary = a.binary.substr(0, a.binary.find_last_of('/') + 1) + "gi";
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string k = argv[i], v = argv[i + 1];
    if (k == "--scene") a.scene = v;
    else if (k == "--frames") a.frames = std::atoi(v.c_str());
    else if (k == "--width") a.width = std::atoi(v.c_str());
    else if (k == "--height") a.height = std::atoi(v.c_str());
    else if (k == "--gi") a.binary = v;
    else { std::fprintf(stderr, "unknown option %s\n", k.c_str()); return 2; }
  }
  try {
    cl::Context ctx(cl::selectDevice(""));
    std::printf("device: %s (%s, driver %s)\n", ctx.device().name.c_str(), ctx.device().platformName.c_str(),
                ctx.device().driverVersion.c_str());
    auto t0 = Clock::now();
    Scene scene = loadScene(a.scene, "");
    double load = seconds(t0);
    std::printf("scene %s: %zu triangles, %zu textures, load (parse, decode, mips) %.2f s\n", a.scene.c_str(),
                scene.triangles.size(), scene.textures.size(), load);
    runFrames(ctx, scene, a, a.width, a.height, true);
    runFrames(ctx, scene, a, 1280, 720, false);
    std::printf("peak resident memory after 1280x720 frames: %ld MiB\n", peakRssMiB());

    // Warm start: the second run of `gi render` on the Cornell box (program cache warm).
    std::string cmd = a.binary + " render --out /tmp/gi_bench_cornell.png > /dev/null 2>&1";
    if (std::system(cmd.c_str()) == 0) {
      std::vector<double> runs;
      for (int i = 0; i < 3; ++i) {
        auto t = Clock::now();
        if (std::system(cmd.c_str()) != 0) break;
        runs.push_back(seconds(t));
      }
      std::printf("warm start to first Cornell box frame written (gi render, median of 3): %.2f s\n", median(runs));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "frame_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
