// Binned-SAH BVH2 build, collapse to BVH8, device upload. See bvh.h for the layout.
#include "reference/bvh.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

#include "util/error.h"

namespace gi {

namespace {

struct Box {
  glm::vec3 lo{1e30f}, hi{-1e30f};
  void grow(const glm::vec3& p) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
  void grow(const Box& b) { lo = glm::min(lo, b.lo); hi = glm::max(hi, b.hi); }
  float area() const {
    glm::vec3 e = glm::max(hi - lo, glm::vec3(0.0f));
    return 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
  }
  bool empty() const { return lo.x > hi.x; }
};

struct Node2 {
  Box box;
  int left = -1, right = -1;   // inner: child indices (into the same vector)
  uint32_t first = 0, count = 0;  // leaf: range of the index array
  bool leaf() const { return left < 0; }
};

// One triangle's bounds and id, kept in an array that is partitioned in place, so binning reads
// memory sequentially (an index array into separate bounds would miss the cache on every read).
struct Prim {
  glm::vec3 lo;
  uint32_t id;
  glm::vec3 hi;
  float pad;
  glm::vec3 centroid() const { return (lo + hi) * 0.5f; }
};

struct Builder {
  std::vector<Prim>& prims;
  BvhBuildOptions opt;

  // Builds [begin, end) (whose bounds and centroid bounds the caller knows) into `out`, returns
  // the node's index in `out`. depth < spawnDepth splits hand their right child to a new thread.
  int build(std::vector<Node2>& out, uint32_t begin, uint32_t end, const Box& box, const Box& cbox, int depth,
            int spawnDepth, uint32_t& maxDepth) {
    maxDepth = std::max<uint32_t>(maxDepth, depth);
    uint32_t n = end - begin;
    int me = static_cast<int>(out.size());
    out.push_back(Node2{box, -1, -1, begin, n});
    if (n <= 1) return me;

    // Binned SAH over the centroid bounds, all three axes; small nodes use fewer bins.
    const int B = std::min<int>(opt.bins, std::max<int>(4, int(n)));
    glm::vec3 ext = cbox.hi - cbox.lo;
    // Only the B bins in use are initialised: clearing all 64 per node cost more than the binning.
    Box bins[3][64] __attribute__((uninitialized)), cbins[3][64] __attribute__((uninitialized));
    uint32_t counts[3][64];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < B; ++b) { bins[a][b] = Box{}; cbins[a][b] = Box{}; counts[a][b] = 0; }
    glm::vec3 scale;
    for (int a = 0; a < 3; ++a) scale[a] = ext[a] > 1e-12f ? float(B) * (1.0f - 1e-6f) / ext[a] : 0.0f;
    for (uint32_t i = begin; i < end; ++i) {
      const Prim& p = prims[i];
      glm::vec3 c = p.centroid();
      for (int a = 0; a < 3; ++a) {
        int b = std::min(B - 1, std::max(0, int((c[a] - cbox.lo[a]) * scale[a])));
        Box& bb = bins[a][b];
        bb.lo = glm::min(bb.lo, p.lo);
        bb.hi = glm::max(bb.hi, p.hi);
        cbins[a][b].grow(c);
        counts[a][b]++;
      }
    }
    int bestAxis = -1, bestSplit = -1;
    float bestCost = 1e30f;
    for (int a = 0; a < 3; ++a) {
      if (scale[a] == 0.0f) continue;
      float rightArea[64];
      uint32_t rightCount[64];
      Box acc;
      uint32_t c = 0;
      for (int b = B - 1; b > 0; --b) {
        acc.grow(bins[a][b]);
        c += counts[a][b];
        rightArea[b] = acc.area();
        rightCount[b] = c;
      }
      acc = Box{};
      c = 0;
      for (int b = 0; b < B - 1; ++b) {
        acc.grow(bins[a][b]);
        c += counts[a][b];
        if (c == 0 || rightCount[b + 1] == 0) continue;
        float cost = acc.area() * float(c) + rightArea[b + 1] * float(rightCount[b + 1]);
        if (cost < bestCost) { bestCost = cost; bestAxis = a; bestSplit = b; }
      }
    }
    // SAH with traversal cost 1 and triangle cost 1 (relative to the parent's area).
    float parentArea = std::max(box.area(), 1e-30f);
    float splitCost = 1.0f + bestCost / parentArea;
    float leafCost = float(n);
    uint32_t mid;
    Box lbox, rbox, lc, rc;
    if (bestAxis < 0) {
      // All centroids coincide: no spatial split exists. Small sets become a leaf, large ones
      // are cut in the middle of the range so leaves stay small.
      if (n <= uint32_t(kBvhMaxLeafSize)) return me;
      mid = begin + n / 2;
      for (uint32_t i = begin; i < end; ++i) {
        Box& bb = i < mid ? lbox : rbox;
        bb.grow(prims[i].lo); bb.grow(prims[i].hi);
      }
      lc = rc = cbox;
    } else {
      if (n <= uint32_t(opt.maxLeafSize) && leafCost <= splitCost) return me;
      float lo = cbox.lo[bestAxis], sc = scale[bestAxis];
      auto it = std::partition(prims.begin() + begin, prims.begin() + end, [&](const Prim& p) {
        return std::min(B - 1, std::max(0, int((p.centroid()[bestAxis] - lo) * sc))) <= bestSplit;
      });
      mid = uint32_t(it - prims.begin());
      for (int b = 0; b < B; ++b) {
        if (b <= bestSplit) { lbox.grow(bins[bestAxis][b]); lc.grow(cbins[bestAxis][b]); }
        else { rbox.grow(bins[bestAxis][b]); rc.grow(cbins[bestAxis][b]); }
      }
      if (mid == begin || mid == end) {  // float edge case: never an empty side
        mid = begin + n / 2;
        lbox = rbox = box;
        lc = rc = cbox;
      }
    }

