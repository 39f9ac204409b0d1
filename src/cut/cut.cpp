#include "cut/cut.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <optional>

#include "core/cut_along_edges.hpp"
#include "core/error.hpp"
#include "core/graph.hpp"
#include "cut/cut_graph.hpp"
#include "prepare/handles.hpp"
#include "prepare/holes.hpp"

namespace tightex {

namespace {

/// A disk deeper than this times a flat round disk of its perimeter (perimeter / 2 pi) is slit.
constexpr double kDeepDisk = 1.5;
/// The most slits per cut (requested ones included).
constexpr int kMaxSlits = 16;

/// Handles first: a genus-0 surface whose handle loops are boundary loops (remove_handles, or the
/// caller's earlier result), or the component itself for the plain method and a genus-0 component.
Surface without_handles(const Surface& component, const CutOptions& options, CutStats& st) {
  if (options.method == CutMethod::kPlain) return with_identity_parents(component);
  if (options.handles_removed) {
    st.handle_loops = options.handles_removed->handle_loops;
    return options.handles_removed->surface;
  }
  if (st.before.genus() > 0) return remove_handles(component, &st.handle_loops, options.seams);
  return with_identity_parents(component);
}

double surface_area(const Surface& s) {
  double area = 0;
  for (const Tri& f : s.triangles) area += triangle_area(s.positions, f);
  return area;
}

/// The holes HoleMode::kFill caps.
struct HoleCaps {
  std::vector<std::vector<uint32_t>> loops;  // smallest cap first
  double area = 0;                           // the caps' total area
  bool longest_capped = false;               // the longest loop is among them
};

/// Chooses the caps: centroid fans, smallest first, while their total area stays within `budget_area`;
/// the longest loop (`keep`) stays the boundary unless `cap_longest_loop`.
HoleCaps choose_caps(const Surface& base, const std::vector<std::vector<uint32_t>>& loops, size_t keep, double budget_area,
                     bool cap_longest_loop) {
  std::vector<double> cap_area(loops.size(), 0.0);
  for (size_t i = 0; i < loops.size(); ++i) {
    Vec3 c = Vec3::Zero();
    for (uint32_t h : loops[i]) c += base.positions[base.from(h)];
    c /= double(loops[i].size());
    for (uint32_t h : loops[i]) cap_area[i] += triangle_area(c, base.positions[base.from(h)], base.positions[base.to(h)]);
  }
  std::vector<size_t> order(loops.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return cap_area[a] < cap_area[b]; });
  HoleCaps caps;
  for (size_t i : order) {
    if ((i == keep && !cap_longest_loop) || caps.area + cap_area[i] > budget_area) continue;
    caps.area += cap_area[i];
    caps.loops.push_back(loops[i]);
    caps.longest_capped = caps.longest_capped || i == keep;
  }
  return caps;
}

/// fill_holes with the maps composed through `base`, so that they point where base's point.
Surface cap_holes(const Surface& base, const std::vector<std::vector<uint32_t>>& loops) {
  Surface s = fill_holes(base, loops);
  for (uint32_t& p : s.vertex_parent)
    if (p != kNone) p = base.vertex_parent[p];
  for (uint32_t& p : s.face_parent)
    if (p != kNone) p = base.face_parent[p];
  return s;
}

/// Slits a deep disk. A deep disk maps its far end into a tiny spot (a tube closed at one end: a vase,
/// an object resting on the ground; harmonic maps crowd exponentially with depth, down to below double
/// precision). While the farthest vertex from the disk's boundary (the surface boundary and both sides
/// of every cut) lies deeper than kDeepDisk flat round disks of that perimeter allow, the disk is slit
/// from its boundary to that vertex; each slit lengthens the perimeter, so this ends, and `max_slits`
/// bounds it all the same. The first slits go to the vertices whose vertex_parent is in `slit_to`
/// (skipped where there is none or it is unreached). Adds the slits to `cut_edge`; returns their count.
size_t slit_deep_parts(const Surface& s, const EdgeGraph& g, const std::vector<uint32_t>& slit_to, int max_slits,
                       std::vector<char>& cut_edge) {
  const size_t nv = s.num_vertices();
  size_t slits = 0;
  for (int slit = 0; slit < max_slits; ++slit) {
    double perimeter = 0;
    std::vector<uint32_t> sources;
    for (uint32_t e = 0; e < g.num_edges(); ++e) {
      const bool boundary = s.opposite[g.edge_halfedge[e]] == kNone;
      if (!boundary && !cut_edge[e]) continue;
      perimeter += (boundary ? 1.0 : 2.0) * g.length[e];
      sources.push_back(s.from(g.edge_halfedge[e]));
      sources.push_back(s.to(g.edge_halfedge[e]));
    }
    if (sources.empty()) break;
    std::vector<double> dist;
    std::vector<uint32_t> pred;
    dijkstra(g, nv, sources, g.length, dist, pred);
    uint32_t far = farthest(dist);
    if (size_t(slit) < slit_to.size()) {
      far = kNone;  // requested slits first
      for (uint32_t v = 0; v < nv && far == kNone; ++v)
        if (s.vertex_parent[v] == slit_to[size_t(slit)]) far = v;
      if (far == kNone || !std::isfinite(dist[far])) continue;
    } else if (!(dist[far] > kDeepDisk * perimeter / (2 * std::numbers::pi))) {
      break;
    }
    slits++;
    for (uint32_t v = far; pred[v] != kNone; v = other_end(s, g, pred[v], v)) cut_edge[pred[v]] = 1;
  }
  return slits;
}

/// `s` cut open along `cut_edge`, its maps composed through s's so that they point into the component
/// (the input map comes with cut_along_edges), and its boundary listed. nullopt if it is not a disk
/// (`why` says how).
std::optional<Disk> cut_open(const Surface& s, const EdgeGraph& g, const std::vector<char>& cut_edge, std::string* why) {
  Disk disk;
  disk.mesh = cut_along_edges(s, g, cut_edge);
  for (uint32_t& p : disk.mesh.vertex_parent) p = s.vertex_parent[p];
  for (uint32_t& p : disk.mesh.face_parent) p = s.face_parent[p];  // kNone stays kNone: scaffolding
  const Topology dt = topology_of(disk.mesh);
  const auto disk_loops = boundary_loops(disk.mesh);
  if (disk_loops.size() != 1 || dt.euler() != 1) {
    *why = fmt::format("cut_to_disk: result has {} boundary loops and Euler characteristic {} (expected a disk)", disk_loops.size(),
                       dt.euler());
    return std::nullopt;
  }
  for (uint32_t h : disk_loops[0]) disk.boundary.push_back(disk.mesh.from(h));
  return disk;
}

/// The seam this component gets in the output (docs/metrics.md): its edges whose two triangles end up apart
/// (handle loops, hole connections, the cut graph, slits), each counted once from both sides, and the
/// part of it that lies on the input's texture seams.
void measure_seam(const Surface& component, const Surface& disk, std::span<const char> seams, CutStats& st) {
  for (uint32_t h = 0; h < disk.opposite.size(); ++h) {
    const uint32_t f = disk.face_parent[h / 3], o = disk.opposite[h];
    if (f == kNone || (o != kNone && disk.face_parent[o / 3] != kNone)) continue;
    const uint32_t ch = 3 * f + h % 3;
    if (component.opposite[ch] == kNone) continue;  // the surface's own boundary
    const double half = 0.5 * component.edge_length(ch);
    st.seam_length += half;
    if (!seams.empty() && seams[ch]) st.seam_on_input_seams += half;
  }
}

/// cut_to_disk with the options as given. Returns nullopt where the caps would be the only link
/// between some real faces (the output would hold them as a chart of their own), or where the trial
/// with the longest loop capped gives no disk; `stats` is then left as it was.
std::optional<Disk> try_cut_to_disk(const Surface& component, const CutOptions& options, CutStats* stats) {
  const bool plain = options.method == CutMethod::kPlain;
  CutStats st;
  st.before = topology_of(component);
  st.fill_budget = options.holes == HoleMode::kFill && !plain ? options.fill_budget : 0.0;
  Surface base = without_handles(component, options, st);
  auto loops = boundary_loops(base);
  const size_t keep = longest_loop(base, loops);
  if (!loops.empty()) st.longest_loop_edges = loops[keep].size();

  // Holes: the longest loop stays the disk boundary (unless cap_longest_loop); with kFill the others
  // are capped smallest first within the area budget.
  Surface s;
  if (!plain && options.holes == HoleMode::kFill && (loops.size() > 1 || (options.cap_longest_loop && loops.size() == 1))) {
    const double component_area = surface_area(component);
    const HoleCaps caps = choose_caps(base, loops, keep, options.fill_budget * component_area, options.cap_longest_loop);
    st.holes_filled = caps.loops.size();
    st.filled_area = component_area > 0 ? caps.area / component_area : 0.0;
    st.longest_loop_capped = caps.longest_capped;
    s = cap_holes(base, caps.loops);
    loops = boundary_loops(s);
  } else {
    s = std::move(base);
  }
  st.holes_cut = loops.empty() ? 0 : loops.size() - 1;

  const EdgeGraph g(s, plain ? std::span<const char>{} : options.seams);
  CutGraph cut = compute_cut_graph(s, g);
  st.method = std::move(cut.method);
  st.slits = slit_deep_parts(s, g, options.slit_to, plain ? 0 : kMaxSlits, cut.cut_edge);
  if (st.slits) st.method += "+slit";
  if (plain) st.method += " (plain fallback)";
  if (options.holes == HoleMode::kFill && st.holes_filled > 0 && real_faces_apart(s, g, cut.cut_edge)) return std::nullopt;

  for (uint32_t e = 0; e < g.num_edges(); ++e)
    if (cut.cut_edge[e]) st.cut_edges++, st.cut_length += g.length[e];
  std::string why;
  std::optional<Disk> disk = cut_open(s, g, cut.cut_edge, &why);
  // Capping the longest loop too is a trial beside the usual cut: where it gives no disk (a degenerate
  // closed piece), the caller gets the cut without caps, not capped. Otherwise a broken invariant.
  if (!disk && options.cap_longest_loop) return std::nullopt;
  if (!disk) fail_internal("{}", why);
  measure_seam(component, disk->mesh, options.seams, st);
  if (stats) *stats = st;
  return disk;
}

}  // namespace

Disk cut_to_disk(const Surface& component, const CutOptions& options, CutStats* stats) {
  if (std::optional<Disk> disk = try_cut_to_disk(component, options, stats)) return std::move(*disk);
  // One chart per component: a cap can be the only link between a few faces and the rest (a handle's
  // capped side on one hand, the cut graph on the other). Cut again without caps: every face real.
  CutOptions open = options;
  open.holes = HoleMode::kCut;
  open.cap_longest_loop = false;
  std::optional<Disk> disk = try_cut_to_disk(component, open, stats);
  if (!disk) fail_internal("cut_to_disk: the real faces fall apart with no cap");
  if (stats) stats->method += " (caps would split the chart: holes opened)";
  return std::move(*disk);
}

std::optional<Disk> cut_to_disk_capped(const Surface& component, CutOptions options, CutStats* stats) {
  options.cap_longest_loop = true;
  CutStats st;
  std::optional<Disk> disk = try_cut_to_disk(component, options, &st);
  if (!disk || !st.longest_loop_capped) return std::nullopt;
  if (stats) *stats = std::move(st);
  return disk;
}

}  // namespace tightex
