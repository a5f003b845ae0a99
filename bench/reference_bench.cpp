// Ray throughput of the reference BVH (kernels/reference/bvh_traverse.h) on Sponza, next to
// Embree 3 single-ray queries (rtcIntersect1 / rtcOccluded1, 2 threads) on the same rays in the
// same run. Three ray sets from the scene's default camera at 1280×720:
//   primary:  one ray per pixel centre (coherent);
//   diffuse:  from each primary hit, a cosine-distributed direction about the geometric normal
//             (incoherent, the path tracer's bounce rays);
//   shadow:   from each primary hit to a point near the top centre of the scene bounds
//             (any-hit, finite length).
// Our rays are traced by the batch kernels in kernels/reference/trace_rays.cl; times are wall
// clock around launch + finish (device-resident rays, no transfers). Embree is optional: without
// libembree-dev the Embree benchmarks are not built.
//
// Scene: $GI_BENCH_SCENE or sponza/Sponza.gltf through the media search path.
// Run: build-ref/reference_bench --benchmark_min_time=2   (rays/s in the items_per_second column)
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <atomic>
#include <random>
#include <thread>

#include "cl/runtime.h"
#include "reference/bvh.h"
#include "render/views.h"
#include "scene/device_scene.h"
#include "scene/scene_loader.h"

#ifdef GI_HAVE_EMBREE
#include <embree3/rtcore.h>
#endif

using namespace gi;

