#include "layout/layout.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "core/error.hpp"

namespace tightex {

namespace {

/// A rectangle up to this elongated costs a chart nothing in the layout's error model (Bisector::cost):
/// most components are not round either.
constexpr double kFreeAspect = 2.0;
/// The layout moves a cut away from the proportional split only for a modelled gain above this.
constexpr double kMinLayoutGain = 1e-3;

/// The two groups a cut separates: their total weights and their largest items' weights.
struct CutGroups {
  double weight_a = 0, largest_a = 0;
  double weight_b = 0, largest_b = 0;
};

/// Where a cut may go: at lo..hi texels along a side of `extent` texels, the other side `across`.
struct CutRange {
  int lo = 0, hi = 0, extent = 0, across = 0;
};

/// The split point of `items` (sorted, largest first) whose prefix weight is closest to half.
size_t balanced_split(const std::vector<uint32_t>& items, const std::vector<double>& weight, double total) {
  double acc = 0;
  size_t split = 1;
  double best = 1e300;
  for (size_t k = 1; k < items.size(); ++k) {
    acc += weight[items[k - 1]];
    const double d = std::abs(acc - total / 2);
    if (d < best) best = d, split = k;
  }
  return split;
}

/// Every split point of n items, `split` first, then the others by distance from it.
std::vector<size_t> split_candidates(size_t n, size_t split) {
  std::vector<size_t> ks;
  for (size_t k = 1; k < n; ++k) ks.push_back(k);
  std::stable_sort(ks.begin(), ks.end(), [&](size_t a, size_t b) {
    const size_t da = a > split ? a - split : split - a, db = b > split ? b - split : split - b;
    return da < db;
  });
  return ks;
}

/// The recursive bisection of layout_atlas.
struct Bisector {
  const std::vector<double>& weight;
  int min_side;
  AtlasShares shares;
  std::vector<Rect>& out;
  /// Where the bisection found no room (set when place returns false).
  Rect failed_region;
  size_t failed_items = 0;

  /// The modelled colour error of a group of items in a w x h rectangle. A chart of weight (share) a
  /// holding t texels loses about a^2 / t (its texel spacing squared, over its area: docs/maps.md), and
  /// the proportional split minimises the sum. A chart squeezed into a strip keeps its texel count but
  /// not its resolution across the strip: sampled e:1 instead of 1:1 at the same count, it loses
  /// (e + 1/e) / 2 times more, e the elongation beyond kFreeAspect of the rectangle the group's largest
  /// item would get (its long side cut in proportion).
  double cost(double wsum, double wmax, long w, long h) const {
    if (w <= 0 || h <= 0 || !(wsum > 0)) return 0.0;
    const double r = double(std::max(w, h)) / double(std::min(w, h));
    const double e = std::max(1.0, std::max(1.0, r * wmax / wsum) / kFreeAspect);
    return wsum * wsum / (double(w) * double(h)) * 0.5 * (e + 1.0 / e);
  }

  /// The cut in `range` with the least cost of the two groups, if that beats the proportional cut
  /// `first` by kMinLayoutGain; else `first`. A coarse scan (at most 513 cuts), then the texels around
  /// its best.
  int least_cost_cut(int first, const CutRange& range, const CutGroups& g) const {
    auto split_cost = [&](int x) {
      return cost(g.weight_a, g.largest_a, x, range.across) + cost(g.weight_b, g.largest_b, range.extent - x, range.across);
    };
    const int lo = range.lo, hi = range.hi;
    const double proportional = split_cost(first);
    const int stride = std::max(1, (hi - lo) / 512);
    int best = first;
    double best_cost = proportional;
    for (int x = lo; x <= hi; x += stride)
      if (const double c = split_cost(x); c < best_cost) best_cost = c, best = x;
    for (int x = std::max(lo, best - stride); x <= std::min(hi, best + stride); ++x)
      if (const double c = split_cost(x); c < best_cost) best_cost = c, best = x;
    return best_cost < proportional * (1 - kMinLayoutGain) ? best : first;
  }

  // Smallest extent along a cut direction that a group of n items can take when the other side is
  // `across` texels: enough area for n min_side squares, and at least min_side.
  int min_extent(size_t n, int across) const {
    const long cells_across = std::max(1, across / min_side);
    const long rows = (long(n) + cells_across - 1) / cells_across;
    return int(rows * min_side);
  }

