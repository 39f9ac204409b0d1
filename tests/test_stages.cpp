// Invariants after each pipeline stage, over the catalogue of meshes generated in code
// (mesh_catalogue.hpp): prepare_surface, split_components, cut_to_disk (both hole modes),
// map_to_square, the whole optimize() pipeline, and the two layouts.
//
// Every check recomputes the property from the stage's output (topology counted independently of
// topology_of, UV areas summed independently of count_folds, tilings painted texel by texel), so a
// stage that breaks its contract fails here even when its own statistics claim success.
#include <dlfcn.h>
#include <gtest/gtest-spi.h>  // ScopedFakeTestPartResultReporter: the checkers' own test
#include <gtest/gtest.h>
#include <Eigen/SVD>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <numeric>
#include <random>
#include <set>
#include <thread>

#include "core/eigen_vector.hpp"
#include "core/error.hpp"
#include "core/statistics.hpp"
#include "cut/cut.hpp"
#include "layout/layout.hpp"
#include "mesh_catalogue.hpp"
#include "param/param.hpp"
#include "param/sparse_cholesky.hpp"
#include "pipeline/plan_state.hpp"
#include "prepare/components.hpp"
#include "prepare/repair.hpp"
#include "report/metrics.hpp"
#include "report/report.hpp"
#include "run/budget_search.hpp"
#include "tightex/tightex.hpp"

namespace tightex {
namespace {

namespace cat = tightex::testing;

// ---- what each catalogue entry should turn into ----

struct Expected {
  std::string name;
  std::function<TexturedMesh()> make;
  size_t components = 1;
  long euler = 0;                                        // of the whole prepared surface (sum over components)
  size_t boundary_loops = 0;                             // of the whole prepared surface
  std::multiset<std::pair<long, size_t>> per_component;  // (genus, boundary loops) of each component
  size_t zero_area = 0, duplicates = 0, non_manifold_edges = 0, inconsistent_edges = 0, sliced_vertices = 0;
  std::string cut_method;        // when set: CutStats::method expected for every component
  bool fills_rectangles = true;  // every component can fill its rectangle (not a lone triangle)
  bool closed = false;           // every component closed: orientation checked by enclosed volume
  double min_psnr = 30.0;        // surface PSNR (dB) the pipeline must reach on the gradient texture
};

const std::vector<Expected>& expectations() {
  static const std::vector<Expected> all = [] {
    std::vector<Expected> e;
    auto add = [&](std::string name, std::function<TexturedMesh()> make, long euler, size_t loops,
                   std::multiset<std::pair<long, size_t>> per) {
      Expected x;
      x.name = std::move(name);
      x.make = std::move(make);
      x.euler = euler;
      x.boundary_loops = loops;
      x.components = per.size();
      x.per_component = std::move(per);
      e.push_back(std::move(x));
      return &e.back();
    };
    add("disk", cat::disk, 1, 1, {{0, 1}});
    add("sphere", cat::sphere, 2, 0, {{0, 0}})->closed = true;
    add("open_cylinder", cat::open_cylinder, 0, 2, {{0, 2}});
    add("sphere_with_holes", cat::sphere_with_holes, 2 - cat::kSphereHoles, cat::kSphereHoles, {{0, cat::kSphereHoles}});
    add("torus", cat::torus, 0, 0, {{1, 0}})->closed = true;
    add("double_torus", cat::double_torus, -2, 0, {{2, 0}})->closed = true;
    {
      // A perforated plate: 25 real holes through it, not noise. Cutting all 25 handles and joining
      // the 50 loops into one boundary gives a comb-shaped disk that a map onto a square crowds badly
      // (about 17 dB). The floor guards against regressions and misplaced colours (a
      // mirrored result scores far lower), not the quality goal.
      auto* e = add("holey_slab", cat::holey_slab, 2 - 2 * cat::kSlabHandles, 0, {{cat::kSlabHandles, 0}});
      e->closed = true;
      e->min_psnr = 15.0;
    }
    add("bowtie", cat::bowtie, 2, 2, {{0, 1}, {0, 1}})->sliced_vertices = 1;
    {
      Expected* x = add("non_manifold_edge", cat::non_manifold_edge, 3, 3, {{0, 1}, {0, 1}, {0, 1}});
      x->non_manifold_edges = cat::kSpineSegments;
      x->sliced_vertices = cat::kSpineSegments + 1;
    }
    {
      Expected* x = add("degenerate_disk", cat::degenerate_disk, 1, 1, {{0, 1}});
      x->zero_area = cat::kAddedZeroArea;
      x->duplicates = cat::kAddedDuplicates;
    }
    add("obtuse_strip", cat::obtuse_strip, 1, 1, {{0, 1}});
    add("single_triangle", cat::single_triangle, 1, 1, {{0, 1}})->fills_rectangles = false;
    add("two_triangles", cat::two_triangles, 1, 1, {{0, 1}});
    add("multi_component", cat::multi_component, 3, 3, {{1, 0}, {0, 1}, {0, 1}, {0, 1}});
    add("cup", cat::cup, 1, 1, {{0, 1}})->cut_method = "disk+slit";
    {
      // Slicing the one inconsistent edge (2 vertices become 4) leaves an orientable strip: a disk.
      Expected* x = add("mobius_strip", cat::mobius_strip, 1, 1, {{0, 1}});
      x->inconsistent_edges = 1;
      x->sliced_vertices = 2;
    }
    {
      std::multiset<std::pair<long, size_t>> per{{0, 0}};
      for (int i = 0; i < cat::kFloaters; ++i) per.insert({0, 1});
      // Floaters are lone triangles: each leaves half of its (minimum-size) rectangle empty.
      add("sphere_with_floaters", cat::sphere_with_floaters, 2 + cat::kFloaters, cat::kFloaters, per)->fills_rectangles = false;
    }
    return e;
  }();
  return all;
}

const Expected& expected(const std::string& name) {
  for (const Expected& e : expectations())
    if (e.name == name) return e;
  throw std::runtime_error("no catalogue entry " + name);
}

std::vector<std::string> catalogue_names() {
  std::vector<std::string> names;
  for (const auto& [name, make] : cat::catalogue()) names.push_back(name);
  return names;
}

// ---- independent checks ----

bool same_bits(const Vec3& a, const Vec3& b) { return a.x() == b.x() && a.y() == b.y() && a.z() == b.z(); }

/// A manifold surface as surface.hpp defines it: opposite is a symmetric pairing of halfedges running
/// in opposite directions between the same two vertices, no undirected edge is used more than twice
/// (and when twice, the two halfedges are paired), and the corners around each vertex form a single
/// fan with at most one outgoing boundary halfedge.
::testing::AssertionResult is_manifold(const Surface& s) {
  const size_t nf = s.num_faces(), nv = s.num_vertices(), nh = 3 * nf;
  if (s.opposite.size() != nh)
    return ::testing::AssertionFailure() << "opposite has " << s.opposite.size() << " entries for " << nf << " faces";
  if (s.positions.size() != nv) return ::testing::AssertionFailure() << "positions";
  for (uint32_t t = 0; t < nf; ++t) {
    const Tri& f = s.triangles[t];
    for (uint32_t v : f)
      if (v >= nv) return ::testing::AssertionFailure() << "triangle " << t << " uses vertex " << v << " of " << nv;
    if (f[0] == f[1] || f[1] == f[2] || f[2] == f[0]) return ::testing::AssertionFailure() << "triangle " << t << " repeats a vertex";
  }
  for (uint32_t h = 0; h < nh; ++h) {
    const uint32_t o = s.opposite[h];
    if (o == kNone) continue;
    if (o >= nh || s.opposite[o] != h || o / 3 == h / 3 || s.from(o) != s.to(h) || s.to(o) != s.from(h))
      return ::testing::AssertionFailure() << "halfedge " << h << " (" << s.from(h) << "->" << s.to(h) << ") has a bad opposite " << o;
  }
  std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>> edge_use;
  for (uint32_t h = 0; h < nh; ++h) edge_use[{std::min(s.from(h), s.to(h)), std::max(s.from(h), s.to(h))}].push_back(h);
  for (const auto& [edge, hs] : edge_use) {
    if (hs.size() > 2)
      return ::testing::AssertionFailure() << "edge (" << edge.first << ", " << edge.second << ") is used by " << hs.size() << " triangles";
    if (hs.size() == 2 && s.opposite[hs[0]] != hs[1])
      return ::testing::AssertionFailure() << "edge (" << edge.first << ", " << edge.second << ") is used twice but not paired";
  }
  // Fans: rotate around each vertex through its outgoing halfedges.
  std::vector<std::vector<uint32_t>> outgoing(nv);
  for (uint32_t h = 0; h < nh; ++h) outgoing[s.from(h)].push_back(h);
  for (uint32_t v = 0; v < nv; ++v) {
    if (outgoing[v].empty()) continue;
    size_t boundary_out = 0;
    for (uint32_t h : outgoing[v]) boundary_out += s.opposite[h] == kNone;
    if (boundary_out > 1)
      return ::testing::AssertionFailure() << "vertex " << v << " has " << boundary_out << " outgoing boundary halfedges";
    std::set<uint32_t> reached{outgoing[v][0]};
    for (uint32_t h = outgoing[v][0];;) {  // clockwise: h -> opposite(prev(h))
      const uint32_t o = s.opposite[Surface::prev(h)];
      if (o == kNone || !reached.insert(o).second) break;
      h = o;
    }
    for (uint32_t h = outgoing[v][0];;) {  // counter-clockwise: h -> next(opposite(h))
      const uint32_t o = s.opposite[h];
      if (o == kNone) break;
      const uint32_t n = Surface::next(o);
      if (!reached.insert(n).second) break;
      h = n;
    }
    if (reached.size() != outgoing[v].size())
      return ::testing::AssertionFailure() << "vertex " << v << " has " << outgoing[v].size() << " corners but its fan reaches "
                                           << reached.size();
  }
  return ::testing::AssertionSuccess();
}

struct Counts {
  long vertices = 0, edges = 0, faces = 0;
  size_t boundary_halfedges = 0;
  long euler() const { return vertices - edges + faces; }
};
/// V, E, F counted from vertex pairs (valid for a manifold surface), without topology_of.
Counts count(const Surface& s) {
  Counts c;
  std::set<uint32_t> used;
  std::set<std::pair<uint32_t, uint32_t>> edges;
  for (uint32_t h = 0; h < 3 * s.num_faces(); ++h) {
    used.insert(s.from(h));
    edges.insert({std::min(s.from(h), s.to(h)), std::max(s.from(h), s.to(h))});
    c.boundary_halfedges += s.opposite[h] == kNone;
  }
  c.vertices = long(used.size());
  c.edges = long(edges.size());
  c.faces = long(s.num_faces());
  return c;
}

/// (genus, boundary loops) of a connected manifold surface.
std::pair<long, size_t> genus_and_loops(const Surface& s) {
  const size_t loops = boundary_loops(s).size();
  return {(2 - count(s).euler() - long(loops)) / 2, loops};
}

/// Per input triangle: how many times prepare_surface must keep it (0 or 1), and the group of
/// triangles it is equal to (same welded vertices in the same cyclic order), computed from the input.
struct InputTriangles {
  std::vector<char> has_area;   // distinct welded vertices and non-zero 3D area
  std::vector<uint32_t> group;  // index of the first equal triangle with area
  size_t zero_area = 0, duplicates = 0;
};
InputTriangles classify(const TexturedMesh& m) {
  InputTriangles r;
  std::map<std::array<double, 3>, uint32_t> weld;
  std::vector<uint32_t> id(m.num_vertices());
  for (size_t v = 0; v < m.num_vertices(); ++v) {
    const Vec3& p = m.positions[v];
    id[v] = weld.try_emplace({p.x() + 0.0, p.y() + 0.0, p.z() + 0.0}, uint32_t(weld.size())).first->second;
  }
  std::map<std::array<uint32_t, 3>, uint32_t> first;
  r.has_area.assign(m.num_triangles(), 0);
  r.group.assign(m.num_triangles(), kNone);
  for (uint32_t t = 0; t < m.num_triangles(); ++t) {
    std::array<uint32_t, 3> f{id[m.triangles[t][0]], id[m.triangles[t][1]], id[m.triangles[t][2]]};
    const Vec3 &a = m.positions[m.triangles[t][0]], &b = m.positions[m.triangles[t][1]], &c = m.positions[m.triangles[t][2]];
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2] || (b - a).cross(c - a).norm() == 0.0) {
      ++r.zero_area;
      continue;
    }
    r.has_area[t] = 1;
    std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
    const auto [it, inserted] = first.try_emplace(f, t);
    r.group[t] = it->second;
    r.duplicates += !inserted;
  }
  return r;
}

/// The (x, y) coordinate that a point on side k of the unit square (0: bottom, 1: right, 2: top,
/// 3: left) has fixed, its value there, and the sign of "outward".
struct Side {
  int fixed_axis;
  double value;
  double outward;
  int along_axis;
  double along_sign;  // +1 when walking the side counter-clockwise increases the along coordinate
};
constexpr Side kSides[4] = {{1, 0.0, -1, 0, +1}, {0, 1.0, +1, 1, +1}, {1, 1.0, +1, 0, -1}, {0, 0.0, -1, 1, -1}};

// ---- the catalogue itself ----

class Catalogue : public ::testing::TestWithParam<std::string> {
 protected:
  const Expected& want() const { return expected(GetParam()); }
  TexturedMesh mesh() const { return want().make(); }
};

std::string param_name(const ::testing::TestParamInfo<std::string>& info) { return info.param; }

INSTANTIATE_TEST_SUITE_P(Meshes, Catalogue, ::testing::ValuesIn(catalogue_names()), param_name);

TEST(CatalogueList, EveryEntryHasExpectations) {
  for (const auto& name : catalogue_names()) EXPECT_NO_THROW(expected(name)) << name;
  EXPECT_EQ(catalogue_names().size(), expectations().size());
}

// The generators themselves: complete meshes, outward orientation, the properties their names promise.
TEST_P(Catalogue, GeneratorIsWellFormed) {
  const TexturedMesh m = mesh();
  EXPECT_EQ(m.source, GetParam());
  ASSERT_GT(m.num_triangles(), 0u);
  ASSERT_EQ(m.corner_uv.size(), 3 * m.num_triangles());
  ASSERT_EQ(m.face_material.size(), m.num_triangles());
  ASSERT_EQ(m.materials.size(), 1u);
  ASSERT_EQ(m.textures.size(), 1u);
  EXPECT_EQ(m.materials[0].texture, 0);
  EXPECT_FALSE(m.textures[0].image.empty());
  for (const Tri& f : m.triangles)
    for (uint32_t v : f) ASSERT_LT(v, m.num_vertices());
  for (const Vec2& uv : m.corner_uv) {
    EXPECT_GE(uv.minCoeff(), 0.0);
    EXPECT_LE(uv.maxCoeff(), 1.0);
  }
  for (int32_t mat : m.face_material) EXPECT_EQ(mat, 0);
  if (want().closed) {
    double volume = 0;  // divergence theorem: positive for outward-facing triangles
    for (const Tri& f : m.triangles) volume += m.positions[f[0]].dot(m.positions[f[1]].cross(m.positions[f[2]])) / 6;
    EXPECT_GT(volume, 0.0);
  }
  if (GetParam() == "obtuse_strip") {
    // Some interior edge must have a negative cotangent weight (cot of both opposite angles summed).
    std::map<std::pair<uint32_t, uint32_t>, double> weight;
    for (const Tri& f : m.triangles)
      for (int k = 0; k < 3; ++k) {
        const Vec3 &a = m.positions[f[k]], &b = m.positions[f[(k + 1) % 3]], &c = m.positions[f[(k + 2) % 3]];
        const Vec3 u = a - c, v = b - c;
        weight[{std::min(f[k], f[(k + 1) % 3]), std::max(f[k], f[(k + 1) % 3])}] += u.dot(v) / u.cross(v).norm();
      }
    size_t negative = 0;
    for (const auto& [e, w] : weight) negative += w < 0;
    EXPECT_GT(negative, 100u);
  }
}

// ---- 1. prepare_surface ----