    int left, right;
    if (depth < spawnDepth && n > 20000) {
      std::vector<Node2> sub;
      sub.reserve((end - mid) / 2 + 16);
      uint32_t subDepth = 0;
      std::thread th([&] { build(sub, mid, end, rbox, rc, depth + 1, spawnDepth, subDepth); });
      left = build(out, begin, mid, lbox, lc, depth + 1, spawnDepth, maxDepth);
      th.join();
      maxDepth = std::max(maxDepth, subDepth);
      int offset = static_cast<int>(out.size());
      for (Node2 nd : sub) {
        if (!nd.leaf()) { nd.left += offset; nd.right += offset; }
        out.push_back(nd);
      }
      right = offset;
    } else {
      left = build(out, begin, mid, lbox, lc, depth + 1, spawnDepth, maxDepth);
      right = build(out, mid, end, rbox, rc, depth + 1, spawnDepth, maxDepth);
    }
    out[me].left = left;
    out[me].right = right;
    return me;
  }
};


// Collapses the binary tree into 8-wide nodes: each wide node takes its binary node's two
// children and keeps opening the inner child with the largest surface area (the one most likely
// to be visited) until it has 8 children or only leaves.
struct Collapser {
  const std::vector<Node2>& n2;
  std::vector<GiBvhNode>& out;
  std::vector<GiBvhTriPack>& packs;
  const std::vector<glm::vec4>& tris;  // 3 per slot, leaf order
  uint32_t leaves = 0;

  // A leaf's triangles as packs of 4 (the last one padded with lanes that never hit).
  uint32_t leafRef(const Node2& n) {
    uint32_t first = uint32_t(packs.size());
    for (uint32_t s0 = n.first; s0 < n.first + n.count; s0 += 4) {
      GiBvhTriPack p{};
      for (int l = 0; l < 4; ++l) {
        uint32_t s = s0 + uint32_t(l);
        if (s >= n.first + n.count) { p.id[l] = 0xFFFFFFFFu; continue; }
        const glm::vec4 &v0 = tris[3 * s], &e1 = tris[3 * s + 1], &e2 = tris[3 * s + 2];
        p.v0x[l] = v0.x; p.v0y[l] = v0.y; p.v0z[l] = v0.z;
        p.e1x[l] = e1.x; p.e1y[l] = e1.y; p.e1z[l] = e1.z;
        p.e2x[l] = e2.x; p.e2y[l] = e2.y; p.e2z[l] = e2.z;
        std::memcpy(&p.id[l], &v0.w, 4);
      }
      packs.push_back(p);
    }
    uint32_t count = uint32_t(packs.size()) - first;
    return kBvhLeafBit | ((count - 1) << 27) | first;
  }

