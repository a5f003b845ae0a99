// Seed 000's experiment (Hahn 2012, interleaved sampling in RSM gather and splatting), on this
// engine (issue 4, item 4). For N = 64…1024 VPLs per light and patterns 1×1 (un-interleaved),
// 2×2, 2×4, 4×4, 8×8:
//   - time per configuration: the technique's kernels from VPL generation through the
//     discontinuity filter (the thesis's span "after RSM generation through the blur"), device
//     median over frames;
//   - error against the un-interleaved image of the same N: sum over pixels of squared intensity
//     differences, intensity = 0.2989 R + 0.5870 G + 0.1140 B of the display-transformed image
//     in [0, 1] (the thesis's weights);
//   - error against the path-traced one-bounce reference (diffuse only): SSIM of the display
//     images, relMSE of the linear indirect images.
// Gather = `vpl` (1×1) and `igi` (n×m): all-pairs VPL gathering, interleaved, with the box
// discontinuity filter (the default) and with the separable one (the thesis's form). Splatting = `splat`
// un-interleaved and interleaved (ε = 1e-4; both VPL-to-set orderings; rows marked
// "[vs splat 1x1]" compare with the un-interleaved splat, the thesis's SII comparison; interleaved
// splatting is masked per lane, so its time is not an interleaving speed-up). `rsm` (RSM gather
// with N samples per pixel, half resolution) is timed and compared un-interleaved.
// Scene: by default the Cornell box with blocks under the downward spot light (as in the tests);
// `--scene` takes any scene spec `gi` accepts (e.g. scenes/sponza.json, with its own lights and
// camera). Indirect light only. Prints markdown tables (docs/results/interleaving.md records runs).
//
//   build/interleaving_bench [--size 256] [--width W --height H] [--spp 512] [--frames 5] [--scene SPEC]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "cl/runtime.h"
#include "metrics/metrics.h"
#include "reference/path_tracer.h"
#include "render/renderer.h"
#include "render/views.h"
#include "scene/cornell_box.h"
#include "scene/scene_loader.h"

using namespace gi;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

struct Result {
  double ms = 0;
  Image indirect;
};

Result run(cl::Context& ctx, const Scene& s, int width, int height, int frames, const std::string& tech,
           std::vector<std::string> sets) {
  RenderSettings rs;
  rs.width = width;
  rs.height = height;
  rs.technique = tech;
  rs.sets = std::move(sets);
  Renderer r(ctx, s, rs);
  r.renderFrame();
  r.renderFrame();
  std::vector<double> totals;
  for (int f = 0; f < frames; ++f) {
    double t = 0;
    for (auto& [name, ms] : r.renderFrame())
      if (name.rfind(tech + ":", 0) == 0 && name.find("resolve") == std::string::npos &&
          name.find("setup") == std::string::npos && name.find("binning") == std::string::npos &&
          name.find("tiles") == std::string::npos)
        t += ms;  // the technique's kernels only (not the renderer's "rsm: …" raster passes)
    totals.push_back(t);
  }
  return {median(totals), r.indirectRadiance()};
}

