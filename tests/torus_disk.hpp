// A torus of 4608 vertices cut to a disk (its boundary is the cut: two loops around it), the surface
// the multigrid and multilevel solvers' tests map.
#pragma once
#include <vector>

#include "cut/cut.hpp"
#include "mesh_catalogue.hpp"
#include "prepare/components.hpp"
#include "prepare/repair.hpp"

namespace tightex::testing {

inline Disk torus_disk() {
  auto g = torus_geometry(96, 48);
  const TexturedMesh mesh = make_textured("torus", g.positions, g.triangles);
  const std::vector<Surface> parts = split_components(prepare_surface(mesh, nullptr));
  return cut_to_disk(parts.at(0), CutOptions{}, nullptr);
}

}  // namespace tightex::testing