TEST_P(Catalogue, PrepareSurface) {
  const TexturedMesh m = mesh();
  const Expected& e = want();
  RepairStats st;
  const Surface s = prepare_surface(m, &st);
  ASSERT_TRUE(is_manifold(s));
  EXPECT_EQ(st.reoriented_triangles, 0u) << "the catalogue's meshes are wound consistently (a Mobius strip as far as it can be)";
  ASSERT_EQ(s.input_face, s.face_parent);
  ASSERT_EQ(s.input_corner.size(), 3 * s.num_faces());
  ASSERT_EQ(s.face_parent.size(), s.num_faces());
  ASSERT_EQ(s.vertex_parent.size(), s.num_vertices());

  const Counts c = count(s);
  EXPECT_EQ(c.euler(), e.euler);
  const auto loops = boundary_loops(s);
  EXPECT_EQ(loops.size(), e.boundary_loops);
  size_t loop_halfedges = 0;
  for (const auto& l : loops) loop_halfedges += l.size();
  EXPECT_EQ(loop_halfedges, c.boundary_halfedges);
  const Topology topo = topology_of(s);
  EXPECT_EQ(topo.euler(), c.euler());
  EXPECT_EQ(topo.boundary_loops, loops.size());

  // Statistics: what the generator put in.
  const InputTriangles in = classify(m);
  EXPECT_EQ(in.zero_area, e.zero_area) << "catalogue";  // the generator did what it says
  EXPECT_EQ(in.duplicates, e.duplicates) << "catalogue";
  EXPECT_EQ(st.zero_area_triangles, e.zero_area);
  EXPECT_EQ(st.repeated_triangles, e.duplicates);
  EXPECT_EQ(st.non_manifold_edges, e.non_manifold_edges);
  EXPECT_EQ(st.inconsistent_edges, e.inconsistent_edges);
  EXPECT_EQ(st.sliced_vertices, e.sliced_vertices);
  EXPECT_EQ(st.input_vertices, m.num_vertices());

  // No triangle with area lost: of each group of equal triangles exactly one is kept, once, with the
  // input's corners in the input's order (as input_corner says); nothing without
  // area is kept.
  std::vector<size_t> kept(m.num_triangles(), 0);
  for (uint32_t t = 0; t < s.num_faces(); ++t) {
    const uint32_t p = s.face_parent[t];
    ASSERT_LT(p, m.num_triangles());
    kept[p]++;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = s.triangles[t][k];
      EXPECT_TRUE(same_bits(s.positions[v], m.positions[m.triangles[p][s.input_corner[3 * t + size_t(k)]]]))
          << "face " << t << " corner " << k;
    }
  }
  std::map<uint32_t, size_t> group_kept;
  for (uint32_t t = 0; t < m.num_triangles(); ++t) {
    if (!in.has_area[t]) {
      EXPECT_EQ(kept[t], 0u) << "zero-area input triangle " << t << " kept";
      continue;
    }
    EXPECT_LE(kept[t], 1u) << "input triangle " << t;
    group_kept[in.group[t]] += kept[t];
  }
  for (const auto& [g, n] : group_kept) EXPECT_EQ(n, 1u) << "triangle group of input triangle " << g;
  EXPECT_EQ(s.num_faces(), m.num_triangles() - e.zero_area - e.duplicates);
  for (uint32_t v = 0; v < s.num_vertices(); ++v) {
    ASSERT_LT(s.vertex_parent[v], m.num_vertices());
    EXPECT_TRUE(same_bits(s.positions[v], m.positions[s.vertex_parent[v]])) << "vertex " << v;
  }
}

// ---- 2. split_components ----

TEST_P(Catalogue, SplitComponents) {
  const Expected& e = want();
  const Surface s = prepare_surface(mesh(), nullptr);
  const std::vector<Surface> comps = split_components(s);
  ASSERT_EQ(comps.size(), e.components);
  std::vector<size_t> seen(s.num_faces(), 0);
  std::multiset<std::pair<long, size_t>> per;
  uint32_t previous_first = 0;
  size_t faces = 0;
  for (size_t ci = 0; ci < comps.size(); ++ci) {
    SCOPED_TRACE("component " + std::to_string(ci));
    const Surface& c = comps[ci];
    ASSERT_GT(c.num_faces(), 0u);
    faces += c.num_faces();
    ASSERT_TRUE(is_manifold(c));
    std::vector<uint32_t> label;
    EXPECT_EQ(face_components(c, label), 1u);
    ASSERT_EQ(c.face_parent.size(), c.num_faces());
    ASSERT_EQ(c.vertex_parent.size(), c.num_vertices());
    for (uint32_t t = 0; t < c.num_faces(); ++t) {
      const uint32_t p = c.face_parent[t];
      ASSERT_LT(p, s.num_faces());
      seen[p]++;
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(c.vertex_parent[c.triangles[t][k]], s.triangles[p][k]);
        // Adjacency carried over: same neighbour (mapped back), boundary stays boundary.
        const uint32_t o = c.opposite[3 * t + k], so = s.opposite[3 * p + k];
        if (o == kNone) {
          EXPECT_EQ(so, kNone);
        } else {
          EXPECT_EQ(so, 3 * c.face_parent[o / 3] + o % 3);
        }
      }
    }
    for (uint32_t v = 0; v < c.num_vertices(); ++v) EXPECT_TRUE(same_bits(c.positions[v], s.positions[c.vertex_parent[v]]));
    const uint32_t first = *std::min_element(c.face_parent.begin(), c.face_parent.end());
    if (ci > 0) EXPECT_GT(first, previous_first) << "components not ordered by first triangle";
    previous_first = first;
    per.insert(genus_and_loops(c));
  }
  EXPECT_EQ(faces, s.num_faces());
  for (uint32_t t = 0; t < s.num_faces(); ++t) EXPECT_EQ(seen[t], 1u) << "surface face " << t;
  EXPECT_EQ(per, e.per_component);
}

// ---- 3. cut_to_disk ----

/// Checks one disk against the component it was cut from.
void check_disk(const Surface& comp, const Disk& disk, HoleMode mode, const CutStats& st) {
  const Surface& d = disk.mesh;
  ASSERT_TRUE(is_manifold(d));
  ASSERT_EQ(d.face_parent.size(), d.num_faces());
  ASSERT_EQ(d.vertex_parent.size(), d.num_vertices());
  const auto loops = boundary_loops(d);
  EXPECT_EQ(loops.size(), 1u);
  EXPECT_EQ(count(d).euler(), 1);
  std::vector<uint32_t> label;
  EXPECT_EQ(face_components(d, label), 1u);

  // Faces: each component face exactly once, with its corners in order; the rest is scaffolding.
  std::vector<size_t> seen(comp.num_faces(), 0);
  size_t scaffolding = 0;
  for (uint32_t f = 0; f < d.num_faces(); ++f) {
    const uint32_t p = d.face_parent[f];
    if (p == kNone) {
      ++scaffolding;
      continue;
    }
    ASSERT_LT(p, comp.num_faces());
    seen[p]++;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = d.triangles[f][k];
      EXPECT_EQ(d.vertex_parent[v], comp.triangles[p][k]) << "disk face " << f << " corner " << k;
    }
  }
  for (uint32_t t = 0; t < comp.num_faces(); ++t) EXPECT_EQ(seen[t], 1u) << "component face " << t;
  for (uint32_t v = 0; v < d.num_vertices(); ++v) {
    if (d.vertex_parent[v] == kNone) continue;
    ASSERT_LT(d.vertex_parent[v], comp.num_vertices());
    EXPECT_TRUE(same_bits(d.positions[v], comp.positions[d.vertex_parent[v]]));
  }
  const auto comp_loops = boundary_loops(comp);
  const Counts cc = count(comp);
  const long genus = (2 - cc.euler() - long(comp_loops.size())) / 2;
  if (mode == HoleMode::kCut) {
    // Nothing is capped: every face and vertex of the disk comes from the component.
    EXPECT_EQ(scaffolding, 0u);
    EXPECT_EQ(st.holes_filled, 0u);
    for (uint32_t p : d.vertex_parent) EXPECT_NE(p, kNone);
  } else {
    // Caps (of holes and of cut handles) stay within the area budget, so they waste few texels.
    double comp_area = 0, cap_area = 0;
    for (const Tri& f : comp.triangles) comp_area += triangle_area(comp.positions[f[0]], comp.positions[f[1]], comp.positions[f[2]]);
    for (uint32_t f = 0; f < d.num_faces(); ++f)
      if (d.face_parent[f] == kNone)
        cap_area += triangle_area(d.positions[d.triangles[f][0]], d.positions[d.triangles[f][1]], d.positions[d.triangles[f][2]]);
    EXPECT_LE(cap_area, kFillBudget * comp_area * (1 + 1e-9));
    if (genus == 0) EXPECT_EQ(scaffolding > 0, st.holes_filled > 0);
  }
  // Every loop but the boundary's root is capped or joined (cut_to_disk's cap_kept: all of them).
  if (genus == 0 && !comp_loops.empty()) EXPECT_EQ(st.holes_filled + st.holes_cut, comp_loops.size() - (st.longest_loop_capped ? 0 : 1));
  // A component that already is a disk is used as is, unless it is deep (then slit open); anything
  // else must be cut.
  if (comp_loops.size() == 1 && cc.euler() == 1 && !st.longest_loop_capped) {
    if (st.method == "disk") {
      EXPECT_EQ(st.cut_edges, 0u);
      EXPECT_EQ(d.num_vertices(), comp.num_vertices());
    } else {
      EXPECT_EQ(st.method, "disk+slit");
      EXPECT_GT(st.cut_edges, 0u);
    }
  } else {
    EXPECT_GT(st.cut_edges, 0u);
  }
  // Without caps on a genus-0 surface, the boundary grows by both sides of every cut edge.
  if (genus == 0 && scaffolding == 0) EXPECT_EQ(count(d).boundary_halfedges, cc.boundary_halfedges + 2 * st.cut_edges);
  EXPECT_EQ(st.before.euler(), cc.euler());
  EXPECT_EQ(st.before.boundary_loops, comp_loops.size());

  // disk.boundary: a closed walk along the boundary halfedges, each once, in the faces' orientation.
  const auto& b = disk.boundary;
  ASSERT_GE(b.size(), 3u);
  EXPECT_EQ(b.size(), count(d).boundary_halfedges);
  std::map<std::pair<uint32_t, uint32_t>, size_t> boundary_he;
  for (uint32_t h = 0; h < 3 * d.num_faces(); ++h)
    if (d.opposite[h] == kNone) boundary_he[{d.from(h), d.to(h)}]++;
  std::set<uint32_t> distinct(b.begin(), b.end());
  EXPECT_EQ(distinct.size(), b.size()) << "a boundary vertex appears twice";
  for (size_t i = 0; i < b.size(); ++i) {
    const auto key = std::make_pair(b[i], b[(i + 1) % b.size()]);
    EXPECT_EQ(boundary_he.count(key), 1u) << "no boundary halfedge " << key.first << "->" << key.second;
  }
}

// A closed sphere with one triangle missing (pepper noise): its only hole, 3 edges, is the disk's
// boundary as it comes; with cap_kept it is capped too and the closed sphere gets the path cut. Both are
// disks holding every face once; beyond the cap budget the hole stays the boundary.
TEST(CutToDisk, ASmallLongestHoleIsCappedTooWhenAsked) {
  cat::Geometry g = cat::sphere_geometry();
  g.triangles.erase(g.triangles.begin() + std::ptrdiff_t(g.triangles.size() / 3));
  const std::vector<Surface> comps =
      split_components(prepare_surface(cat::make_textured("pepper_sphere", g.positions, g.triangles), nullptr));
  ASSERT_EQ(comps.size(), 1u);
  CutStats kept, capped, over;
  const Disk a = cut_to_disk(comps[0], {.holes = HoleMode::kFill}, &kept);
  check_disk(comps[0], a, HoleMode::kFill, kept);
  EXPECT_EQ(kept.longest_loop_edges, 3u);
  EXPECT_FALSE(kept.longest_loop_capped);
  EXPECT_EQ(kept.holes_filled, 0u);
  const Disk b = cut_to_disk(comps[0], {.holes = HoleMode::kFill, .fill_budget = kFillBudget, .cap_longest_loop = true}, &capped);
  check_disk(comps[0], b, HoleMode::kFill, capped);
  EXPECT_TRUE(capped.longest_loop_capped);
  EXPECT_EQ(capped.holes_filled, 1u);
  EXPECT_EQ(capped.longest_loop_edges, 3u);
  EXPECT_EQ(capped.method.rfind("path", 0), 0u) << capped.method;
  EXPECT_GT(b.mesh.num_faces(), a.mesh.num_faces());  // the cap
  const Disk c = cut_to_disk(comps[0], {.holes = HoleMode::kFill, .fill_budget = 0.0, .cap_longest_loop = true}, &over);
  check_disk(comps[0], c, HoleMode::kFill, over);
  EXPECT_FALSE(over.longest_loop_capped);
  EXPECT_EQ(over.longest_loop_edges, 3u);
  // Without kFill nothing is capped, whatever cap_kept says.
  CutStats cut;
  cut_to_disk(comps[0], {.holes = HoleMode::kCut, .fill_budget = kFillBudget, .cap_longest_loop = true}, &cut);
  EXPECT_FALSE(cut.longest_loop_capped);
  EXPECT_EQ(cut.holes_filled, 0u);
}

// The pipeline maps such a component both ways and keeps the one whose estimated colour error is lower;
// the report says what each was estimated to give. The paper's map keeps the paper's cut.
TEST(Pipeline, ASmallLongestHoleIsMappedBothWaysAndTheBetterKept) {
  cat::Geometry g = cat::sphere_geometry();
  g.triangles.erase(g.triangles.begin() + std::ptrdiff_t(g.triangles.size() / 3));
  const TexturedMesh in = cat::make_textured("pepper_sphere", g.positions, g.triangles, cat::checker_image(128, 128, 8));
  const Result r = optimize(in, Options{});
  const auto& comp = report_json(r.report)["components"].at(0);
  const auto& db = comp["longest_hole_kept_capped_estimated_psnr_db"];
  ASSERT_EQ(db.size(), 2u) << comp.dump();
  const bool capped = comp["longest_hole_capped"];
  EXPECT_EQ(capped, db[1].get<double>() > db[0].get<double>()) << db.dump();
  EXPECT_EQ(comp["longest_hole_edges"].get<size_t>(), 3u);
  EXPECT_EQ(report_json(r.report)["preparation"]["components_longest_hole_capped"].get<size_t>(), capped ? 1u : 0u);
  EXPECT_EQ(report_json(r.report)["metrics"]["flipped"].get<size_t>(), 0u);
  EXPECT_EQ(report_json(r.report)["metrics"]["charts"].get<size_t>(), 1u);
  EXPECT_EQ(report_json(r.report)["metrics"]["lost_triangles"].get<size_t>(), 0u);
  Options h;
  h.map = MapKind::kHarmonic;
  const Result rh = optimize(in, h);
  EXPECT_TRUE(report_json(rh.report)["components"].at(0)["longest_hole_kept_capped_estimated_psnr_db"].is_null());
  EXPECT_FALSE(report_json(rh.report)["components"].at(0)["longest_hole_capped"].get<bool>());
}

TEST_P(Catalogue, CutToDisk) {
  const std::vector<Surface> comps = split_components(prepare_surface(mesh(), nullptr));
  for (HoleMode mode : {HoleMode::kFill, HoleMode::kCut}) {
    for (size_t ci = 0; ci < comps.size(); ++ci) {
      SCOPED_TRACE(std::string(mode == HoleMode::kFill ? "kFill" : "kCut") + " component " + std::to_string(ci));
      CutStats st;
      Disk disk;
      try {
        disk = cut_to_disk(comps[ci], {.holes = mode}, &st);
      } catch (const std::exception& ex) {
        ADD_FAILURE() << "cut_to_disk threw: " << ex.what();
        continue;
      }
      check_disk(comps[ci], disk, mode, st);
      if (!want().cut_method.empty()) EXPECT_EQ(st.method, want().cut_method);
    }
  }
}

// ---- 4. map_to_square ----

/// Whether some boundary vertex of the map lies strictly inside the unit square.
bool inward_anywhere(const Disk& disk, const std::vector<Vec2>& uv) {
  constexpr double kEps = 1e-12;
  for (uint32_t v : disk.boundary)
    if (uv[v].x() > kEps && uv[v].x() < 1 - kEps && uv[v].y() > kEps && uv[v].y() < 1 - kEps) return true;
  return false;
}

