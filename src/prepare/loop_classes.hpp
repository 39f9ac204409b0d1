// Whether a closed path of edges separates its surface, decided edge by edge: a Z2 cohomology basis of
// the surface with each hole capped (the handle search's notion of a hole: one point). Each edge gets a
// bit per generator; a closed path is non-separating exactly where the xor of its edges' bits is not
// zero. So the handle search can test a loop through a root from the part of the surface within the
// loop's reach, without a tree-cotree over the whole surface per root.
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "core/graph.hpp"
#include "core/surface.hpp"

namespace tightex {

/// One class per edge: `words` 64-bit words, bit i the value of basis cocycle i on the edge (2g bits:
/// 8 bytes an edge up to genus 32, 64 at genus 256).
struct LoopClasses {
  size_t words = 0;            // ceil(2g / 64); 0 on a genus-0 surface
  std::vector<uint64_t> bits;  // per edge, `words` words
  std::span<const uint64_t> of_edge(uint32_t e) const { return {bits.data() + size_t(e) * words, words}; }
};

/// The classes of `s`'s edges. `tree_pred`: any spanning tree of s's vertices (breadth_first_tree, a
/// shortest-path tree), per vertex its tree edge towards the root (kNone at the root); every tree edge
/// gets class 0. The classes differ from tree to tree; which loops they call separating does not.
/// `loops`: s's boundary loops (boundary_loops), each capped by one face.
/// Construction: a spanning tree of the dual graph (faces and caps) over the edges off the primal tree;
/// the 2g edges in neither tree each own one bit, and the dual tree's edges are solved leaf first so
/// that the xor over every face's and cap's edges is 0 (a cocycle). The loop of leftover edge i (it and
/// the tree paths to the root) then has exactly bit i, so the 2g cocycles are independent and span the
/// cohomology: a closed path is null-homologous (separating) iff every bit of its xor is 0.
/// Throws: InternalError if the trees do not span s (s not connected, or tree_pred not a spanning tree).
LoopClasses loop_classes(const Surface& s, const EdgeGraph& g, const std::vector<std::vector<uint32_t>>& loops,
                         const std::vector<uint32_t>& tree_pred);

/// The cheapest non-separating loop through one root: a Dijkstra search from the root (on `weight`:
/// the handle search gives boundary edges 0, so a hole is one point) that tests each non-tree interior
/// edge (v, w) as it closes the loop v -> root -> w -> v, by its class. Arrays the size of the surface,
/// kept from root to root and reset only where the last search reached: a search costs the ball it
/// covers, which ends where no cheaper loop can close (2 x the distance reached >= the best loop's cost).
class RootLoopSearch {
 public:
  RootLoopSearch(const Surface& s, const EdgeGraph& g, const LoopClasses& classes, std::span<const double> weight);
  /// The closing edge of the cheapest non-separating loop through `root` that reaches no vertex
  /// farther than `radius` (ties: the higher edge id, as the tree-cotree's first leftover edge), or
  /// kNone. Its loop: the edge and the tree paths (pred) from its ends to the root; its cost
  /// dist(from) + dist(to) + g.cost[e] (loop_cost).
  uint32_t search(uint32_t root, double radius);
  double loop_cost() const { return loop_cost_; }
  /// Per vertex, the tree edge towards the last search's root (kNone where it did not reach).
  const std::vector<uint32_t>& pred() const { return pred_; }

 private:
  void reset();
  void settle(uint32_t v);                               // v's distance is final: its class, from its parent's
  void try_closing(uint32_t v, uint32_t w, uint32_t e);  // edge e from v to settled w closes a loop: the cheapest yet?

  const Surface& s_;
  const EdgeGraph& g_;
  const LoopClasses& classes_;
  std::span<const double> weight_;
  std::vector<double> dist_;
  std::vector<uint32_t> pred_;
  std::vector<char> settled_;
  // Per settled vertex, the xor of the classes along its tree path: written when the vertex settles,
  // never read before, so left uninitialised and only the pages of the ball searched are ever touched
  // (words x 8 bytes a vertex, per root searched at once).
  std::unique_ptr<uint64_t[]> vertex_class_;
  std::vector<uint32_t> reached_;
  std::vector<std::pair<double, uint32_t>> heap_;
  uint32_t closing_edge_ = kNone;
  double loop_cost_ = 0;
};

}  // namespace tightex
