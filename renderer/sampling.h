// sampling.h: discrete importance sampling (Walker's alias method) and multiple
// importance sampling's weights. Used for environment importance sampling.
#pragma once

#include "renderer/math.h"

#include <cstdint>
#include <span>
#include <vector>

namespace glaze {

// Multiple importance sampling's power heuristic (Veach 1997, beta = 2): the weight of
// a sample drawn by strategy a that strategy b could also have drawn.
inline float power_heuristic(float pdf_a, float pdf_b) {
  const float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
  return a + b > 0.0f ? a / (a + b) : 0.0f;
}

// n outcomes drawn with probability pmf(i) proportional to non-negative weights (all
// zero: uniform), by Walker's alias method in Vose's construction: a draw reads one
// table entry, chosen uniformly, and keeps it or takes its alias by a coin against the
// entry's threshold. That is one memory access with no search, so a caller drawing
// many samples can prefetch every entry before reading any (an inverted CDF needs a
// search whose reads depend on each other: on a large environment map, two cache misses
// in a row). Outcomes of zero weight are never drawn.
class AliasTable {
 public:
  explicit AliasTable(std::span<const float> weights);

  int size() const { return static_cast<int>(entries_.size()); }
  float pmf(int i) const { return entries_[i].pmf; }

  // The entry that 64 uniform random bits select (exactly uniform to 2^-64 for any n),
  // then the outcome that a coin uniform in [0, 1) picks from it, with its pmf.
  int slot(uint64_t bits) const {
    return static_cast<int>((static_cast<unsigned __int128>(bits) * entries_.size()) >> 64);
  }
  void prefetch(int slot) const { __builtin_prefetch(&entries_[slot]); }
  int sample(int slot, float coin, float* pmf) const {
    const Entry& entry = entries_[slot];
    const bool keep = coin < entry.threshold;
    if (pmf) *pmf = keep ? entry.pmf : entry.alias_pmf;
    return keep ? slot : entry.alias;
  }

  // The probability that sample() returns i, summed from the table (for tests: it must
  // equal pmf(i) up to float rounding of the thresholds).
  double selection_probability(int i) const;

 private:
  struct Entry {
    float threshold;  // keep this entry's outcome if coin < threshold
    int32_t alias;    // else this outcome
    float pmf;        // of this entry's outcome
    float alias_pmf;  // of the alias, stored here so that a draw reads one entry
  };
  std::vector<Entry> entries_;
};

}  // namespace glaze