/// Checks a map of `disk` onto the unit square made with `options`.
void check_square_map(const Disk& disk, const std::vector<Vec2>& uv, const SquareMapOptions& options, const SquareMapStats& st) {
  const Surface& d = disk.mesh;
  ASSERT_EQ(uv.size(), d.num_vertices());
  for (uint32_t v = 0; v < uv.size(); ++v) ASSERT_TRUE(uv[v].allFinite()) << "vertex " << v;
  const auto& b = disk.boundary;
  const size_t nb = b.size();
  const double bump = options.bump_texels / double(std::max(1, std::min(options.rect_width, options.rect_height) - 1));
  constexpr double kEps = 1e-12;

  // Corners.
  static const Vec2 kCorner[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  std::array<size_t, 4> at{};
  for (int k = 0; k < 4; ++k) {
    const auto it = std::find(b.begin(), b.end(), st.corners[k]);
    ASSERT_NE(it, b.end()) << "corner " << k << " is not a boundary vertex";
    at[k] = size_t(it - b.begin());
  }
  if (nb == 3) {
    // A lone triangle cannot have four corners: three of them, the last repeated.
    EXPECT_EQ(st.corners[3], st.corners[2]);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(uv[st.corners[k]], kCorner[k]) << "corner " << k;
  } else {
    for (int k = 0; k < 4; ++k) EXPECT_EQ(uv[st.corners[k]], kCorner[k]) << "corner " << k;
    // Corners in counter-clockwise boundary order, distinct.
    for (int k = 1; k < 4; ++k) EXPECT_GT((at[k] + nb - at[0]) % nb, (at[k - 1] + nb - at[0]) % nb) << "corner " << k;

    // Each side: its vertices on that side of the square (or lifted outward by at most the bump; a
    // density map's bumps and their chords' ends may have moved inwards), moving monotonically along it.
    size_t off_side = 0, inward = 0;
    for (int k = 0; k < 4; ++k) {
      const Side& side = kSides[k];
      const size_t len = (at[(k + 1) % 4] + nb - at[k]) % nb;
      double last_along = -1e300;
      for (size_t j = 0; j <= len; ++j) {
        const Vec2& p = uv[b[(at[k] + j) % nb]];
        const double off = (p[side.fixed_axis] - side.value) * side.outward;  // > 0: outside
        const double along = p[side.along_axis] * side.along_sign;
        if (off < -kEps && j > 0 && j < len) ++inward;
        EXPECT_TRUE(off >= -kEps || (!options.face_target.empty() && j > 0 && j < len))
            << "side " << k << " vertex " << j << " at (" << p.x() << ", " << p.y() << ") is inside";
        EXPECT_LE(off, bump + kEps) << "side " << k << " vertex " << j << " beyond the bump";
        if (off > kEps && j > 0 && j < len) ++off_side;
        EXPECT_GE(p[side.along_axis], -kEps);
        EXPECT_LE(p[side.along_axis], 1 + kEps);
        if (j > 0) EXPECT_GT(along, last_along) << "side " << k << " vertex " << j << " goes backwards";
        last_along = along;
      }
    }
    EXPECT_LE(off_side, st.bumped_vertices) << "boundary vertices off the square that were not bumped";
    // A bump's vertices and the two ends of its chords.
    EXPECT_LE(inward, 3 * st.bumped_vertices) << "boundary vertices inside the square that were neither bumped nor a chord's end";
  }
  // Interior strictly inside: inside the unit square, or, next to a bump (whose bulge interior
  // vertices may follow), strictly inside the square grown by the bump height.
  std::vector<char> on_boundary(d.num_vertices(), 0);
  for (uint32_t v : b) on_boundary[v] = 1;
  std::set<uint32_t> used;
  for (const Tri& f : d.triangles) used.insert(f.begin(), f.end());
  const double margin = st.bumped_vertices > 0 ? bump : 0.0;
  for (uint32_t v : used)
    if (!on_boundary[v])
      EXPECT_TRUE(uv[v].x() > -margin && uv[v].x() < 1 + margin && uv[v].y() > -margin && uv[v].y() < 1 + margin)
          << "interior vertex " << v << " at (" << uv[v].x() << ", " << uv[v].y() << ")";

  // No fold, and the triangles cover the boundary polygon exactly once (total area = polygon area):
  // with every triangle positive, that makes the map a bijection onto the polygon.
  size_t folds = 0;
  double area = 0;
  for (const Tri& f : d.triangles) {
    const double a = signed_area(uv[f[0]], uv[f[1]], uv[f[2]]);
    folds += !(a > 0);
    area += a;
  }
  EXPECT_EQ(folds, 0u);
  EXPECT_EQ(count_folds(d, uv), folds);
  EXPECT_EQ(st.flipped, 0u);
  double polygon = 0;
  for (size_t i = 0; i < nb; ++i) {
    const Vec2 &p = uv[b[i]], &q = uv[b[(i + 1) % nb]];
    polygon += 0.5 * (p.x() * q.y() - q.x() * p.y());
  }
  EXPECT_NEAR(area, polygon, 1e-9);
  if (nb == 3) {
    EXPECT_NEAR(polygon, 0.5, 1e-12);
  } else {
    // Where bumps moved inwards, the notches beside them leave a little of the square empty.
    EXPECT_GE(polygon, 1 - 1e-12 - (inward_anywhere(disk, uv) ? 0.05 : 0.0));
    EXPECT_LE(polygon, 1 + 4 * bump);
  }
  EXPECT_FALSE(st.weights.empty());
}

TEST_P(Catalogue, MapToSquare) {
  const std::vector<Surface> comps = split_components(prepare_surface(mesh(), nullptr));
  SquareMapOptions options;
  options.rect_width = options.rect_height = 256;
  size_t negative = 0;
  for (HoleMode mode : {HoleMode::kFill, HoleMode::kCut}) {
    for (size_t ci = 0; ci < comps.size(); ++ci) {
      SCOPED_TRACE(std::string(mode == HoleMode::kFill ? "kFill" : "kCut") + " component " + std::to_string(ci));
      const Disk disk = cut_to_disk(comps[ci], {.holes = mode}, nullptr);
      SquareMapStats st;
      const auto uv = map_to_square(disk, options, &st);
      check_square_map(disk, uv, options, st);
      negative += st.negative_weights;
    }
  }
  if (GetParam() == "obtuse_strip") EXPECT_GT(negative, 0u) << "the obtuse mesh must exercise negative weights";
}

/// Area-weighted P5 and P95 of log2(UV area / target) over the faces that have a parent (not scaffolding),
/// the targets scaled to the same total as the areas.
std::pair<double, double> density_error(const Disk& disk, const std::vector<Vec2>& uv, const std::vector<double>& target) {
  const Surface& m = disk.mesh;
  double total = 0, sum_t = 0;
  for (size_t f = 0; f < m.num_faces(); ++f)
    if (m.face_parent[f] != kNone)
      total += signed_area(uv[m.triangles[f][0]], uv[m.triangles[f][1]], uv[m.triangles[f][2]]), sum_t += target[f];
  std::vector<std::pair<double, double>> vw;
  for (size_t f = 0; f < m.num_faces(); ++f)
    if (m.face_parent[f] != kNone)
      vw.push_back(
          {std::log2(signed_area(uv[m.triangles[f][0]], uv[m.triangles[f][1]], uv[m.triangles[f][2]]) / (target[f] * total / sum_t)),
           target[f]});
  std::sort(vw.begin(), vw.end());
  auto q = [&](double p) {
    double acc = 0;
    for (const auto& [v, w] : vw)
      if ((acc += w) >= p * sum_t) return v;
    return vw.back().first;
  };
  return {q(0.05), q(0.95)};
}

// The area map: fold-free, fills the square like the harmonic map, and spreads texels evenly: the
// density of 90% of the surface within a factor 2 of the mean, never worse than the harmonic map's.
// Also with larger hole caps than the default (fill_budget 2%): other holes stay open, and the holey
// slab's boundary then has bumps that a vertex sliding along the side could pass, turning the boundary
// back on itself (check_square_map's order check) unless the bumps' neighbours are held.
TEST_P(Catalogue, AreaMapEvensTheDensity) {
  const std::vector<Surface> comps = split_components(prepare_surface(mesh(), nullptr));
  for (size_t cb = 0; cb < 2 * comps.size(); ++cb) {
    const size_t ci = cb % comps.size();
    const double budget = cb < comps.size() ? kFillBudget : 0.02;
    SCOPED_TRACE("component " + std::to_string(ci) + ", cap budget " + std::to_string(budget));
    const Disk disk = cut_to_disk(comps[ci], {.holes = HoleMode::kFill, .fill_budget = budget}, nullptr);
    if (disk.mesh.num_faces() < 8) continue;  // a few triangles: nothing to even out
    SquareMapOptions options;
    options.rect_width = options.rect_height = 256;
    std::vector<double> area3(disk.mesh.num_faces());
    for (size_t f = 0; f < area3.size(); ++f) {
      const Tri& t = disk.mesh.triangles[f];
      area3[f] = triangle_area(disk.mesh.positions[t[0]], disk.mesh.positions[t[1]], disk.mesh.positions[t[2]]) *
                 (disk.mesh.face_parent[f] == kNone ? 0.25 : 1.0);
    }
    SquareMapStats hs, st;
    const auto harmonic = map_to_square(disk, options, &hs);
    options.face_target = area3;
    options.density_flow = true;  // as the pipeline's area map
    const auto uv = map_to_square(disk, options, &st);
    check_square_map(disk, uv, options, st);
    const auto [h5, h95] = density_error(disk, harmonic, area3);
    const auto [p5, p95] = density_error(disk, uv, area3);
    const double harmonic_spread = std::max(-h5, h95), spread = std::max(-p5, p95);
    EXPECT_LE(spread, std::max(1.0, harmonic_spread + 0.05))
        << "harmonic P5/P95 " << h5 << "/" << h95 << ", area " << p5 << "/" << p95 << " (" << st.iterations << " iterations, " << st.stopped
        << ", before " << st.spread_before_p5 << "/" << st.spread_before_p95 << ", refine " << st.refine_iterations << " "
        << st.refine_stopped << ", rounds " << st.correction_rounds << ")";
    // A strip whose vertices all lie on its boundary (the Mobius strip's) can only slide them along the
    // sides; it is not held to the improvement.
    const size_t interior = disk.mesh.num_vertices() - disk.boundary.size();
    if (harmonic_spread > 1.5 && 2 * interior >= disk.mesh.num_vertices())
      EXPECT_LT(spread, harmonic_spread - 0.5) << "the area map must improve on a crowded harmonic map"
                                               << " (" << st.iterations << " iterations, " << st.stopped << ", before "
                                               << st.spread_before_p5 << "/" << st.spread_before_p95 << ", faces " << disk.mesh.num_faces()
                                               << ")";
  }
}

// The residual check every map solve passes (SparseCholesky::solves): a sound factorisation's solution
// passes, simplicial or supernodal, on a badly scaled system; one off by 1% (a broken factorisation
// gives worse) does not, nor does zero.
TEST(SparseCholesky, ResidualCheckAcceptsTheSolutionAndRejectsAWrongOne) {
  const int n = 3000;
  std::vector<Eigen::Triplet<double>> trips;
  auto scale = [](int i) { return std::pow(10.0, (i % 7) - 3); };  // entries from 1e-3 to 1e3
  for (int i = 0; i < n; ++i) {
    trips.emplace_back(i, i, 2.5 * scale(i));  // diagonally dominant: positive definite
    if (i > 0) trips.emplace_back(i, i - 1, -std::min(scale(i), scale(i - 1)));
  }
  SparseCholesky::Matrix a(n, n);
  a.setFromTriplets(trips.begin(), trips.end());
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) b(i) = std::sin(0.01 * i) + 0.5;
  for (long from : {1L << 40, 0L}) {
    SCOPED_TRACE(from == 0 ? "supernodal" : "simplicial");
    SparseCholesky solver(from);
    solver.analyzePattern(a);
    ASSERT_TRUE(solver.factorize(a));
    EXPECT_EQ(solver.supernodal(), from == 0);
    Eigen::VectorXd x;
    ASSERT_TRUE(solver.solve(a, b, x));
    EXPECT_TRUE(SparseCholesky::solves(a, x, b));
    Eigen::VectorXd wrong = x;
    for (int i = 0; i < n; ++i) wrong(i) *= 1 + 0.01 * std::sin(1.7 * i);  // off by up to 1%
    EXPECT_FALSE(SparseCholesky::solves(a, wrong, b));
    EXPECT_FALSE(SparseCholesky::solves(a, Eigen::VectorXd::Zero(n), b));
  }
}

// The weighted quantile by selection is the one read off the sorted pairs: integer weights (sums exact
// in any order, so the answers must be equal), with zero weights and repeated values, at quantiles
// that fall on a cumulative weight exactly and between.
TEST(Statistics, WeightedQuantileBySelectionIsTheSortedOne) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const size_t n = 1 + rng() % 400;
    std::vector<std::pair<double, double>> pairs(n);
    for (auto& [v, w] : pairs) v = double(rng() % 50) - 20, w = double(rng() % 4);
    std::vector<std::pair<double, double>> sorted = pairs;
    std::sort(sorted.begin(), sorted.end());
    double total = 0;
    for (const auto& [v, w] : sorted) total += w;
    for (double q : {0.0, 0.05, 0.25, 0.5, 0.95, 1.0}) {
      double expected = sorted.back().first, acc = 0;
      for (const auto& [v, w] : sorted)
        if ((acc += w) >= q * total) {
          expected = v;
          break;
        }
      std::vector<std::pair<double, double>> scratch = pairs;
      EXPECT_EQ(weighted_quantile(scratch, q), expected) << "n " << n << ", q " << q;
    }
  }
  std::vector<std::pair<double, double>> none;
  EXPECT_EQ(weighted_quantile(none, 0.5), 0.0);
}

// A supernodal factor of more than 4M entries gets its storage allocated and written on every core
// before its first factorisation (OrderedCholmod::allocate_supernodal_factor); CHOLMOD factorises
// into it: the solves pass the residual check, again after the values change (the storage reused).
TEST(SparseCholesky, ALargeFactorAllocatedAheadSolves) {
  const int side = 420, n = side * side;  // a grid's Laplacian plus a small shift
  auto at = [&](int i, int j) { return i * side + j; };
  std::vector<Eigen::Triplet<double>> trips;
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      trips.emplace_back(at(i, j), at(i, j), 4.01);
      if (i > 0) trips.emplace_back(at(i, j), at(i - 1, j), -1.0);
      if (j > 0) trips.emplace_back(at(i, j), at(i, j - 1), -1.0);
    }
  SparseCholesky::Matrix a(n, n);
  a.setFromTriplets(trips.begin(), trips.end());
  Eigen::VectorXd b(n);
  for (int k = 0; k < n; ++k) b(k) = std::sin(0.001 * k);
  SparseCholesky solver(0);
  solver.analyzePattern(a);
  ASSERT_TRUE(solver.supernodal());
  ASSERT_GE(solver.factor_entries(), double(1 << 22));
  for (double diagonal : {4.01, 5.0}) {
    SCOPED_TRACE(diagonal);
    for (int k = 0; k < n; ++k) a.coeffRef(k, k) = diagonal;
    ASSERT_TRUE(solver.factorize(a));
    Eigen::VectorXd x;
    ASSERT_TRUE(solver.solve(a, b, x));
    EXPECT_TRUE(SparseCholesky::solves(a, x, b));
  }
}

// An analysis that fails (here an order that is not a permutation) leaves no factor: factorize()
// says so instead of handing CHOLMOD a missing one, simplicial or supernodal.
TEST(SparseCholesky, AFailedAnalysisFailsTheFactorisationWithoutCrashing) {
  const int n = 200;
  std::vector<Eigen::Triplet<double>> trips;
  for (int i = 0; i < n; ++i) {
    trips.emplace_back(i, i, 4.0);
    if (i > 0) trips.emplace_back(i, i - 1, -1.0);
  }
  SparseCholesky::Matrix a(n, n);
  a.setFromTriplets(trips.begin(), trips.end());
  const std::vector<int> not_a_permutation(size_t(n), 0);
  for (long from : {1L << 40, 0L}) {
    SCOPED_TRACE(from == 0 ? "supernodal" : "simplicial");
    SparseCholesky solver(from);
    solver.analyzePattern(a, &not_a_permutation);
    EXPECT_FALSE(solver.factorize(a));
    solver.analyzePattern(a);  // analysed again, in CHOLMOD's order: it factorises
    EXPECT_TRUE(solver.factorize(a));
  }
}

extern "C" void GOMP_parallel(void (*body)(void*), void* data, unsigned num_threads, unsigned flags);

