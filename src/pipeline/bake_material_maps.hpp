// The maps a material binds besides its base colour (MaterialSlot), re-baked through the same layout as the
// base colour: one output map per group of slots that read the same input textures (glTF's occlusion
// and metallic-roughness in one image stay one image), one image per page, each at the size its content
// needs (Options::material_map_budget_db).
#pragma once
#include <string>
#include <vector>

#include "pipeline/output_model.hpp"
#include "tightex/options.hpp"

namespace tightex {

/// Bakes every other map of `input` into `om` (after its base colour pages are baked): appends the new
/// textures to om.mesh.textures, sets the new materials' `maps`, and sets om.mesh.corner_tangent (the
/// output's frames: from the new texture coordinates for mapped triangles, the input's for kept ones)
/// when the input has a tangent-space normal map or tangents. Returns the report's "maps" entries.
/// Requires: `om` built by build_output_model from `input`, its first om.new_images textures baked.
/// Throws: nothing but std::bad_alloc.
std::vector<MaterialMapEntry> bake_material_maps(const TexturedMesh& input, const Options& options, OutputModel& om);

}  // namespace tightex
