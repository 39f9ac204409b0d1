#include "prepare/components.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <queue>

namespace tightex {

namespace {

/// What the split reads per face: its centroid and its 3D area.
struct FaceSites {
  std::vector<Vec3> centroid;
  std::vector<double> area;
};

/// Geodesic Voronoi regions of `parts` seeds over the faces (distances between neighbouring faces'
/// centroids): the first seed is the face farthest from face 0, each next one the face farthest from
/// the seeds so far (farthest-point sampling), so the regions come out compact, about equal where the
/// surface is even, and each connected. Per face, its region.
std::vector<uint32_t> voronoi_labels(const Surface& s, const FaceSites& sites, int parts) {
  const uint32_t n = uint32_t(s.num_faces());
  std::vector<double> dist(n, INFINITY);
  std::vector<uint32_t> label(n, 0);
  using Entry = std::pair<double, uint32_t>;
  auto grow = [&](uint32_t seed, uint32_t l) {  // Dijkstra from `seed`, taking the faces it reaches first
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
    dist[seed] = 0, label[seed] = l;
    queue.push({0.0, seed});
    while (!queue.empty()) {
      const auto [d, f] = queue.top();
      queue.pop();
      if (d > dist[f]) continue;
      for (int k = 0; k < 3; ++k) {
        const uint32_t o = s.opposite[3 * f + k];
        if (o == kNone) continue;
        const double nd = d + (sites.centroid[f] - sites.centroid[o / 3]).norm();
        if (nd < dist[o / 3]) dist[o / 3] = nd, label[o / 3] = l, queue.push({nd, o / 3});
      }
    }
  };
  grow(0, 0);
  auto farthest = [&] { return uint32_t(std::max_element(dist.begin(), dist.end()) - dist.begin()); };
  const uint32_t first = farthest();
  std::fill(dist.begin(), dist.end(), INFINITY);
  grow(first, 0);
  for (int l = 1; l < parts; ++l) grow(farthest(), uint32_t(l));
  return label;
}

/// Smooths the lines between labels: a face whose neighbours across two or three of its edges share
/// another label takes it (a face with two edges on a split line would be an ear of the piece's
/// boundary, squeezed flat where the boundary goes onto the square's straight side). A few passes.
void smooth_labels(const Surface& s, std::vector<uint32_t>& label) {
  for (int pass = 0; pass < 4; ++pass) {
    size_t changed = 0;
    for (uint32_t f = 0; f < s.num_faces(); ++f) {
      uint32_t neighbour[3];
      for (int k = 0; k < 3; ++k) {
        const uint32_t o = s.opposite[3 * f + k];
        neighbour[k] = o == kNone ? kNone : label[o / 3];
      }
      for (int k = 0; k < 3; ++k) {
        const uint32_t l = neighbour[k];
        if (l != kNone && l != label[f] && (l == neighbour[(k + 1) % 3] || l == neighbour[(k + 2) % 3])) {
          label[f] = l, ++changed;
          break;
        }
      }
    }
    if (changed == 0) break;
  }
}

/// Per face, its piece: faces joined across edges within one label. Returns the count.
uint32_t label_pieces(const Surface& s, const std::vector<uint32_t>& label, std::vector<uint32_t>& piece) {
  Surface within = s;
  for (uint32_t h = 0; h < 3 * s.num_faces(); ++h)
    if (s.opposite[h] != kNone && label[h / 3] != label[s.opposite[h] / 3]) within.opposite[h] = kNone;
  return face_components(within, piece);
}

/// Gives each label one connected piece: a label's smaller pieces (a plane cuts a curved surface into
/// islands) join the label they share the most edges with, so the parts stay few and whole.
void merge_islands(const Surface& s, const FaceSites& sites, std::vector<uint32_t>& label) {
  for (int round = 0; round < 8; ++round) {
    std::vector<uint32_t> piece;
    const uint32_t pieces = label_pieces(s, label, piece);
    std::vector<double> area(pieces, 0.0);
    std::vector<uint32_t> piece_label(pieces);
    for (uint32_t f = 0; f < s.num_faces(); ++f) area[piece[f]] += sites.area[f], piece_label[piece[f]] = label[f];
    std::map<uint32_t, uint32_t> largest;  // label -> its largest piece
    for (uint32_t p = 0; p < pieces; ++p) {
      auto [it, added] = largest.try_emplace(piece_label[p], p);
      if (!added && area[p] > area[it->second]) it->second = p;
    }
    std::vector<std::map<uint32_t, size_t>> shared(pieces);  // island -> label beyond its edges -> edges
    for (uint32_t h = 0; h < 3 * s.num_faces(); ++h) {
      const uint32_t o = s.opposite[h], p = piece[h / 3];
      if (o != kNone && label[o / 3] != label[h / 3] && largest[piece_label[p]] != p) ++shared[p][label[o / 3]];
    }
    bool changed = false;
    std::vector<uint32_t> new_label(pieces);
    for (uint32_t p = 0; p < pieces; ++p) {
      new_label[p] = piece_label[p];
      if (shared[p].empty()) continue;
      new_label[p] = std::max_element(shared[p].begin(), shared[p].end(), [](auto& a, auto& b) { return a.second < b.second; })->first;
      changed = true;
    }
    for (uint32_t f = 0; f < s.num_faces(); ++f) label[f] = new_label[piece[f]];
    if (!changed) return;
  }
}

}  // namespace

std::vector<Surface> split_into_parts(const Surface& component, int parts) {
  FaceSites sites;
  sites.centroid.resize(component.num_faces());
  sites.area.resize(component.num_faces());
  for (uint32_t f = 0; f < component.num_faces(); ++f) {
    const Tri& t = component.triangles[f];
    const Vec3 &a = component.positions[t[0]], &b = component.positions[t[1]], &c = component.positions[t[2]];
    sites.centroid[f] = (a + b + c) / 3.0;
    sites.area[f] = triangle_area(a, b, c);
  }
  std::vector<uint32_t> label = voronoi_labels(component, sites, std::max(1, parts));
  smooth_labels(component, label);
  merge_islands(component, sites, label);
  // Corners stay one vertex only across edges within a label: the split lines open, and a vertex
  // pinched between two labels gets a copy per fan.
  uint32_t groups = 0;
  const auto corner_vertex = group_corners(
      component, [&](uint32_t h) { return label[h / 3] == label[component.opposite[h] / 3]; }, &groups);
  Surface opened = regroup(component, corner_vertex, groups);
  inherit_input_map(opened, component);  // regroup's face_parent: the identity
  std::vector<Surface> pieces = split_components(opened);
  for (Surface& piece : pieces)
    for (uint32_t& v : piece.vertex_parent) v = opened.vertex_parent[v];
  return pieces;
}

std::vector<Surface> split_components(const Surface& s) {
  std::vector<uint32_t> comp;
  const uint32_t n = face_components(s, comp);
  std::vector<Surface> out(n);
  std::vector<uint32_t> local_vertex(s.num_vertices(), kNone), local_face(s.num_faces());
  for (uint32_t t = 0; t < s.num_faces(); ++t) {
    Surface& c = out[comp[t]];
    local_face[t] = uint32_t(c.triangles.size());
    Tri f;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = s.triangles[t][k];
      if (local_vertex[v] == kNone) {
        local_vertex[v] = uint32_t(c.positions.size());
        c.positions.push_back(s.positions[v]);
        c.vertex_parent.push_back(v);
      }
      f[k] = local_vertex[v];
    }
    c.triangles.push_back(f);
    c.face_parent.push_back(t);
  }
  for (Surface& c : out) {
    c.opposite.assign(3 * c.num_faces(), kNone);
    for (uint32_t lt = 0; lt < c.num_faces(); ++lt)
      for (int k = 0; k < 3; ++k) {
        const uint32_t o = s.opposite[3 * c.face_parent[lt] + k];
        if (o != kNone) c.opposite[3 * lt + k] = 3 * local_face[o / 3] + o % 3;
      }
    inherit_input_map(c, s);
  }
  return out;
}

}  // namespace tightex
