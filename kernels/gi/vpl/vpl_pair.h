// The VPL–receiver term of ALGORITHMS.md §2 for GI_VW receivers (structure of arrays) and one VPL
// (position a.xyz, d_min² a.w, normal b.xyz), in the kernels' VPL layout:
//   max(0, n_p·ω)·max(0, −n·ω) / max(d², d_min²)
// computed from unnormalised vectors (the two cosines' 1/d go into the first max(d², 1e-20)).
// Times Φ_p/π it is E_p; a negative flux (second-order's negative lights) subtracts.
#pragma once
#include "common/vector_width.h"

inline floatV vpl_pair_term(floatV px, floatV py, floatV pz, floatV nx, floatV ny, floatV nz, float4 a, float4 b) {
  floatV vx = a.x - px, vy = a.y - py, vz = a.z - pz;  // receiver -> VPL
  floatV d2 = vx * vx + vy * vy + vz * vz;
  floatV cp = -(b.x * vx + b.y * vy + b.z * vz);  // n_p·(x − x_p)
  floatV cr = nx * vx + ny * vy + nz * vz;        // −n·(x − x_p)
  return max(cp, 0.0f) * max(cr, 0.0f) / (max(d2, 1e-20f) * max(d2, a.w));
}
