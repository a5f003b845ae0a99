// Voxel cone tracing benchmark (issue 7, item 7): per-kernel device milliseconds (medians over
// frames after warm-up) of `vct` configurations, and the device memory of each voxel
// configuration. Sponza 640×360 with its sun when the media are present, else the built-in
// Cornell box. Not a test: the machine is noisy; docs/PERFORMANCE.md records the numbers.
//
//   build/vct_bench [--scene scenes/sponza.json] [--width 640 --height 360] [--frames 5] [--quick]
//                   [--only voxelize|cones]
// --quick: only the default configuration and the targets (128³).
// --only voxelize: only the voxelization passes at 128³ (clear, voxelize, occupied list), repeated
//   `frames` times without rendering, with the lanes kernel (vct_voxelize) and the trianglewise
//   one (vct_voxelize_trianglewise) alternately; prints the minimum beside the median (on a shared
//   machine the minimum is the better estimate of the unloaded time).
// --only cones: only the two isotropic 128³ configurations (diffuse cones at full and at half
//   resolution, specular cone), for A/B timing of the cone marches.
// GI_AB_KERNEL_DIRS=DIR_A,DIR_B (two kernel trees, as for GI_KERNEL_DIR): each configuration is
//   rendered by one renderer per tree, frames alternating, and both variants' passes are printed
//   (min and median): the way to compare a kernel change on a noisy machine.
#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "gi/vct/voxel_scene.h"
#include "technique_timing.h"

using namespace gi;

int main(int argc, char** argv) {
  timing::BenchArgs args;
  args.frames.frames = 5;
  if (!timing::parseBenchArgs(argc, argv, "vct_bench", args)) return 2;
  const timing::FrameSettings& a = args.frames;
  bool quick = args.quick;
  try {
    cl::Context ctx(cl::selectDevice(""));
    Scene scene = timing::loadBenchScene(args.scenePath);
    std::printf("vct bench: %s (%zu triangles), %dx%d, %s, median of %d frames after %d warm-up\n", scene.name.c_str(),
                scene.triangleCount(), a.width, a.height, ctx.device().name.c_str(), a.frames, a.warmup);
    std::printf("targets (issue 7, Sponza 640x360): voxelize 128^3 <= 60 ms, inject <= 5 ms, mips <= 3 ms "
                "(anisotropic <= 10 ms), 6 diffuse cones half-res + upsample <= 15 ms, full res <= 40 ms, "
                "specular cone <= 10 ms\n");
    for (int res : {32, 64, 128, 256})
      std::printf("memory %3d^3: isotropic %7.1f MB, anisotropic %7.1f MB; SH voxels: isotropic %7.1f MB, "
                  "anisotropic %7.1f MB; directional voxels %7.1f MB; + continuous specular march's empty-space map "
                  "%5.1f MB\n", res, VoxelScene::bytesFor(res, false) / 1e6,
                  VoxelScene::bytesFor(res, true) / 1e6, VoxelScene::bytesFor(res, false, true) / 1e6,
                  VoxelScene::bytesFor(res, true, true) / 1e6, VoxelScene::bytesFor(res, true, false, true) / 1e6,
                  VoxelScene::emptySpaceBytesFor(res) / 1e6);
    if (args.only == "voxelize") {
      // The lanes kernel and the trianglewise reference alternately, frame by frame, so that both
      // see the same machine load.
      DeviceScene ds(ctx, scene);
      VoxelScene vs(ctx, scene, 128);
      using K = VoxelScene::VoxelizeKernel;
      const std::pair<K, const char*> kernels[] = {{K::Lanes, "lanes"}, {K::Trianglewise, "trianglewise"}};
      for (int i = 0; i < a.warmup; ++i)
        for (auto& k : kernels) vs.voxelize(ds, k.first);
      ctx.profiler().discard();
      std::map<std::string, std::vector<double>> per;
      for (int f = 0; f < a.frames; ++f)
        for (auto& k : kernels) {
          vs.voxelize(ds, k.first);
          for (auto& [name, ms] : ctx.profiler().collect()) per[std::string(k.second) + "  " + name].push_back(ms);
        }
      std::printf("\n128^3 voxelization only, %d repetitions of each kernel, alternating\n", a.frames);
      for (auto& [name, ms] : per)
        std::printf("  %-48s median %8.3f ms, min %8.3f ms\n", name.c_str(), timing::median(ms),
                    *std::min_element(ms.begin(), ms.end()));
      return 0;
    }
    struct Config {
      std::vector<std::string> sets;
      std::string title;
    };
    std::vector<Config> configs = {
        {{"vct.resolution=128", "vct.mips=isotropic"}, "128^3 isotropic, 6 cones, full resolution, specular, re-voxelized every frame"},
        {{"vct.resolution=128", "vct.mips=anisotropic"}, "128^3 anisotropic, 6 cones, full resolution"},
        {{"vct.resolution=128", "vct.mips=isotropic", "vct.downsample=2"}, "128^3 isotropic, 6 cones at half resolution + upsampling"},
        {{"vct.resolution=128", "vct.mips=anisotropic", "vct.downsample=2"}, "128^3 anisotropic, half resolution"},
    };
    if (args.only == "cones") configs = {configs[0], configs[2]};
    else if (!args.only.empty()) throw std::runtime_error("--only: expected voxelize or cones, got '" + args.only + "'");
    if (!quick && args.only.empty()) {
      configs.push_back({{"vct.resolution=128", "vct.mips=isotropic", "vct.cones=9"}, "128^3 isotropic, 9 cones (ten Brug)"});
      configs.push_back({{"vct.resolution=128", "vct.bounces=2"}, "128^3 anisotropic, second bounce"});
      configs.push_back({{"vct.resolution=128", "vct.mips=isotropic", "vct.voxels=sh", "vct.downsample=2"},
                         "128^3 SH voxels, isotropic mips, half resolution"});
      configs.push_back({{"vct.resolution=128", "vct.voxels=sh", "vct.downsample=2"},
                         "128^3 SH voxels, anisotropic mips, half resolution"});
      configs.push_back({{"vct.resolution=128", "vct.static=1"}, "128^3 anisotropic, voxelized once (static)"});
      configs.push_back({{"vct.resolution=32"}, "32^3 anisotropic"});
      configs.push_back({{"vct.resolution=64"}, "64^3 anisotropic"});
      configs.push_back({{"vct.resolution=256", "vct.downsample=2"}, "256^3 anisotropic, half resolution"});
    }
    for (const Config& c : configs)
      if (!timing::abTechnique(ctx, scene, a, "vct", c.sets, c.title))
        timing::timeTechnique(ctx, scene, a, "vct", c.sets, c.title);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