// The OpenMP regions CHOLMOD opens: on a thread set for serial dense kernels the region's body runs
// once, on that thread, without libgomp opening a region (its nesting level stays 0; libgomp's own
// region of one thread would count a level); on any other thread libgomp still opens the team asked for.
TEST(SparseCholesky, OpenMpRegionsRunOnTheCallingThreadOnlyWhereTeamsAreOff) {
  using Level = int (*)();
  const auto omp_level = reinterpret_cast<Level>(dlsym(RTLD_DEFAULT, "omp_get_level"));
  ASSERT_NE(omp_level, nullptr) << "libgomp is loaded with CHOLMOD";
  struct Calls {
    Level level;
    std::mutex mutex;
    std::set<std::thread::id> threads;
    std::set<int> levels;
    int count = 0;
  };
  const auto body = [](void* data) {
    auto& calls = *static_cast<Calls*>(data);
    const std::lock_guard lock(calls.mutex);
    calls.threads.insert(std::this_thread::get_id());
    calls.levels.insert(calls.level());
    ++calls.count;
  };
  std::thread([&] {
    use_serial_dense_kernels();
    Calls calls{omp_level};
    GOMP_parallel(body, &calls, 2, 0);
    EXPECT_EQ(calls.count, 1);
    EXPECT_EQ(calls.threads, std::set<std::thread::id>{std::this_thread::get_id()});
    EXPECT_EQ(calls.levels, std::set<int>{0});
  }).join();
  std::thread([&] {
    Calls calls{omp_level};
    GOMP_parallel(body, &calls, 2, 0);
    EXPECT_EQ(calls.count, 2);
    EXPECT_EQ(calls.threads.size(), 2u);
    EXPECT_EQ(calls.levels, std::set<int>{1});
  }).join();
}

// METIS (which finds the nested dissection) draws from the C library's rand(), one sequence for the
// process: orders found on two threads at once are each the order found alone (metis_mutex), so a
// model whose pieces are mapped side by side gives the same output every run.
TEST(SparseCholesky, NestedDissectionOrdersFoundAtOnceAreEachTheOrderFoundAlone) {
  const auto g = testing::param_grid(160, 120, false, false, [](int i, int j) { return Vec3(i, j, 0.1 * std::sin(0.3 * i)); });
  const Surface m = split_components(prepare_surface(testing::make_textured("sheet", g.positions, g.triangles), nullptr)).at(0);
  const std::vector<int> alone = nested_dissection_order(m);
  ASSERT_EQ(alone.size(), m.num_vertices());
  std::atomic<int> differing{0};
  auto find_orders = [&] {
    for (int k = 0; k < 6; ++k)
      if (nested_dissection_order(m) != alone) ++differing;
  };
  std::thread other(find_orders);
  find_orders();
  other.join();
  EXPECT_EQ(differing.load(), 0);
}

// One fill-reducing order of a mesh's vertices (nested dissection) serves every system over them:
// it is a permutation of the vertices, and restricted to a Laplacian's unknowns (boundary held) the
// factorisation in that order solves the system as CHOLMOD's own order does.
TEST(SparseCholesky, AMeshsNestedDissectionOrderSolvesItsLaplacianAsCholmodsOwn) {
  const auto g = testing::param_grid(90, 70, false, false, [](int i, int j) { return Vec3(i, j, 0.1 * std::sin(0.3 * i)); });
  const auto comps = split_components(prepare_surface(testing::make_textured("sheet", g.positions, g.triangles), nullptr));
  ASSERT_EQ(comps.size(), 1u);
  const Disk disk = cut_to_disk(comps[0], {.holes = HoleMode::kFill}, nullptr);
  const Surface& m = disk.mesh;
  const std::vector<int> order = nested_dissection_order(m);
  ASSERT_EQ(order.size(), m.num_vertices());
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (size_t k = 0; k < sorted.size(); ++k) ASSERT_EQ(sorted[k], int(k));
  // The Laplacian of the interior (uniform weights), its unknowns numbered in the mesh's order.
  const std::vector<char> on_boundary = boundary_mask(m.num_vertices(), disk.boundary);
  std::vector<int> unknown(m.num_vertices(), -1);
  int n = 0;
  for (size_t v = 0; v < m.num_vertices(); ++v)
    if (!on_boundary[v]) unknown[v] = n++;
  std::vector<Eigen::Triplet<double>> trips;
  Eigen::VectorXd diag = Eigen::VectorXd::Zero(n), b = Eigen::VectorXd::Zero(n);
  for (uint32_t h = 0; h < m.opposite.size(); ++h) {
    if (m.opposite[h] != kNone && m.opposite[h] < h) continue;
    const int a = unknown[m.from(h)], c = unknown[m.to(h)];
    if (a >= 0) diag(a) += 1, b(a) += m.positions[m.to(h)].x();
    if (c >= 0) diag(c) += 1, b(c) += m.positions[m.from(h)].x();
    if (a >= 0 && c >= 0)
      trips.emplace_back(std::max(a, c), std::min(a, c), -1.0), b(a) -= m.positions[m.to(h)].x(), b(c) -= m.positions[m.from(h)].x();
  }
  for (int i = 0; i < n; ++i) trips.emplace_back(i, i, diag(i));
  SparseCholesky::Matrix a(n, n);
  a.setFromTriplets(trips.begin(), trips.end());
  const std::vector<int> restricted = order_of_unknowns(order, unknown, 1);
  ASSERT_EQ(restricted.size(), size_t(n));
  Eigen::VectorXd own, given;
  for (const std::vector<int>* o : {static_cast<const std::vector<int>*>(nullptr), &restricted}) {
    SparseCholesky solver;
    solver.analyzePattern(a, o);
    ASSERT_TRUE(solver.factorize(a));
    ASSERT_TRUE(solver.solve(a, b, o ? given : own));
  }
  EXPECT_LT((given - own).norm(), 1e-9 * own.norm());
  // Supernodal, the system copied into the factor's order once: the same solution, for one right-hand
  // side and two, and again after the values change (the copy's values follow a's).
  SparseCholesky supernodal(0);
  supernodal.analyzePattern(a, &restricted);
  ASSERT_TRUE(supernodal.factorises_permuted_copy());
  ASSERT_TRUE(supernodal.factorize(a));
  Eigen::VectorXd x;
  ASSERT_TRUE(supernodal.solve(a, b, x));
  EXPECT_LT((x - own).norm(), 1e-9 * own.norm());
  Eigen::MatrixX2d b2(n, 2), x2;
  b2 << b, 2 * b;
  ASSERT_TRUE(supernodal.solve(a, b2, x2));
  EXPECT_LT((x2.col(1) - 2 * own).norm(), 1e-9 * own.norm());
  SparseCholesky::Matrix doubled = 2 * a;
  ASSERT_TRUE(supernodal.factorize(doubled));
  ASSERT_TRUE(supernodal.solve(doubled, b, x));
  EXPECT_LT((2 * x - own).norm(), 1e-9 * own.norm());
}

/// The one component of the generated surface `g` cut to a disk, its holes capped.
Disk one_disk(const testing::Geometry& g, const std::string& name) {
  const auto comps = split_components(prepare_surface(testing::make_textured(name, g.positions, g.triangles), nullptr));
  EXPECT_EQ(comps.size(), 1u);
  return cut_to_disk(comps.at(0), {.holes = HoleMode::kFill}, nullptr);
}

// Large systems are factorised supernodally (BLAS kernels), small ones simplicially; components are
// mapped in parallel. Here the supernodal path is forced on a small sheet, mapped by four threads at
// once: every result must be fold-free and the same map as the simplicial one (a BLAS that is not
// safe for concurrent calls, without the lock in SparseCholesky, gave garbage and folds).
TEST(MapToSquare, SupernodalMatchesSimplicialWhenComponentsRunConcurrently) {
  const auto g = testing::param_grid(48, 40, false, false, [](int i, int j) {
    const double x = i / 47.0, y = j / 39.0;
    return Vec3(x, 0.8 * y, 0.15 * std::sin(6 * x) * std::cos(5 * y) + 0.3 * x * x);
  });
  const Disk disk = one_disk(g, "sheet");
  SquareMapOptions options;
  options.rect_width = options.rect_height = 256;
  options.face_target.resize(disk.mesh.num_faces());
  for (size_t f = 0; f < disk.mesh.num_faces(); ++f) {
    const Tri& t = disk.mesh.triangles[f];
    // Denser towards one corner: the reweighting and the symmetric Dirichlet steps both have work.
    const Vec3 c = (disk.mesh.positions[t[0]] + disk.mesh.positions[t[1]] + disk.mesh.positions[t[2]]) / 3.0;
    options.face_target[f] =
        triangle_area(disk.mesh.positions[t[0]], disk.mesh.positions[t[1]], disk.mesh.positions[t[2]]) * (1 + 3 * c.x() * c.y());
  }
  options.refine_keeps_density = false;  // the detail map's steps: all of them run (Newton's first widens the density here)
  options.supernodal_from = 1L << 40;    // simplicial everywhere
  SquareMapStats ref_stats;
  const auto reference = map_to_square(disk, options, &ref_stats);
  ASSERT_EQ(ref_stats.flipped, 0u);
  ASSERT_GT(ref_stats.refine_iterations, 0) << "the symmetric Dirichlet steps must run";
  options.supernodal_from = 0;  // supernodal everywhere
  std::vector<std::vector<Vec2>> uv(4);
  std::vector<SquareMapStats> stats(4);
  std::vector<std::thread> threads;
  for (size_t k = 0; k < uv.size(); ++k) threads.emplace_back([&, k] { uv[k] = map_to_square(disk, options, &stats[k]); });
  for (auto& t : threads) t.join();
  for (size_t k = 0; k < uv.size(); ++k) {
    SCOPED_TRACE("thread " + std::to_string(k));
    check_square_map(disk, uv[k], options, stats[k]);
    EXPECT_EQ(stats[k].refine_iterations, ref_stats.refine_iterations);
    double worst = 0;
    for (size_t v = 0; v < uv[k].size(); ++v) worst = std::max(worst, (uv[k][v] - reference[v]).norm());
    EXPECT_LT(worst, 1e-6) << "the supernodal map must be the simplicial one up to rounding";
  }
}

// A bump is sized in texels of the rectangle: a narrow rectangle gets a larger bump along its short
// side; the map must stay valid for any rectangle shape.
// A map is written as texture coordinates in its rectangle: a triangle whose area is within what that
// rounding can move is as good as folded (the paper's map crowded meshroom_esp32cam, with six patches
// of its surface missing, to triangles of 1e-14 texels, and 3 came out folded). A small but clean
// triangle is not.
TEST(MapToSquare, CollapsedTrianglesAreThoseRoundingCanFold) {
  Surface s;
  s.positions.assign(9, Vec3::Zero());
  s.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}};
  SquareMapOptions o;
  o.rect_width = o.rect_height = 1024;
  const double y = 0.000527425151;
  std::vector<Vec2> uv = {{0.1, 0.1},   {0.1 + 1e-6, 0.1}, {0.1, 0.1 + 1e-6},      // 5e-7 texels: clean
                          {0.3, 0.3},   {0.6, 0.3},        {0.3, 0.6},             // large: clean
                          {0.37331, y}, {0.37466, y},      {0.37354, y + 1e-17}};  // 1e-14 texels
  uint32_t worst = kNone;
  EXPECT_EQ(count_collapsed(s, uv, o, &worst), 1u);
  EXPECT_EQ(worst, 6u);
  EXPECT_EQ(count_folds(s, uv), 0u) << "positive in double precision: only the rounding test sees it";
  o.texel_extent = 1e12;  // the same triangles 1e12 texels out: the small one is not safe there
  EXPECT_EQ(count_collapsed(s, uv, o), 2u);
  std::swap(uv[1], uv[2]);  // folded counts too
  o.texel_extent = 0;
  EXPECT_EQ(count_collapsed(s, uv, o), 2u);
}

// The pipeline never writes a collapsed triangle with the paper's map either: it slits to the crowded
// region, and where that does not help, the component gets the area map (and the report says so). The
// holey slab cut open with the turning-angle corners crowds 35 triangles below 2e-12 texels.
TEST(Pipeline, HarmonicMapNeverWritesACollapsedTriangle) {
  Options opt;
  opt.size = 256;
  opt.map = MapKind::kHarmonic;
  opt.holes = HoleMode::kCut;
  opt.corners = CornerRule::kTurningAngle;
  const Result r = optimize(cat::holey_slab(), opt);
  EXPECT_EQ(report_json(r.report)["metrics"]["flipped"], 0);
  EXPECT_EQ(report_json(r.report)["metrics"]["degenerate"], 0);
  const auto& c = report_json(r.report)["components"][0];
  EXPECT_TRUE(c["slits"].get<int>() > 0 || c["fallback"].get<std::string>().find("area map") != std::string::npos) << c.dump();
}

// Holes are capped within 2% of the area while the caps take at most 0.8% of the square, else with a
// budget cut down to fit (never below kFillBudget). A torus with every 100th triangle missing (93 holes
// beside its handle): at the old 0.5% budget 30 of them were opened and the map failed (the plain
// fallback's cut: 44.3 dB); at 2% all 91 capped take 0.83% of the square, so the budget comes down to
// keep 85 of them capped and the square >= 99% used (57.5 dB).
TEST(Pipeline, CapBudgetKeepsTheSquareUsed) {
  testing::Geometry g = testing::torus_geometry(96, 48);
  std::vector<Tri> kept;
  std::vector<char> gone(g.positions.size(), 0);
  for (size_t t = 0; t < g.triangles.size(); ++t) {
    const Tri& f = g.triangles[t];
    if (t % 100 == 7 && !gone[f[0]] && !gone[f[1]] && !gone[f[2]]) {
      gone[f[0]] = gone[f[1]] = gone[f[2]] = 1;
      continue;
    }
    kept.push_back(f);
  }
  Options opt;
  opt.size = 512;
  const Result r = optimize(cat::make_textured("pepper_torus", g.positions, kept), opt);
  const auto& c = report_json(r.report)["components"][0];
  EXPECT_EQ(c["fallback"], "") << c.dump();
  EXPECT_LT(c["cap_budget"].get<double>(), 0.02) << "the caps took too much of the square at 2%";
  EXPECT_GE(c["cap_budget"].get<double>(), kFillBudget);
  EXPECT_GE(c["holes_filled"].get<int>(), 80);
  EXPECT_GE(report_json(r.report)["metrics"]["output"]["utilization"].get<double>(), 0.99);
  EXPECT_EQ(report_json(r.report)["metrics"]["flipped"], 0);
  EXPECT_EQ(report_json(r.report)["metrics"]["charts"], 1);
}

// A hole whose cap (a fan from the mean of its rim's vertices) has faces of zero 3D area: an S-shaped
// hole of four grid cells in a flat plate, whose rim's mean lies on the line of two of its rim edges.
// Such a cap face had a target area of zero, the area map's reweighting squeezed it without end, and
// real faces beside the cap were crushed to slivers (found on the bust with six patches missing:
// density P5 -1.10, angle distortion mean 3e5; with the detail map 1 triangle flipped).
TEST(Pipeline, AHoleCapWithFacesOfZeroAreaDoesNotCrushTheAreaMap) {
  constexpr int n = 24;
  const testing::Geometry g = testing::param_grid(n + 1, n + 1, false, false, [](int i, int j) { return Vec3(i, j, 0); });
  const std::set<std::pair<int, int>> hole = {{10, 11}, {10, 12}, {11, 10}, {11, 11}};  // cells (i, j)
  std::vector<Tri> kept;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      if (!hole.count({i, j}))
        for (int k = 0; k < 2; ++k) kept.push_back(g.triangles[size_t(2 * (j * n + i) + k)]);
  Options opt;
  opt.size = 256;
  opt.map = MapKind::kArea;
  const Result r = optimize(cat::make_textured("s_hole_plate", g.positions, kept), opt);
  const auto& c = report_json(r.report)["components"][0];
  ASSERT_EQ(c["holes_filled"], 1) << c.dump();
  // The reweighting does not stop at a fold (edge weights 1e-7..1e13 would follow), and no face of the
  // plate comes out crushed: each above 0.4x the mean density. The faces at the plate's four corners
  // have a floor of their own, 0.25x: the square plate is mapped at 1:2 (the aspect probe's choice),
  // and the symmetric Dirichlet steps before the area map's flow squeeze the two faces at a corner
  // where a square's map meets a rectangle's (to about 0.30x).
  EXPECT_NE(c["density_stopped"], "fold") << c.dump();
  const TexturedMesh& out = r.output;
  double uv_total = 0, area_total = 0;
  std::vector<double> density;
  for (size_t t = 0; t < out.triangles.size(); ++t) {
    const Tri& f = out.triangles[t];
    const double a3 = triangle_area(out.positions[f[0]], out.positions[f[1]], out.positions[f[2]]);
    const double at = std::abs(signed_area(out.corner_uv[3 * t], out.corner_uv[3 * t + 1], out.corner_uv[3 * t + 2]));
    uv_total += at, area_total += a3;
    density.push_back(at / a3);
  }
  const double mean = uv_total / area_total;
  auto at_corner = [&](const Tri& f) {
    for (uint32_t v : f) {
      const Vec3& p = out.positions[v];
      if ((p.x() == 0 || p.x() == n) && (p.y() == 0 || p.y() == n)) return true;
    }
    return false;
  };
  size_t corner_faces = 0;
  for (size_t t = 0; t < density.size(); ++t) {
    const Tri& f = out.triangles[t];
    const bool corner = at_corner(f);
    corner_faces += corner;
    EXPECT_GT(density[t], (corner ? 0.25 : 0.4) * mean)
        << "triangle " << t << " squeezed at " << out.positions[f[0]] << " / " << out.positions[f[1]] << " / " << out.positions[f[2]];
  }
  EXPECT_EQ(corner_faces, 6u);  // one face at two corners, two at the others (the cells' diagonals)
  EXPECT_EQ(report_json(r.report)["metrics"]["flipped"], 0);
  // The maps refine to convergence: the cap's two faces of zero 3D area have no 3D shape to aim at, so
  // they keep their start shape as their target frame. Without one they would have no energy to keep
  // them open, the step direction would collapse them and the line search would cut every step short
  // (3 steps instead of 8 here). In a 1:2 texture, where the start map is sheared and the refinement
  // has work to do (the square's start map of this square plate is isometric already).
  opt.aspect = 0.5;
  for (MapKind map : {MapKind::kTexel, MapKind::kDetail}) {
    SCOPED_TRACE(map == MapKind::kTexel ? "texel map" : "detail map");
    opt.map = map;
    const Result q = optimize(cat::make_textured("s_hole_plate", g.positions, kept), opt);
    const auto& e = report_json(q.report)["components"][0]["refine_energy"];
    EXPECT_LT(e[1].get<double>(), 0.8 * e[0].get<double>()) << report_json(q.report)["components"][0].dump();
    EXPECT_EQ(report_json(q.report)["metrics"]["flipped"], 0);
  }
}

