// Ray-tracing acceleration structure for the reference path tracer and for every later technique
// that needs visibility (VPL visibility, probe updates).
//
// What it computes: a binned-SAH binary BVH over the scene's world-space triangles (Wald 2007,
// "On fast construction of SAH-based BVHs"; 16 bins per axis), collapsed into an 8-wide BVH whose
// nodes store their children's boxes as structure-of-arrays, so one node test is a handful of
// float8 operations on the device (PoCL turns each work-item's traversal loop into scalar code,
// but explicit float8 maths stays 8 lanes wide; docs/PERFORMANCE_FACTS.md). The top levels of the
// build run on std::threads.
//
// Device layout (kernels/reference/bvh_traverse.h reads it):
//   nodes: GiBvhNode (256 bytes): lo/hi of the 8 child boxes per axis, the 8 child references.
//          A child reference is an inner node index, a leaf (bit 31 set, pack count − 1 in
//          bits 27..30, first triangle pack in bits 0..26) or GI_BVH_EMPTY (empty box, never hit).
//          Node 0 is the root and is always an inner node.
//   packs: GiBvhTriPack (160 bytes): 4 triangles of a leaf as structure-of-arrays v0, e1 = v1 − v0,
//          e2 = v2 − v0 per axis, so one float4 Möller–Trumbore test checks 4 triangles; id = the
//          original triangle index, bit 31 set when its material is alpha-masked (the traversal
//          then knows without a material fetch whether an alpha test is needed); unused lanes
//          have id 0xFFFFFFFF and zero edges (never hit).
//
// Not handled: instancing (the scene is flattened), motion, refitting (static scenes only), more
// than 2^27 triangles or 2^31 − 1 triangles with the alpha flag (checked, throws gi::Error).
#pragma once
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "cl/runtime.h"
#include "scene/device_scene.h"
#include "scene/scene.h"

namespace gi {

inline constexpr uint32_t kBvhLeafBit = 0x80000000u;
inline constexpr uint32_t kBvhEmpty = 0x7FFFFFFFu;  // GI_BVH_EMPTY in the kernels
inline constexpr uint32_t kBvhAlphaBit = 0x80000000u;  // in the triangle index stored in v0.w
inline constexpr int kBvhMaxLeafSize = 16;           // what 4 count bits can encode

struct GiBvhNode {
  float lo_x[8], hi_x[8], lo_y[8], hi_y[8], lo_z[8], hi_z[8];
  uint32_t child[8];
  uint32_t pad[8];  // 256 bytes: whole cache lines
};
static_assert(sizeof(GiBvhNode) == 256, "GiBvhNode layout");

struct GiBvhTriPack {
  float v0x[4], v0y[4], v0z[4], e1x[4], e1y[4], e1z[4], e2x[4], e2y[4], e2z[4];
  uint32_t id[4];
};
static_assert(sizeof(GiBvhTriPack) == 160, "GiBvhTriPack layout");

struct BvhBuildOptions {
  int maxLeafSize = 4;   // leaves hold at most this many triangles where a split exists
  int bins = 16;         // SAH bins per axis
  int threads = 0;       // 0: std::thread::hardware_concurrency()
};

struct BvhStats {
  uint32_t innerNodes = 0, leaves = 0, maxDepth = 0;
  double buildSeconds = 0.0;
  double sahCost = 0.0;  // SAH cost of the binary tree (traversal cost 1, triangle cost 1)
};

// The host-side BVH in the device layout.
struct Bvh {
  std::vector<GiBvhNode> nodes;
  std::vector<GiBvhTriPack> packs;   // what leaves reference (the device layout)
  std::vector<glm::vec4> tris;       // 3 per triangle slot in leaf order (v0+tagged index, e1, e2)
  std::vector<uint32_t> triIndex;    // original triangle index of each slot
  BvhStats stats;
};

Bvh buildBvh(const Scene& scene, const BvhBuildOptions& options = {});

// Host reference of the device traversal, for tests and tools: closest hit (no alpha test).
struct HostHit {
  float t = 0.0f, u = 0.0f, v = 0.0f;
  uint32_t prim = 0xFFFFFFFFu;  // original triangle index; 0xFFFFFFFF = miss
};
// Möller–Trumbore, the same operations in the same order as the kernel.
bool intersectTriangle(const glm::vec3& o, const glm::vec3& d, const glm::vec3& v0, const glm::vec3& e1,
                       const glm::vec3& e2, float tmin, float tmax, float& t, float& u, float& v);

// The BVH on the device plus the scene buffers its alpha test needs. Kernels that trace rays take
// the arguments GI_BVH_ARGS (kernels/reference/bvh_traverse.h); setArgs() fills them in that order.
class DeviceBvh {
public:
  DeviceBvh(cl::Context& ctx, const Scene& scene, const DeviceScene& deviceScene,
            const BvhBuildOptions& options = {});

  // Sets the GI_BVH_ARGS_COUNT arguments starting at `first`; returns the index after them.
  unsigned setArgs(cl::Kernel& kernel, unsigned first) const;

  const BvhStats& stats() const { return stats_; }
  uint32_t nodeCount() const { return nodeCount_; }
  uint64_t bytes() const { return nodes_.bytes() + tris_.bytes(); }

private:
  const DeviceScene* scene_;
  cl::Buffer nodes_, tris_;
  uint32_t nodeCount_ = 0;
  BvhStats stats_;
};

}  // namespace gi
