#include "renderer/sampling.h"

#include <algorithm>
#include <stdexcept>

namespace glaze {

AliasTable::AliasTable(std::span<const float> weights) {
  const size_t n = weights.size();
  if (n == 0) throw std::invalid_argument("AliasTable: no weights");
  // Probabilities in double, so that tiny weights beside huge ones keep their share.
  std::vector<double> probability(n);
  double total = 0.0;
  for (size_t i = 0; i < n; ++i) {
    probability[i] = weights[i] > 0.0f ? weights[i] : 0.0;  // also maps NaN to 0
    total += probability[i];
  }
  for (double& p : probability) p = total > 0.0 ? p / total : 1.0 / n;

  // Vose: entries whose scaled probability n p is below 1 are filled up from ones above.
  entries_.resize(n);
  std::vector<double> scaled(n);
  std::vector<int32_t> small, large;
  for (size_t i = 0; i < n; ++i) {
    scaled[i] = probability[i] * n;
    (scaled[i] < 1.0 ? small : large).push_back(static_cast<int32_t>(i));
  }
  while (!small.empty() && !large.empty()) {
    const int32_t under = small.back(), over = large.back();
    small.pop_back();
    entries_[under].threshold = static_cast<float>(scaled[under]);
    entries_[under].alias = over;
    scaled[over] -= 1.0 - scaled[under];
    if (scaled[over] < 1.0) {
      large.pop_back();
      small.push_back(over);
    }
  }
  // What is left has n p = 1 up to rounding: it keeps its own outcome.
  for (const auto* rest : {&small, &large})
    for (int32_t i : *rest) entries_[i] = {1.0f, i, 0.0f, 0.0f};
  for (size_t i = 0; i < n; ++i) entries_[i].pmf = static_cast<float>(probability[i]);
  for (Entry& entry : entries_) entry.alias_pmf = entries_[entry.alias].pmf;
}

double AliasTable::selection_probability(int i) const {
  double p = 0.0;
  for (int s = 0; s < size(); ++s) {
    const double keep = std::min(1.0, double(entries_[s].threshold));
    if (s == i) p += keep;
    if (entries_[s].alias == i) p += 1.0 - keep;
  }
  return p / size();
}

}  // namespace glaze