  /// Places `items` (sorted, largest first) in r. Returns false, with failed_region and failed_items
  /// set, where some region cannot hold its items at min_side x min_side.
  bool place(const std::vector<uint32_t>& items, Rect r) {
    if (items.size() == 1) {
      r.image = 0;
      out[items[0]] = r;
      return true;
    }
    double total = 0;
    for (uint32_t i : items) total += weight[i];
    // Cut across the longer side in proportion to the weights; when the minimum sizes make that
    // impossible (many tiny components in a narrow strip), try the other side, then other split points.
    for (const size_t k : split_candidates(items.size(), balanced_split(items, weight, total))) {
      const std::vector<uint32_t> a(items.begin(), items.begin() + long(k)), b(items.begin() + long(k), items.end());
      double wa = 0;
      for (uint32_t i : a) wa += weight[i];
      const double share = wa / total;
      for (const bool cut_x : {r.w >= r.h, r.w < r.h}) {
        const int extent = cut_x ? r.w : r.h, across = cut_x ? r.h : r.w;
        const int lo = min_extent(a.size(), across), hi = extent - min_extent(b.size(), across);
        if (lo > hi) continue;
        int first = std::clamp(int(std::lround(extent * share)), lo, hi);
        // The proportional cut, unless it squeezes a group into a strip (one big component and a small
        // one: the small one's strip spans the texture): then the cut that the error model prefers.
        if (shares == AtlasShares::kLeastError)
          first = least_cost_cut(first, CutRange{lo, hi, extent, across}, CutGroups{wa, weight[a.front()], total - wa, weight[b.front()]});
        Rect ra = r, rb = r;
        if (cut_x) {
          ra.w = first;
          rb.x = r.x + first;
          rb.w = r.w - first;
        } else {
          ra.h = first;
          rb.y = r.y + first;
          rb.h = r.h - first;
        }
        return place(a, ra) && place(b, rb);
      }
    }
    failed_region = r;
    failed_items = items.size();
    return false;
  }
};

/// layout_atlas's work: the rectangles, or the message of the InputError it throws.
struct AtlasAttempt {
  std::vector<Rect> rects;
  std::optional<std::string> failure;
};

AtlasAttempt attempt_atlas(const std::vector<double>& areas, int width, int height, int min_side, AtlasShares shares) {
  AtlasAttempt attempt;
  attempt.rects.resize(areas.size());
  if (areas.empty()) return attempt;
  if (long(areas.size()) > long(width / min_side) * long(height / min_side)) {
    attempt.failure = fmt::format("a {}x{} texture cannot hold {} components at {}x{} texels each; use a larger --size", width, height,
                                  areas.size(), min_side, min_side);
    return attempt;
  }
  double total = 0;
  for (double a : areas) total += std::max(a, 0.0);
  // Round tiny shares up to the minimum rectangle so the proportional cut leaves them room.
  const double min_share = double(min_side) * min_side / (double(width) * height);
  std::vector<double> weight(areas.size());
  for (size_t i = 0; i < areas.size(); ++i) weight[i] = std::max(total > 0 ? areas[i] / total : 1.0, min_share);
  std::vector<uint32_t> items(areas.size());
  std::iota(items.begin(), items.end(), 0u);
  std::stable_sort(items.begin(), items.end(), [&](uint32_t a, uint32_t b) { return weight[a] > weight[b]; });
  Bisector bisector{weight, min_side, shares, attempt.rects, Rect{}, 0};
  if (!bisector.place(items, Rect{0, 0, 0, width, height})) {
    const Rect& r = bisector.failed_region;
    attempt.failure = fmt::format("a {}x{} region cannot hold {} components at {}x{} texels each; use a larger --size", r.w, r.h,
                                  bisector.failed_items, min_side, min_side);
  }
  return attempt;
}

}  // namespace

std::vector<Rect> layout_atlas(const std::vector<double>& areas, int width, int height, int min_side, AtlasShares shares) {
  AtlasAttempt attempt = attempt_atlas(areas, width, height, min_side, shares);
  if (attempt.failure) throw InputError(*attempt.failure);
  return std::move(attempt.rects);
}

std::optional<std::vector<Rect>> try_layout_atlas(const std::vector<double>& areas, int width, int height, int min_side,
                                                  AtlasShares shares) {
  AtlasAttempt attempt = attempt_atlas(areas, width, height, min_side, shares);
  if (attempt.failure) return std::nullopt;
  return std::move(attempt.rects);
}

std::vector<Rect> layout_per_component(const std::vector<double>& areas, int size, int min_side, double aspect) {
  std::vector<Rect> out(areas.size());
  const double max_area = areas.empty() ? 1.0 : *std::max_element(areas.begin(), areas.end());
  const double sx = std::sqrt(aspect > 0 ? aspect : 1.0);
  for (size_t i = 0; i < areas.size(); ++i) {
    const double share = max_area > 0 ? std::sqrt(std::max(areas[i], 0.0) / max_area) : 1.0;
    const int w = std::max(min_side, int(std::lround(size * share * sx))), h = std::max(min_side, int(std::lround(size * share / sx)));
    out[i] = Rect{int(i), 0, 0, w, h};
  }
  return out;
}

}  // namespace tightex
