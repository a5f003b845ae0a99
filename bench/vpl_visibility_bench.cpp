// VPL visibility benchmark (issue 5, item 6): `vpl` with `vpl.visibility=rays` — device ms of the
// gather with its shadow rays vs without, the number of rays it traced (pairs that face each
// other: counted on the host from the read-back G-buffer and VPLs with the kernel's formula) and
// rays per second; then the same rays, written out on the host, traced by the reference tracer's
// batch kernel (trace_any_rays, one ray per work-item) for its throughput in the same run — and
// their answers compared with the gather's (the gather's irradiance must equal the host sum over
// the pairs the batch kernel found unoccluded). Not a test: the machine is noisy; record the numbers
// with the load average in docs/PERFORMANCE.md.
//
//   build/vpl_visibility_bench [--scene scenes/sponza.json] [--width 320 --height 180] [--count 64] [--frames 3]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cl/runtime.h"
#include "gi/vpl/vpl_lights.h"
#include "reference/bvh.h"
#include "render/renderer.h"
#include "scene/cornell_box.h"
#include "scene/scene_loader.h"
#include "technique_timing.h"

using namespace gi;

int main(int argc, char** argv) {
  timing::FrameSettings a;
  a.width = 320;
  a.height = 180;
  a.frames = 3;
  a.warmup = 1;
  std::string scenePath = "scenes/sponza.json";
  int count = 64;
  for (int i = 1; i < argc; ++i) {
    std::string k = argv[i];
    auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (k == "--scene") scenePath = next();
    else if (k == "--width") a.width = std::stoi(next());
    else if (k == "--height") a.height = std::stoi(next());
    else if (k == "--count") count = std::stoi(next());
    else if (k == "--frames") a.frames = std::stoi(next());
    else {
      std::fprintf(stderr, "usage: vpl_visibility_bench [--scene S|cornell] [--width W --height H] [--count N] [--frames F]\n");
      return 2;
    }
  }
  try {
    cl::Context ctx(cl::selectDevice(""));
    Scene scene;
    if (scenePath == "cornell") {
      scene = makeCornellBox();
    } else {
      try {
        scene = loadScene(scenePath, "");
      } catch (const std::exception& e) {
        std::printf("(%s not loadable: %s; using the built-in Cornell box)\n", scenePath.c_str(), e.what());
        scene = makeCornellBox();
      }
    }
    std::printf("vpl visibility bench: %s (%zu triangles), %dx%d, %d VPLs per light, %s, median of %d frames\n",
                scene.name.c_str(), scene.triangles.size(), a.width, a.height, count, ctx.device().name.c_str(),
                a.frames);
    std::string n = "vpl.count=" + std::to_string(count);
    auto none = timing::timeTechnique(ctx, scene, a, "vpl", {n}, "no visibility");
    auto rays = timing::timeTechnique(ctx, scene, a, "vpl", {n, "vpl.visibility=rays"}, "visibility rays");

    // The pairs the gather traced: one frame's G-buffer and VPLs on the host.
    RenderSettings rs;
    rs.width = a.width;
    rs.height = a.height;
    rs.technique = "vpl";
    rs.sets = {n, "vpl.visibility=rays"};
    Renderer r(ctx, scene, rs);
    r.renderFrame();
    Image gathered = r.indirectRadiance();
    VplGenerator gen(ctx);
    VplSet v;
    gen.generate(r.rsms(), count, 0.0f, v);
    auto raw = ctx.download<glm::vec4>(v.vpls);
    auto pos = ctx.download<glm::vec4>(r.gbuffer().position), nrm = ctx.download<glm::vec4>(r.gbuffer().normal),
         alb = ctx.download<glm::vec4>(r.gbuffer().albedo);
    ctx.profiler().discard();
    const float eps = 1e-3f;  // vpl.ray_epsilon default
    std::vector<glm::vec4> origins, dirs;
    std::vector<std::pair<uint32_t, uint32_t>> pairOf;  // (pixel, VPL)
    for (size_t p = 0; p < pos.size(); ++p) {
      if (pos[p].w <= 0) continue;
      glm::vec3 x(pos[p]), nn(nrm[p]);
      for (int k = 0; k < v.count; ++k) {
        glm::vec3 d = glm::vec3(raw[3 * k]) - x;
        float d2 = glm::dot(d, d);
        float g = std::max(-glm::dot(glm::vec3(raw[3 * k + 1]), d), 0.0f) * std::max(glm::dot(nn, d), 0.0f) /
                  (std::max(d2, 1e-20f) * std::max(d2, raw[3 * k].w));
        if (!(g > 0.0f)) continue;
        float t0 = eps / std::sqrt(d2);
        if (!(t0 < 0.5f)) continue;
        origins.emplace_back(x, t0);
        dirs.emplace_back(d, 1.0f - t0);
        pairOf.emplace_back(uint32_t(p), uint32_t(k));
      }
    }
    double pairsAll = double(a.width) * a.height * v.count;
    double shadeNone = none["vpl: shade"], shadeRays = rays["vpl: shade + rays"];
    double traced = double(origins.size());
    std::printf("\npairs: %.0f pixel*VPL, %.0f traced (facing each other, %.1f %%)\n", pairsAll, traced,
                100.0 * traced / pairsAll);
    std::printf("gather: %.2f ms without visibility, %.2f ms with rays -> %.2f Mrays/s in the gather "
                "(%.2f ms per million rays more than no visibility)\n",
                shadeNone, shadeRays, traced / (shadeRays * 1e-3) / 1e6, (shadeRays - shadeNone) / (traced / 1e6));

    // The same rays through the reference tracer's batch any-hit kernel.
    DeviceBvh bvh(ctx, scene, r.deviceScene());
    cl::Program prog = ctx.buildProgram("kernels/reference/trace_rays.cl");
    cl::Kernel k = prog.kernel("trace_any_rays");
    cl::Buffer ob = ctx.upload(origins, "origins"), db = ctx.upload(dirs, "directions");
    cl::Buffer occ(ctx, std::max<size_t>(1, origins.size()) * 4);
    unsigned i = bvh.setArgs(k, 0);
    k.setArg(i++, ob);
    k.setArg(i++, db);
    k.setArg(i++, occ);
    k.setArg(i++, uint32_t(origins.size()));
    std::vector<double> ms;
    for (int f = 0; f < a.frames + 1; ++f) {
      auto t0 = std::chrono::steady_clock::now();
      ctx.launch(k, cl::NDRange::d1(cl::roundUp(origins.size(), 64), 64), "trace_any_rays");
      ctx.finish();
      auto t1 = std::chrono::steady_clock::now();
      if (f > 0) ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    }
    ctx.profiler().discard();
    double batch = timing::median(ms);
    std::printf("reference tracer (trace_any_rays, same rays, wall time): %.2f ms -> %.2f Mrays/s; "
                "in-gather / batch = %.2f\n", batch, traced / (batch * 1e-3) / 1e6, batch / shadeRays);

    // Cross-check: the gather's irradiance = the host sum over the pairs the batch kernel left open.
    auto occluded = ctx.download<uint32_t>(occ);
    std::vector<glm::vec3> e(pos.size(), glm::vec3(0.0f));
    size_t blocked = 0;
    for (size_t j = 0; j < pairOf.size(); ++j) {
      if (occluded[j]) {
        ++blocked;
        continue;
      }
      auto [p, kk] = pairOf[j];
      glm::vec3 d = glm::vec3(raw[3 * kk]) - glm::vec3(pos[p]);
      float d2 = glm::dot(d, d);
      float g = std::max(-glm::dot(glm::vec3(raw[3 * kk + 1]), d), 0.0f) * std::max(glm::dot(glm::vec3(nrm[p]), d), 0.0f) /
                (std::max(d2, 1e-20f) * std::max(d2, raw[3 * kk].w));
      e[p] += glm::vec3(raw[3 * kk + 2]) * g;
    }
    size_t agree = 0;
    for (size_t p = 0; p < pos.size(); ++p) {
      glm::vec3 expected = glm::vec3(alb[p]) * e[p] * (0.31830988618379067154f * 0.31830988618379067154f);
      bool same = true;
      for (int c = 0; c < 3; ++c)
        same &= std::abs(gathered.pixels[p * 3 + c] - expected[c]) <= 1e-3f * expected[c] + 1e-7f;
      agree += same;
    }
    std::printf("occluded: %.1f %% of the traced pairs; %zu of %zu pixels of the gather equal the host sum over "
                "the batch kernel's unoccluded pairs\n", 100.0 * blocked / std::max(1.0, traced), agree, pos.size());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
