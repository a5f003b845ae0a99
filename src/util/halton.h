// The radical inverse Φ_base(i), a coordinate of the Halton sequence, computed in float in the same
// order as the kernels (kernels/gi/vpl/vpl_sequence.h) so host mirrors and host-generated sample
// sets match them bit for bit.
#pragma once
#include <cstdint>

namespace gi {

inline float radicalInverse(uint32_t i, uint32_t base) {
  float inv = 1.0f / float(base), f = inv, r = 0.0f;
  while (i > 0) {
    r += float(i % base) * f;
    i /= base;
    f *= inv;
  }
  return r;
}

// Φ_base(i) with every digit d replaced by (multiplier · d) mod base (linear digit scrambling).
inline float scrambledRadicalInverse(uint32_t i, uint32_t base, uint32_t multiplier) {
  float inv = 1.0f / float(base), f = inv, r = 0.0f;
  while (i > 0) {
    r += float((i % base) * multiplier % base) * f;
    i /= base;
    f *= inv;
  }
  return r;
}

}  // namespace gi
