// The output model (before its textures are baked): the input's positions and triangles (same
// corners, wound as the repaired surface), the new texture coordinates of the mapped components, and
// the kept components as they were.
#pragma once
#include <vector>

#include "bake/bake.hpp"
#include "pipeline/plan_state.hpp"

namespace tightex {

struct OutputModel {
  TexturedMesh mesh;  // its first `new_images` textures are the new, still black ones
  int new_images = 0;
  std::vector<BakeTriangle> bake_triangles;  // every mapped triangle, as the bake reads it
  std::vector<Rect> rects;                   // every mapped component's rectangle (images renumbered)
  /// Per corner of mesh (3 per triangle): which corner of its input triangle (mesh.input_triangle) it is.
  std::vector<uint8_t> input_corner;
  bool budget_is_default = true;  // the plan's TextureBudget::is_default
};

/// Builds the output model of `plan` for `input` (the mesh it was made from).
OutputModel build_output_model(const Plan::State& plan, const TexturedMesh& input);

}  // namespace tightex
