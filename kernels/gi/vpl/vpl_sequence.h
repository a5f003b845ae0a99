// The low-discrepancy coordinates of VPL generation (ALGORITHMS.md §2.2; docs/techniques/vpl.md
// "Bounces"). Host mirrors: radicalInverse / scrambledRadicalInverse in src/util/halton.h (same
// float arithmetic in the same order).
#pragma once

// Φ_base(i): the digits of i in `base` mirrored about the radix point (Halton coordinate).
inline float radical_inverse(uint i, uint base) {
  float inv = 1.0f / (float)base, f = inv, r = 0.0f;
  while (i > 0) {
    r += (float)(i % base) * f;
    i /= base;
    f *= inv;
  }
  return r;
}

// Φ_base(i) with every digit d replaced by (multiplier · d) mod base (linear digit scrambling,
// Matoušek 1998). Keeps the stratification of the Halton sequence and spreads the first points of
// a large base over [0, 1): unscrambled, points 1..16 in base 29 all lie below 16/29.
inline float scrambled_radical_inverse(uint i, uint base, uint multiplier) {
  float inv = 1.0f / (float)base, f = inv, r = 0.0f;
  while (i > 0) {
    r += (float)((i % base) * multiplier % base) * f;
    i /= base;
    f *= inv;
  }
  return r;
}
