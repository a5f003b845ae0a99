#include "raster/rasterizer.h"

#include <algorithm>

#include "kernels/raster/raster_types.h"

namespace gi {

void VisibilityBuffer::allocate(cl::Context& ctx, int w, int h, const std::string& what) {
  if (w == width && h == height && triangle) return;
  width = w;
  height = h;
  triangle = cl::Buffer(ctx, size_t(w) * h * sizeof(uint32_t), CL_MEM_READ_WRITE, what + " triangle ids");
  depth = cl::Buffer(ctx, size_t(w) * h * sizeof(float), CL_MEM_READ_WRITE, what + " depth");
}

Rasterizer::Rasterizer(cl::Context& ctx) : ctx_(ctx) {
  program_ = ctx.buildProgram("kernels/raster/raster.cl", {{"GI_TILE", std::to_string(kTile)}});
  setup_ = program_.kernel("raster_setup");
  binCount_ = program_.kernel("raster_bin_count");
  binScan_ = program_.kernel("raster_bin_scan");
  binFill_ = program_.kernel("raster_bin_fill");
  tiles_ = program_.kernel("raster_tiles");
  counters_ = cl::Buffer(ctx, 2 * sizeof(uint32_t), CL_MEM_READ_WRITE, "rasterizer counters");
}

void Rasterizer::ensureCapacity(size_t& capacity, cl::Buffer& buffer, size_t needed, size_t elementBytes,
                                const char* what) {
  if (needed <= capacity && buffer) return;
  capacity = std::max<size_t>(needed + needed / 4, 1024);
  buffer = cl::Buffer(ctx_, capacity * elementBytes, CL_MEM_READ_WRITE, what);
}

void Rasterizer::render(const DeviceScene& scene, const GiView& view, VisibilityBuffer& out, const std::string& label) {
  out.allocate(ctx_, view.width, view.height, label);
  const int tilesX = (view.width + kTile - 1) / kTile, tilesY = (view.height + kTile - 1) / kTile;
  const uint32_t tileCount = uint32_t(tilesX * tilesY);
  if (tileCount > tileCapacity_) {
    tileCapacity_ = tileCount;
    tileCounts_ = cl::Buffer(ctx_, tileCount * sizeof(uint32_t), CL_MEM_READ_WRITE, "rasterizer tile counts");
    tileOffsets_ = cl::Buffer(ctx_, tileCount * sizeof(uint32_t), CL_MEM_READ_WRITE, "rasterizer tile offsets");
    tileCursors_ = cl::Buffer(ctx_, tileCount * sizeof(uint32_t), CL_MEM_READ_WRITE, "rasterizer tile cursors");
  }
  // One slot per scene triangle, then room for the pieces of clipped triangles. On overflow the
  // capacity grows and the setup runs again (counters read back below): nothing is dropped.
  ensureCapacity(recordCapacity_, records_, scene.triangleCount + 4096, sizeof(GiRasterTriangle), "rasterizer triangles");
  const size_t triGroups = 64;
  uint32_t counters[2] = {0, 0};
  for (;;) {
    ctx_.fill(counters_, uint32_t(0));
    ctx_.fill(tileCounts_, uint32_t(0));
    setup_.args(scene.positions, scene.triangles, scene.materials, view, scene.triangleCount, records_, counters_,
                uint32_t(recordCapacity_));
    ctx_.launch(setup_, cl::NDRange::d1(cl::roundUp(std::max<uint32_t>(scene.triangleCount, 1), triGroups), triGroups),
                label + ": setup");
    binCount_.args(records_, counters_, scene.triangleCount, uint32_t(recordCapacity_), tilesX, tilesY, tileCounts_);
    ctx_.launch(binCount_, cl::NDRange::d1(recordCapacity_, triGroups), label + ": binning");
    binScan_.args(tileCounts_, tileCount, tileOffsets_, tileCursors_, counters_);
    ctx_.launch(binScan_, cl::NDRange::d1(1), label + ": binning");
    ctx_.read(counters_, counters, sizeof counters);
    if (scene.triangleCount + counters[0] <= recordCapacity_) break;
    ensureCapacity(recordCapacity_, records_, scene.triangleCount + counters[0], sizeof(GiRasterTriangle),
                   "rasterizer triangles");
  }
  ensureCapacity(binCapacity_, binList_, std::max<uint32_t>(counters[1], 1), sizeof(uint32_t), "rasterizer tile lists");
  binFill_.args(records_, counters_, scene.triangleCount, uint32_t(recordCapacity_), tilesX, tilesY, tileCursors_, binList_,
                uint32_t(binCapacity_));
  ctx_.launch(binFill_, cl::NDRange::d1(recordCapacity_, triGroups), label + ": binning");

  // CPU devices: one work-item per tile (GI_VW == GI_TILE); GPUs: one per pixel.
  const int vw = ctx_.vectorWidth();
  const size_t itemsPerTile = vw == kTile ? 1 : size_t(kTile) * (kTile / vw);
  tiles_.args(records_, tileOffsets_, tileCounts_, binList_, tilesX, tilesY, view, scene.positions, scene.uvs,
              scene.triangles, scene.materials, scene.textures, scene.texels, out.triangle, out.depth);
  ctx_.launch(tiles_, cl::NDRange::d1(tileCount * itemsPerTile, itemsPerTile), label + ": tiles");
}

}  // namespace gi
