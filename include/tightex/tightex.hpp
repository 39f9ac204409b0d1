// tightex: global-parameterization texture space optimization (Chen, Ren, Lei, Luo, Gu; arXiv 2406.04115).
//
// The library's public entry point: take a textured mesh with a loose, fragmented UV atlas and return
// the same geometry with one chart per connected surface, each filling its own rectangle of texture.
#pragma once
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "core/mesh.hpp"
#include "io/image_io.hpp"
#include "layout/layout.hpp"
#include "topology/topology.hpp"

namespace tightex {

enum class Layout { kAtlas, kPerComponent };

struct Options {
  int size = 4096;                 // atlas: the texture's side; per-component: the largest texture's side
  Layout layout = Layout::kAtlas;
  HoleMode holes = HoleMode::kFill;
  /// Compute the METRICS.md figures into report["metrics"]. A caller that writes the result can turn
  /// this off and run measure() beside the write (the CLI does).
  bool measure = true;
  /// Called with a stage name and the fraction [0,1] done; may be called from the calling thread only.
  std::function<void(std::string_view stage, double fraction)> progress;
};

struct Result {
  TexturedMesh output;      // geometry of the input (same corner positions), new UVs, new textures
  nlohmann::json report;    // what was done and measured (see ../shared/METRICS.md)
};

/// The geometric half of the method (repair, components, handles, holes, cut, layout, map): needs the
/// input's geometry and UVs, not its texture pixels, so a caller can decode textures meanwhile.
struct Plan {
  Surface surface;                       // repaired; face_parent -> input triangle
  std::vector<Surface> components;       // face_parent -> surface face
  std::vector<Disk> disks;               // face_parent -> component face (kNone: scaffolding)
  std::vector<std::vector<Vec2>> uv;     // per disk vertex, unit square
  std::vector<Rect> rects;               // per component
  std::vector<std::pair<int, int>> image_size;
  int num_images = 1;
  nlohmann::json report;                 // what was done so far
};
Plan plan_charts(const TexturedMesh& input, const Options& options);

/// The texture half: output model, bake, metrics. `input` must be the mesh the plan was made from
/// (same triangles and UVs), now with its textures loaded.
Result bake_plan(const Plan& plan, const TexturedMesh& input, const Options& options);

/// Runs the whole method: repair, components, holes, cut, harmonic map, layout, bake, metrics.
/// Requires a mesh as returned by read_obj (validated). Throws InputError for input it cannot handle
/// (e.g. nothing left after dropping degenerate triangles) and InternalError for broken invariants.
Result optimize(const TexturedMesh& input, const Options& options);

}  // namespace tightex
