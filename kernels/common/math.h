// Small maths shared by all kernels: constants, column-major 4×4 matrix products (glm layout,
// as stored in GiView), safe normalisation, orthonormal bases.
#pragma once

#define GI_PI 3.14159265358979323846f
#define GI_INV_PI 0.31830988618379067154f
#define GI_INF (__builtin_inff())

// m is column-major: element (row r, column c) at m[c*4 + r].
inline float4 mat4_mul(const float* m, float4 v) {
  return (float4)(m[0], m[1], m[2], m[3]) * v.x + (float4)(m[4], m[5], m[6], m[7]) * v.y +
         (float4)(m[8], m[9], m[10], m[11]) * v.z + (float4)(m[12], m[13], m[14], m[15]) * v.w;
}
inline float4 mat4_mul_global(global const float* m, float4 v) {
  return (float4)(m[0], m[1], m[2], m[3]) * v.x + (float4)(m[4], m[5], m[6], m[7]) * v.y +
         (float4)(m[8], m[9], m[10], m[11]) * v.z + (float4)(m[12], m[13], m[14], m[15]) * v.w;
}

inline float3 safe_normalize(float3 v, float3 fallback) {
  float l2 = dot(v, v);
  return l2 > 1e-30f ? v * rsqrt(l2) : fallback;
}

// Right-handed orthonormal basis (t, b, n) around unit n (Duff et al. 2017).
inline void orthonormal_basis(float3 n, float3* t, float3* b) {
  float s = n.z >= 0.0f ? 1.0f : -1.0f;
  float a = -1.0f / (s + n.z);
  float c = n.x * n.y * a;
  *t = (float3)(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
  *b = (float3)(c, s + n.y * n.y * a, -n.y);
}

inline float luminance(float3 c) { return dot(c, (float3)(0.2126f, 0.7152f, 0.0722f)); }
