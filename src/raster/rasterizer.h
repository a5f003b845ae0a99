// Host side of the compute rasterizer (kernels/raster/raster.cl): one machinery for every view.
// render() fills a visibility buffer (source triangle per pixel, GI_INVALID_ID = background) and
// the linear view depth (+inf = background); the G-buffer, shadow-map and RSM passes build on it.
#pragma once
#include <string>

#include "cl/runtime.h"
#include "kernels/common/shared_types.h"
#include "scene/device_scene.h"

namespace gi {

struct VisibilityBuffer {
  int width = 0, height = 0;
  cl::Buffer triangle;  // uint per pixel
  cl::Buffer depth;     // float per pixel, view-space distance along the view axis
  void allocate(cl::Context& ctx, int w, int h, const std::string& what);
};

class Rasterizer {
public:
  explicit Rasterizer(cl::Context& ctx);

  // Kernel launches are profiled as "<label>: setup", "<label>: binning", "<label>: tiles".
  void render(const DeviceScene& scene, const GiView& view, VisibilityBuffer& out, const std::string& label);

  static constexpr int kTile = 16;  // GI_TILE

private:
  void ensureCapacity(size_t& capacity, cl::Buffer& buffer, size_t needed, size_t elementBytes, const char* what);

  cl::Context& ctx_;
  cl::Program program_;
  cl::Kernel setup_, binCount_, binScan_, binFill_, tiles_;
  cl::Buffer records_, counters_, tileCounts_, tileOffsets_, tileCursors_, binList_;
  size_t recordCapacity_ = 0, binCapacity_ = 0, tileCapacity_ = 0;
};

}  // namespace gi
