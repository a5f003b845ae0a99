// Shared by the technique benchmarks: render frames of one technique and print the median device
// milliseconds of each of its kernels (the profiler's names that start with the technique's name).
#pragma once
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "render/renderer.h"
#include "scene/cornell_box.h"
#include "scene/scene_loader.h"

namespace gi::timing {

inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

struct FrameSettings {
  int frames = 9, warmup = 2, width = 640, height = 360;
};

// The common command line of the technique benchmarks:
//   [--scene S] [--width W --height H] [--frames N] [--quick] [--only NAME]
struct BenchArgs {
  FrameSettings frames;
  std::string scenePath = "scenes/sponza.json";
  bool quick = false;
  std::string only;  // a benchmark with several parts runs only this one
};

// False (with the usage printed) on an unknown argument.
inline bool parseBenchArgs(int argc, char** argv, const char* program, BenchArgs& a) {
  for (int i = 1; i < argc; ++i) {
    std::string k = argv[i];
    auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (k == "--scene") a.scenePath = next();
    else if (k == "--width") a.frames.width = std::stoi(next());
    else if (k == "--height") a.frames.height = std::stoi(next());
    else if (k == "--frames") a.frames.frames = std::stoi(next());
    else if (k == "--quick") a.quick = true;
    else if (k == "--only") a.only = next();
    else {
      std::fprintf(stderr, "usage: %s [--scene S] [--width W --height H] [--frames N] [--quick] [--only NAME]\n",
                   program);
      return false;
    }
  }
  return true;
}

// The benchmark's scene, or the built-in Cornell box (with a note) when it does not load.
inline Scene loadBenchScene(const std::string& path) {
  try {
    return loadScene(path, "");
  } catch (const std::exception& e) {
    std::printf("(%s not loadable: %s; using the built-in Cornell box)\n", path.c_str(), e.what());
    return makeCornellBox();
  }
}

// The renderer settings of one benchmark configuration.
inline RenderSettings renderSettings(const FrameSettings& a, const std::string& technique,
                                     const std::vector<std::string>& sets) {
  RenderSettings rs;
  rs.width = a.width;
  rs.height = a.height;
  rs.technique = technique;
  rs.sets = sets;
  return rs;
}

// "\n<title>  (<technique> <set> <set> …)", the heading of a configuration's table (no newline).
inline void printConfiguration(const std::string& title, const std::string& technique,
                               const std::vector<std::string>& sets) {
  std::printf("\n%s  (%s", title.c_str(), technique.c_str());
  for (auto& s : sets) std::printf(" %s", s.c_str());
  std::printf(")");
}

// Renders warm-up frames, then `frames` timed ones; prints the technique's kernels (not the shared
// raster passes) and a total; returns every pass's median by name, plus "__total".
inline std::map<std::string, double> timeTechnique(cl::Context& ctx, const Scene& scene, const FrameSettings& a,
                                                   const std::string& technique, std::vector<std::string> sets,
                                                   const std::string& title) {
  Renderer r(ctx, scene, renderSettings(a, technique, sets));
  for (int i = 0; i < a.warmup; ++i) r.renderFrame();
  std::map<std::string, std::vector<double>> per;
  std::vector<std::string> order;
  for (int f = 0; f < a.frames; ++f)
    for (auto& [name, ms] : r.renderFrame()) {
      if (!per.count(name)) order.push_back(name);
      per[name].push_back(ms);
    }
  printConfiguration(title, technique, sets);
  std::printf("\n");
  std::map<std::string, double> out;
  double total = 0;
  for (auto& name : order) {
    double m = median(per[name]);
    out[name] = m;
    if (name.rfind(technique, 0) == 0) {
      std::printf("  %-34s %8.3f ms\n", name.c_str(), m);
      total += m;
    }
  }
  std::printf("  %-34s %8.3f ms\n", "technique total", total);
  out["__total"] = total;
  return out;
}

// The two kernel trees of a kernel A/B (GI_AB_KERNEL_DIRS="DIR_A,DIR_B", each a folder holding
// kernels/ as for GI_KERNEL_DIR): the benches build the judged passes once from each tree and
// run them alternately in one process, so that both variants see the same machine load. Empty
// when the variable is unset; an error without the comma.
inline std::vector<std::string> abKernelDirs() {
  const char* e = std::getenv("GI_AB_KERNEL_DIRS");
  if (!e) return {};
  std::string s(e);
  size_t c = s.find(',');
  if (c == std::string::npos || c == 0 || c + 1 == s.size())
    throw std::runtime_error("GI_AB_KERNEL_DIRS = '" + s + "': expected two kernel folders, DIR_A,DIR_B");
  return {s.substr(0, c), s.substr(c + 1)};
}

// Kernel A/B of one technique configuration (abKernelDirs): one renderer per tree, each built and
// warmed up with GI_KERNEL_DIR set to its tree, then frames rendered alternately A, B, A, B, …;
// prints each technique pass's minimum and median device milliseconds per variant.
// Returns false (printing nothing) when GI_AB_KERNEL_DIRS is unset.
inline bool abTechnique(cl::Context& ctx, const Scene& scene, const FrameSettings& a, const std::string& technique,
                        const std::vector<std::string>& sets, const std::string& title) {
  const std::vector<std::string> dirs = abKernelDirs();
  if (dirs.empty()) return false;
  const RenderSettings rs = renderSettings(a, technique, sets);
  std::vector<std::unique_ptr<Renderer>> r;
  for (const std::string& d : dirs) {
    setenv("GI_KERNEL_DIR", d.c_str(), 1);
    r.push_back(std::make_unique<Renderer>(ctx, scene, rs));
    for (int i = 0; i < a.warmup; ++i) r.back()->renderFrame();
  }
  unsetenv("GI_KERNEL_DIR");
  std::map<std::string, std::vector<double>> per[2];
  std::vector<std::string> order;
  for (int f = 0; f < a.frames; ++f)
    for (int k = 0; k < 2; ++k)
      for (auto& [name, ms] : r[k]->renderFrame()) {
        if (k == 0 && !per[0].count(name)) order.push_back(name);
        per[k][name].push_back(ms);
      }
  printConfiguration(title, technique, sets);
  std::printf(", kernel A/B, %d alternating frames: A = %s, B = %s\n", a.frames, dirs[0].c_str(), dirs[1].c_str());
  for (auto& name : order) {
    if (name.rfind(technique, 0) != 0) continue;
    for (int k = 0; k < 2; ++k) {
      const std::vector<double>& ms = per[k][name];
      std::printf("  %-34s %c: min %8.3f, median %8.3f ms\n", name.c_str(), char('A' + k),
                  *std::min_element(ms.begin(), ms.end()), median(ms));
    }
  }
  return true;
}

}  // namespace gi::timing
