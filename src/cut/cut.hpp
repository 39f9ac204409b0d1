// The cut (paper §4.2): a component made a topological disk, with its holes capped or opened.
#pragma once
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/disk.hpp"
#include "core/stage_stats.hpp"
#include "core/surface.hpp"
#include "prepare/handles.hpp"
#include "tightex/options.hpp"

namespace tightex {

/// The cap budget of HoleMode::kFill unless the caller gives another (fraction of the component's area).
/// Chosen by measurement: docs/decisions.md.
constexpr double kFillBudget = 0.005;

/// What cut_to_disk does to a component.
enum class CutMethod {
  /// The paper's method: handles cut along short loops (remove_handles), holes capped or joined into
  /// the boundary (HoleMode), the cut graph, and slits to deep parts.
  kFull,
  /// The safety net where the full method fails on a component: no handle search, no caps, no slits,
  /// only the cut graph (the complement of a dual spanning tree, pruned), which makes a disk of any
  /// connected manifold surface.
  kPlain,
};

/// cut_to_disk's choices. The defaults are the paper's method with the default cap budget.
struct CutOptions {
  /// kFill: holes are capped with scaffolding (smallest first, within `fill_budget`), the longest loop
  /// stays the disk boundary; kCut: every hole is joined into the boundary.
  HoleMode holes = HoleMode::kFill;
  /// kFill's cap budget, as a fraction of the component's area.
  double fill_budget = kFillBudget;
  /// kFill caps the longest loop too when it fits the budget (smallest first, as the others), so a
  /// surface whose holes are all small becomes closed and gets the path cut. A 3-edge boundary loop
  /// cannot hold the square's four corners, but a cap is not always better: the caller compares both
  /// (see cut_to_disk_capped).
  bool cap_longest_loop = false;
  /// Component vertices to slit to as well (shortest path from the disk boundary), where a map crowded
  /// a region there; before the slits to deep parts.
  std::vector<uint32_t> slit_to;
  /// remove_handles(component) computed earlier, so that cutting again (more slits, another budget)
  /// does not search the handles again; null: computed here. Must outlive the call.
  const Denoised* handles_removed = nullptr;
  /// The input's texture seams (find_texture_seams, one flag per halfedge of the component), preferred
  /// by the handle loops, the hole connections and the cut graph (not by the slits, which aim at depth);
  /// empty: none. A view: the flags must outlive the call.
  std::span<const char> seams;
  CutMethod method = CutMethod::kFull;
};

/// Turns a connected manifold surface into a topological disk (paper §4.1 holes and handles, §4.2 the
/// cut): handles are cut along short loops (remove_handles); holes are capped with scaffolding or joined
/// into the boundary (CutOptions::holes); the cut graph is computed (compute_cut_graph) and cut along
/// (cut_along_edges); a deep disk is slit from its boundary to its deepest vertex while that lies deeper
/// than a flat round disk of its perimeter allows (a harmonic map crowds exponentially with depth).
/// The real faces (not scaffolding) of the result always hang together through uncut edges, so the
/// component becomes one chart: should the caps be the only link between some of them, the holes are
/// opened instead (CutStats::method says "holes opened").
/// Requires: `component` connected and manifold (`opposite` built), e.g. an element of split_components.
/// Guarantees: a disk (one boundary loop, Euler characteristic 1) whose face_parent / vertex_parent map
/// into `component` (kNone: scaffolding) and whose input map is the component's; `stats`, if given,
/// says what was done.
/// Throws: InternalError if the result is not a disk (a broken invariant: it always is).
Disk cut_to_disk(const Surface& component, const CutOptions& options = {}, CutStats* stats = nullptr);

/// The trial beside the usual cut: cut_to_disk with CutOptions::cap_longest_loop, or nullopt where the
/// longest loop could not be capped (it does not fit the budget, the caps would split the chart, or the
/// capped surface's cut gives no disk); the caller then keeps the usual cut. `stats` is written only
/// when a disk is returned.
std::optional<Disk> cut_to_disk_capped(const Surface& component, CutOptions options, CutStats* stats = nullptr);

}  // namespace tightex
