// A component cut to a topological disk: what the cut (src/cut) makes and the map (src/param) lays
// onto the square.
#pragma once
#include <cstdint>
#include <vector>

#include "core/surface.hpp"

namespace tightex {

/// A component cut to a topological disk: the chart-to-be.
struct Disk {
  Surface mesh;                    // a topological disk; face_parent -> component face (kNone: scaffolding)
                                   // vertex_parent -> component vertex (kNone: scaffolding)
  std::vector<uint32_t> boundary;  // boundary vertices in order (counter-clockwise w.r.t. the faces)
};

}  // namespace tightex
