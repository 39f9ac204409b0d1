// Small statistics shared by the stages.
#pragma once
#include <algorithm>
#include <utility>
#include <vector>

namespace tightex {

/// The weighted quantile q in [0, 1] of (value, weight) pairs: the smallest value at which the
/// cumulative weight, in ascending order of value, reaches q of the total. Sorts the pairs. 0 if empty.
inline double weighted_quantile(std::vector<std::pair<double, double>>& value_weight, double q) {
  std::sort(value_weight.begin(), value_weight.end());
  double total = 0;
  for (const auto& [v, w] : value_weight) total += w;
  double acc = 0;
  for (const auto& [v, w] : value_weight) {
    acc += w;
    if (acc >= q * total) return v;
  }
  return value_weight.empty() ? 0.0 : value_weight.back().first;
}

}  // namespace tightex
