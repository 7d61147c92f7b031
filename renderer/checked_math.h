// checked_math.h: arithmetic on sizes, counts, offsets and indices read from files.
//
// A hostile file can give any number: a count near 2^64, an offset that wraps, an
// index of 1e300. Sums and products of such numbers are computed here with overflow
// reported (never wrapped), and a JSON number becomes an integer only when it is
// finite, whole and in range (a cast of an out-of-range double is undefined behaviour).
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>

namespace glaze {

// a + b, or nothing when the sum does not fit in 64 bits.
inline std::optional<uint64_t> checked_add(uint64_t a, uint64_t b) {
  uint64_t sum = 0;
  if (__builtin_add_overflow(a, b, &sum)) return std::nullopt;
  return sum;
}

// a * b, or nothing when the product does not fit in 64 bits.
inline std::optional<uint64_t> checked_mul(uint64_t a, uint64_t b) {
  uint64_t product = 0;
  if (__builtin_mul_overflow(a, b, &product)) return std::nullopt;
  return product;
}

// a * b, or UINT64_MAX when it does not fit: for memory estimates, where "more than
// any machine has" is the right answer to an overflow.
inline uint64_t saturating_mul(uint64_t a, uint64_t b) { return checked_mul(a, b).value_or(UINT64_MAX); }

// `value` as an integer when it is finite, whole and in [lowest, highest]; nothing
// otherwise. Bounds beyond +-2^63 are treated as +-2^63.
inline std::optional<int64_t> integer_from(double value, int64_t lowest, int64_t highest) {
  constexpr double kTwoTo63 = 9223372036854775808.0;
  if (!std::isfinite(value) || value != std::floor(value)) return std::nullopt;
  if (value < -kTwoTo63 || value >= kTwoTo63) return std::nullopt;
  const auto integer = static_cast<int64_t>(value);
  if (integer < lowest || integer > highest) return std::nullopt;
  return integer;
}

}  // namespace glaze
