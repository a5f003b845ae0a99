// The record the triangle-setup kernel writes for each (clipped) triangle that may cover a pixel
// centre, read by binning and tile rasterization. Shared with the host for sizes only.
//
// Edge functions are exact integer arithmetic on vertex positions snapped to 1/256 pixel
// (GI_SUBPIXEL_BITS), with the top-left fill rule folded into the constant term: a pixel centre
// (X, Y) in fixed point is inside when every E_i = a_i·X + b_i·Y + c_i >= 0. Two triangles that
// share an edge therefore cover every pixel on it exactly once, whatever order they arrive in.
#pragma once

#define GI_SUBPIXEL_BITS 8
#define GI_SUBPIXEL_ONE 256
// Vertices are clipped to a guard band this many pixels outside the viewport, which keeps the
// fixed-point edge terms below 2^46 (exact in 64-bit integers).
#define GI_GUARD_BAND_PIXELS 8192

#define GI_RASTER_FLAG_ALPHA_TEST 1u
#define GI_RASTER_FLAG_VALID 2u  // the slot holds a triangle (culled triangles leave 0)

#ifdef __OPENCL_VERSION__
#define GI_I64 long
#else
#include <cstdint>
#define GI_I64 int64_t
namespace gi {
#endif

typedef struct {
  GI_I64 c[3];      // edge constants (top-left bias applied)
  GI_I32 a[3];      // edge x coefficients (per fixed-point unit)
  GI_I32 b[3];      // edge y coefficients
  float q[3];       // depth plane over pixel coordinates: q = q[0]·px + q[1]·py + q[2]
                    // (perspective: q = 1/w, larger is nearer; orthographic: q = z01, smaller is nearer)
  GI_I32 bbox[4];   // pixel-centre bounding box, inclusive: x0, y0, x1, y1
  GI_U32 triangle;  // index of the source triangle in the scene
  GI_U32 flags;     // GI_RASTER_FLAG_*
  GI_U32 pad[3];
} GiRasterTriangle;  // 96 bytes

#ifndef __OPENCL_VERSION__
}  // namespace gi
static_assert(sizeof(gi::GiRasterTriangle) == 96, "GiRasterTriangle layout");
#endif
