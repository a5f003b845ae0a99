// The voxel grid of voxel cone tracing (ALGORITHMS.md §5), shared by the host (src/gi/vct/) and
// the kernels (kernels/gi/vct/). Same layout rules as common/shared_types.h.
//
// Grid: resolution N³ cubic voxels of edge voxel_size, a power of two from 32 to 256, whose corner
// (0, 0, 0) sits at `origin`; mip level l has (N >> l)³ voxels of edge voxel_size · 2^l, down to
// 1³ (levels = log2 N + 1).
//
// Voxelization accumulators (one record of GI_VOX_RECORD 32-bit integers per voxel, voxel v's
// field f at acc[v · GI_VOX_RECORD + f]: the 14 fields of a voxel share one 64-byte cache line, so
// a triangle–voxel pair's atomics, the clear and the injection touch one line per voxel;
// order-independent integer atomics, ALGORITHMS.md §7). Each triangle–voxel pair adds, in fixed
// point:
//   albedo ρ · opacity, emission · opacity, shading normal · opacity, the offset of the
//   triangle's point nearest the voxel centre from that centre (in voxels) · opacity, opacity, 1.
#pragma once

#include "../../common/shared_types.h"

#ifndef __OPENCL_VERSION__
namespace gi {
#endif

typedef struct {
  float origin[3];   // world position of the grid's minimum corner
  float voxel_size;  // edge of a level-0 voxel, metres
  GI_I32 resolution; // N
  GI_I32 levels;     // log2(N) + 1
  GI_I32 pad[2];
} GiVoxelGrid;  // 32 bytes

// Accumulator fields (voxel v's field f at acc[v · GI_VOX_RECORD + f]).
#define GI_VOX_ALBEDO 0    // 3 fields, uint, ρ·opacity · GI_VOX_UNIT
#define GI_VOX_EMISSION 3  // 3 fields, uint, L_e·opacity · GI_VOX_EMISSION_UNIT
#define GI_VOX_NORMAL 6    // 3 fields, biased, n·opacity · GI_VOX_UNIT / 4
#define GI_VOX_OFFSET 9    // 3 fields, biased, (nearest point − centre)/voxel_size · opacity · GI_VOX_UNIT / 4
#define GI_VOX_OPACITY 12  // uint, opacity · GI_VOX_UNIT
#define GI_VOX_COUNT 13    // uint, triangles touching the voxel
#define GI_VOX_FIELDS 14
#define GI_VOX_RECORD 16   // words per voxel: the fields padded to 64 bytes (one cache line; vct_clear_occupied
                           // zeroes it as one uint16)

// The signed fields (normal, offset; each pair's value in [-1, 1] · GI_VOX_UNIT / 4) are stored
// biased: every pair that adds to them (every pair not cut away, i.e. opacity / GI_VOX_UNIT of
// them) adds value + GI_VOX_SIGNED_BIAS >= 0, so that the voxelization can add two of them with
// one 64-bit atomic without a borrow between the words. The signed sum is
// field − (opacity / GI_VOX_UNIT) · GI_VOX_SIGNED_BIAS (vox_signed_sum in voxel_grid.h), exact.
#define GI_VOX_SIGNED_BIAS 16384u

// Fixed-point units: values in [0, 1] get 16 fractional bits, so 65535 contributions fit in 32 bits
// (signed quantities in [-2, 2] one bit fewer). Emission (W/(m²·sr)) gets 8 fractional bits and
// is clamped at 65535 per contribution.
#define GI_VOX_UNIT 65536.0f
#define GI_VOX_EMISSION_UNIT 256.0f
#define GI_VOX_EMISSION_MAX 65535.0f

// SH voxels (vct.voxels=sh; seed 003 §3.4.5): per voxel and colour channel the l <= 1 SH
// coefficients (common/sh.h's basis) of its premultiplied exitant radiance L·α as a function of
// the direction of travel ω, stored as 3 float4 (R, G, B) per voxel. A voxel whose surface has
// normal n and radiance L holds L·α·(k0, k1·n_y, k1·n_z, k1·n_x) with the lobe:
//   hemisphere: L on the front hemisphere (n·ω > 0), 0 behind: k0 = 2π·Y00 = √π, k1 = π·Y1 = √(3π)/2.
//               Our voxels are opaque from every side (thickened surfaces), so what a cone sees of
//               the voxel is the surface's radiance L where its front faces the cone, else nothing.
//               Irradiance from it is exact in l <= 1: the clamped cosine has no odd l >= 3 and the
//               hemisphere no even l >= 2 coefficients.
//   cosine:     ten Brug's (seed 003 appendix B.1) clamped cosine lobe max(0, n·ω): k0 = √π/2,
//               k1 = √(π/3) (the radiant intensity of a thin surface per unit cross-section).
// Voxels lit from both sides (normals cancel) hold both lobes: (2·k0, 0, 0, 0).
#define GI_VCT_SH_HEMISPHERE0 1.772453851f  // √π
#define GI_VCT_SH_HEMISPHERE1 1.534990062f  // √(3π) / 2
#define GI_VCT_SH_COSINE0 0.886226925f      // √π / 2 (= GI_SH_LOBE0)
#define GI_VCT_SH_COSINE1 1.023326708f      // √(π/3) (= GI_SH_LOBE1)

#ifndef __OPENCL_VERSION__
}  // namespace gi
static_assert(sizeof(gi::GiVoxelGrid) == 32, "GiVoxelGrid layout");
#endif
