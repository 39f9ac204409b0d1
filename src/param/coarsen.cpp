#include "param/coarsen.hpp"

#include <algorithm>
#include <cmath>

#include "param/harmonic.hpp"

namespace tightex {

namespace {

/// A changed face keeps its orientation: its normal within this angle's cosine of the old one.
constexpr double kMinNormalCosine = 0.7;
/// A changed face keeps a fair shape: 4 sqrt(3) area / sum of squared edges (1: equilateral) at least
/// this, or at least its old shape's.
constexpr double kMinQuality = 0.3;

double quality(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double l2 = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  return l2 > 0 ? 2 * std::sqrt(3.0) * (b - a).cross(c - a).norm() / l2 : 0.0;
}

/// The vertices waiting to collapse, shortest edge first (ties: the lower vertex): a 4-ary heap with
/// each vertex's place in it, so a vertex queued again moves instead of leaving a stale entry behind.
/// A heap of stale entries grew to about eight per vertex, and popping it was a third of the
/// collapses' time, in cache misses; four children a node (64 bytes, read together) halve a binary heap's
/// depth, and so its misses: the coarsening of a 1M-triangle disk 1633 / 2791 -> 1336 / 1916 ms, of
/// a 2M-triangle disk 4111 / 4678 -> 3708 / 3907 ms (`tightex_bench --benchmark_filter=CoarsenDisk`,
/// the fastest of 5 and of 3 runs, two alternating rounds each), the same collapses (the order is
/// total).
class VertexQueue {
 public:
  explicit VertexQueue(size_t vertices) : place_(vertices, kNone) {}

  bool empty() const { return heap_.empty(); }

  /// Queues v at `length`, or moves it there if it is queued (where it is already, nothing moves).
  void set(uint32_t v, double length) {
    if (place_[v] == kNone) {
      place_[v] = uint32_t(heap_.size());
      heap_.emplace_back(length, v);
    } else {
      if (heap_[place_[v]].first == length) return;
      heap_[place_[v]].first = length;
      down(place_[v]);
    }
    up(place_[v]);
  }

  /// Removes and returns the first vertex.
  uint32_t pop() {
    const uint32_t v = heap_.front().second;
    place_[v] = kNone;
    if (heap_.size() > 1) {
      heap_.front() = heap_.back();
      place_[heap_.front().second] = 0;
    }
    heap_.pop_back();
    if (!heap_.empty()) down(0);
    return v;
  }

 private:
  void swap_at(size_t a, size_t b) {
    std::swap(heap_[a], heap_[b]);
    place_[heap_[a].second] = uint32_t(a);
    place_[heap_[b].second] = uint32_t(b);
  }
  void up(size_t i) {
    for (; i > 0 && heap_[i] < heap_[(i - 1) / kArity]; i = (i - 1) / kArity) swap_at(i, (i - 1) / kArity);
  }
  void down(size_t i) {
    for (;;) {
      size_t first = i;
      for (size_t c = kArity * i + 1; c <= kArity * i + kArity && c < heap_.size(); ++c)
        if (heap_[c] < heap_[first]) first = c;
      if (first == i) return;
      swap_at(i, first);
      i = first;
    }
  }
  static constexpr size_t kArity = 4;  // children per node

  std::vector<std::pair<double, uint32_t>> heap_;  // (length, vertex); pairs compare as the order above
  std::vector<uint32_t> place_;                    // per vertex its index in heap_, kNone if not queued
};

/// The fine mesh under half-edge collapses: faces stay in place (dead ones flagged), each vertex keeps
/// the list of its live faces.
class Collapser {
 public:
  Collapser(const Disk& fine, const std::vector<double>& face_target)
      : m_(fine.mesh),
        tri_(fine.mesh.triangles),
        mass_(face_target),
        face_alive_(tri_.size(), 1),
        vertex_alive_(m_.num_vertices(), 1),
        locked_(boundary_mask(m_.num_vertices(), fine.boundary)),
        on_boundary_(locked_),
        merged_into_(m_.num_vertices()),
        faces_(m_.num_vertices()),
        queue_(m_.num_vertices()) {
    for (uint32_t f = 0; f < tri_.size(); ++f)
      for (uint32_t v : tri_[f]) {
        faces_[v].push_back(f);
        if (m_.face_parent[f] == kNone) locked_[v] = 1;
      }
    alive_ = m_.num_vertices();
    for (uint32_t v = 0; v < m_.num_vertices(); ++v) merged_into_[v] = v;
  }

