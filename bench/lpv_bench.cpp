// Light propagation volume benchmark (issue 6, item 4): per-kernel device milliseconds (medians
// over frames after warm-up) of the `lpv` technique and the device memory of each configuration.
// Sponza 640×360 with its sun when the media are present, else the built-in Cornell box. Not a
// test: the machine is noisy; docs/PERFORMANCE.md records the numbers next to the targets:
// injection from a 256² RSM <= 2 ms, geometry volume <= 2 ms, one 32³ grid with 32 iterations
// <= 6 ms, lookup <= 2 ms, 3 cascades of 32³ all together <= 25 ms.
//
//   build/lpv_bench [--scene scenes/sponza.json] [--width 640 --height 360] [--frames 9] [--large]
//   (--large adds 64³ cascades and a 128³ grid with 128 iterations)
#include <cstdio>
#include <string>
#include <vector>

#include "cl/runtime.h"
#include "gi/lpv/lpv_volume.h"
#include "scene/cornell_box.h"
#include "scene/scene_loader.h"
#include "technique_timing.h"

using namespace gi;

int main(int argc, char** argv) {
  timing::FrameSettings a;
  std::string sceneName = "scenes/sponza.json";
  bool large = false;
  for (int i = 1; i < argc; ++i) {
    std::string k = argv[i];
    auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (k == "--scene") sceneName = next();
    else if (k == "--width") a.width = std::stoi(next());
    else if (k == "--height") a.height = std::stoi(next());
    else if (k == "--frames") a.frames = std::stoi(next());
    else if (k == "--large") large = true;
    else {
      std::fprintf(stderr, "usage: lpv_bench [--scene S] [--width W --height H] [--frames N] [--large]\n");
      return 2;
    }
  }
  try {
    cl::Context ctx(cl::selectDevice(""));
    Scene scene;
    try {
      scene = loadScene(sceneName, "");
    } catch (const std::exception& e) {
      std::printf("(%s not loadable: %s; using the built-in Cornell box)\n", sceneName.c_str(), e.what());
      scene = makeCornellBox();
    }
    std::printf("lpv bench: %s, %dx%d, %s, median of %d frames after %d warm-up\n", scene.name.c_str(), a.width,
                a.height, ctx.device().name.c_str(), a.frames, a.warmup);
    struct Config {
      int resolution, cascades, rsm;
      const char* title;
    };
    std::vector<Config> configs = {
        {32, 0, 256, "one 32^3 grid over the scene, 32 iterations, RSM 256^2"},
        {32, 0, 512, "one 32^3 grid, 32 iterations, RSM 512^2 merged to 256^2"},
        {32, 3, 512, "3 cascades of 32^3, 32 iterations (default)"},
        {64, 0, 512, "one 64^3 grid, 64 iterations"},
    };
    if (large) {
      configs.push_back({64, 3, 512, "3 cascades of 64^3, 64 iterations"});
      configs.push_back({128, 0, 512, "one 128^3 grid, 128 iterations"});
    }
    for (const Config& c : configs) {
      std::vector<std::string> sets = {"lpv.resolution=" + std::to_string(c.resolution),
                                       "lpv.cascades=" + std::to_string(c.cascades),
                                       "rsm.resolution=" + std::to_string(c.rsm), "lpv.rsm_size=256"};
      auto t = timing::timeTechnique(ctx, scene, a, "lpv", sets, c.title);
      int iterations = c.resolution;
      double perStep = t["lpv: propagate"] / iterations / std::max(c.cascades, 1);
      LpvVolume volume(ctx, c.resolution, std::max(c.cascades, 1));
      std::printf("  propagation per step and grid: %.3f ms; device memory of the volumes: %.1f MiB\n", perStep,
                  volume.bytes() / 1048576.0);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