namespace {

struct RaySet {
  std::vector<glm::vec4> o, d;  // origin + tmin, direction + tmax
};

struct Fixture {
  Scene scene;
  std::unique_ptr<cl::Context> ctx;
  std::unique_ptr<DeviceScene> ds;
  std::unique_ptr<DeviceBvh> bvh;
  cl::Program prog;
  RaySet primary, diffuse, shadow;
  std::vector<float> primaryHitT;
#ifdef GI_HAVE_EMBREE
  RTCDevice edev = nullptr;
  RTCScene escene = nullptr;
  double embreeBuildSeconds = 0;
#endif
};

Fixture& fixture() {
  static std::unique_ptr<Fixture> f;
  if (f) return *f;
  f = std::make_unique<Fixture>();
  const char* spec = std::getenv("GI_BENCH_SCENE");
  f->scene = loadScene(spec ? spec : "sponza/Sponza.gltf", "");
  f->ctx = std::make_unique<cl::Context>(cl::selectDevice("cpu"));
  f->ds = std::make_unique<DeviceScene>(*f->ctx, f->scene);
  f->bvh = std::make_unique<DeviceBvh>(*f->ctx, f->scene, *f->ds);
  f->prog = f->ctx->buildProgram("kernels/reference/trace_rays.cl");
  std::fprintf(stderr, "scene %s: %zu triangles; our BVH build %.3f s (%u wide nodes, depth %u, SAH %.1f)\n",
               f->scene.name.c_str(), f->scene.triangleCount(), f->bvh->stats().buildSeconds, f->bvh->nodeCount(),
               f->bvh->stats().maxDepth, f->bvh->stats().sahCost);

  // Primary rays, host-generated with the engine's camera convention.
  const int W = 1280, H = 720;
  const Camera& cam = f->scene.cameras[f->scene.defaultCamera];
  GiView v = makeCameraView(cam, W, H);
  glm::mat4 inv;
  std::memcpy(&inv, v.inv_view_proj, 64);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      glm::vec4 p = inv * glm::vec4((x + 0.5f) / W * 2 - 1, 1 - (y + 0.5f) / H * 2, 1, 1);
      glm::vec3 d = glm::normalize(glm::vec3(p) / p.w - cam.position);
      f->primary.o.push_back(glm::vec4(cam.position, 0.0f));
      f->primary.d.push_back(glm::vec4(d, 1e30f));
    }
  // Trace them once (our BVH) to place the secondary rays.
  uint32_t n = uint32_t(f->primary.o.size());
  cl::Buffer ob = f->ctx->upload(f->primary.o, "o"), db = f->ctx->upload(f->primary.d, "d");
  cl::Buffer hb(*f->ctx, n * sizeof(glm::vec4));
  cl::Kernel k = f->prog.kernel("trace_closest_rays");
  unsigned a = f->bvh->setArgs(k, 0);
  k.setArg(a, ob); k.setArg(a + 1, db); k.setArg(a + 2, hb); k.setArg(a + 3, n);
  f->ctx->launch(k, cl::NDRange::d1(n, 64));
  f->ctx->profiler().discard();
  auto hits = f->ctx->download<glm::vec4>(hb);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  glm::vec3 lightP = glm::vec3(f->scene.bounds.center().x, f->scene.bounds.hi.y * 0.9f + f->scene.bounds.lo.y * 0.1f,
                               f->scene.bounds.center().z);
  float eps = 1e-4f * f->scene.bounds.radius();
  for (uint32_t i = 0; i < n; ++i) {
    uint32_t prim;
    std::memcpy(&prim, &hits[i].w, 4);
    if (prim == 0xFFFFFFFFu) continue;
    glm::vec3 x = glm::vec3(f->primary.o[i]) + glm::vec3(f->primary.d[i]) * hits[i].x;
    glm::uvec3 t = f->scene.triangles[prim];
    glm::vec3 ng = glm::normalize(glm::cross(f->scene.positions[t[1]] - f->scene.positions[t[0]],
                                             f->scene.positions[t[2]] - f->scene.positions[t[0]]));
    if (glm::dot(ng, glm::vec3(f->primary.d[i])) > 0) ng = -ng;
    glm::vec3 org = x + ng * eps;
    // Cosine-weighted direction about ng.
    glm::vec3 tt = std::fabs(ng.x) > 0.5f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
    glm::vec3 b1 = glm::normalize(glm::cross(ng, tt)), b2 = glm::cross(ng, b1);
    float r = std::sqrt(U(rng)), phi = 6.2831853f * U(rng);
    glm::vec3 dir = glm::normalize(b1 * (r * std::cos(phi)) + b2 * (r * std::sin(phi)) + ng * std::sqrt(std::max(0.0f, 1 - r * r)));
    f->diffuse.o.push_back(glm::vec4(org, 0.0f));
    f->diffuse.d.push_back(glm::vec4(dir, 1e30f));
    glm::vec3 toL = lightP - org;
    float dist = glm::length(toL);
    f->shadow.o.push_back(glm::vec4(org, 0.0f));
    f->shadow.d.push_back(glm::vec4(toL / dist, dist * 0.999f));
  }
  std::fprintf(stderr, "rays: %zu primary, %zu diffuse, %zu shadow\n", f->primary.o.size(), f->diffuse.o.size(),
               f->shadow.o.size());

#ifdef GI_HAVE_EMBREE
  auto t0 = std::chrono::steady_clock::now();
  f->edev = rtcNewDevice("threads=2");
  f->escene = rtcNewScene(f->edev);
  RTCGeometry g = rtcNewGeometry(f->edev, RTC_GEOMETRY_TYPE_TRIANGLE);
  float* vb = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), f->scene.positions.size()));
  for (size_t i = 0; i < f->scene.positions.size(); ++i) std::memcpy(vb + 3 * i, &f->scene.positions[i], 12);
  unsigned* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                3 * sizeof(unsigned), f->scene.triangles.size()));
  std::memcpy(ib, f->scene.triangles.data(), f->scene.triangles.size() * 12);
  rtcCommitGeometry(g);
  rtcAttachGeometry(f->escene, g);
  rtcReleaseGeometry(g);
  rtcCommitScene(f->escene);
  f->embreeBuildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::fprintf(stderr, "Embree build %.3f s\n", f->embreeBuildSeconds);
#endif
  return *f;
}

RaySet& raySet(Fixture& f, int which) { return which == 0 ? f.primary : which == 1 ? f.diffuse : f.shadow; }