// A flat 7 x 7 grid of unit squares (testing::param_grid), mapped onto the unit square by scaling
// (an isometry up to scale); the boundary held. For refine_map's failure cases below.
namespace {
struct GridDisk {
  Surface mesh;
  std::vector<Vec2> uv;
  std::vector<char> fixed;
  std::vector<double> target;
};
GridDisk grid_disk() {
  constexpr int n = 7;
  const testing::Geometry grid = testing::param_grid(n + 1, n + 1, false, false, [](int i, int j) { return Vec3(i, j, 0); });
  GridDisk g;
  g.mesh.positions = grid.positions;
  g.mesh.triangles = grid.triangles;
  for (const Vec3& p : grid.positions) {
    g.uv.push_back(Vec2(p.x() / n, p.y() / n));
    g.fixed.push_back(p.x() == 0 || p.y() == 0 || p.x() == n || p.y() == n ? 3 : 0);
  }
  g.mesh = with_identity_parents(g.mesh);
  build_opposite(g.mesh);
  g.target.assign(g.mesh.num_faces(), 1.0 / g.mesh.num_faces());
  return g;
}
double uv_area(const GridDisk& g, size_t f) {
  const Tri& t = g.mesh.triangles[f];
  return signed_area(g.uv[t[0]], g.uv[t[1]], g.uv[t[2]]);
}
}  // namespace

// A triangle squeezed to a sliver in the start map (1e-13 of its target: found on the bust with six
// patches missing) gives SLIM weights near 1e39, and its system fails to factorise. The step is then
// solved with the weights capped, and the refinement goes on: the sliver opens up and nothing folds,
// and CHOLMOD's warning about the failed factorisation is not printed.
TEST(RefineMap, ASliverInTheStartMapIsRefinedNotGivenUp) {
  GridDisk g = grid_disk();
  // Vertex (3, 3) moved to just inside the edge (4, 3)-(4, 4) of its triangle {(3,3), (4,3), (4,4)}.
  const uint32_t v = 3 * 8 + 3, a = 3 * 8 + 4, b = 4 * 8 + 4;
  g.uv[v] = 0.5 * (g.uv[a] + g.uv[b]) + Vec2(-1e-13, 0);
  size_t sliver = kNone;
  for (size_t f = 0; f < g.mesh.num_faces(); ++f)
    if (g.mesh.triangles[f] == Tri{v, a, b}) sliver = f;
  ASSERT_NE(sliver, kNone);
  for (size_t f = 0; f < g.mesh.num_faces(); ++f) ASSERT_GT(uv_area(g, f), 0.0) << "the start map must be fold-free";
  const double before = uv_area(g, sliver);
  ::testing::internal::CaptureStderr();
  ::testing::internal::CaptureStdout();
  const SlimStats st = refine_map(g.mesh, g.fixed, g.target, 10, g.uv);
  const std::string out = ::testing::internal::GetCapturedStdout(), err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(out + err, "") << "CHOLMOD printed its warning (tightex -q prints nothing but errors)";
  EXPECT_NE(st.stopped, "solver");
  EXPECT_GT(st.iterations, 0);
  EXPECT_GT(st.capped_steps, 0) << "the uncapped system solved: the test no longer reaches the retry";
  EXPECT_LT(st.energy, st.energy_before);
  EXPECT_GT(uv_area(g, sliver), 1e6 * before);
  for (size_t f = 0; f < g.mesh.num_faces(); ++f) EXPECT_GT(uv_area(g, f), 0.0) << "face " << f;
}

// A vertex none of whose faces has a target frame (target 0, or a 3D-degenerate face) has no energy;
// its unknowns would make the system singular and leave the whole map unrefined. It stays put while
// the rest is refined.
TEST(RefineMap, AVertexWithoutTargetFramesStaysWhileTheRestIsRefined) {
  GridDisk g = grid_disk();
  const uint32_t v = 2 * 8 + 5;  // an interior vertex
  for (size_t f = 0; f < g.mesh.num_faces(); ++f) {
    const Tri& t = g.mesh.triangles[f];
    if (t[0] == v || t[1] == v || t[2] == v) g.target[f] = 0;
  }
  // A start map with something to refine: the interior pushed off the isometry.
  for (size_t w = 0; w < g.uv.size(); ++w)
    if (!g.fixed[w] && w != v) g.uv[w] += Vec2(0.02 * std::sin(3.0 * g.uv[w].y()), 0.0);
  for (size_t f = 0; f < g.mesh.num_faces(); ++f) ASSERT_GT(uv_area(g, f), 0.0);
  const Vec2 at = g.uv[v];
  const SlimStats st = refine_map(g.mesh, g.fixed, g.target, 10, g.uv);
  EXPECT_NE(st.stopped, "solver");
  EXPECT_GT(st.iterations, 0);
  EXPECT_LT(st.energy, st.energy_before);
  EXPECT_EQ(g.uv[v], at);
  for (size_t f = 0; f < g.mesh.num_faces(); ++f) EXPECT_GT(uv_area(g, f), 0.0) << "face " << f;
}

// Newton's steps converge fast near the minimum, where SLIM's proxy alone crawls (each of its steps
// gains about a fixed fraction): from the isometric grid pushed off by 2% of its width, with the
// boundary held, the refinement stops (a step gaining under 0.1%) within 7e-5 of the isometry and 8e-8
// above its energy after 2 steps. SLIM's steps alone stop after 2 as well, 2e-3 away and 1e-4 above.
TEST(RefineMap, NewtonStepsStopCloseToTheIsometry) {
  GridDisk g = grid_disk();
  const std::vector<Vec2> isometry = g.uv;
  for (size_t w = 0; w < g.uv.size(); ++w)
    if (!g.fixed[w]) g.uv[w] += Vec2(0.02 * std::sin(3.0 * g.uv[w].y()), 0.01 * std::cos(2.0 * g.uv[w].x()));
  for (size_t f = 0; f < g.mesh.num_faces(); ++f) ASSERT_GT(uv_area(g, f), 0.0);
  const SlimStats st = refine_map(g.mesh, g.fixed, g.target, 30, g.uv);
  EXPECT_EQ(st.stopped, "converged");
  EXPECT_LE(st.iterations, 5);
  EXPECT_EQ(st.proxy_steps, 0);
  double off = 0;
  for (size_t w = 0; w < g.uv.size(); ++w) off = std::max(off, (g.uv[w] - isometry[w]).norm());
  EXPECT_LT(off, 3e-4);
  EXPECT_NEAR(st.energy, 4.0 * std::accumulate(g.target.begin(), g.target.end(), 0.0), 1e-6);
}

// refine_map with a system made ahead (prepare_refinement) or by an earlier refinement gives the map
// it gives alone, bit for bit, and keeps that system; one made for other free coordinates (another
// vertex held) is replaced, and the map is still the one for refine_map's own coordinates.
TEST(RefineMap, APreparedSystemGivesTheSameMapAndOneForOtherCoordinatesIsReplaced) {
  GridDisk g = grid_disk();
  for (size_t w = 0; w < g.uv.size(); ++w)
    if (!g.fixed[w]) g.uv[w] += Vec2(0.02 * std::sin(3.0 * g.uv[w].y()), 0.01 * std::cos(2.0 * g.uv[w].x()));
  for (size_t f = 0; f < g.mesh.num_faces(); ++f) ASSERT_GT(uv_area(g, f), 0.0);
  std::vector<Vec2> alone = g.uv;
  const SlimStats expected = refine_map(g.mesh, g.fixed, g.target, 3, alone);
  ASSERT_GT(expected.iterations, 0);
  std::shared_ptr<RefinementSystem> system = prepare_refinement(g.mesh, g.fixed, g.target);
  ASSERT_NE(system, nullptr);
  const RefinementSystem* made = system.get();
  for (int run = 0; run < 2; ++run) {  // prepared, then left by the first run
    std::vector<Vec2> uv = g.uv;
    const SlimStats st = refine_map(g.mesh, g.fixed, g.target, 3, uv, kSupernodalFrom, {}, nullptr, nullptr, &system);
    EXPECT_EQ(st.iterations, expected.iterations);
    EXPECT_EQ(st.energy, expected.energy);
    EXPECT_EQ(uv, alone);
    EXPECT_EQ(system.get(), made) << "run " << run << ": the system was made again";
  }
  std::vector<char> other = g.fixed;
  other[3 * 8 + 3] = 3;
  system = prepare_refinement(g.mesh, other, g.target);
  made = system.get();
  std::vector<Vec2> uv = g.uv;
  refine_map(g.mesh, g.fixed, g.target, 3, uv, kSupernodalFrom, {}, nullptr, nullptr, &system);
  EXPECT_EQ(uv, alone);
  EXPECT_NE(system.get(), made);
  EXPECT_NE(system, nullptr);
}

// The density-equalising flow (flow_density) on a flat 24 x 24 grid whose left half asks for 4x the
// texels of its right half, from the identity map (log2(area / target) -0.68 / +1.32): it evens the
// density out to within +-0.3 (the faces along the step in the targets stay a little off), folds
// nothing, keeps the corners where they are and every side vertex on its side, in the square and in a
// 2:1 rectangle.
/// A flat n x n grid of unit squares mapped onto the unit square as it lies, its sides' vertices
/// sliding along them (fixed: bit 0 holds u, bit 1 v), as flow_density and refine_map take them.
struct FlatGrid {
  Surface mesh;
  std::vector<Vec2> start;
  std::vector<char> fixed;
};

FlatGrid flat_grid(int n) {
  const testing::Geometry grid = testing::param_grid(n + 1, n + 1, false, false, [](int i, int j) { return Vec3(i, j, 0); });
  FlatGrid g;
  g.mesh.positions = grid.positions;
  g.mesh.triangles = grid.triangles;
  g.mesh = with_identity_parents(g.mesh);
  build_opposite(g.mesh);
  for (const Vec3& p : grid.positions) {
    g.start.push_back(Vec2(p.x() / n, p.y() / n));
    const bool side_x = p.x() == 0 || p.x() == n, side_y = p.y() == 0 || p.y() == n;
    g.fixed.push_back(char((side_x ? 1 : 0) | (side_y ? 2 : 0)));
  }
  return g;
}

TEST(DensityFlow, EvensOutATargetFourTimesDenserOnOneSide) {
  constexpr int n = 24;
  const auto& [mesh, start, fixed] = flat_grid(n);
  std::vector<double> target(mesh.num_faces());
  for (size_t f = 0; f < target.size(); ++f) {
    const Tri& t = mesh.triangles[f];
    target[f] = (start[t[0]].x() + start[t[1]].x() + start[t[2]].x()) / 3 < 0.5 ? 4.0 : 1.0;
  }
  const Disk disk{mesh, {}};  // every face real: density_error over all of them
  auto spread = [&](const std::vector<Vec2>& uv) { return density_error(disk, uv, target); };
  const auto [s5, s95] = spread(start);
  ASSERT_LT(s5, -0.6);
  ASSERT_GT(s95, 1.3);
  for (double aspect : {1.0, 2.0}) {
    SCOPED_TRACE("aspect " + std::to_string(aspect));
    std::vector<Vec2> uv = start;
    const FlowStats st = flow_density(mesh, fixed, target, aspect, uv);
    EXPECT_EQ(st.stopped, "converged");
    EXPECT_GT(st.steps, 0);
    EXPECT_EQ(count_folds(mesh, uv), 0u);
    const auto [p5, p95] = spread(uv);
    EXPECT_GT(p5, -0.3) << p95;
    EXPECT_LT(p95, 0.3) << p5;
    for (size_t v = 0; v < uv.size(); ++v) {
      if (fixed[v] & 1) EXPECT_EQ(uv[v].x(), start[v].x()) << "vertex " << v;
      if (fixed[v] & 2) EXPECT_EQ(uv[v].y(), start[v].y()) << "vertex " << v;
      EXPECT_TRUE(uv[v].x() >= 0 && uv[v].x() <= 1 && uv[v].y() >= 0 && uv[v].y() <= 1) << "vertex " << v;
    }
    // The dense half grew: the grid's centre moved right, to about 4/5 of the width.
    for (size_t v = 0; v < uv.size(); ++v)
      if (mesh.positions[v] == Vec3(n / 2, n / 2, 0)) EXPECT_GT(uv[v].x(), 0.7);
  }
}

TEST(DensityFlow, TracersFollowTheVerticesAndSmallCopiesOfFacesNeverFold) {
  // A coarse grid (each face spans several cells of the flow's grid) whose corner asks for 16x the
  // texels, flowed without the fold-free check. Tracers move as the vertices do, and a small copy of
  // every face carried as tracers keeps its orientation: the flow's own local map never folds (the
  // area map takes its shapes from such copies, where the flowed vertices of long faces can fold).
  constexpr int n = 4;
  const auto& [mesh, start, fixed] = flat_grid(n);
  std::vector<double> target(mesh.num_faces(), 1.0);
  for (size_t f = 0; f < target.size(); ++f) {
    const Tri& t = mesh.triangles[f];
    const Vec2 c = (start[t[0]] + start[t[1]] + start[t[2]]) / 3;
    if (c.x() < 0.3 && c.y() < 0.3) target[f] = 16.0;
  }
  FlowOptions options;
  options.fold_free = false;
  options.grid = 32;
  // Tracers: every interior vertex, then a copy of each face shrunk 64x about its centroid.
  std::vector<Vec2> tracers;
  std::vector<uint32_t> interior;
  for (uint32_t v = 0; v < start.size(); ++v)
    if (fixed[v] == 0) interior.push_back(v), tracers.push_back(start[v]);
  const size_t first_copy = tracers.size();
  constexpr double kShrink = 1.0 / 64;
  for (const Tri& t : mesh.triangles) {
    const Vec2 c = (start[t[0]] + start[t[1]] + start[t[2]]) / 3;
    for (uint32_t v : t) tracers.push_back(c + kShrink * (start[v] - c));
  }
  std::vector<Vec2> uv = start;
  const FlowStats st = flow_density(mesh, fixed, target, 1.0, uv, options, &tracers);
  ASSERT_GT(st.steps, 0);
  ASSERT_EQ(tracers.size(), first_copy + 3 * mesh.num_faces());
  for (size_t i = 0; i < interior.size(); ++i) {
    EXPECT_NEAR(tracers[i].x(), uv[interior[i]].x(), 1e-12) << "vertex " << interior[i];
    EXPECT_NEAR(tracers[i].y(), uv[interior[i]].y(), 1e-12) << "vertex " << interior[i];
  }
  // The dense corner's faces grew, so the flow moved things: an interior vertex beside it moved by
  // more than a tenth of a face.
  double moved = 0;
  for (uint32_t v : interior) moved = std::max(moved, (uv[v] - start[v]).norm());
  EXPECT_GT(moved, 0.1 / n);
  for (size_t f = 0; f < mesh.num_faces(); ++f) {
    const Vec2 &a = tracers[first_copy + 3 * f], &b = tracers[first_copy + 3 * f + 1], &c = tracers[first_copy + 3 * f + 2];
    EXPECT_GT(signed_area(a, b, c), 0) << "face " << f;
  }
}

