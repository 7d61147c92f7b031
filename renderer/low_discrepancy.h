// low_discrepancy.h: the first two dimensions of the Sobol sequence, randomised by
// XOR scrambling, for placing a pixel's samples.
//
// Points i = 0..2^m-1 of these two dimensions form a (0, m, 2)-net: every elementary
// interval of area 2^-m (every way of cutting the pixel into 2^m equal rectangles)
// holds exactly one point. That stratifies the pixel at all aspect ratios at once,
// which matters most where a pixel straddles a sharp edge (a reflected light source):
// the error there falls faster than with jittered or Latin-hypercube samples. XOR with
// a random word per pixel keeps the net property and makes every point uniformly
// distributed, so the estimate stays unbiased.
#pragma once

#include "renderer/math.h"

#include <cstdint>

namespace glaze {

// Radical inverse in base 2 (van der Corput): the first Sobol dimension, as 32 bits.
inline uint32_t sobol_dimension_0(uint32_t i) {
  i = (i << 16) | (i >> 16);
  i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
  i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
  i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
  i = ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
  return i;
}

// The second Sobol dimension (direction numbers v_k = v_(k-1) ^ (v_(k-1) >> 1)).
inline uint32_t sobol_dimension_1(uint32_t i) {
  uint32_t result = 0;
  for (uint32_t v = 1u << 31; i != 0; i >>= 1, v ^= v >> 1)
    if (i & 1u) result ^= v;
  return result;
}

// Sample i of a pixel's scrambled (0, 2)-sequence, in [0, 1)^2.
inline Vec2 scrambled_sobol_2d(uint32_t i, uint32_t scramble_x, uint32_t scramble_y) {
  // The top 24 bits: exactly representable as floats below 1.
  return {static_cast<float>((sobol_dimension_0(i) ^ scramble_x) >> 8) * 0x1p-24f,
          static_cast<float>((sobol_dimension_1(i) ^ scramble_y) >> 8) * 0x1p-24f};
}

}  // namespace glaze