  /// Collapses until at most max_vertices are left or nothing more may collapse. A later call goes on
  /// from there, as one call with its size would have.
  void run(size_t max_vertices) {
    if (!queued_)
      for (uint32_t v = 0; v < m_.num_vertices(); ++v) push(v);
    queued_ = true;
    while (alive_ > max_vertices && !queue_.empty()) {
      const uint32_t v = queue_.pop();
      // v's neighbours, nearest first (each distance computed once; the comparisons, and so the order
      // of equally near ones, are the same as sorting the ids by distance).
      neighbours(v, nv_);
      by_distance_.clear();
      for (uint32_t u : nv_) by_distance_.emplace_back(dist(v, u), u);
      std::sort(by_distance_.begin(), by_distance_.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      for (const auto& [d, u] : by_distance_)
        if (allowed(v, u)) {
          collapse(v, u);
          // Only u and v's neighbours have new edges (their edges to v are now to u); u's other
          // neighbours keep their shortest edge, and so their place in the queue.
          push(u);
          for (uint32_t w : nv_)
            if (w != u) push(w);
          break;
        }
    }
  }

  CoarseDisk result(const Disk& fine) const;

  /// Per vertex, the vertex it has been moved onto, through every later collapse of that one (itself
  /// where it is still there).
  std::vector<uint32_t> standing_for() {
    std::vector<uint32_t> stands(m_.num_vertices());
    for (uint32_t v = 0; v < m_.num_vertices(); ++v) stands[v] = find(v);
    return stands;
  }

 private:
  /// The live vertex v has been moved onto (union-find with path halving).
  uint32_t find(uint32_t v) {
    while (merged_into_[v] != v) v = merged_into_[v] = merged_into_[merged_into_[v]];
    return v;
  }

  double dist(uint32_t a, uint32_t b) const { return (m_.positions[a] - m_.positions[b]).norm(); }

  /// v's neighbours, sorted, into r (a buffer reused: the collapses ask hundreds of thousands of times).
  void neighbours(uint32_t v, std::vector<uint32_t>& r) const {
    r.clear();
    for (uint32_t f : faces_[v])
      for (uint32_t w : tri_[f])
        if (w != v) r.push_back(w);
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
  }

  /// Queues v (again) at its shortest edge's length, unless it is gone or may not move.
  void push(uint32_t v) {
    if (!vertex_alive_[v] || locked_[v]) return;
    double shortest = INFINITY;  // squared, until the end
    for (uint32_t f : faces_[v])
      for (uint32_t w : tri_[f])
        if (w != v) shortest = std::min(shortest, (m_.positions[v] - m_.positions[w]).squaredNorm());
    queue_.set(v, std::sqrt(shortest));
  }

  /// Whether v may move onto its neighbour u (see coarsen_disk); nv_ holds v's neighbours.
  bool allowed(uint32_t v, uint32_t u) {
    std::vector<uint32_t>& apex = apex_;
    apex.clear();
    for (uint32_t f : faces_[v])
      if (std::find(tri_[f].begin(), tri_[f].end(), u) != tri_[f].end())
        for (uint32_t w : tri_[f])
          if (w != u && w != v) apex.push_back(w);
    if (apex.size() != 2 || apex[0] == apex[1]) return false;
    const std::vector<uint32_t>& nv = nv_;
    std::vector<uint32_t>& nu = nu_;
    std::vector<uint32_t>& common = common_;
    neighbours(u, nu);
    common.clear();
    std::set_intersection(nv.begin(), nv.end(), nu.begin(), nu.end(), std::back_inserter(common));
    std::sort(apex.begin(), apex.end());
    if (common != apex) return false;  // the link condition
    if (on_boundary_[u])
      for (uint32_t w : nv)
        if (w != u && on_boundary_[w] && w != apex[0] && w != apex[1]) return false;  // a new chord
    for (uint32_t f : faces_[v]) {
      const Tri& t = tri_[f];
      if (std::find(t.begin(), t.end(), u) != t.end()) continue;
      Vec3 p[3], q[3];
      for (int k = 0; k < 3; ++k) p[k] = q[k] = m_.positions[t[k]];
      for (int k = 0; k < 3; ++k)
        if (t[k] == v) q[k] = m_.positions[u];
      const Vec3 n0 = (p[1] - p[0]).cross(p[2] - p[0]), n1 = (q[1] - q[0]).cross(q[2] - q[0]);
      if (!(n0.dot(n1) > kMinNormalCosine * n0.norm() * n1.norm())) return false;
      if (quality(q[0], q[1], q[2]) < std::min(kMinQuality, quality(p[0], p[1], p[2]))) return false;
    }
    return true;
  }

  void collapse(uint32_t v, uint32_t u) {
    std::vector<uint32_t>& removed = removed_;
    std::vector<uint32_t>& kept = kept_;
    removed.clear(), kept.clear();
    for (uint32_t f : faces_[v]) (std::find(tri_[f].begin(), tri_[f].end(), u) != tri_[f].end() ? removed : kept).push_back(f);
    double spare = 0;
    for (uint32_t f : removed) {
      face_alive_[f] = 0;
      spare += mass_[f];
      for (uint32_t w : tri_[f])
        if (w != v) std::erase(faces_[w], f);
    }
    for (uint32_t f : kept) {
      for (uint32_t& w : tri_[f])
        if (w == v) w = u;
      mass_[f] += spare / double(kept.size());
      faces_[u].push_back(f);
    }
    faces_[v].clear();
    vertex_alive_[v] = 0;
    merged_into_[v] = u;
    --alive_;
  }

  const Surface& m_;
  std::vector<Tri> tri_;
  std::vector<double> mass_;
  std::vector<char> face_alive_, vertex_alive_, locked_, on_boundary_;
  std::vector<uint32_t> merged_into_;  // per vertex, the one it was moved onto (itself while it is there)
  std::vector<std::vector<uint32_t>> faces_;
  std::vector<uint32_t> apex_, nv_, nu_, common_, removed_, kept_;  // scratch of run(), allowed() and collapse()
  std::vector<std::pair<double, uint32_t>> by_distance_;            // scratch of run()
  size_t alive_ = 0;
  bool queued_ = false;  // every vertex pushed once (the first run)
  VertexQueue queue_;
};

CoarseDisk Collapser::result(const Disk& fine) const {
  CoarseDisk c;
  std::vector<uint32_t> index(m_.num_vertices(), kNone);
  Surface& s = c.disk.mesh;
  for (uint32_t v = 0; v < m_.num_vertices(); ++v)
    if (vertex_alive_[v]) {
      index[v] = uint32_t(c.fine_vertex.size());
      c.fine_vertex.push_back(v);
      s.positions.push_back(m_.positions[v]);
      s.vertex_parent.push_back(m_.vertex_parent[v]);
    }
  for (uint32_t f = 0; f < tri_.size(); ++f)
    if (face_alive_[f]) {
      s.triangles.push_back({index[tri_[f][0]], index[tri_[f][1]], index[tri_[f][2]]});
      s.face_parent.push_back(m_.face_parent[f]);
      c.face_target.push_back(mass_[f]);
    }
  build_opposite(s);
  for (uint32_t v : fine.boundary) c.disk.boundary.push_back(index[v]);
  return c;
}

}  // namespace

CoarseDisk coarsen_disk(const Disk& fine, const std::vector<double>& face_target, size_t max_vertices) {
  Collapser collapser(fine, face_target);
  collapser.run(max_vertices);
  return collapser.result(fine);
}

std::vector<CoarseDisk> coarsen_disk_in_steps(const Disk& fine, const std::vector<double>& face_target,
                                              const std::vector<size_t>& max_vertices, const std::vector<size_t>& aggregate_sizes,
                                              VertexAggregates* aggregates) {
  Collapser collapser(fine, face_target);
  std::vector<CoarseDisk> copies;
  auto copy = max_vertices.begin();
  auto level = aggregate_sizes.begin();
  while (copy != max_vertices.end() || (aggregates && level != aggregate_sizes.end())) {
    const bool copy_next = copy != max_vertices.end() && (!aggregates || level == aggregate_sizes.end() || *copy >= *level);
    collapser.run(copy_next ? *copy : *level);
    if (copy_next) {
      copies.push_back(collapser.result(fine));
      ++copy;
    } else {
      aggregates->levels.push_back(collapser.standing_for());
      ++level;
    }
  }
  return copies;
}

}  // namespace tightex