/// The largest ratio of the singular values of a real face's map from its 3D triangle to its texels
/// in the options' rectangle: how far the map crushes a triangle in one direction against the other.
double max_anisotropy(const Disk& disk, const std::vector<Vec2>& uv, const SquareMapOptions& options) {
  const Surface& m = disk.mesh;
  double worst = 1;
  for (size_t f = 0; f < m.num_faces(); ++f) {
    if (m.face_parent[f] == kNone) continue;
    const Tri& t = m.triangles[f];
    const Vec3 e1 = m.positions[t[1]] - m.positions[t[0]], e2 = m.positions[t[2]] - m.positions[t[0]];
    const Vec3 x = e1.normalized(), y = e1.cross(e2).normalized().cross(x);
    Eigen::Matrix2d surface, texels;
    surface << e1.dot(x), e2.dot(x), e1.dot(y), e2.dot(y);
    const Vec2 scale(options.rect_width, options.rect_height);
    const Vec2 u1 = (uv[t[1]] - uv[t[0]]).cwiseProduct(scale), u2 = (uv[t[2]] - uv[t[0]]).cwiseProduct(scale);
    texels.col(0) = as_eigen(u1), texels.col(1) = as_eigen(u2);
    const Eigen::Vector2d sv = Eigen::JacobiSVD<Eigen::Matrix2d>(texels * surface.inverse()).singularValues();
    worst = std::max(worst, sv(0) / sv(1));
  }
  return worst;
}

// A triangle with two edges on a disk's rim (an ear, common on a scan's jagged rim) lies beyond a
// chord: with both of the chord's ends on one side of the square, Alg. 1 leaves it only the bump's
// sliver, a fraction of a texel high however large its target. The detail map's symmetric Dirichlet
// steps move the bump and the chord's ends inwards, so the ear gets its share of the square and no
// triangle is crushed more than 20:1; the map stays fold-free with its boundary in order. (The area
// map's steps stop where they would widen the density error, which the ear, a sliver of the area,
// does not count in: they leave it crushed.)
TEST(MapToSquare, AnEarOnTheRimIsNotCrushedOntoItsSide) {
  constexpr int nu = 13, nv = 9;
  auto g = testing::param_grid(nu, nv, false, false, [](int i, int j) { return Vec3(0.125 * i, 0.125 * j, 0.0); });
  const uint32_t ear = uint32_t(g.positions.size());
  g.add(Vec3(0.125 * 6.5, -0.3, 0.0));
  g.triangles.push_back({7, 6, ear});  // below the bottom row's edge (6, 7), which becomes the chord
  const Disk disk = one_disk(g, "eared_sheet");
  SquareMapOptions options;
  options.rect_width = options.rect_height = 256;
  options.face_target.resize(disk.mesh.num_faces());
  for (size_t f = 0; f < disk.mesh.num_faces(); ++f) options.face_target[f] = triangle_area(disk.mesh.positions, disk.mesh.triangles[f]);
  options.refine_keeps_density = false;  // the detail map's steps, as set_face_targets sets them
  options.refine_iterations = 30;
  SquareMapStats st;
  const auto uv = map_to_square(disk, options, &st);
  ASSERT_GT(st.bumped_vertices, 0u) << "the ear's chord must have both ends on one side";
  check_square_map(disk, uv, options, st);
  EXPECT_LT(max_anisotropy(disk, uv, options), 20.0) << st.refine_iterations << " steps, " << st.refine_stopped;
}

TEST(MapToSquare, NonSquareRectangles) {
  for (const char* name : {"bowtie", "obtuse_strip", "sphere_with_holes"}) {
    const auto comps = split_components(prepare_surface(expected(name).make(), nullptr));
    for (auto [w, h] : {std::pair{16, 512}, std::pair{512, 16}, std::pair{4, 4}}) {
      SCOPED_TRACE(std::string(name) + " " + std::to_string(w) + "x" + std::to_string(h));
      SquareMapOptions options;
      options.rect_width = w;
      options.rect_height = h;
      for (const Surface& c : comps) {
        const Disk disk = cut_to_disk(c, {.holes = HoleMode::kFill}, nullptr);
        SquareMapStats st;
        const auto uv = map_to_square(disk, options, &st);
        check_square_map(disk, uv, options, st);
      }
    }
  }
}

// ---- 5. the whole pipeline ----

/// Runs optimize() and checks the output model and the metrics of its report.
void check_pipeline(const TexturedMesh& input, const Expected& e, const Options& options, bool check_fill) {
  Result r;
  try {
    r = optimize(input, options);
  } catch (const std::exception& ex) {
    FAIL() << "optimize threw: " << ex.what();
  }
  const TexturedMesh& out = r.output;
  ASSERT_EQ(out.corner_uv.size(), 3 * out.num_triangles());
  ASSERT_EQ(out.face_material.size(), out.num_triangles());
  EXPECT_EQ(out.num_triangles(), input.num_triangles() - e.zero_area);  // an exact repeat is written as a copy
  for (const Vec2& uv : out.corner_uv) {
    ASSERT_TRUE(uv.allFinite());
    EXPECT_TRUE(uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1) << "(" << uv.x() << ", " << uv.y() << ")";
  }
  for (int32_t mat : out.face_material) {
    ASSERT_GE(mat, 0);
    ASSERT_LT(size_t(mat), out.materials.size());
    ASSERT_GE(out.materials[size_t(mat)].texture, 0);
  }

  const nlohmann::json& m = report_json(r.report)["metrics"];
  ASSERT_TRUE(m.is_object()) << report_json(r.report).dump();
  EXPECT_EQ(m["lost_triangles"].get<size_t>(), 0u);
  EXPECT_EQ(m["flipped"].get<size_t>(), 0u);
  EXPECT_EQ(m["degenerate"].get<size_t>(), 0u);
  EXPECT_EQ(m["overlap"].get<double>(), 0.0);
  EXPECT_EQ(m["charts"].get<size_t>(), e.components);
  EXPECT_EQ(report_json(r.report)["preparation"]["components"].get<size_t>(), e.components);
  if (check_fill) EXPECT_GE(m["output"]["utilization"].get<double>(), 0.99);
  // The input texture is a smooth gradient: the bake must reproduce it closely.
  EXPECT_GT(m["surface_psnr_db"].get<double>(), e.min_psnr);

  // The report's metrics agree with measuring the output afresh.
  const Metrics fresh = measure(input, out, 20000);
  EXPECT_EQ(fresh.lost_triangles, 0u);
  EXPECT_EQ(fresh.flipped, 0u);
  EXPECT_EQ(fresh.charts, e.components);
}

TEST_P(Catalogue, OptimizeAtlas) {
  Options options;
  options.size = 256;
  check_pipeline(mesh(), want(), options, want().fills_rectangles);
}

TEST_P(Catalogue, OptimizeCutHolesPerComponent) {
  Options options;
  options.size = 128;
  options.holes = HoleMode::kCut;
  options.layout = Layout::kPerComponent;
  check_pipeline(mesh(), want(), options, want().fills_rectangles);
}

// Every map through the whole pipeline: one fold-free chart per component (detail is the default and
// runs in OptimizeAtlas).
TEST_P(Catalogue, OptimizeHarmonicTexelAndAreaMaps) {
  for (MapKind kind : {MapKind::kHarmonic, MapKind::kTexel, MapKind::kArea}) {
    SCOPED_TRACE(kind == MapKind::kHarmonic ? "harmonic" : kind == MapKind::kTexel ? "texel" : "area");
    Options options;
    options.size = 128;
    options.map = kind;
    check_pipeline(mesh(), want(), options, want().fills_rectangles);
  }
}

// ---- 6. layouts ----

/// Checks that `rects` tile width x height exactly, each at least min_side, with areas proportional to
/// `areas` within a factor 1.5 for items whose share is at least 16 minimum squares.
void check_atlas(const std::vector<double>& areas, const std::vector<Rect>& rects, int width, int height, int min_side) {
  ASSERT_EQ(rects.size(), areas.size());
  std::vector<int> cover(size_t(width) * size_t(height), 0);
  long sum = 0;
  for (size_t i = 0; i < rects.size(); ++i) {
    const Rect& r = rects[i];
    EXPECT_EQ(r.image, 0);
    ASSERT_GE(r.w, min_side) << "rect " << i;
    ASSERT_GE(r.h, min_side) << "rect " << i;
    ASSERT_TRUE(r.x >= 0 && r.y >= 0 && r.x + r.w <= width && r.y + r.h <= height)
        << "rect " << i << " (" << r.x << ", " << r.y << ", " << r.w << ", " << r.h << ") outside";
    sum += long(r.w) * r.h;
    for (int y = r.y; y < r.y + r.h; ++y)
      for (int x = r.x; x < r.x + r.w; ++x) cover[size_t(y) * size_t(width) + size_t(x)]++;
  }
  EXPECT_EQ(sum, long(width) * height);
  size_t overlapped = 0, uncovered = 0;
  for (int c : cover) overlapped += c > 1, uncovered += c == 0;
  EXPECT_EQ(overlapped, 0u);
  EXPECT_EQ(uncovered, 0u);
  double total = 0;
  for (double a : areas) total += a;
  for (size_t i = 0; i < areas.size(); ++i) {
    const double ideal = areas[i] / total * double(width) * height;
    if (ideal < 16.0 * min_side * min_side) continue;
    const double got = double(rects[i].w) * rects[i].h;
    // Near its share; up to 4x where its share alone would have made it a strip (the layout's error
    // model trades a little of the others' texels for its shape; Layout.ASmallComponentBesideABig...).
    EXPECT_LE(got, 4.0 * ideal) << "rect " << i << " of area share " << areas[i] / total;
    EXPECT_GE(got, ideal / 1.5) << "rect " << i << " of area share " << areas[i] / total;
  }
}

TEST(Layout, AtlasTilesTheTexture) {
  std::mt19937 rng(12345);
  std::vector<std::vector<double>> sets = {{1.0}, {1.0, 1.0}, {3.0, 1.0}, {1, 2, 3, 4, 5}, {10, 1e-6, 1e-9, 5, 0.5}};
  {
    std::lognormal_distribution<double> spread(0.0, 1.5);  // areas over ~3 orders of magnitude
    for (int n : {7, 20, 60}) {
      std::vector<double> a(static_cast<size_t>(n), 0.0);
      for (double& x : a) x = spread(rng);
      sets.push_back(a);
    }
  }
  {  // the catalogue's multi-component mesh
    const auto comps = split_components(prepare_surface(cat::multi_component(), nullptr));
    std::vector<double> a;
    for (const Surface& c : comps) {
      double area = 0;
      for (const Tri& f : c.triangles) area += triangle_area(c.positions[f[0]], c.positions[f[1]], c.positions[f[2]]);
      a.push_back(area);
    }
    sets.push_back(a);
  }
  for (auto [w, h] : {std::pair{256, 256}, std::pair{300, 200}, std::pair{1024, 64}, std::pair{97, 131}}) {
    for (size_t i = 0; i < sets.size(); ++i) {
      SCOPED_TRACE("set " + std::to_string(i) + " in " + std::to_string(w) + "x" + std::to_string(h));
      std::vector<Rect> rects;
      ASSERT_NO_THROW(rects = layout_atlas(sets[i], w, h, 4));
      check_atlas(sets[i], rects, w, h, 4);
    }
  }
}

// Without a strip in sight the rectangles are exactly proportional.
TEST(Layout, AtlasIsProportionalWhenNoComponentIsSqueezed) {
  const auto four = layout_atlas({1, 1, 1, 1}, 256, 256, 4);
  for (const Rect& r : four) {
    EXPECT_EQ(r.w, 128);
    EXPECT_EQ(r.h, 128);
  }
  const auto three = layout_atlas({2, 1, 1}, 256, 256, 4);
  EXPECT_EQ(three[0].w * three[0].h, 128 * 256);
  EXPECT_EQ(three[1].w * three[1].h, 128 * 128);
  EXPECT_EQ(three[2].w * three[2].h, 128 * 128);
}

// A scan's main surface beside a fragment of 1% of its area (generated vases: 216 triangles beside
// 2600): in proportion the fragment gets a 1024 x 10 strip, a round patch flattened 100:1, whose texels
// resolve nothing across it (vase seed 3, 40 segments: 36.0 dB; with this layout 38.7). The layout's
// error model (a^2 / texels, times (e + 1/e) / 2 for an elongation e beyond 2:1) puts the optimum near
// 38 rows: it must give the fragment 2.5x to 6x its share and leave the main surface at least 94%.
TEST(Layout, ASmallComponentBesideABigOneIsNotAStrip) {
  const std::vector<double> areas = {0.99, 0.01};
  const auto rects = layout_atlas(areas, 1024, 1024, 4);
  check_atlas(areas, rects, 1024, 1024, 4);
  const double ideal = 0.01 * 1024 * 1024, got = double(rects[1].w) * rects[1].h;
  EXPECT_GE(got, 2.5 * ideal);
  EXPECT_LE(got, 6.0 * ideal);
  EXPECT_GE(double(rects[0].w) * rects[0].h, 0.94 * 1024 * 1024);
  // AtlasShares::kExact (the area map's same texels per unit area) keeps the proportion, strip or not.
  const auto exact = layout_atlas(areas, 1024, 1024, 4, AtlasShares::kExact);
  check_atlas(areas, exact, 1024, 1024, 4);
  EXPECT_NEAR(double(exact[1].w) * exact[1].h, ideal, 1024.0);
  // The same in a 2:1 texture, both ways round (the auto shape's probes).
  for (auto [w, h] : {std::pair{1448, 724}, std::pair{724, 1448}}) {
    const auto r2 = layout_atlas(areas, w, h, 4);
    check_atlas(areas, r2, w, h, 4);
    EXPECT_GE(double(r2[1].w) * r2[1].h, 2.0 * 0.01 * w * h) << w << "x" << h;
  }
}

TEST(Layout, AtlasAtCapacity) {
  // 16 equal items exactly fill a 16x16 texture with 4x4 squares.
  const std::vector<double> equal(16, 1.0);
  const auto rects = layout_atlas(equal, 16, 16, 4);
  check_atlas(equal, rects, 16, 16, 4);
  for (const Rect& r : rects) {
    EXPECT_EQ(r.w, 4);
    EXPECT_EQ(r.h, 4);
  }
  // One more than fits: refused as bad input, not a crash or an overlapping layout.
  EXPECT_THROW(layout_atlas(std::vector<double>(17, 1.0), 16, 16, 4), InputError);
  // The same question asked as an attempt: no rectangles instead of the error, the same ones otherwise.
  EXPECT_FALSE(try_layout_atlas(std::vector<double>(17, 1.0), 16, 16, 4).has_value());
  const auto attempt = try_layout_atlas(equal, 16, 16, 4);
  ASSERT_TRUE(attempt.has_value());
  for (size_t i = 0; i < rects.size(); ++i)
    EXPECT_TRUE((*attempt)[i].x == rects[i].x && (*attempt)[i].y == rects[i].y && (*attempt)[i].w == rects[i].w &&
                (*attempt)[i].h == rects[i].h)
        << i;
  // Many tiny items beside one big one: the tiny ones still get min_side squares.
  std::vector<double> skewed(40, 1e-12);
  skewed[0] = 1.0;
  const auto r2 = layout_atlas(skewed, 128, 128, 4);
  check_atlas(skewed, r2, 128, 128, 4);
}

// A scan's usual debris: one big component and many specks, far below the texture's capacity (at most
// a quarter of it in min_side squares). The layout must not refuse them.
TEST(Layout, AtlasOneBigManyTiny) {
  size_t refused = 0;
  for (auto [size, max_tiny] : {std::pair{64, 64}, std::pair{256, 300}}) {  // up to 1/4 and 1/13 of capacity
    for (int tiny = 1; tiny <= max_tiny; ++tiny) {
      SCOPED_TRACE("1 big + " + std::to_string(tiny) + " tiny in " + std::to_string(size) + "x" + std::to_string(size));
      std::vector<double> areas(size_t(tiny) + 1, 1e-9);
      areas[0] = 1.0;
      std::vector<Rect> rects;
      try {
        rects = layout_atlas(areas, size, size, 4);
      } catch (const std::exception& ex) {
        if (++refused <= 3) ADD_FAILURE() << "layout_atlas threw: " << ex.what();
        continue;
      }
      check_atlas(areas, rects, size, size, 4);
    }
  }
  EXPECT_EQ(refused, 0u) << "layouts refused although the texture had room";
}

