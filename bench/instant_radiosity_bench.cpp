// Instant radiosity benchmark (issues 4 and 5, speed items): per-kernel device milliseconds (medians
// over frames after warm-up) of the `vpl`, `igi`, `rsm`, `splat` and `sh-igi` techniques, the gather rate in pixel·VPL
// pairs per second, and the d_min bias (energy lost by the clamp vs d_min → 0). Sponza 640×360
// with its sun when the media are present, else the built-in Cornell box. Not a test: the
// machine is noisy; docs/PERFORMANCE.md records the numbers.
//
//   build/instant_radiosity_bench [--scene scenes/sponza.json] [--width 640 --height 360] [--frames 9]
//                                 [--only vpl|igi|rsm|splat|sh-igi]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "cl/runtime.h"
#include "render/renderer.h"
#include "scene/cornell_box.h"
#include "scene/scene_loader.h"
#include "technique_timing.h"

using namespace gi;

namespace {

struct Args : timing::FrameSettings {
  std::string scene = "scenes/sponza.json";
  std::string only;  // "vpl", "igi", "rsm", "splat" or "" (all)
};

std::map<std::string, double> bench(cl::Context& ctx, const Scene& scene, const Args& a, const std::string& technique,
                                    std::vector<std::string> sets, const std::string& title) {
  return timing::timeTechnique(ctx, scene, a, technique, std::move(sets), title);
}

double meanIndirect(cl::Context& ctx, const Scene& scene, const Args& a, std::vector<std::string> sets) {
  RenderSettings rs;
  rs.width = a.width;
  rs.height = a.height;
  rs.technique = "vpl";
  rs.sets = sets;
  Renderer r(ctx, scene, rs);
  r.renderFrame();
  Image im = r.indirectRadiance();
  double s = 0;
  for (float v : im.pixels) s += v;
  return s / double(im.pixels.size());
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    std::string k = argv[i];
    auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (k == "--scene") a.scene = next();
    else if (k == "--width") a.width = std::stoi(next());
    else if (k == "--height") a.height = std::stoi(next());
    else if (k == "--frames") a.frames = std::stoi(next());
    else if (k == "--only") a.only = next();
    else {
      std::fprintf(stderr, "usage: instant_radiosity_bench [--scene S] [--width W --height H] [--frames N] [--only vpl|igi|rsm|splat|sh-igi]\n");
      return 2;
    }
  }
  try {
    cl::Context ctx(cl::selectDevice(""));
    Scene scene;
    try {
      scene = loadScene(a.scene, "");
    } catch (const std::exception& e) {
      std::printf("(%s not loadable: %s; using the built-in Cornell box)\n", a.scene.c_str(), e.what());
      scene = makeCornellBox();
    }
    std::printf("instant radiosity bench: %s, %dx%d, %s, GI_VW=%d, median of %d frames after %d warm-up\n",
                scene.name.c_str(), a.width, a.height, ctx.device().name.c_str(), ctx.vectorWidth(), a.frames,
                a.warmup);
    double pixels = double(a.width) * a.height;
    auto want = [&](const char* t) { return a.only.empty() || a.only == t; };
    for (int n : {64, 256, 1024}) {
      if (!want("vpl")) break;
      auto t = bench(ctx, scene, a, "vpl", {"vpl.count=" + std::to_string(n)}, "vpl all-pairs, N=" + std::to_string(n));
      double ms = t["vpl: shade"];
      double lights = double(scene.lights.size());
      std::printf("  gather rate: %.2f G pixel*VPL pairs/s\n", pixels * n * lights / (ms * 1e-3) / 1e9);
    }
    for (auto [n, m] : {std::pair{2, 2}, std::pair{4, 4}, std::pair{8, 8}, std::pair{4, 2}})
      if (want("igi")) bench(ctx, scene, a, "igi",
            {"igi.count=256", "igi.n=" + std::to_string(n), "igi.m=" + std::to_string(m)},
            "igi " + std::to_string(n) + "x" + std::to_string(m) + ", N=256");
    if (want("rsm")) {
      bench(ctx, scene, a, "rsm", {"rsm.samples=400", "rsm.downsample=2"}, "rsm gather, 400 samples, half resolution");
      // The option that shares one sample centre per 8×4 block (docs/techniques/rsm.md).
      bench(ctx, scene, a, "rsm", {"rsm.samples=400", "rsm.downsample=2", "rsm.sample_centre=block"},
            "rsm gather, 400 samples, half resolution, block centres (tolerance 4)");
      bench(ctx, scene, a, "rsm",
            {"rsm.samples=400", "rsm.downsample=2", "rsm.sample_centre=block", "rsm.block_tolerance=1000"},
            "rsm gather, 400 samples, half resolution, block centres for every pixel");
    }
    if (want("splat")) {
      bench(ctx, scene, a, "splat", {"splat.count=256"}, "splat, N=256, default epsilon 1/256");
      bench(ctx, scene, a, "splat", {"splat.count=256", "splat.epsilon=1e-4"}, "splat, N=256, epsilon 1e-4");
    }
    if (want("sh-igi")) {
      bench(ctx, scene, a, "sh-igi", {"sh-igi.count=256"}, "sh-igi 4x4, N=256, 27-channel filter 4x4, glossy");
      bench(ctx, scene, a, "sh-igi", {"sh-igi.count=256", "sh-igi.filter=separable"},
            "sh-igi 4x4, N=256, 27-channel separable filter 4+4, glossy");
    }
    if (!want("vpl")) return 0;
    // d_min bias: mean indirect with the default clamp vs a clamp 100x smaller (≈ no clamp).
    double withClamp = meanIndirect(ctx, scene, a, {"vpl.count=256"});
    double tiny = meanIndirect(ctx, scene, a, {"vpl.count=256", "vpl.d_min=1e-6"});
    std::printf("\nd_min bias (vpl N=256): mean indirect %.6g with default d_min, %.6g with d_min=1e-6 m: "
                "%.3f %% of the energy removed by the clamp\n", withClamp, tiny, 100.0 * (1.0 - withClamp / tiny));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
