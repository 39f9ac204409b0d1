// The output model (before its textures are baked): the input's positions and triangles (same
// corners, wound as the repaired surface), the new texture coordinates of the mapped components, and
// the kept components as they were.
#pragma once
#include <array>
#include <map>
#include <optional>
#include <string>
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
  /// The plan's Plan::State::fixed_map_scales: per map name, its side over the base colour's, taken as
  /// it is instead of sized again.
  std::map<std::string, double> fixed_map_scales;
  /// Per material of the mapped triangles (the first materials of mesh, one per input material and
  /// new image they use): the input material it copies (-1: none) and its new image.
  std::vector<std::pair<int32_t, int>> mapped_materials;
};

/// Builds the output model of `plan` for `input` (the mesh it was made from). Each input material
/// that mapped triangles use becomes one new material per new image it spans (OutputModel::
/// mapped_materials): its name, factors and statements as they were, its base colour the new image.
/// Its colour factor stays where the input material had a texture (the OBJ writer writes it as Kd, the
/// glTF writer keeps the material's own factor); where the material had none, its colour is baked into
/// the new image and the factor is white.
OutputModel build_output_model(const Plan::State& plan, const TexturedMesh& input);

}  // namespace tightex