TEST(Layout, AtlasRandomAreas) {
  std::mt19937 rng(1);
  std::lognormal_distribution<double> spread(0.0, 1.5);
  size_t refused = 0;
  for (int n : {10, 20, 40, 55, 80, 120, 200}) {
    for (int trial = 0; trial < 10; ++trial) {
      SCOPED_TRACE(std::to_string(n) + " areas, trial " + std::to_string(trial));
      std::vector<double> areas(static_cast<size_t>(n), 0.0);
      for (double& a : areas) a = spread(rng);
      std::vector<Rect> rects;
      try {
        rects = layout_atlas(areas, 256, 256, 4);  // capacity 4096 squares
      } catch (const std::exception& ex) {
        if (++refused <= 3) ADD_FAILURE() << "layout_atlas threw: " << ex.what();
        continue;
      }
      check_atlas(areas, rects, 256, 256, 4);
    }
  }
  EXPECT_EQ(refused, 0u) << "layouts refused although the texture had room";
}

TEST(Layout, PerComponent) {
  const std::vector<double> areas = {2.0, 8.0, 0.5, 1e-9, 8.0 / 9.0};
  const int size = 256;
  const auto rects = layout_per_component(areas, size, 4);
  ASSERT_EQ(rects.size(), areas.size());
  int largest = 0;
  for (size_t i = 0; i < rects.size(); ++i) {
    const Rect& r = rects[i];
    EXPECT_EQ(r.image, int(i));
    EXPECT_EQ(r.x, 0);
    EXPECT_EQ(r.y, 0);
    EXPECT_EQ(r.w, r.h);
    EXPECT_GE(r.w, 4);
    largest = std::max(largest, r.w);
    // side proportional to the square root of the area share
    const double ideal = size * std::sqrt(areas[i] / 8.0);
    if (ideal >= 4) EXPECT_NEAR(r.w, ideal, 1.0) << "component " << i;
  }
  EXPECT_EQ(largest, size);
  EXPECT_EQ(rects[1].w, size);
  EXPECT_EQ(rects[0].w, size / 2);
  EXPECT_EQ(rects[4].w, 85);  // sqrt(1/9) * 256 = 85.33
  EXPECT_EQ(rects[3].w, 4);   // a speck still gets min_side
}

// ---- the checks themselves catch broken output (so a passing stage test means something) ----

/// Runs f with gtest failures captured; succeeds when at least one captured failure mentions `needle`.
template <typename F>
::testing::AssertionResult fails_with(F&& f, const std::string& needle) {
  ::testing::TestPartResultArray results;
  {
    ::testing::ScopedFakeTestPartResultReporter capture(::testing::ScopedFakeTestPartResultReporter::INTERCEPT_ONLY_CURRENT_THREAD,
                                                        &results);
    f();
  }
  for (int i = 0; i < results.size(); ++i)
    if (std::string(results.GetTestPartResult(i).message()).find(needle) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << results.size() << " failures, none mentioning \"" << needle << "\"";
}

TEST(Checkers, CatchBrokenOutput) {
  // is_manifold: an unsliced bowtie, and a one-sided opposite.
  {
    const TexturedMesh m = cat::bowtie();
    Surface raw;
    raw.positions = m.positions;
    raw.triangles = m.triangles;
    build_opposite(raw);
    EXPECT_FALSE(is_manifold(raw));
    Surface s = prepare_surface(cat::disk(), nullptr);
    ASSERT_TRUE(is_manifold(s));
    for (uint32_t h = 0; h < s.opposite.size(); ++h)
      if (s.opposite[h] != kNone) {
        s.opposite[h] = kNone;
        break;
      }
    EXPECT_FALSE(is_manifold(s));
  }
  const auto comps = split_components(prepare_surface(cat::sphere_with_holes(), nullptr));
  ASSERT_EQ(comps.size(), 1u);
  CutStats st;
  const Disk disk = cut_to_disk(comps[0], {.holes = HoleMode::kCut}, &st);
  // check_disk: a face listed twice and another missing.
  {
    Disk broken = disk;
    broken.mesh.face_parent[0] = broken.mesh.face_parent[1];
    EXPECT_TRUE(fails_with([&] { check_disk(comps[0], broken, HoleMode::kCut, st); }, "component face"));
    Disk reversed = disk;
    std::reverse(reversed.boundary.begin(), reversed.boundary.end());
    EXPECT_TRUE(fails_with([&] { check_disk(comps[0], reversed, HoleMode::kCut, st); }, "no boundary halfedge"));
  }
  // check_square_map: an interior vertex moved out of the square; the map mirrored.
  {
    SquareMapOptions options;
    SquareMapStats ms;
    const auto uv = map_to_square(disk, options, &ms);
    std::vector<char> on_boundary(disk.mesh.num_vertices(), 0);
    for (uint32_t v : disk.boundary) on_boundary[v] = 1;
    auto moved = uv;
    for (uint32_t v = 0; v < moved.size(); ++v)
      if (!on_boundary[v]) {
        moved[v] = Vec2(0.5, 1.5);
        break;
      }
    EXPECT_TRUE(fails_with([&] { check_square_map(disk, moved, options, ms); }, "interior vertex"));
    auto mirrored = uv;
    for (Vec2& p : mirrored) p.x() = 1 - p.x();
    EXPECT_TRUE(fails_with([&] { check_square_map(disk, mirrored, options, ms); }, "folds"));
  }
  // check_atlas: two items on the same rectangle.
  {
    const std::vector<double> areas = {1, 2, 3};
    auto rects = layout_atlas(areas, 64, 64, 4);
    rects[2] = rects[1];
    EXPECT_TRUE(fails_with([&] { check_atlas(areas, rects, 64, 64, 4); }, "overlapped"));
  }
}

// Progress: stages in pipeline order, fractions within [0, 1] and never decreasing within a stage,
// calls never overlapping (the components are mapped in parallel and report from their threads).
// Options::size 0 (the default): as the CLI, the texture holds the input's used texels (docs/metrics.md),
// rounded up to a side that is a multiple of 4 - not a fixed 4096².
TEST(Pipeline, DefaultSizeKeepsTheInputsUsedTexels) {
  // A sheet whose UVs cover most of a 256 x 128 texture (26680 used texels: a 164² output).
  auto g = cat::param_grid(33, 17, false, false, [](int i, int j) { return Vec3(i / 16.0, j / 16.0, 0.0); });
  Image img(256, 128);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) img.at(x, y) = Rgba8{uint8_t(x), uint8_t(2 * y), 90, 255};
  const TexturedMesh in = cat::make_textured("sheet", g.positions, g.triangles, std::move(img));
  const double used = input_used_texels(in);
  ASSERT_GT(used, 20000);
  for (double aspect : {1.0, 0.0, 2.0}) {  // the square, the auto shape, a 2:1 texture
    SCOPED_TRACE(aspect);
    Options opt;
    opt.aspect = aspect;
    const Result r = optimize(in, opt);
    const int side = report_json(r.report)["options"]["size"];
    EXPECT_EQ(side, default_size(in));
    EXPECT_EQ(side % 4, 0);
    EXPECT_GE(double(side) * side, used);
    EXPECT_LT(double(side - 4) * (side - 4), used);
    ASSERT_EQ(r.output.textures.size(), 1u);
    const Image& img = r.output.textures[0].image;
    EXPECT_EQ(img.width % 4, 0);
    EXPECT_EQ(img.height % 4, 0);
    EXPECT_GE(double(img.width) * img.height, used) << "never fewer texels than the input uses";
    EXPECT_LT(double(img.width) * (img.height - 4), double(side) * side) << "and no more than the square's rounding";
    if (aspect == 1.0) EXPECT_EQ(img.width, side);
    if (aspect == 2.0) EXPECT_NEAR(double(img.width) / img.height, 2.0, 0.1);
    EXPECT_EQ(report_json(r.report)["aspect"]["chosen"].get<double>() == 1.0, img.width == img.height);
  }
  EXPECT_EQ(default_size(in, 64), 64) << "capped at max_side";
}

constexpr int kQuads = 500;

/// 500 separate unit quads of 2 triangles (the last a fan of 4), a 64² texture.
TexturedMesh many_quads() {
  std::vector<Vec3> positions;
  std::vector<Tri> triangles;
  for (int i = 0; i < kQuads; ++i) {
    const double x = 3.0 * (i % 25), y = 3.0 * (i / 25);
    const auto v = uint32_t(positions.size());
    positions.insert(positions.end(), {Vec3(x, y, 0), Vec3(x + 1, y, 0), Vec3(x + 1, y + 1, 0), Vec3(x, y + 1, 0)});
    if (i + 1 < kQuads) {
      triangles.push_back({v, v + 1, v + 2});
      triangles.push_back({v, v + 2, v + 3});
    } else {
      positions.push_back(Vec3(x + 0.5, y + 0.5, 0));  // v + 4: the centre
      for (uint32_t k = 0; k < 4; ++k) triangles.push_back({v + k, v + (k + 1) % 4, v + 4});
    }
  }
  Image img(64, 64);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) img.at(x, y) = Rgba8{uint8_t(4 * x), uint8_t(4 * y), 90, 255};
  return cat::make_textured("quads", positions, triangles, std::move(img));
}

// The default budget (TextureBudget::is_default): 500 separate quads (a city tile's buildings, a scan's floaters) whose used
// texels fit a 64² texture, which has room for only 256 rectangles of 4 x 4. The default budget grows
// to hold them all, each its own chart; an explicit size that cannot hold them is an InputError.
// The report lists the 256 largest components (the last quad is a fan of 4 triangles: listed though
// it comes last) and the totals over all of them.
TEST(Pipeline, TheDefaultBudgetGrowsToHoldEveryComponent) {
  const TexturedMesh in = many_quads();
  ASSERT_EQ(default_size(in), 64) << "the used texels alone ask for the smallest texture";
  Options opt;
  const Result r = optimize(in, opt);
  EXPECT_EQ(report_json(r.report)["options"]["size_grown_from"], 64);
  const int side = report_json(r.report)["options"]["size"];
  EXPECT_GE(side, 4 * int(std::ceil(std::sqrt(double(kQuads)))));
  EXPECT_LE(side, size_for_texels(64.0 * 64.0 + 16.0 * kQuads)) << "no more than 16 texels more per component";
  EXPECT_EQ(report_json(r.report)["metrics"]["charts"], kQuads);
  EXPECT_EQ(report_json(r.report)["metrics"]["flipped"], 0);
  EXPECT_EQ(r.output.num_triangles(), in.num_triangles());
  EXPECT_GT(report_json(r.report)["metrics"]["surface_psnr_db"].get<double>(), 30.0);
  const nlohmann::json& comps = report_json(r.report)["components"];
  ASSERT_EQ(comps.size(), 256u);
  EXPECT_EQ(report_json(r.report)["preparation"]["components"], kQuads);
  EXPECT_EQ(report_json(r.report)["preparation"]["components_listed"], 256);
  EXPECT_EQ(report_json(r.report)["preparation"]["holes_cut"], 0);
  size_t last = 0;
  for (size_t k = 0; k < comps.size(); ++k) {
    const size_t index = comps[k]["index"];
    if (k > 0) EXPECT_GT(index, last) << "in plan order";
    last = index;
  }
  EXPECT_EQ(comps.back()["triangles"], 4) << "the largest component is listed, wherever it comes";
  opt.size = 64;  // asked for: not grown
  EXPECT_THROW(optimize(in, opt), InputError);
  const Result grown = bake_plan(plan_charts(in, opt, TextureBudget{64, true}), in, opt);  // tightex's own budget of 64²
  EXPECT_EQ(report_json(grown.report)["options"]["size"], side);
  opt.size = 512;  // room enough: not grown, and reported as such
  EXPECT_TRUE(report_json(optimize(in, opt).report)["options"]["size_grown_from"].is_null());
}

// The default budget in the per-component layout: the 500 textures hold the budget together (not
// each the whole of it); an asked-for size is the largest's side.
TEST(Pipeline, PerComponentTexturesShareTheDefaultBudget) {
  const TexturedMesh in = many_quads();
  Options opt;
  opt.layout = Layout::kPerComponent;
  opt.map = MapKind::kHarmonic;
  const Result r = optimize(in, opt);
  ASSERT_EQ(r.output.textures.size(), size_t(kQuads));
  double texels = 0;
  int largest = 0;
  for (const Texture& t : r.output.textures) texels += double(t.image.width) * t.image.height, largest = std::max(largest, t.image.width);
  EXPECT_LE(texels, 64.0 * 64.0 + 16.0 * kQuads) << "the budget and each component's 4 x 4 least";
  EXPECT_EQ(largest, 4) << "each its 4 x 4 least";
  EXPECT_EQ(report_json(r.report)["metrics"]["flipped"], 0);
  EXPECT_EQ(report_json(r.report)["metrics"]["charts"], kQuads);
  opt.size = 64;
  const Result asked = optimize(in, opt);
  largest = 0;
  for (const Texture& t : asked.output.textures) largest = std::max(largest, t.image.width);
  EXPECT_EQ(largest, 64);
}

// Options::fine_fit changes only the texels (same texture coordinates), reports itself, and reproduces
// the input at least as well as the default fit.
TEST(Pipeline, FineFitChangesOnlyTheTexelsAndDoesNotLoseFidelity) {
  Options opt;
  opt.size = 128;
  const TexturedMesh in = cat::multi_component();
  const Result normal = optimize(in, opt);
  opt.fine_fit = true;
  const Result fine = optimize(in, opt);
  EXPECT_EQ(report_json(fine.report)["options"]["fine_fit"], true);
  EXPECT_EQ(report_json(normal.report)["options"]["fine_fit"], false);
  ASSERT_EQ(fine.output.corner_uv.size(), normal.output.corner_uv.size());
  for (size_t i = 0; i < fine.output.corner_uv.size(); ++i) ASSERT_EQ(fine.output.corner_uv[i], normal.output.corner_uv[i]) << i;
  const double p_normal = report_json(normal.report)["metrics"]["surface_psnr_db"],
               p_fine = report_json(fine.report)["metrics"]["surface_psnr_db"];
  EXPECT_GE(p_fine, p_normal) << "fit " << p_normal << " dB, fine fit " << p_fine << " dB";
  EXPECT_NE(fine.output.textures[0].image.pixels, normal.output.textures[0].image.pixels);
}

// Scans and merged exports hold triangles wound the other way. Repair orients each patch the way most
// of its area is wound, so the model stays one chart, as if it had come clean (slicing every such edge
// instead would split a sphere with every 5th triangle reversed into about 200 charts).
TEST(Pipeline, TrianglesWoundTheOtherWayAreReoriented) {
  const TexturedMesh clean = cat::sphere();
  TexturedMesh messy = clean;
  size_t reversed = 0;
  for (size_t t = 0; t < messy.num_triangles(); t += 5, ++reversed) {
    std::swap(messy.triangles[t][1], messy.triangles[t][2]);
    std::swap(messy.corner_uv[3 * t + 1], messy.corner_uv[3 * t + 2]);
  }
  RepairStats st;
  const Surface s = prepare_surface(messy, &st);
  EXPECT_EQ(st.reoriented_triangles, reversed);
  EXPECT_EQ(st.inconsistent_edges, 0u);
  size_t swapped = 0;  // faces whose corner 1 is the input triangle's corner 2
  for (size_t f = 0; f < s.num_faces(); ++f) swapped += s.input_corner[3 * f + 1] == 2;
  EXPECT_EQ(swapped, reversed);
  EXPECT_EQ(split_components(s).size(), 1u);
  Options opt;
  opt.size = 128;
  const Result a = optimize(clean, opt), b = optimize(messy, opt);
  EXPECT_EQ(report_json(b.report)["preparation"]["reoriented_triangles"], reversed);
  EXPECT_EQ(report_json(b.report)["metrics"]["charts"], 1);
  EXPECT_EQ(report_json(b.report)["metrics"]["flipped"], 0);
  EXPECT_EQ(report_json(b.report)["metrics"]["lost_triangles"], 0);
  EXPECT_NEAR(report_json(b.report)["metrics"]["surface_psnr_db"].get<double>(),
              report_json(a.report)["metrics"]["surface_psnr_db"].get<double>(), 0.5);
  // Written the way the rest is wound: every output triangle faces out of the sphere.
  for (size_t t = 0; t < b.output.num_triangles(); ++t) {
    const Tri& f = b.output.triangles[t];
    const Vec3 &p0 = b.output.positions[f[0]], &p1 = b.output.positions[f[1]], &p2 = b.output.positions[f[2]];
    ASSERT_GT((p1 - p0).cross(p2 - p0).dot(p0 + p1 + p2), 0.0) << "output triangle " << t;
  }
}

