#include "layout/layout.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.hpp"

namespace tightex {

namespace {

struct Bisector {
  const std::vector<double>& weight;
  int min_side;
  std::vector<Rect>& out;

  // Smallest extent along a cut direction that a group of n items can take when the other side is
  // `across` texels: enough area for n min_side squares, and at least min_side.
  int min_extent(size_t n, int across) const {
    const long cells_across = std::max(1, across / min_side);
    const long rows = (long(n) + cells_across - 1) / cells_across;
    return int(rows * min_side);
  }

  void place(const std::vector<uint32_t>& items, Rect r) {
    if (items.size() == 1) {
      r.image = 0;
      out[items[0]] = r;
      return;
    }
    double total = 0;
    for (uint32_t i : items) total += weight[i];
    // Split point: prefix whose weight is closest to half.
    double acc = 0;
    size_t split = 1;
    double best = 1e300;
    for (size_t k = 1; k < items.size(); ++k) {
      acc += weight[items[k - 1]];
      const double d = std::abs(acc - total / 2);
      if (d < best) best = d, split = k;
    }
    // Cut across the longer side in proportion to the weights; when the minimum sizes make that
    // impossible (many tiny components in a narrow strip), try the other side, then other split points.
    // Candidate split points: the area split first, then the others by distance from it.
    std::vector<size_t> ks;
    for (size_t k = 1; k < items.size(); ++k) ks.push_back(k);
    std::stable_sort(ks.begin(), ks.end(), [&](size_t a, size_t b) {
      const size_t da = a > split ? a - split : split - a, db = b > split ? b - split : split - b;
      return da < db;
    });
    for (const size_t k : ks) {
      const std::vector<uint32_t> a(items.begin(), items.begin() + long(k)), b(items.begin() + long(k), items.end());
      double wa = 0;
      for (uint32_t i : a) wa += weight[i];
      const double share = wa / total;
      for (const bool cut_x : {r.w >= r.h, r.w < r.h}) {
        const int extent = cut_x ? r.w : r.h, across = cut_x ? r.h : r.w;
        const int lo = min_extent(a.size(), across), hi = extent - min_extent(b.size(), across);
        if (lo > hi) continue;
        const int first = std::clamp(int(std::lround(extent * share)), lo, hi);
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
        place(a, ra);
        place(b, rb);
        return;
      }
    }
    fail_input("a {}x{} region cannot hold {} components at {}x{} texels each; use a larger --size", r.w, r.h,
               items.size(), min_side, min_side);
  }
};

}  // namespace

std::vector<Rect> layout_atlas(const std::vector<double>& areas, int width, int height, int min_side) {
  std::vector<Rect> out(areas.size());
  if (areas.empty()) return out;
  if (long(areas.size()) > long(width / min_side) * long(height / min_side))
    fail_input("a {}x{} texture cannot hold {} components at {}x{} texels each; use a larger --size", width, height,
               areas.size(), min_side, min_side);
  double total = 0;
  for (double a : areas) total += std::max(a, 0.0);
  // Round tiny shares up to the minimum rectangle so the proportional cut leaves them room.
  const double min_share = double(min_side) * min_side / (double(width) * height);
  std::vector<double> weight(areas.size());
  for (size_t i = 0; i < areas.size(); ++i) weight[i] = std::max(total > 0 ? areas[i] / total : 1.0, min_share);
  std::vector<uint32_t> items(areas.size());
  std::iota(items.begin(), items.end(), 0u);
  std::stable_sort(items.begin(), items.end(), [&](uint32_t a, uint32_t b) { return weight[a] > weight[b]; });
  Bisector{weight, min_side, out}.place(items, Rect{0, 0, 0, width, height});
  return out;
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
