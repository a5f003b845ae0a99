// Light propagation volume benchmark (issue 6, item 4): per-kernel device milliseconds (medians
// over frames after warm-up) of the `lpv` technique and the device memory of each configuration.
// Sponza 640×360 with its sun when the media are present, else the built-in Cornell box. Not a
// test: the machine is noisy; docs/PERFORMANCE.md records the numbers next to the targets:
// injection from a 256² RSM <= 2 ms, geometry volume <= 2 ms, one 32³ grid with 32 iterations
// <= 6 ms, lookup <= 2 ms, 3 cascades of 32³ all together <= 25 ms.
//
//   build/lpv_bench [--scene scenes/sponza.json] [--width 640 --height 360] [--frames 9] [--large]
//                   [--falloff] [--propagation] [--config I] [--passes all|propagate|lookup]
//                   [--set lpv.bounces=true ...]
//   (--large adds 64³ cascades and a 128³ grid with 128 iterations; --falloff only prints how
//   far light travels: the on-axis irradiance above one cosine-lobe cell in an empty grid after
//   `resolution` iterations, against the exact Φ/(π r²) of that emitter, at 32³, 64³ and 128³;
//   --propagation only times the propagation of one 16³ and one 32³ grid of random light and
//   blockers: device ms and process CPU ms per step, median and least of --frames runs of
//   `resolution` steps;
//   --config I times only the I-th configuration of the list below, 0-based; --passes times the
//   propagation and/or the lookup alone, repeated on one rendered frame: timePasses; --set adds a
//   parameter to every configuration of the list, e.g. the extensions lpv.bounces, lpv.damping,
//   whose passes show as "lpv: bounces" and inside "lpv: lookup")
#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "cl/runtime.h"
#include "gi/lpv/lpv_volume.h"
#include "gi/technique.h"
#include "kernels/common/sh.h"
#include "scene/cornell_box.h"
#include "scene/scene_loader.h"
#include "technique_timing.h"

using namespace gi;

namespace {

// One upward cosine lobe of flux 1 in cell (n/2, 1, n/2) of an empty n³ grid with 1 m cells,
// propagated n times without blocking; prints E(r) / (1/(π r²)) along the axis above it.
void printFalloff(cl::Context& ctx, int n) {
  LpvVolume v(ctx, n, 1);
  v.begin({LpvCascade{glm::vec3(0.0f), 1.0f}}, 1.0f);
  size_t cells = v.cellsPerGrid();
  std::vector<glm::vec4> grid(cells * 3, glm::vec4(0.0f));
  auto index = [&](int x, int y, int z) { return (size_t(z) * n + y) * n + x; };
  const float kPi = 3.14159265f;
  glm::vec4 lobe(GI_SH_LOBE0 / kPi, GI_SH_LOBE1 / kPi, 0.0f, 0.0f);  // along +y, Φ = 1
  for (int ch = 0; ch < 3; ++ch) grid[ch * cells + index(n / 2, 1, n / 2)] = lobe;
  v.setInjected(grid);
  v.propagate(n, false);
  std::vector<glm::vec4> acc = v.readAccumulated();
  std::printf("  %d^3, %d iterations: E / exact at r =", n, n);
  for (int r = 2; r + 1 < n; r *= 2) {
    glm::vec4 c = acc[index(n / 2, 1 + r, n / 2)];
    double e = GI_SH_COSCONV0 * GI_SH_Y0 * c.x + GI_SH_COSCONV1 * GI_SH_Y1 * c.y;  // receiver facing down
    std::printf("  %d: %.3g", r, e / (1.0 / (kPi * r * r)));
  }
  std::printf(" cells\n");
}

double processCpuMs() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return (u.ru_utime.tv_sec + u.ru_stime.tv_sec) * 1e3 + (u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-3;
}

// Propagation alone on one n³ grid of random light and random blockers: per step, the device time
// (profiler) and the process CPU time (all PoCL threads; less inflated by other processes' load).
void timePropagation(cl::Context& ctx, int n, int runs) {
  LpvVolume v(ctx, n, 1);
  v.begin({LpvCascade{glm::vec3(0.0f), 1.0f}}, 1.0f);
  v.resolve(false);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), pos(0.0f, 1.0f);
  std::vector<glm::vec4> grid(v.cellsPerGrid() * 3), geometry(v.nodesPerGrid());
  for (glm::vec4& c : grid) c = glm::vec4(pos(rng), 0.5f * u(rng), 0.5f * u(rng), 0.5f * u(rng));
  for (glm::vec4& c : geometry) c = 0.3f * glm::vec4(pos(rng), 0.5f * u(rng), 0.5f * u(rng), 0.5f * u(rng));
  v.setGeometry(geometry);
  for (bool blocking : {false, true}) {
    std::vector<double> device, cpu;
    for (int r = 0; r < runs + 1; ++r) {  // the first run warms up
      v.setInjected(grid);
      ctx.finish();
      double c0 = processCpuMs();
      v.propagate(n, blocking);
      double ms = 0.0;
      for (auto& [name, t] : ctx.profiler().collect())
        if (name == "lpv: propagate") ms = t;
      double c1 = processCpuMs();
      if (r == 0) continue;
      device.push_back(ms / n);
      cpu.push_back((c1 - c0) / n);
    }
    std::printf("  %d^3, %d steps, blocking %s: %.3f ms per step on the device, %.3f ms CPU per step (least: %.3f, %.3f)\n",
                n, n, blocking ? "on " : "off", timing::median(device), timing::median(cpu),
                *std::min_element(device.begin(), device.end()), *std::min_element(cpu.begin(), cpu.end()));
  }
}