  void emit(uint32_t slot, int bin) {
    std::vector<int> kids;
    const Node2& root = n2[bin];
    if (root.leaf()) kids.push_back(bin);  // only at the root of a tiny scene
    else { kids.push_back(root.left); kids.push_back(root.right); }
    while (kids.size() < 8) {
      int best = -1;
      float bestArea = -1.0f;
      for (size_t i = 0; i < kids.size(); ++i) {
        const Node2& k = n2[kids[i]];
        if (!k.leaf() && k.box.area() > bestArea) { bestArea = k.box.area(); best = int(i); }
      }
      if (best < 0) break;
      int open = kids[best];
      kids[best] = n2[open].left;
      kids.push_back(n2[open].right);
    }
    GiBvhNode node{};
    for (int i = 0; i < 8; ++i) {
      node.lo_x[i] = node.lo_y[i] = node.lo_z[i] = INFINITY;
      node.hi_x[i] = node.hi_y[i] = node.hi_z[i] = -INFINITY;
      node.child[i] = kBvhEmpty;
    }
    std::vector<std::pair<size_t, int>> inner;
    for (size_t i = 0; i < kids.size(); ++i) {
      const Node2& k = n2[kids[i]];
      node.lo_x[i] = k.box.lo.x; node.lo_y[i] = k.box.lo.y; node.lo_z[i] = k.box.lo.z;
      node.hi_x[i] = k.box.hi.x; node.hi_y[i] = k.box.hi.y; node.hi_z[i] = k.box.hi.z;
      if (k.leaf()) {
        if (k.count == 0) { node.child[i] = kBvhEmpty; continue; }
        node.child[i] = leafRef(k);
        ++leaves;
      } else {
        inner.emplace_back(i, kids[i]);
      }
    }
    // Children of one node are allocated consecutively (better locality), then filled.
    uint32_t base = uint32_t(out.size());
    out.resize(out.size() + inner.size());
    for (size_t j = 0; j < inner.size(); ++j) node.child[inner[j].first] = base + uint32_t(j);
    out[slot] = node;
    for (size_t j = 0; j < inner.size(); ++j) emit(base + uint32_t(j), inner[j].second);
  }
};

}  // namespace

bool intersectTriangle(const glm::vec3& o, const glm::vec3& d, const glm::vec3& v0, const glm::vec3& e1,
                       const glm::vec3& e2, float tmin, float tmax, float& t, float& u, float& v) {
  glm::vec3 p = glm::cross(d, e2);
  float det = glm::dot(e1, p);
  if (std::fabs(det) < 1e-30f) return false;
  float inv = 1.0f / det;
  glm::vec3 s = o - v0;
  u = glm::dot(s, p) * inv;
  if (u < 0.0f || u > 1.0f) return false;
  glm::vec3 q = glm::cross(s, e1);
  v = glm::dot(d, q) * inv;
  if (v < 0.0f || u + v > 1.0f) return false;
  t = glm::dot(e2, q) * inv;
  return t > tmin && t < tmax;
}

