#include "pipeline/validate.hpp"

#include <cmath>

#include "core/error.hpp"

namespace tightex {

void validate_mesh(const TexturedMesh& m) {
  const std::string& f = m.source.empty() ? std::string("mesh") : m.source;
  if (m.triangles.empty()) fail_input("{}: no triangles", f);
  if (m.corner_uv.size() != 3 * m.triangles.size())
    fail_input("{}: {} texture coordinates for {} triangles (needs 3 per triangle)", f, m.corner_uv.size(), m.triangles.size());
  if (m.face_material.size() != m.triangles.size())
    fail_input("{}: {} face materials for {} triangles", f, m.face_material.size(), m.triangles.size());
  for (size_t v = 0; v < m.positions.size(); ++v)
    if (!m.positions[v].allFinite()) fail_input("{}: vertex {} has a NaN or infinite coordinate", f, v);
  for (size_t t = 0; t < m.triangles.size(); ++t) {
    for (uint32_t v : m.triangles[t])
      if (v >= m.positions.size()) fail_input("{}: triangle {} uses vertex {} (mesh has {})", f, t, v, m.positions.size());
    for (int k = 0; k < 3; ++k)
      if (!m.corner_uv[3 * t + size_t(k)].allFinite()) fail_input("{}: triangle {} has a NaN or infinite texture coordinate", f, t);
    const int32_t mat = m.face_material[t];
    if (mat < -1 || mat >= int32_t(m.materials.size()))
      fail_input("{}: triangle {} uses material {} (mesh has {})", f, t, mat, m.materials.size());
  }
  for (size_t i = 0; i < m.materials.size(); ++i) {
    if (m.materials[i].texture >= int(m.textures.size()))
      fail_input("{}: material {} uses texture {} (mesh has {})", f, i, m.materials[i].texture, m.textures.size());
    for (size_t s = 0; s < kMaterialSlots; ++s)
      if (m.materials[i].maps[s] < -1 || m.materials[i].maps[s] >= int(m.textures.size()))
        fail_input("{}: material {} binds texture {} as its {} map (mesh has {})", f, i, m.materials[i].maps[s],
                   material_slot_name(MaterialSlot(s)), m.textures.size());
  }
  if (!m.source_mesh.empty()) {
    if (m.source_mesh.size() != m.triangles.size())
      fail_input("{}: {} source meshes for {} triangles (needs 1 per triangle or none)", f, m.source_mesh.size(), m.triangles.size());
    std::vector<uint32_t> vertex_mesh(m.positions.size(), kNone);
    for (size_t t = 0; t < m.triangles.size(); ++t)
      for (uint32_t v : m.triangles[t]) {
        if (vertex_mesh[v] != kNone && vertex_mesh[v] != m.source_mesh[t])
          fail_input("{}: vertex {} is used by source meshes {} and {} (they share no vertex)", f, v, vertex_mesh[v], m.source_mesh[t]);
        vertex_mesh[v] = m.source_mesh[t];
      }
  }
  if (!m.source_mesh_area_scale.empty()) {
    for (size_t i = 0; i < m.source_mesh_area_scale.size(); ++i)
      if (!(m.source_mesh_area_scale[i] >= 0 && std::isfinite(m.source_mesh_area_scale[i])))
        fail_input("{}: source mesh {} has area scale {} (needs a finite one, 0 or more)", f, i, m.source_mesh_area_scale[i]);
    for (size_t t = 0; t < m.source_mesh.size(); ++t)
      if (m.source_mesh[t] >= m.source_mesh_area_scale.size())
        fail_input("{}: triangle {} is of source mesh {}, which has no area scale ({} given)", f, t, m.source_mesh[t],
                   m.source_mesh_area_scale.size());
  }
  if (!m.corner_tangent.empty() && m.corner_tangent.size() != 3 * m.triangles.size())
    fail_input("{}: {} corner tangents for {} triangles (needs 3 per triangle or none)", f, m.corner_tangent.size(), m.triangles.size());
}

}  // namespace tightex
