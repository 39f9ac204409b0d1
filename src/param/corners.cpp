// Which four boundary vertices of a disk go to the square's corners (docs/corners.md).
#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "param/corners.hpp"

namespace tightex {

namespace {

/// The four corners where the boundary length is shared out as the rectangle's perimeter is (the
/// quarters on a square), starting at the first ear (or vertex 0); an ear within 5% of such a point is
/// taken instead of the nearest vertex.
std::array<size_t, 4> equal_arc_corners(size_t nb, const std::vector<double>& arc, const std::vector<size_t>& ears, double aspect) {
  const double total = arc[nb];
  std::array<size_t, 4> corner{};
  const size_t start = ears.empty() ? 0 : ears[0];
  corner[0] = start;
  // Sides in boundary order: bottom (width), right (height), top (width), left (height).
  const double bottom = aspect / (2 * (aspect + 1)), right = 1 / (2 * (aspect + 1));
  const double share_before[4] = {0, bottom, bottom + right, 2 * bottom + right};
  for (int k = 1; k < 4; ++k) {
    const double target = std::fmod(arc[start] + total * share_before[k], total);
    auto dist_to = [&](size_t i) {
      const double d = std::abs(arc[i] - target);
      return std::min(d, total - d);
    };
    size_t best = 0;
    for (size_t i = 0; i < nb; ++i)
      if (dist_to(i) < dist_to(best)) best = i;
    for (size_t e : ears)
      if (dist_to(e) < 0.05 * total && dist_to(e) < dist_to(best) + 0.05 * total) {
        best = e;
        break;
      }
    corner[k] = best;
  }
  // Corners must be distinct and in boundary order; fall back to index quarters otherwise.
  auto rel = [&](size_t i) { return (i + nb - start) % nb; };
  bool ok = true;
  for (int k = 1; k < 4; ++k) ok = ok && rel(corner[k]) > rel(corner[k - 1]);
  if (!ok)
    for (int k = 1; k < 4; ++k) corner[k] = (start + k * nb / 4) % nb;
  return corner;
}

/// The four most turning boundary stretches, each arc between them at least kMinShare of the length.
std::array<size_t, 4> turning_corners(const Disk& disk, const std::vector<double>& arc, const std::vector<size_t>& ears) {
  constexpr double kMinShare = 0.10;  // no side of the square gets less than this share of the boundary
  constexpr double kWindow = 0.025;   // half-width of the tent that integrates the turning, share of the length
  const Surface& m = disk.mesh;
  const auto& bnd = disk.boundary;
  const size_t nb = bnd.size();
  const double total = arc[nb];

  // Interior angle sum at each boundary vertex (3D corner angles of its faces, scaffolding included);
  // the boundary's turning there is pi minus it (a flat square's corners: pi/2, its sides: 0).
  std::vector<double> angle_sum(m.num_vertices(), 0.0);
  for (const Tri& f : m.triangles)
    for (int k = 0; k < 3; ++k) {
      const Vec3 u = m.positions[f[(k + 1) % 3]] - m.positions[f[k]], v = m.positions[f[(k + 2) % 3]] - m.positions[f[k]];
      const double a = std::atan2(u.cross(v).norm(), u.dot(v));
      if (std::isfinite(a)) angle_sum[f[k]] += a;
    }
  std::vector<double> turning(nb);
  for (size_t i = 0; i < nb; ++i) turning[i] = std::numbers::pi - angle_sum[bnd[i]];

  // Scanned boundaries zigzag: the turning is integrated over a stretch of the boundary (tent weights,
  // so a square's corner vertex outscores its neighbours) and a zigzag's turns cancel.
  auto circular = [&](size_t i, size_t j) {
    const double d = std::abs(arc[i] - arc[j]);
    return std::min(d, total - d);
  };
  const double w = kWindow * total;
  std::vector<double> score(nb, 0.0);
  for (size_t i = 0; i < nb; ++i) {
    score[i] = turning[i];
    for (int dir : {-1, 1})
      for (size_t s = 1; 2 * s < nb; ++s) {
        const size_t j = dir > 0 ? (i + s) % nb : (i + nb - s) % nb;
        const double d = circular(i, j);
        if (!(d < w)) break;
        score[i] += (1 - d / w) * turning[j];
      }
  }

  // Greedy: ears first (a single triangle must sit on a corner or collapse onto a side), then by score;
  // a vertex closer than kMinShare to a chosen one is skipped, so every side keeps a fair share.
  std::vector<size_t> order(nb);
  for (size_t i = 0; i < nb; ++i) order[i] = i;
  std::vector<char> is_ear(nb, 0);
  for (size_t e : ears) is_ear[e] = 1;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    if (is_ear[a] != is_ear[b]) return is_ear[a] > is_ear[b];
    return score[a] > score[b];
  });
  std::vector<size_t> chosen;
  for (size_t i : order) {
    if (chosen.size() == 4) break;
    bool far = true;
    for (size_t c : chosen) far = far && circular(i, c) >= kMinShare * total;
    if (far) chosen.push_back(i);
  }
  // A boundary of few long edges may leave no vertex far enough: the best remaining ones then.
  for (size_t i : order) {
    if (chosen.size() == 4) break;
    if (std::find(chosen.begin(), chosen.end(), i) == chosen.end()) chosen.push_back(i);
  }
  std::sort(chosen.begin(), chosen.end());
  // Corner 0 (the square's (0,0)): the first ear if any, else the best scored; the rest follow in boundary order.
  const size_t first = ears.empty() ? order[0] : ears[0];
  size_t k0 = size_t(std::find(chosen.begin(), chosen.end(), first) - chosen.begin());
  if (k0 == chosen.size()) k0 = 0;
  std::array<size_t, 4> corner{};
  for (int k = 0; k < 4; ++k) corner[k] = chosen[(k0 + k) % 4];
  return corner;
}

}  // namespace

std::array<size_t, 4> choose_corners(const Disk& disk, const std::vector<double>& arc, CornerRule rule, double aspect) {
  const Surface& m = disk.mesh;
  const auto& bnd = disk.boundary;
  const size_t nb = bnd.size();
  if (nb < 3 || arc.size() != nb + 1) fail_internal("choose_corners: boundary of {} vertices, {} arc lengths", nb, arc.size());
  if (!(aspect > 0) || !std::isfinite(aspect)) fail_internal("choose_corners: aspect {}", aspect);
  if (nb == 3) return {0, 1, 2, 2};  // a lone triangle: three corners, the fourth side has no edge
  // Ears: boundary vertices with one triangle.
  std::vector<uint32_t> face_count(m.num_vertices(), 0);
  for (const Tri& f : m.triangles)
    for (uint32_t v : f) face_count[v]++;
  std::vector<size_t> ears;
  for (size_t i = 0; i < nb; ++i)
    if (face_count[bnd[i]] == 1) ears.push_back(i);
  return rule == CornerRule::kTurningAngle ? turning_corners(disk, arc, ears) : equal_arc_corners(nb, arc, ears, aspect);
}

}  // namespace tightex
