// The output model (before its textures are baked): the input's positions and triangles (same
// corners, wound as the repaired surface), the new texture coordinates of the mapped components, and
// the kept components as they were.
#pragma once
#include <array>
#include <optional>
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

/// The colour factor (Material::kd) every textured material of `mesh` shares, or nullopt where they
/// differ or none has a texture.
std::optional<std::array<double, 3>> shared_texture_factor(const TexturedMesh& mesh);

/// Builds the output model of `plan` for `input` (the mesh it was made from). Its new materials take
/// the factor every textured material of `input` shares (OBJ's Kd, glTF's baseColorFactor: the same
/// number; white where they differ), so that each viewer shows the output as it shows the input: the
/// OBJ writer writes it as Kd (the MTL specification and three.js multiply map_Kd by it, Blender and
/// MeshLab show the texture alone; Meshroom writes Kd 0.6 beside its textures). The glTF writer leaves
/// a textured material's factor white: every glTF viewer multiplies it, which would darken what those
/// OBJ viewers show as it is.
OutputModel build_output_model(const Plan::State& plan, const TexturedMesh& input);

}  // namespace tightex
