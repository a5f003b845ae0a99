#include "cl/tile_groups.h"

#include <algorithm>

namespace gi::cl {

NDRange balancedTileGroups(const DeviceInfo& device, size_t itemsX, size_t itemsY, size_t groupW, size_t groupH) {
  size_t gw = groupW, gh = groupH;
  if (!device.isGpu) {
    const size_t minGroups = 200 * std::max(1u, device.computeUnits);
    auto groups = [&] { return ((itemsX + gw - 1) / gw) * ((itemsY + gh - 1) / gh); };
    while (groups() < minGroups && gw * gh > 1) (gh >= gw ? gh : gw) /= 2;
  }
  return NDRange::d2(roundUp(itemsX, gw), roundUp(itemsY, gh), gw, gh);
}

}  // namespace gi::cl