void BM_Ours(benchmark::State& state) {
  Fixture& f = fixture();
  int which = int(state.range(0));
  RaySet& rs = raySet(f, which);
  uint32_t n = uint32_t(rs.o.size());
  cl::Buffer ob = f.ctx->upload(rs.o, "o"), db = f.ctx->upload(rs.d, "d");
  cl::Buffer out(*f.ctx, n * sizeof(glm::vec4));
  cl::Kernel k = f.prog.kernel(which == 2 ? "trace_any_rays" : "trace_closest_rays");
  unsigned a = f.bvh->setArgs(k, 0);
  k.setArg(a, ob); k.setArg(a + 1, db); k.setArg(a + 2, out); k.setArg(a + 3, n);
  size_t local = size_t(state.range(1));
  f.ctx->launch(k, cl::NDRange::d1(n, local));  // warm-up (first enqueue of this local size)
  f.ctx->finish();
  f.ctx->profiler().discard();
  for (auto _ : state) {
    f.ctx->launch(k, cl::NDRange::d1(n, local));
    f.ctx->finish();
    f.ctx->profiler().discard();
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * n);
  state.counters["Mrays/s"] = benchmark::Counter(double(n) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}

#ifdef GI_HAVE_EMBREE
void BM_Embree(benchmark::State& state) {
  Fixture& f = fixture();
  int which = int(state.range(0));
  RaySet& rs = raySet(f, which);
  size_t n = rs.o.size();
  std::vector<uint32_t> sink(n);
  auto work = [&](size_t begin, size_t end) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (size_t i = begin; i < end; ++i) {
      if (which == 2) {
        RTCRay r{};
        r.org_x = rs.o[i].x; r.org_y = rs.o[i].y; r.org_z = rs.o[i].z; r.tnear = rs.o[i].w;
        r.dir_x = rs.d[i].x; r.dir_y = rs.d[i].y; r.dir_z = rs.d[i].z; r.tfar = rs.d[i].w;
        r.mask = 0xFFFFFFFFu;
        rtcOccluded1(f.escene, &ctx, &r);
        sink[i] = r.tfar < 0.0f;
      } else {
        RTCRayHit rh{};
        rh.ray.org_x = rs.o[i].x; rh.ray.org_y = rs.o[i].y; rh.ray.org_z = rs.o[i].z; rh.ray.tnear = rs.o[i].w;
        rh.ray.dir_x = rs.d[i].x; rh.ray.dir_y = rs.d[i].y; rh.ray.dir_z = rs.d[i].z; rh.ray.tfar = rs.d[i].w;
        rh.ray.mask = 0xFFFFFFFFu;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(f.escene, &ctx, &rh);
        sink[i] = rh.hit.primID;
      }
    }
  };
  for (auto _ : state) {
    // Two threads over interleaved blocks of 4096 rays (the machine has 2 cores).
    std::vector<std::thread> th;
    std::atomic<size_t> next{0};
    for (int t = 0; t < 2; ++t)
      th.emplace_back([&] {
        for (size_t b; (b = next.fetch_add(4096)) < n;) work(b, std::min(n, b + 4096));
      });
    for (auto& t : th) t.join();
    benchmark::DoNotOptimize(sink.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(n));
  state.counters["Mrays/s"] = benchmark::Counter(double(n) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}
#endif

void rayArgs(benchmark::internal::Benchmark* b) {
  b->ArgNames({"rays", "local"});
  for (int which : {0, 1, 2}) b->Args({which, 64});
  if (std::getenv("GI_BENCH_LOCAL_SWEEP"))
    for (int local : {8, 16, 256}) b->Args({1, local});
}
void embreeArgs(benchmark::internal::Benchmark* b) {
  b->ArgNames({"rays"});
  for (int which : {0, 1, 2}) b->Args({which});
}

}  // namespace

// rays: 0 = primary, 1 = diffuse bounce, 2 = shadow (any hit).
BENCHMARK(BM_Ours)->Apply(rayArgs)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);
#ifdef GI_HAVE_EMBREE
BENCHMARK(BM_Embree)->Apply(embreeArgs)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);
#endif

BENCHMARK_MAIN();
