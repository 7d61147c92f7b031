// rng.h: PCG32 (O'Neill 2014), a small, fast generator whose stream depends only on its
// seed and sequence index. Every sampler in glaze derives its stream from (seed, pixel
// or task index), never from thread identity, so results do not depend on scheduling.
#pragma once

#include <cstdint>

namespace glaze {

class Pcg32 {
 public:
  explicit Pcg32(uint64_t seed = 0, uint64_t sequence = 0) {
    state_ = 0;
    increment_ = (sequence << 1u) | 1u;
    next_uint();
    state_ += seed;
    next_uint();
  }

  uint32_t next_uint() {
    const uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + increment_;
    const auto xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    const auto rot = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((-rot) & 31u));
  }

  // Uniform in [0, 1): the top 24 bits, so the result is exactly representable and < 1.
  float next_float() { return static_cast<float>(next_uint() >> 8) * 0x1p-24f; }

 private:
  uint64_t state_;
  uint64_t increment_;
};

}  // namespace glaze
