#include "cl/tile_groups.h"

#include <algorithm>

namespace gi::cl {

NDRange tileGroups2D(const DeviceInfo& device, size_t itemsX, size_t itemsY, size_t maxSide) {
  size_t side = maxSide;
  if (!device.isGpu) {
    const size_t threads = std::max(1u, device.computeUnits);
    auto groups = [&](size_t s) { return ((itemsX + s - 1) / s) * ((itemsY + s - 1) / s); };
    while (side > 1 && groups(side) <= 32 * threads * threads) side /= 2;
  }
  return NDRange::d2(roundUp(itemsX, side), roundUp(itemsY, side), side, side);
}

}  // namespace gi::cl