double intensitySsd(const Image& a, const Image& b, float exposure) {
  Image da = displayTransform(a, exposure), db = displayTransform(b, exposure);
  double s = 0;
  for (size_t i = 0; i < da.pixelCount(); ++i) {
    const float* p = &da.pixels[i * da.channels];
    const float* q = &db.pixels[i * db.channels];
    double d = 0.2989 * (p[0] - q[0]) + 0.5870 * (p[1] - q[1]) + 0.1140 * (p[2] - q[2]);
    s += d * d;
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  int size = 256, width = 0, height = 0, spp = 512, frames = 5;
  std::string sceneSpec;  // empty: the Cornell box with blocks under the spot light
  const char* usage =
      "usage: interleaving_bench [--size 256] [--width W --height H] [--spp 512] [--frames 5] [--scene SPEC]\n";
  for (int i = 1; i < argc; i += 2) {
    std::string k = argv[i];
    if (k == "--scene" && i + 1 < argc) {
      sceneSpec = argv[i + 1];
      continue;
    }
    int* target = k == "--size"     ? &size
                  : k == "--width"  ? &width
                  : k == "--height" ? &height
                  : k == "--spp"    ? &spp
                  : k == "--frames" ? &frames
                                    : nullptr;
    char* end = nullptr;
    long v = i + 1 < argc ? std::strtol(argv[i + 1], &end, 10) : 0;
    if (!target || i + 1 >= argc || *end != '\0' || v < 1 || v > 100000) {
      std::fprintf(stderr, "error: bad argument '%s'%s\n%s", argv[i],
                   target ? " (expects a whole number 1..100000)" : "", usage);
      return k == "--help" || k == "-h" ? 0 : 2;
    }
    *target = int(v);
  }
  if (width == 0) width = size;
  if (height == 0) height = size;
  try {
    cl::Context ctx(cl::selectDevice(""));
    Scene s;
    std::string sceneName = "Cornell box (blocks), spot light";
    if (sceneSpec.empty()) {
      CornellOptions o;
      o.withAreaLight = false;
      o.spotLight = CornellSpotLight{};
      o.spotLight->intensity = glm::vec3(1.2f, 1.0f, 0.8f);
      s = makeCornellBox(o);
    } else {
      s = loadScene(sceneSpec, "");
      sceneName = sceneSpec;
    }
    RenderSettings rs;
    rs.width = width;
    rs.height = height;
    Renderer probe(ctx, s, rs);
    PathTracerOptions po;
    po.width = width;
    po.height = height;
    po.mode = ReferenceMode::OneBounce;
    po.diffuseOnly = true;
    po.seed = 1;
    PathTracer pt(ctx, s, makeCameraView(probe.camera(), width, height), po);
    while (pt.samplesDone() < spp) pt.addSamples(std::min(64, spp - pt.samplesDone()));
    Image ref = pt.image();
    Image refDisplay = displayTransform(ref, s.exposure);
    std::printf("# Interleaving experiment: %s, %dx%d, indirect only, %s, GI_VW=%d\n", sceneName.c_str(), width,
                height, ctx.device().name.c_str(), ctx.vectorWidth());
    std::printf("reference: path tracer, one-bounce indirect, diffuse only, %d spp\n\n", spp);
    std::printf("| technique | N | pattern | time (ms) | speed-up vs 1x1 | SSD vs 1x1 | SSIM vs reference | relMSE vs reference |\n");
    std::printf("| --- | --- | --- | --- | --- | --- | --- | --- |\n");
    const std::vector<std::pair<int, int>> patterns = {{2, 2}, {2, 4}, {4, 4}, {8, 8}};
    for (int n : {64, 128, 256, 512, 1024}) {
      std::string N = std::to_string(n);
      Result base = run(ctx, s, width, height, frames, "vpl", {"vpl.count=" + N});
      auto row = [&](const char* tech, const std::string& pat, const Result& r, const Result& b) {
        double ssim = metrics::ssim(refDisplay, displayTransform(r.indirect, s.exposure)).mean;
        std::printf("| %s | %d | %s | %.3f | %.1fx | %.4g | %.4f | %.4g |\n", tech, n, pat.c_str(), r.ms, b.ms / r.ms,
                    intensitySsd(r.indirect, b.indirect, s.exposure), ssim, metrics::relMse(ref, r.indirect));
      };
      row("gather (vpl)", "1x1", base, base);
      for (const char* filter : {"box", "separable"})
        for (auto [pn, pm] : patterns) {
          Result r = run(ctx, s, width, height, frames, "igi",
                         {"igi.count=" + N, "igi.n=" + std::to_string(pn), "igi.m=" + std::to_string(pm),
                          std::string("igi.filter=") + filter});
          row(filter == std::string("box") ? "gather (igi)" : "gather (igi, separable filter)",
              std::to_string(pn) + "x" + std::to_string(pm), r, base);
        }
      Result sp = run(ctx, s, width, height, frames, "splat", {"splat.count=" + N});
      row("splat eps=1/256", "1x1", sp, base);
      Result sp4 = run(ctx, s, width, height, frames, "splat", {"splat.count=" + N, "splat.epsilon=1e-4"});
      row("splat eps=1e-4", "1x1", sp4, base);
      // Interleaved splatting against the un-interleaved splat (the thesis's SII comparison).
      for (const char* ord : {"stride", "contiguous"})
        for (auto [pn, pm] : patterns) {
          Result r = run(ctx, s, width, height, frames, "splat",
                         {"splat.count=" + N, "splat.epsilon=1e-4", "splat.n=" + std::to_string(pn),
                          "splat.m=" + std::to_string(pm), std::string("splat.ordering=") + ord});
          row((std::string("splat eps=1e-4 ") + ord + " [vs splat 1x1]").c_str(),
              std::to_string(pn) + "x" + std::to_string(pm), r, sp4);
        }
      Result rg = run(ctx, s, width, height, frames, "rsm", {"rsm.samples=" + N});
      row("rsm gather (N samples, half res)", "1x1", rg, base);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