// The passes one by one on one rendered Sponza frame (its G-buffer and RSM), each repeated `runs`
// times after a warm-up: median device ms (profiler) and process CPU ms per repetition, and the
// least of each (under load the least disturbed repetition). One 32³
// grid over the scene and 3 cascades of 32³ (finest edge = a quarter of the bounds' longest edge,
// centred on the camera). Less noisy than whole frames: nothing else runs between the launches.
// `bounces`, `damping`: the extensions lpv.bounces (its face albedo and reflection passes inside
// "propagate") and lpv.damping (inside "lookup").
void timePasses(cl::Context& ctx, const Scene& scene, const timing::FrameSettings& a, const std::string& which,
                bool bounces, bool damping) {
  RenderSettings rs;
  rs.width = a.width;
  rs.height = a.height;
  rs.technique = "lpv";
  rs.sets = {"lpv.cascades=0", "rsm.resolution=512", "lpv.rsm_size=256"};  // the frame's G-buffer and RSM only
  Renderer r(ctx, scene, rs);
  r.renderFrame();
  const GBuffer& g = r.gbuffer();
  glm::vec3 camera(g.view.eye[0], g.view.eye[1], g.view.eye[2]);
  glm::vec3 e = scene.bounds.extent();
  cl::Buffer out(ctx, size_t(g.width) * g.height * 16, CL_MEM_READ_WRITE, "lpv bench output");
  for (int cascades : {0, 3}) {
    const int n = 32;
    LpvVolume v(ctx, n, std::max(cascades, 1), LpvLookupStorage::Buffer, bounces);
    auto layout = lpvCascadeLayout(scene.bounds, camera, n, cascades, std::max({e.x, e.y, e.z}) / 4.0f);
    auto runPass = [&](const char* what, auto&& pass) {
      std::vector<double> device, cpu;
      for (int i = 0; i < a.frames + 1; ++i) {  // the first run warms up
        ctx.finish();
        ctx.profiler().discard();
        double c0 = processCpuMs();
        pass();
        double ms = 0.0;
        for (auto& [name, t] : ctx.profiler().collect()) ms += t;
        double c1 = processCpuMs();
        if (i == 0) continue;
        device.push_back(ms);
        cpu.push_back(c1 - c0);
      }
      std::printf("  %-44s %8.3f ms device, %8.3f ms CPU (least: %.3f, %.3f)\n", what, timing::median(device),
                  timing::median(cpu), *std::min_element(device.begin(), device.end()),
                  *std::min_element(cpu.begin(), cpu.end()));
    };
    std::printf("%s:\n", cascades ? "3 cascades of 32^3" : "one 32^3 grid over the scene");
    auto fill = [&] {
      v.begin(layout, lpvInjectionFixedScale(scene, r.rsms()));
      for (const ReflectiveShadowMap& m : r.rsms()) {
        v.inject(m.position, m.normal, m.flux, m.view.width, 2, 0.5f);
        v.addGeometryRsm(m.view, m.position, m.normal, m.view.width);
      }
      v.addGeometryCamera(g);
      v.resolve(true);
    };
    runPass("inject + geometry + resolve", fill);
    if (which != "lookup") runPass("propagate, 32 steps with blocking", [&] { v.propagate(n, true); });
    if (which != "propagate") runPass("lookup (lookup grid + per pixel)", [&] { v.lookup(g, cascades > 0, out, damping); });
  }
}

}  // namespace

