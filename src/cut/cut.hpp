// The cut (paper §4.2): a component made a topological disk, with its holes capped or opened.
#pragma once
#include <string>
#include <vector>

#include "core/surface.hpp"
#include "prepare/handles.hpp"
#include "tightex/options.hpp"

namespace tightex {

/// The cap budget of HoleMode::kFill unless the caller gives another (fraction of the component's area).
constexpr double kFillBudget = 0.005;

struct CutStats {
  Topology before;              // of the component as given (holes not yet filled)
  size_t holes_filled = 0;
  size_t holes_cut = 0;         // joined into the disk boundary
  double fill_budget = 0;       // the cap budget it was cut with (fraction of the component's area)
  double filled_area = 0;       // the caps' area (fraction of the component's area)
  size_t cut_edges = 0;         // interior edges cut open
  double cut_length = 0;        // their 3D length
  double seam_length = 0;       // 3D length of the seam the output gets here (handle loops, holes joined, cut, slits)
  double seam_on_input_seams = 0;  // the part of it on the input's texture seams
  std::string method;           // "disk", "path", "cut-graph", with "+slit" when deep parts were slit
  size_t slits = 0;             // slits from the boundary to deep vertices
  std::string fallback_reason;  // non-empty: the full method failed here and the plain cut was used
  std::vector<double> handle_loops;  // 3D length of each handle loop cut (see remove_handles)
  size_t longest_loop_edges = 0;  // edges of the longest boundary loop (handles removed, before any cap; 0: closed)
  bool longest_loop_capped = false;  // cap_kept asked for it and the longest loop was capped too
  // Set by the pipeline where a small longest hole was tried both ways (kept as the boundary, then
  // capped too): each map's estimated colour error (resampling_mse); empty where not tried.
  std::vector<double> compared_mse;
};

struct Disk {
  Surface mesh;                 // a topological disk; face_parent -> component face (kNone: scaffolding)
                                // vertex_parent -> component vertex (kNone: scaffolding)
  std::vector<uint32_t> boundary;  // boundary vertices in order (counter-clockwise w.r.t. the faces)
};

/// Turns a connected manifold surface into a topological disk (one boundary loop, Euler characteristic
/// 1): handles are cut along short loops (remove_handles); holes are capped with scaffolding or joined
/// into the boundary (see HoleMode; the longest loop is kept as the boundary unless `cap_kept`); a closed genus-0 surface is cut along the shortest path between two far-apart vertices
/// (double Dijkstra sweep: the paper's single seam); otherwise a cut graph is built by tree-cotree
/// (shortest-path tree + greedy dual tree, Erickson & Whittlesey 2005) and pruned of dangling branches.
/// Throws InternalError if the result is not a disk (it always should be).
/// `slit_to`: component vertices to slit to as well (shortest path from the disk boundary), used when
/// a map crowded a region there.
/// `denoised`: remove_handles(component) computed earlier (its loop lengths in `handle_loops`), so that
/// cutting again with more slits does not search the handles again; null: computed here.
/// `plain`: the safety net used when the full method throws on a component: no handle search, no caps,
/// no slits, only the cut graph (the complement of a dual spanning tree, pruned), which makes a disk
/// of any connected manifold surface.
/// `seams`: the input's texture seams (find_texture_seams), preferred by the handle loops, the hole
/// connections and the cut graph (not by the slits, which aim at depth); empty: none.
/// `fill_budget`: kFill's cap budget (fraction of the component's area).
/// `cap_kept`: kFill caps the longest loop too when it fits the budget (smallest first, as the others),
/// so a surface whose holes are all small becomes closed and gets the path cut; the caller compares
/// both (a 3-edge boundary loop cannot hold the square's four corners, but a cap is not always better).
/// The real faces (not scaffolding) of the result always hang together through uncut edges, so the
/// component becomes one chart: where the cut graph would leave the caps as the only link between some
/// of them, it is rebuilt from a dual tree that joins the real faces before it enters any cap (the
/// cut then runs through the caps; CutStats::method says "real-first"); should that still fail, the
/// holes are opened instead ("holes opened").
Disk cut_to_disk(const Surface& component, HoleMode holes, CutStats* stats,
                 const std::vector<uint32_t>& slit_to = {}, const Denoised* denoised = nullptr, bool plain = false,
                 const std::vector<char>& seams = {}, double fill_budget = kFillBudget, bool cap_kept = false);

}  // namespace tightex
