// The light-field probe grid (McGuire et al. 2017 as seed 004 §4 used it; ALGORITHMS.md §6),
// shared by the host (src/gi/probes/) and the kernels (kernels/gi/probes/). Same layout rules as
// common/shared_types.h.
//
// Probe (i, j, k), 0 <= i < count[0] …, sits at origin + (i, j, k) · spacing. Each probe owns two
// octahedral maps (probe_field.h), each with a one-texel border that repeats the texels across
// the octahedral seams so that bilinear filtering needs no wrap logic:
//   irradiance: (irradiance_res + 2)² float4 texels, rgb = irradiance E (W/m²) on a surface at the
//               probe facing the texel's direction, from the light reflected by the scene;
//   distance:   (distance_res + 2)² float2 texels, (mean, mean²) of the distance (metres) to the
//               first surface around the texel's direction (the filtered distance of the paper).
// Probe p's irradiance texel (x, y) is irradiance[p · (irradiance_res + 2)² + y · (irradiance_res + 2) + x];
// interior texels are 1 … res, texel x covers octahedral coordinates [(x − 1)/res, x/res]·2 − 1.
//
// Per probe, a state float4 (DDGI relocation and classification, Majercik et al. 2021): xyz = the
// probe's offset (metres) from its grid point — it traces and is seen from grid point + offset —
// and w = 1 for an active probe, 0 for one classified as inside geometry (it gets no weight).
#pragma once

#include "../../common/shared_types.h"

#ifndef __OPENCL_VERSION__
namespace gi {
#endif

typedef struct {
  float origin[3];           // world position of probe (0, 0, 0)
  float max_distance;        // ray length (metres); a ray that hits nothing records this distance
  float spacing[3];          // metres between neighbouring probes along x, y, z
  float normal_bias;         // shading point moved this far (metres) along its geometric normal ...
  GI_I32 count[3];           // probes along x, y, z
  float view_bias;           // ... and this far towards the viewer before the visibility test
  GI_I32 irradiance_res;     // interior texels per side of an irradiance map
  GI_I32 distance_res;       // interior texels per side of a distance map
  GI_I32 rays;               // rays per probe per update
  float backface_floor;      // smallest backface weight of seed 004's eq. 7 (a point facing away from every probe still blends)
  float pad[4];
} GiProbeGrid;  // 80 bytes

// The probes one update launch traces, blends and border-copies (probes.update_budget). The
// updates go round-robin through an order of all N probes: position i of the order is probe
// (i · stride) mod N, stride coprime to N (1: index order; the budget's stride spreads the probes
// of one update over the grid, ProbeField::update()). Slot s, 0 <= s < probes, of this launch is
// position (first_position + s) mod N (probes <= N: the positions wrap around once at most); its
// rays are rayResults[s · rays …]. Hysteresis is per probe update (the probe's k-th update since
// the running mean started blends with min(max, k/(k+1))): within one launch the slots differ by
// one update at most, the slots from later_slot on having had one more.
typedef struct {
  GI_I32 first_position;    // position in the order of slot 0
  GI_I32 stride;            // position i is probe (i · stride) mod N
  GI_I32 probes;            // slots in this launch (N: every probe)
  GI_I32 later_slot;        // first slot with one update more (probes: none)
  float hysteresis;         // weight of the old value for slots < later_slot
  float later_hysteresis;   // ... for slots >= later_slot
  GI_I32 pad[2];
} GiProbeUpdate;  // 32 bytes

#ifndef __OPENCL_VERSION__
}  // namespace gi
static_assert(sizeof(gi::GiProbeGrid) == 80, "GiProbeGrid layout");
static_assert(sizeof(gi::GiProbeUpdate) == 32, "GiProbeUpdate layout");
#endif