int main(int argc, char** argv) {
  timing::FrameSettings a;
  std::string sceneName = "scenes/sponza.json";
  bool large = false, falloff = false, propagation = false;
  std::string passes;  // --passes all | propagate | lookup
  int onlyConfig = -1;
  std::vector<std::string> extraSets;
  for (int i = 1; i < argc; ++i) {
    std::string k = argv[i];
    auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (k == "--scene") sceneName = next();
    else if (k == "--width") a.width = std::stoi(next());
    else if (k == "--height") a.height = std::stoi(next());
    else if (k == "--frames") a.frames = std::stoi(next());
    else if (k == "--large") large = true;
    else if (k == "--falloff") falloff = true;
    else if (k == "--propagation") propagation = true;
    else if (k == "--passes") passes = next();
    else if (k == "--config") onlyConfig = std::stoi(next());
    else if (k == "--set") extraSets.push_back(next());
    else {
      std::fprintf(stderr, "usage: lpv_bench [--scene S] [--width W --height H] [--frames N] [--large] [--falloff] [--propagation] [--config I] [--passes all|propagate|lookup] [--set K=V]...\n");
      return 2;
    }
  }
  try {
    cl::Context ctx(cl::selectDevice(""));
    if (falloff) {
      std::printf("lpv falloff: on-axis irradiance above one cosine-lobe cell, relative to the exact 1/(pi r^2)\n");
      for (int n : {32, 64, 128}) printFalloff(ctx, n);
      return 0;
    }
    if (propagation) {
      std::printf("lpv propagation alone (%s), median of %d runs\n", ctx.device().name.c_str(), a.frames);
      for (int n : {16, 32}) timePropagation(ctx, n, a.frames);
      return 0;
    }
    Scene scene;
    try {
      scene = loadScene(sceneName, "");
    } catch (const std::exception& e) {
      std::printf("(%s not loadable: %s; using the built-in Cornell box)\n", sceneName.c_str(), e.what());
      scene = makeCornellBox();
    }
    if (!passes.empty()) {
      std::printf("lpv passes alone: %s, %dx%d, %s, median of %d runs\n", scene.name.c_str(), a.width, a.height,
                  ctx.device().name.c_str(), a.frames);
      // The technique's own parameter parsing (true / 1 / on, range checks) for the lpv.* sets.
      ParamSet lpvParams;
      findTechnique("lpv")->declareParams(lpvParams);
      for (const std::string& set : extraSets)
        if (set.rfind("lpv.", 0) == 0) lpvParams.set(set);
      timePasses(ctx, scene, a, passes, lpvParams.getBool("lpv.bounces"), lpvParams.getBool("lpv.damping"));
      return 0;
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
    for (size_t i = 0; i < configs.size(); ++i) {
      if (onlyConfig >= 0 && size_t(onlyConfig) != i) continue;
      const Config& c = configs[i];
      std::vector<std::string> sets = {"lpv.resolution=" + std::to_string(c.resolution),
                                       "lpv.cascades=" + std::to_string(c.cascades),
                                       "rsm.resolution=" + std::to_string(c.rsm), "lpv.rsm_size=256"};
      sets.insert(sets.end(), extraSets.begin(), extraSets.end());
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
