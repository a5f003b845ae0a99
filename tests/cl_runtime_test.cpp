#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "cl/kernel_sources.h"
#include "cl/runtime.h"
#include "cl/tile_groups.h"
#include "kernels/common/shared_types.h"
#include "test_support.h"

using namespace gi;

TEST(ClRuntime, ListsPoclCpuDevice) {
  auto devices = cl::listDevices();
  ASSERT_FALSE(devices.empty());
  auto cpu = cl::selectDevice("cpu");
  EXPECT_TRUE(cpu.isCpu);
  EXPECT_EQ(cl::selectDevice("0").id, devices[0].id);
  EXPECT_THROW(cl::selectDevice("no-such-device-name"), Error);
  EXPECT_THROW(cl::selectDevice("99"), Error);
}

TEST(ClRuntime, KernelRunsAndIsProfiled) {
  auto& ctx = test::context();
  cl::Program prog = ctx.buildProgram("kernels/common/test_kernels.cl");
  cl::Kernel k = prog.kernel("add_one");
  std::vector<float> v(1000, 2.0f);
  cl::Buffer b = ctx.upload(v, "test data", CL_MEM_READ_WRITE);
  ctx.profiler().discard();
  k.args(b, uint32_t(v.size()));
  ctx.launch(k, cl::NDRange::d1(v.size()), "add one");
  auto times = ctx.profiler().collect();
  ASSERT_EQ(times.size(), 1u);
  EXPECT_EQ(times[0].first, "add one");
  EXPECT_GE(times[0].second, 0.0);
  auto out = ctx.download<float>(b);
  for (float f : out) ASSERT_EQ(f, 3.0f);
}

TEST(ClRuntime, SharedStructLayoutMatchesDevice) {
  auto& ctx = test::context();
  cl::Program prog = ctx.buildProgram("kernels/common/test_kernels.cl");
  GiMaterial m{};
  m.base_color[2] = 0.25f;
  m.roughness = 0.5f;
  m.normal_tex = 7;
  m.double_sided = 1;
  cl::Buffer mb = ctx.upload(std::vector<GiMaterial>{m}, "material");
  cl::Buffer out(ctx, 4 * sizeof(float));
  cl::Kernel k = prog.kernel("material_roundtrip");
  k.args(mb, out);
  ctx.launch(k, cl::NDRange::d1(1));
  ctx.profiler().discard();
  auto r = ctx.download<float>(out);
  EXPECT_EQ(r[0], 0.25f);
  EXPECT_EQ(r[1], 0.5f);
  EXPECT_EQ(r[2], 7.0f);
  EXPECT_EQ(r[3], 1.0f);
}

TEST(ClRuntime, WarmStartLoadsCachedBinary) {
  auto dir = test::tempDir("kcache");
  setenv("GI_CACHE_DIR", dir.c_str(), 1);
  auto& ctx = test::context();
  cl::Program cold = ctx.buildProgram("kernels/common/test_kernels.cl", {{"GI_TEST_CACHE", "1"}});
  EXPECT_FALSE(cold.fromCache());
  cl::Program warm = ctx.buildProgram("kernels/common/test_kernels.cl", {{"GI_TEST_CACHE", "1"}});
  EXPECT_TRUE(warm.fromCache());
  // Different options: a different cache entry.
  cl::Program other = ctx.buildProgram("kernels/common/test_kernels.cl", {{"GI_TEST_CACHE", "2"}});
  EXPECT_FALSE(other.fromCache());
  unsetenv("GI_CACHE_DIR");
  std::filesystem::remove_all(dir);
}

TEST(ClRuntime, BuildErrorNamesKernelFileAndLine) {
  auto dir = test::tempDir("kbroken");
  std::filesystem::create_directories(dir / "kernels/common");
  // The broken file includes a real header, so the reported line must survive #line mapping.
  {
    FILE* f = std::fopen((dir / "kernels/common/broken.cl").c_str(), "w");
    std::fputs("#include \"common/shared_types.h\"\n\nkernel void k(global float* x) {\n  x[0] = undefined_name;\n}\n", f);
    std::fclose(f);
  }
  std::filesystem::copy(std::filesystem::path(GI_SOURCE_DIR) / "kernels/common/shared_types.h",
                        dir / "kernels/common/shared_types.h");
  setenv("GI_KERNEL_DIR", dir.c_str(), 1);
  try {
    test::context().buildProgram("kernels/common/broken.cl");
    FAIL() << "broken kernel built";
  } catch (const Error& e) {
    std::string msg = e.what();
    EXPECT_NE(msg.find("kernels/common/broken.cl:4"), std::string::npos) << msg;
    EXPECT_NE(msg.find("undefined_name"), std::string::npos) << msg;
  }
  unsetenv("GI_KERNEL_DIR");
  std::filesystem::remove_all(dir);
}

TEST(ClRuntime, RefusesAllocationLargerThanDevice) {
  auto& ctx = test::context();
  try {
    cl::Buffer huge(ctx, size_t(1) << 50, CL_MEM_READ_WRITE, "absurd test buffer");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("absurd test buffer"), std::string::npos);
  }
}

// Launches at 640 × 360 with 16 lanes on PoCL's 2 threads (at least 400 groups): the RSM gather
// at half resolution, 20 × 45 work-items, 4 × 4 → 2 × 1 (60 → 450 groups); the vct diffuse cones
// at half resolution, 80 × 45, 4 × 4 → 4 × 2 (240 → 460), at full resolution 160 × 90 kept
// (920). 4 threads want 800 groups; a GPU keeps the given group.
TEST(ClTileGroups, HalvesTheGroupUntilPoclCanDealTheLaunchEvenly) {
  cl::DeviceInfo cpu;
  cpu.isCpu = true;
  cpu.computeUnits = 2;
  cl::NDRange r = cl::balancedTileGroups(cpu, 20, 45, 4, 4);
  EXPECT_EQ(r.local[0], 2u);
  EXPECT_EQ(r.local[1], 1u);
  EXPECT_EQ(r.global[0], 20u);
  EXPECT_EQ(r.global[1], 45u);
  r = cl::balancedTileGroups(cpu, 80, 45, 4, 4);
  EXPECT_EQ(r.local[0], 4u);
  EXPECT_EQ(r.local[1], 2u);
  EXPECT_EQ(r.global[1], 46u);
  EXPECT_EQ(cl::balancedTileGroups(cpu, 160, 90, 4, 4).local[1], 4u);
  cpu.computeUnits = 4;
  EXPECT_EQ(cl::balancedTileGroups(cpu, 20, 45, 4, 4).local[0], 1u);
  cl::DeviceInfo gpu;
  gpu.isGpu = true;
  gpu.computeUnits = 2;
  EXPECT_EQ(cl::balancedTileGroups(gpu, 20, 45, 4, 4).local[0], 4u);
}
