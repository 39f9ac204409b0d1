#include "param/boundary.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "param/corners.hpp"

namespace tightex {

namespace {

/// The face of each boundary edge (bnd[i], bnd[i + 1]); kNone where none is found.
std::vector<uint32_t> boundary_edge_faces(const Surface& m, const std::vector<uint32_t>& bnd) {
  const size_t nb = bnd.size();
  std::vector<uint32_t> edge_face(nb, kNone);
  std::vector<uint32_t> boundary_face_from(m.num_vertices(), kNone), boundary_face_to(m.num_vertices(), kNone);
  for (uint32_t h = 0; h < m.opposite.size(); ++h)
    if (m.opposite[h] == kNone) boundary_face_from[m.from(h)] = h / 3, boundary_face_to[m.to(h)] = h / 3;
  for (size_t i = 0; i < nb; ++i) {
    uint32_t f = boundary_face_from[bnd[i]];
    if (f == kNone ||
        !(m.triangles[f][0] == bnd[(i + 1) % nb] || m.triangles[f][1] == bnd[(i + 1) % nb] || m.triangles[f][2] == bnd[(i + 1) % nb]))
      f = boundary_face_to[bnd[i]];
    edge_face[i] = f;
  }
  return edge_face;
}

/// Cumulative length along the boundary (arc[i] at position i, arc[nb] the total). With a density
/// target, each edge's length is scaled by the square root of its face's target density (target area
/// / 3D area), so lengths along a side are in the units the target asks for.
std::vector<double> boundary_arc_lengths(const Disk& disk, const SquareMapOptions& options, const std::vector<uint32_t>& edge_face) {
  const Surface& m = disk.mesh;
  const auto& bnd = disk.boundary;
  const size_t nb = bnd.size();
  std::vector<double> edge_scale(nb, 1.0);
  if (!options.face_target.empty()) {
    for (size_t i = 0; i < nb; ++i) {
      const uint32_t f = edge_face[i];
      if (f == kNone) continue;
      const double a3 = triangle_area(m.positions, m.triangles[f]);
      const double d = a3 > 0 ? options.face_target[f] / a3 : 0.0;
      if (d > 0 && std::isfinite(d)) edge_scale[i] = std::pow(d, 0.5 * std::clamp(options.balance, 0.0, 1.0));
    }
  }
  std::vector<double> arc(nb + 1, 0.0);
  for (size_t i = 0; i < nb; ++i) arc[i + 1] = arc[i] + edge_scale[i] * (m.positions[bnd[(i + 1) % nb]] - m.positions[bnd[i]]).norm();
  return arc;
}

/// Places every position on its side by arc length between the side's corners (b.corner set).
/// Returns each position's parameter along its side, 0 at the side's first corner.
std::vector<double> place_on_sides(const std::vector<double>& arc, SquareBoundary& b) {
  const size_t nb = b.uv.size();
  const double total = arc[nb];
  std::vector<double> side_t(nb, 0.0);
  for (int k = 0; k < 4; ++k) {
    const size_t a = b.corner[k], c = b.corner[(k + 1) % 4];
    const size_t len = (c + nb - a) % nb;
    if (len == 0) continue;
    auto arc_from_a = [&](size_t i) {
      const double d = arc[i] - arc[a];
      return d < 0 ? d + total : d;
    };
    const double side_len = (c == a) ? total : (arc_from_a(c) > 0 ? arc_from_a(c) : total);
    for (size_t j = 0; j < len; ++j) {
      const size_t i = (a + j) % nb;
      const double t = side_len > 0 ? arc_from_a(i) / side_len : double(j) / double(len);
      b.uv[i] = (1 - t) * kSquareCorners[k] + t * kSquareCorners[(k + 1) % 4];
      b.side_of[i] = k;
      side_t[i] = t;
    }
  }
  if (nb == 3) b.uv[2] = kSquareCorners[2];
  return side_t;
}

/// Per side, the intervals [lo, hi] (offsets from the side's first corner) spanned by chords: interior
/// edges whose two ends lie on that side at least two positions apart.
std::vector<std::vector<std::pair<size_t, size_t>>> chord_intervals(const Disk& disk, const std::array<size_t, 4>& corner) {
  const Surface& m = disk.mesh;
  const auto& bnd = disk.boundary;
  const size_t nb = bnd.size();
  std::vector<int> bindex(m.num_vertices(), -1);
  for (size_t i = 0; i < nb; ++i) bindex[bnd[i]] = int(i);
  std::vector<std::vector<std::pair<size_t, size_t>>> intervals(4);
  for (uint32_t h = 0; h < m.opposite.size(); ++h) {
    const uint32_t o = m.opposite[h];
    if (o == kNone || o < h) continue;
    const int ia = bindex[m.from(h)], ib = bindex[m.to(h)];
    if (ia < 0 || ib < 0) continue;
    for (int k = 0; k < 4; ++k) {
      const size_t side_len = (corner[(k + 1) % 4] + nb - corner[k]) % nb;
      const size_t pa = (size_t(ia) + nb - corner[k]) % nb, pb = (size_t(ib) + nb - corner[k]) % nb;
      if (pa <= side_len && pb <= side_len && std::max(pa, pb) - std::min(pa, pb) >= 2)
        intervals[k].push_back({std::min(pa, pb), std::max(pa, pb)});
    }
  }
  return intervals;
}

/// Lifts the positions strictly between offsets lo and hi of side k outward by a sine bump of height
/// `height`, and pins them.
void lift_bump(int k, size_t lo, size_t hi, double height, const std::vector<double>& side_t, SquareBoundary& b) {
  const size_t nb = b.uv.size();
  const size_t side_len = (b.corner[(k + 1) % 4] + nb - b.corner[k]) % nb;
  const Vec2 outward = k == 0 ? Vec2(0, -1) : k == 1 ? Vec2(1, 0) : k == 2 ? Vec2(0, 1) : Vec2(-1, 0);
  const Vec2 along = kSquareCorners[(k + 1) % 4] - kSquareCorners[k];
  const size_t ia = (b.corner[k] + lo) % nb, ib = (b.corner[k] + hi) % nb;
  const double ta = lo == 0 ? 0.0 : side_t[ia], tb = hi == side_len ? 1.0 : side_t[ib];
  for (size_t p = lo + 1; p < hi; ++p) {
    const size_t i = (b.corner[k] + p) % nb;
    const double s = (side_t[i] - ta) / std::max(tb - ta, 1e-300);
    b.uv[i] = kSquareCorners[k] + side_t[i] * along + height * std::sin(std::numbers::pi * std::clamp(s, 0.0, 1.0)) * outward;
    b.pinned[i] = 1;
    b.bumped_vertices++;
  }
}

/// Bumps over chords whose two ends lie on the same side: overlapping chords share one bump.
void lift_chord_bumps(const Disk& disk, const SquareMapOptions& options, const std::vector<double>& side_t, SquareBoundary& b) {
  auto intervals = chord_intervals(disk, b.corner);
  for (int k = 0; k < 4; ++k) {
    auto& iv = intervals[k];
    if (iv.empty()) continue;
    std::sort(iv.begin(), iv.end());
    const bool horizontal = (k % 2 == 0);
    const double height = options.bump_texels / double(std::max(1, (horizontal ? options.rect_height : options.rect_width) - 1));
    size_t lo = iv[0].first, hi = iv[0].second;
    for (size_t j = 1; j < iv.size(); ++j) {
      if (iv[j].first < hi) {
        hi = std::max(hi, iv[j].second);
      } else {
        lift_bump(k, lo, hi, height, side_t, b);
        lo = iv[j].first, hi = iv[j].second;
      }
    }
    lift_bump(k, lo, hi, height, side_t, b);
  }
}

}  // namespace

SquareBoundary map_boundary_to_square(const Disk& disk, const SquareMapOptions& options) {
  const size_t nb = disk.boundary.size();
  SquareBoundary b;
  b.uv.assign(nb, Vec2::Zero());
  b.side_of.assign(nb, 0);
  b.edge_face.assign(nb, kNone);
  if (!options.face_target.empty()) b.edge_face = boundary_edge_faces(disk.mesh, disk.boundary);
  const std::vector<double> arc = boundary_arc_lengths(disk, options, b.edge_face);
  b.corner = choose_corners(disk, arc, options.corners, map_aspect(options));
  b.pinned.assign(nb, 0);
  for (int k = 0; k < 4; ++k) b.pinned[b.corner[k]] = 1;
  if (nb == 3) std::fill(b.pinned.begin(), b.pinned.end(), 1);
  const std::vector<double> side_t = place_on_sides(arc, b);
  if (nb > 4) lift_chord_bumps(disk, options, side_t, b);
  return b;
}

}  // namespace tightex
