// Work-group shape of the 2D launches whose work-items each cover a tile of screen pixels.
#pragma once
#include "cl/runtime.h"

namespace gi::cl {

// A launch of itemsX × itemsY work-items (each side rounded up to the group's) in work-groups of
// groupW × groupH, halved on a CPU device (the height first) while the launch would have fewer
// than 200·T groups, T = the device's compute units (PoCL's threads); GPUs keep the given group.
//
// Why: PoCL's pthread device (3.1, lib/CL/devices/pthread/pthread_scheduler.c) deals a launch's
// work-groups, in row-major order, to its T threads in runs of min(⌈remaining / T⌉, 32·T) groups
// while at most 1024 remain (runs of up to 256·T above). With few groups the first runs are large
// — at most 32·T² groups are cut into halves at once — and where the cost per pixel differs
// across the image (the cone marches and the RSM gather cost more in the upper half of Sponza)
// the thread that took the costlier run finishes last while the other idles. With at least 200·T
// groups every run is at most 16 % of the launch and the last runs are small. Smaller groups than
// that cost CPU time (vct diffuse cones, 2 × 2 at 640 × 360: +12 %). Measured with 2 threads only:
// docs/PERFORMANCE.md, "Diffuse cones: work-groups dealt evenly to PoCL's threads" and "Work-groups
// dealt evenly to PoCL's threads". Each work-item computes the same pixels whatever the group:
// the results are the same bits.
NDRange balancedTileGroups(const DeviceInfo& device, size_t itemsX, size_t itemsY, size_t groupW, size_t groupH);

}  // namespace gi::cl
