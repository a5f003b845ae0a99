// Work-group shape of the 2D launches whose work-items each cover a tile of screen pixels.
#pragma once
#include "cl/runtime.h"

namespace gi::cl {

// A launch of itemsX × itemsY work-items (each side rounded up to the group side) in square
// work-groups of side maxSide (a power of two), halved on a CPU device while the launch would
// have at most 32·T² groups, T = the device's compute units (PoCL's threads).
//
// Why: PoCL's pthread device (3.1, lib/CL/devices/pthread/pthread_scheduler.c) hands a launch's
// work-groups, in row-major order, to its T threads in runs: at most 32·T groups per run while
// at most 1024 remain (more above), and ⌈remaining / T⌉ when that is fewer. With at most 32·T²
// groups the first thread thus takes its whole share of the image in one run, and where the
// cost per pixel differs across the image (the RSM gather and the cone marches cost more in the
// upper half of Sponza) the thread with the costly half finishes late while the other idles.
// With more groups the runs are capped and the end is dealt in halving runs down to single
// groups. Measured on the 2-thread EPYC (docs/PERFORMANCE.md, "Work-groups dealt evenly to
// PoCL's threads"): launches of 60-120 groups left the busiest thread 0.58-0.61 of the CPU time,
// 230-460 groups 0.52-0.55, no better with more. GPUs keep maxSide: they take groups one by one.
// Each work-item computes the same pixels whatever the group shape: the results are the same bits.
NDRange tileGroups2D(const DeviceInfo& device, size_t itemsX, size_t itemsY, size_t maxSide);

}  // namespace gi::cl
