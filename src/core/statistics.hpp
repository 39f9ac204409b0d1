// Small statistics shared by the stages.
#pragma once
#include <algorithm>
#include <utility>
#include <vector>

namespace tightex {

/// The weighted quantile q in [0, 1] of (value, weight) pairs: the smallest value at which the
/// cumulative weight, in ascending order of value, reaches q of the total (the largest value where
/// rounding leaves it short). Reorders the pairs; 0 if empty. A selection, not a sort: each halving
/// keeps the side that holds the answer, so linear time (the density error is measured on every
/// face after each map step).
inline double weighted_quantile(std::vector<std::pair<double, double>>& value_weight, double q) {
  if (value_weight.empty()) return 0.0;
  double total = 0;
  for (const auto& [v, w] : value_weight) total += w;
  const double goal = q * total;
  auto lo = value_weight.begin(), hi = value_weight.end();
  double below = 0;  // the weight of the pairs before lo in ascending order
  while (hi - lo > 1) {
    const auto mid = lo + (hi - lo) / 2;
    std::nth_element(lo, mid, hi);
    double left = 0;
    for (auto it = lo; it != mid; ++it) left += it->second;
    if (below + left >= goal) {
      hi = mid;
    } else {
      below += left;
      lo = mid;
    }
  }
  return lo->first;
}

}  // namespace tightex