TEST(Pipeline, ProgressIsOrderedAndSerialised) {
  Options opt;
  opt.size = 128;
  std::vector<std::pair<std::string, double>> calls;
  std::atomic<int> inside{0};
  bool overlapped = false;
  opt.progress = [&](std::string_view stage, double f) {
    if (inside.fetch_add(1) != 0) overlapped = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));  // widen the window for an overlap
    calls.push_back({std::string(stage), f});
    inside.fetch_sub(1);
    return true;
  };
  const Result r = optimize(cat::multi_component(), opt);
  EXPECT_FALSE(overlapped);
  ASSERT_FALSE(calls.empty());
  const std::vector<std::string> order = {"repair", "components", "cut+map", "bake", "measure", "done"};
  size_t at = 0;
  double last = 0;
  for (const auto& [stage, f] : calls) {
    SCOPED_TRACE(stage + " " + std::to_string(f));
    const size_t i = size_t(std::find(order.begin(), order.end(), stage) - order.begin());
    ASSERT_LT(i, order.size()) << "unknown stage";
    ASSERT_GE(i, at) << "stages out of order";
    if (i > at) at = i, last = 0;
    EXPECT_GE(f, last);
    EXPECT_LE(f, 1.0);
    last = f;
  }
  EXPECT_EQ(calls.back().first, "done");
  EXPECT_EQ(calls.back().second, 1.0);
  EXPECT_TRUE(std::any_of(calls.begin(), calls.end(), [](const auto& c) { return c.first == "cut+map"; }));
}

// A progress callback that answers false stops the run with Cancelled, from whichever stage it is in
// (the maps and the bake call it from worker threads).
TEST(Pipeline, ProgressCallbackCancels) {
  for (const std::string stop_at : {"repair", "cut+map", "bake"}) {
    SCOPED_TRACE(stop_at);
    Options opt;
    opt.size = 128;
    std::atomic<int> calls_after{0};
    std::atomic<bool> stopped{false};
    opt.progress = [&](std::string_view stage, double) {
      if (stopped) calls_after++;
      if (stage == stop_at) stopped = true;
      return !stopped;
    };
    EXPECT_THROW(optimize(cat::multi_component(), opt), Cancelled);
    EXPECT_TRUE(stopped.load());
  }
}

// bake_plan refuses a mesh other than the one planned, with an InputError instead of reading out of
// bounds.
TEST(Pipeline, BakePlanRefusesAnotherMesh) {
  Options opt;
  opt.size = 64;
  const TexturedMesh planned = cat::multi_component();
  const Plan plan = plan_charts(planned, opt);
  TexturedMesh fewer = planned;
  fewer.triangles.pop_back();
  fewer.corner_uv.resize(3 * fewer.triangles.size());
  fewer.face_material.pop_back();
  EXPECT_THROW(bake_plan(plan, fewer, opt), InputError);
  TexturedMesh moved_uv = planned;
  moved_uv.corner_uv[0].x() += 0.25;
  EXPECT_THROW(bake_plan(plan, moved_uv, opt), InputError);
  EXPECT_THROW(bake_plan(Plan(), planned, opt), InputError);
  EXPECT_NO_THROW(bake_plan(plan, planned, opt));
}

// The run's bake, which frees the plan's maps once the output model holds them, bakes what bake_plan
// bakes; the plan still answers its queries (a component kept as it was included), and refuses a
// second bake instead of baking freed maps.
TEST(Pipeline, BakePlanReleasingMapsBakesTheSame) {
  Options opt;
  opt.size = 64;
  const TexturedMesh in = cat::multi_component();
  Plan plan = plan_charts(in, opt, PlanHooks{{1}});
  const Result kept = bake_plan(plan, in, opt);
  const size_t kept_components = plan.kept_components(), kept_triangles = plan.kept_triangles();
  ASSERT_EQ(kept_components, 1u);
  const Result released = bake_plan_releasing_maps(plan, in, opt);
  EXPECT_EQ(released.output.triangles, kept.output.triangles);
  EXPECT_EQ(released.output.corner_uv, kept.output.corner_uv);
  ASSERT_EQ(released.output.textures.size(), kept.output.textures.size());
  for (size_t i = 0; i < kept.output.textures.size(); ++i)
    EXPECT_TRUE(released.output.textures[i].image.pixels == kept.output.textures[i].image.pixels) << i;
  EXPECT_EQ(plan.kept_components(), kept_components);
  EXPECT_EQ(plan.kept_triangles(), kept_triangles);
  EXPECT_TRUE(plan_state(plan).disks[0].mesh.triangles.empty());
  EXPECT_THROW(bake_plan(plan, in, opt), InputError);
}

/// Whether `rects` tile each of the `sizes` pages exactly (every texel in one rectangle), each at least
/// `min_side` a side.
void expect_pages_tiled(const std::vector<Rect>& rects, const std::vector<std::pair<int, int>>& sizes, int min_side) {
  for (size_t p = 0; p < sizes.size(); ++p) {
    const auto [w, h] = sizes[p];
    std::vector<int> cover(size_t(w) * size_t(h), 0);
    for (const Rect& r : rects) {
      if (size_t(r.image) != p) continue;
      EXPECT_GE(std::min(r.w, r.h), min_side);
      ASSERT_TRUE(r.x >= 0 && r.y >= 0 && r.x + r.w <= w && r.y + r.h <= h);
      for (int y = r.y; y < r.y + r.h; ++y)
        for (int x = r.x; x < r.x + r.w; ++x) ++cover[size_t(y) * size_t(w) + size_t(x)];
    }
    EXPECT_EQ(std::count(cover.begin(), cover.end(), 1), long(cover.size())) << "page " << p;
  }
}

// The rate search's second bake (rescale_plan): the same charts on textures of half the side tile them
// as before, and bake every triangle unfolded with the texels used as fully as the first bake did,
// reading better than the first bake's images shrunk to that size; on textures of twice the side
// (a --target-psnr the first bake's texels do not reach), every edge doubles and the bake reads
// higher than the first. A scale at which the small components' rectangles would vanish lays the page
// out again; a plan with a kept component is left to be planned again.
TEST(Pipeline, RescaledPlanBakesTheSameChartsOnSmallerOrLargerTextures) {
  Options opt;
  opt.size = 256;
  {  // Two large components: every edge moves to the same fraction of the side.
    cat::Geometry g = cat::torus_geometry(32, 16);
    g.append(cat::disk_geometry(6, 24, 1.0), Vec3(3, 0, 0));
    const TexturedMesh two = cat::make_textured("torus_and_disk", g.positions, g.triangles, cat::checker_image(256, 256, 8));
    Plan p = plan_charts(two, opt);
    const std::vector<Rect> before = plan_state(p).rects;
    ASSERT_TRUE(rescale_plan(p, 0.5));
    const std::vector<Rect>& after = plan_state(p).rects;
    ASSERT_EQ(after.size(), 2u);
    for (size_t c = 0; c < 2; ++c) {
      EXPECT_EQ(after[c].x, std::lround(before[c].x / 2.0));
      EXPECT_EQ(after[c].x + after[c].w, std::lround((before[c].x + before[c].w) / 2.0));
      EXPECT_EQ(after[c].y + after[c].h, std::lround((before[c].y + before[c].h) / 2.0));
    }
    expect_pages_tiled(after, plan_state(p).image_size, 4);
    EXPECT_EQ(bake_plan(p, two, opt).report.flipped_triangles, 0u);

    Plan grown = plan_charts(two, opt);
    const Result first = bake_plan(grown, two, opt);
    ASSERT_TRUE(rescale_plan(grown, 2));
    ASSERT_EQ(plan_state(grown).image_size, (std::vector<std::pair<int, int>>{{512, 512}}));
    for (size_t c = 0; c < 2; ++c) {
      const Rect &r = plan_state(grown).rects[c], &b = before[c];
      EXPECT_EQ(std::tuple(r.x, r.y, r.w, r.h), std::tuple(2 * b.x, 2 * b.y, 2 * b.w, 2 * b.h)) << "component " << c;
    }
    expect_pages_tiled(plan_state(grown).rects, plan_state(grown).image_size, 4);
    const Result twice = bake_plan(grown, two, opt);
    EXPECT_EQ(twice.report.flipped_triangles, 0u);
    EXPECT_EQ(twice.report.lost_triangles, 0u);
    EXPECT_EQ(twice.output.textures[0].image.width, 512);
    EXPECT_GT(twice.report.surface_psnr_bake_db, first.report.surface_psnr_bake_db + 1);
  }
  TexturedMesh in = cat::multi_component();  // a torus, a disk and two floaters of 4 x 4 texels
  in.textures[0].image = cat::checker_image(256, 256, 8);
  Plan plan = plan_charts(in, opt);
  const Result full = bake_plan(plan, in, opt);
  ASSERT_TRUE(rescale_plan(plan, 0.5));
  const Plan::State& state = plan_state(plan);
  ASSERT_EQ(state.image_size, (std::vector<std::pair<int, int>>{{128, 128}}));
  expect_pages_tiled(state.rects, state.image_size, 4);  // the floaters' 2 x 2: laid out again
  const Result half = bake_plan(plan, in, opt);
  EXPECT_EQ(half.output.triangles, full.output.triangles);
  EXPECT_EQ(half.report.lost_triangles, 0u);
  EXPECT_EQ(half.report.flipped_triangles, 0u);
  EXPECT_EQ(half.report.charts, full.report.charts);
  EXPECT_GE(half.report.output_texels_used, full.report.output_texels_used - 0.02);
  TexturedMesh shrunk = full.output;
  shrunk.textures[0].image = shrink_image(full.output.textures[0].image, {}, 128, 128);
  EXPECT_GT(half.report.surface_psnr_bake_db, surface_psnr(in, shrunk) + 0.5);

  ASSERT_TRUE(rescale_plan(plan, 0.1));  // 12 x 12: the floaters' rectangles would round to nothing
  expect_pages_tiled(plan_state(plan).rects, plan_state(plan).image_size, 4);
  const Result tiny = bake_plan_releasing_maps(plan, in, opt);
  EXPECT_EQ(tiny.report.flipped_triangles, 0u);
  EXPECT_EQ(tiny.output.textures[0].image.width, 12);

  Plan with_kept = plan_charts(in, opt, PlanHooks{{1}});
  const std::vector<Rect> rects = plan_state(with_kept).rects;
  EXPECT_FALSE(rescale_plan(with_kept, 0.5));
  EXPECT_EQ(plan_state(with_kept).image_size, (std::vector<std::pair<int, int>>{{256, 256}}));
}

// A plan whose preparation (repair, components, seams, handles) was made from the geometry alone, as
// the CLI makes it while the textures decode, is the plan made in one call: the same charts and UVs,
// the same texture. A preparation of another mesh, or one used already, is an InputError.
TEST(Pipeline, PlanFromAPreparationWithoutPixelsIsTheSamePlan) {
  Options opt;
  opt.size = 96;
  const TexturedMesh input = cat::multi_component();  // a torus (one handle), a disk, a triangle, a quad
  TexturedMesh geometry = input;
  for (Texture& t : geometry.textures) {
    std::tie(t.width, t.height) = std::pair{t.image.width, t.image.height};
    t.image = Image();
  }
  PreparedMesh prepared = prepare_mesh(geometry, opt);
  const Plan at_once = plan_charts(input, opt);
  const Plan from_prepared = plan_charts(input, opt, std::move(prepared));
  const Plan::State &a = plan_state(at_once), &b = plan_state(from_prepared);
  ASSERT_EQ(a.components.size(), 4u);
  ASSERT_EQ(b.components.size(), a.components.size());
  EXPECT_EQ(b.uv, a.uv);
  const Report report_a = at_once.report(), report_b = from_prepared.report();
  for (const char* key : {"preparation", "components", "aspect"}) EXPECT_EQ(report_json(report_b)[key], report_json(report_a)[key]) << key;
  std::vector<std::string> stages;
  for (const auto& t : report_json(report_b)["timings"]) stages.push_back(t["stage"]);
  EXPECT_EQ(stages, (std::vector<std::string>{"repair", "seams+handles", "cut+map"}));
  const Result ra = bake_plan(at_once, input, opt), rb = bake_plan(from_prepared, input, opt);
  EXPECT_EQ(rb.output.corner_uv, ra.output.corner_uv);
  ASSERT_EQ(rb.output.textures.size(), ra.output.textures.size());
  EXPECT_EQ(rb.output.textures[0].image.pixels, ra.output.textures[0].image.pixels);
  EXPECT_EQ(report_json(ra.report)["metrics"]["flipped"], 0);

  EXPECT_THROW(plan_charts(input, opt, std::move(prepared)), InputError);  // used already
  TexturedMesh moved_uv = input;
  moved_uv.corner_uv[0].x() += 0.25;
  EXPECT_THROW(plan_charts(moved_uv, opt, prepare_mesh(geometry, opt)), InputError);
}

// --map detail: a flat sheet whose texture is a fine checker on its left half and one flat
// colour on its right. The detail map must give the checkered half clearly more texels per unit area
// than the flat half, stay fold-free, and reproduce the texture better than the area map at the same
// (tight) budget; the area map keeps both halves near the same density.
TEST(DetailMap, GivesTheTexelsToTheDetailedHalf) {
  auto g = cat::param_grid(33, 17, false, false, [](int i, int j) { return Vec3(i / 16.0, j / 16.0, 0.0); });
  Image img(256, 128);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      img.at(x, y) =
          x < img.width / 2 ? (((x / 2 + y / 2) % 2) ? Rgba8{230, 60, 40, 255} : Rgba8{30, 90, 200, 255}) : Rgba8{120, 160, 90, 255};
  const TexturedMesh input = cat::make_textured("half_detail", g.positions, g.triangles, std::move(img));
  auto run = [&](MapKind map) {
    Options opt;
    opt.size = 96;
    opt.map = map;
    const Result r = optimize(input, opt);
    // Output texel area per 3D area, mean over each half (by the triangle's 3D centroid).
    double texels[2] = {0, 0}, area[2] = {0, 0};
    const TexturedMesh& out = r.output;
    for (size_t t = 0; t < out.triangles.size(); ++t) {
      const Vec3 c = (out.positions[out.triangles[t][0]] + out.positions[out.triangles[t][1]] + out.positions[out.triangles[t][2]]) / 3.0;
      const int half = c.x() < 0.95 ? 0 : c.x() > 1.05 ? 1 : -1;
      if (half < 0) continue;
      texels[half] += std::abs(signed_area(out.corner_uv[3 * t], out.corner_uv[3 * t + 1], out.corner_uv[3 * t + 2])) * 96.0 * 96.0;
      area[half] +=
          triangle_area(out.positions[out.triangles[t][0]], out.positions[out.triangles[t][1]], out.positions[out.triangles[t][2]]);
    }
    const Metrics m = measure(input, out);
    EXPECT_EQ(m.flipped, 0u);
    EXPECT_EQ(m.lost_triangles, 0u);
    EXPECT_EQ(m.charts, 1u);
    return std::pair{(texels[0] / area[0]) / (texels[1] / area[1]), m.surface_psnr};
  };
  const auto [detail_ratio, detail_psnr] = run(MapKind::kDetail);
  const auto [area_ratio, area_psnr] = run(MapKind::kArea);
  EXPECT_GT(detail_ratio, 3.0);
  EXPECT_LT(area_ratio, 1.5);
  EXPECT_GT(area_ratio, 1 / 1.5);
  EXPECT_GT(detail_psnr, area_psnr + 1.0) << "detail " << detail_psnr << " dB, area " << area_psnr << " dB";
}

// input_detail: positive on a textured triangle with contrast, 0 on a flat colour, and finite (0) where
// absurd material transforms make the texel count overflow (int(inf) would be undefined behaviour).
TEST(DetailMap, InputDetailIsFiniteForAnyUnits) {
  TexturedMesh m =
      cat::make_textured("detail_units", {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}, {Tri{0, 1, 2}}, cat::checker_image(64, 64, 2));
  EXPECT_GT(input_detail(m, 0), 0.0);
  m.materials[0].uv_scale = {1e300, 1e300};
  const double huge = input_detail(m, 0);
  EXPECT_TRUE(std::isfinite(huge));
  m.materials[0].uv_scale = {1, 1};
  m.textures[0].image = Image(64, 64, Rgba8{50, 60, 70, 255});
  EXPECT_EQ(input_detail(m, 0), 0.0);
}

}  // namespace
}  // namespace tightex
