// Real spherical harmonics, the engine's one SH convention (ALGORITHMS.md §4, §2.5), shared by
// every technique that stores directional light in SH (LPV, VCT-SH with l <= 1; SH-IGI with l <= 2).
//
// Basis without the Condon–Shortley phase, coefficients stored in a float4 in this order:
//   .x = Y00 = 0.282095          .y = Y1,-1 = 0.488603·y
//   .z = Y10 = 0.488603·z        .w = Y11   = 0.488603·x
// Order l = 2 (SH-IGI, 9 coefficients: the four above, then index 4..8):
//   Y2,-2 = 1.092548·xy   Y2,-1 = 1.092548·yz   Y20 = 0.315392·(3z² − 1)
//   Y21   = 1.092548·xz   Y22   = 0.546274·(x² − y²)
// The clamped cosine lobe max(0, n·ω) projects to (0.886227, 1.023327·n_y, 1.023327·n_z,
// 1.023327·n_x) (= √π/2 and √(π/3)). Its integral over the sphere is π: a cell storing
// Φ/π × lobe(n) emits flux Φ.
// The constants are plain macros so host code (tests, mirrors) uses the same numbers.
#pragma once

#define GI_SH_Y0 0.282094792f      // 1 / (2√π)
#define GI_SH_Y1 0.488602512f      // √3 / (2√π)
#define GI_SH_LOBE0 0.886226925f   // √π / 2
#define GI_SH_LOBE1 1.023326708f   // √(π/3)
// Zonal coefficients of the clamped-cosine convolution (irradiance from radiance): Â0 = π, Â1 = 2π/3.
#define GI_SH_COSCONV0 3.14159265f
#define GI_SH_COSCONV1 2.09439510f
#define GI_SH_COSCONV2 0.785398163f  // Â2 = π/4 (l = 2)
#define GI_SH_Y2_PRODUCT 1.092548431f  // Y2,-2, Y2,-1, Y21: √15 / (2√π)
#define GI_SH_Y20 0.315391565f         // √5 / (4√π)
#define GI_SH_Y22 0.546274215f         // √15 / (4√π)

#ifdef __OPENCL_VERSION__
// The basis evaluated in unit direction d.
inline float4 sh_basis(float3 d) { return (float4)(GI_SH_Y0, GI_SH_Y1 * d.y, GI_SH_Y1 * d.z, GI_SH_Y1 * d.x); }

// Coefficients of the clamped cosine lobe max(0, n·ω) around unit n.
inline float4 sh_cosine_lobe(float3 n) {
  return (float4)(GI_SH_LOBE0, GI_SH_LOBE1 * n.y, GI_SH_LOBE1 * n.z, GI_SH_LOBE1 * n.x);
}

// The function with coefficients c evaluated in unit direction d.
inline float sh_eval(float4 c, float3 d) { return dot(c, sh_basis(d)); }
#endif
