// Topological denoising (paper §4.1, Fig. 5): every handle of a component is cut along a short
// non-separating loop until the component has genus 0.
#pragma once
#include <span>
#include <vector>

#include "core/surface.hpp"

namespace tightex {

/// Cuts the handles of a component along short loops (paper §4.1, topological denoising): while the
/// component has genus g > 0, finds a short non-separating loop (the cheapest non-separating loop
/// through each of a few roots placed on the handles by a global tree-cotree, each root's search
/// reaching only as far as a cheaper loop could, its loops told apart by loop_classes; edges on
/// `seams` cost kSeamCost of their length), tightens it
/// (roots along the loop and in a band beside it, while the loop gets cheaper) and cuts along it, which
/// leaves two new boundary loops. The hole stage then treats those like any hole.
/// Requires: `component` connected and manifold (`opposite` built); `seams` empty or one flag per
/// halfedge of `component` (find_texture_seams).
/// Guarantees: a genus-0 surface with the same triangles; face_parent / vertex_parent map into
/// `component`, the input map is inherited from it; `loop_lengths` (if given) gets each loop's 3D length.
/// Throws: InternalError if cutting a loop fails to lower the genus (a broken invariant).
Surface remove_handles(const Surface& component, std::vector<double>* loop_lengths, std::span<const char> seams = {});

/// remove_handles' result kept for later cuts of the same component, so that cutting again (with more
/// slits, another cap budget) does not search the handles again.
struct Denoised {
  Surface surface;                   // remove_handles(component, ...)
  std::vector<double> handle_loops;  // its loop_lengths
};

}  // namespace tightex