Bvh buildBvh(const Scene& scene, const BvhBuildOptions& options) {
  auto t0 = std::chrono::steady_clock::now();
  const size_t n = scene.triangles.size();
  if (n >= (size_t(1) << 27)) throw Error("BVH: " + std::to_string(n) + " triangles, at most 2^27 supported");
  BvhBuildOptions opt = options;
  opt.bins = std::clamp(opt.bins, 2, 64);
  opt.maxLeafSize = std::clamp(opt.maxLeafSize, 1, kBvhMaxLeafSize);
  unsigned threads = opt.threads > 0 ? unsigned(opt.threads) : std::max(1u, std::thread::hardware_concurrency());

  std::vector<Prim> prims(n);
  Box rootBox, rootCentroids;
  for (size_t t = 0; t < n; ++t) {
    Prim p{glm::vec3(1e30f), uint32_t(t), glm::vec3(-1e30f), 0.0f};
    for (int k = 0; k < 3; ++k) {
      glm::vec3 v = scene.positions[scene.triangles[t][k]];
      p.lo = glm::min(p.lo, v);
      p.hi = glm::max(p.hi, v);
    }
    prims[t] = p;
    rootBox.grow(p.lo); rootBox.grow(p.hi);
    rootCentroids.grow(p.centroid());
  }

  std::vector<Node2> n2;
  n2.reserve(n + 16);
  Bvh bvh;
  if (n > 0) {
    Builder builder{prims, opt};
    int spawnDepth = 0;
    while ((1u << spawnDepth) < threads * 2) ++spawnDepth;  // a few tasks per core
    if (threads <= 1) spawnDepth = 0;
    builder.build(n2, 0, uint32_t(n), rootBox, rootCentroids, 0, spawnDepth, bvh.stats.maxDepth);
  }
  std::vector<uint32_t> idx(n);
  for (size_t s = 0; s < n; ++s) idx[s] = prims[s].id;

  // SAH cost of the binary tree, for reports.
  if (!n2.empty()) {
    double rootArea = std::max(n2[0].box.area(), 1e-30f), cost = 0.0;
    for (const Node2& nd : n2) cost += nd.box.area() / rootArea * (nd.leaf() ? double(nd.count) : 1.0);
    bvh.stats.sahCost = cost;
  }

  // Triangle slots in leaf order (the index array after partitioning is exactly that order).
  bvh.tris.resize(3 * n);
  bvh.triIndex = idx;
  for (size_t s = 0; s < n; ++s) {
    uint32_t t = idx[s];
    glm::vec3 v0 = scene.positions[scene.triangles[t][0]];
    glm::vec3 v1 = scene.positions[scene.triangles[t][1]];
    glm::vec3 v2 = scene.positions[scene.triangles[t][2]];
    uint32_t m = t < scene.triangleMaterial.size() ? scene.triangleMaterial[t] : 0;
    bool alpha = m < scene.materials.size() && scene.materials[m].alpha_mode == GI_ALPHA_MASK;
    uint32_t tag = t | (alpha ? kBvhAlphaBit : 0u);
    float tagf;
    std::memcpy(&tagf, &tag, 4);
    bvh.tris[3 * s + 0] = glm::vec4(v0, tagf);
    bvh.tris[3 * s + 1] = glm::vec4(v1 - v0, 0.0f);
    bvh.tris[3 * s + 2] = glm::vec4(v2 - v0, 0.0f);
  }
  // Wide nodes. An empty scene gets one root with 8 empty children.
  bvh.nodes.resize(1);
  if (n2.empty()) {
    GiBvhNode& r = bvh.nodes[0];
    for (int i = 0; i < 8; ++i) {
      r.lo_x[i] = r.lo_y[i] = r.lo_z[i] = INFINITY;
      r.hi_x[i] = r.hi_y[i] = r.hi_z[i] = -INFINITY;
      r.child[i] = kBvhEmpty;
    }
  } else {
    Collapser c{n2, bvh.nodes, bvh.packs, bvh.tris};
    c.emit(0, 0);
    bvh.stats.leaves = c.leaves;
  }
  bvh.stats.innerNodes = uint32_t(bvh.nodes.size());

  bvh.stats.buildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return bvh;
}

DeviceBvh::DeviceBvh(cl::Context& ctx, const Scene& scene, const DeviceScene& deviceScene,
                     const BvhBuildOptions& options)
    : scene_(&deviceScene) {
  Bvh bvh = buildBvh(scene, options);
  stats_ = bvh.stats;
  nodeCount_ = uint32_t(bvh.nodes.size());
  nodes_ = ctx.upload(bvh.nodes, "BVH nodes");
  if (bvh.packs.empty()) bvh.packs.resize(1);  // a valid buffer for the empty scene
  tris_ = ctx.upload(bvh.packs, "BVH triangle packs");
}

unsigned DeviceBvh::setArgs(cl::Kernel& k, unsigned i) const {
  k.setArg(i++, nodes_);
  k.setArg(i++, tris_);
  k.setArg(i++, scene_->triangles);
  k.setArg(i++, scene_->uvs);
  k.setArg(i++, scene_->materials);
  k.setArg(i++, scene_->textures);
  k.setArg(i++, scene_->texels);
  return i;
}

}  // namespace gi
