// What a Plan holds (tightex.hpp keeps it opaque): every component with its map back to the input,
// its disk and map onto the unit square, its rectangle of texture, and the report so far.
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/surface.hpp"
#include "cut/cut.hpp"
#include "layout/layout.hpp"
#include "pipeline/map_component.hpp"
#include "prepare/repair.hpp"
#include "report/report.hpp"
#include "tightex/tightex.hpp"

namespace tightex {

/// Input triangles that the surface leaves out and the output still holds (Plan::State::set_aside).
struct SetAside {
  std::vector<std::pair<uint32_t, uint32_t>> repeats;  // (repeat, the triangle it repeats), sorted
  std::vector<uint32_t> untextured;                    // no texture to bake from: kept as they are
};

/// The texel budget a plan is made for: the texture's side, and whether it is tightex's own (the
/// input's used texels, or the fraction of them that --target-psnr tries) rather than a side or texel
/// count the caller asked for. A default budget's atlas grows to hold a 4 x 4 rectangle per component,
/// its per-component textures hold it together, and its maps may be baked larger than the base colour;
/// an asked-for one is what the caller's engine or delivery holds.
struct TextureBudget {
  int side = 0;
  bool is_default = true;
};

/// The budget `options` ask for: `size`, else the side for `texels`, else default_size (at most 16384
/// without allow_large_textures). Throws InputError for both given, or a side out of range.
TextureBudget texture_budget(const TexturedMesh& input, const Options& options);

struct Plan::State {
  std::vector<Surface> components;    // Surface::input_face -> input triangle
  std::vector<Disk> disks;            // per component; face_parent -> component face (kNone: scaffolding)
  std::vector<std::vector<Vec2>> uv;  // per component, per disk vertex, in the unit square
  std::vector<Rect> rects;            // per component
  std::vector<std::pair<int, int>> image_size;
  /// Per component: empty when it was mapped; otherwise why it could not be. Such a component keeps
  /// its input texture coordinates and a copy of its input material(s) and texture(s) (bake_plan), so
  /// no triangle is ever dropped; its disk and uv are empty.
  std::vector<std::string> kept;
  /// Input triangles outside the components that the output still holds: exact repeats, each with the
  /// triangle it repeats (written as a copy of it), and triangles with nothing to bake (no texture),
  /// written as they came.
  SetAside set_aside;
  TextureBudget budget;            // the budget asked for (before an atlas grew to hold every component)
  ReportData report;               // what was done so far
  nlohmann::json report_json;      // the same, as Plan::report() gives it
  uint64_t input_fingerprint = 0;  // input_fingerprint() of the mesh planned
  /// Per material map (its report name, "normal", "metallic_roughness", ...), its side over the base
  /// colour's as an earlier bake sized it (report "maps" scale), baked so again without sizing it anew
  /// (rescale_plan). Empty: every map sized by Options::material_map_budget_db.
  std::map<std::string, double> fixed_map_scales;
  /// The mapped components' surfaces, disks and texture coordinates were freed by a bake
  /// (bake_plan_releasing_maps): the plan cannot be baked again.
  bool maps_released = false;
};

/// What `plan` holds. Throws InputError for an empty plan (one not made by plan_charts).
const Plan::State& plan_state(const Plan& plan);
Plan::State& mutable_plan_state(Plan& plan);

/// bake_plan for a caller that is done with the plan's maps once they are baked (the library's own
/// run): the mapped components' surfaces, disks and texture coordinates are freed as soon as the
/// output model holds their triangles, before the bake, whose peak then holds no second copy of the
/// surface. The plan keeps its report, texture sizes and kept components (Plan's queries answer as
/// before); baking it again is an InputError.
Result bake_plan_releasing_maps(Plan& plan, const TexturedMesh& input, const Options& options);

/// The plan's charts on textures `scale` of each side (texture_side_at), for a second bake at fewer or
/// more texels that skips the planning: every rectangle's edges move to the same fraction of its
/// texture, so the rectangles tile the new textures as they tiled the old, and the texture
/// coordinates are kept fold-free in float at the new size; each material map
/// keeps its side over the base colour's from `map_scales` (the first bake's report "maps": name,
/// scale) instead of being sized again, as the texel search judged every image shrunk alike. Returns false,
/// the plan unchanged, where it cannot: its maps released, a component kept with its input texture
/// coordinates, or a page that cannot hold its rectangles at 4 texels a side; then plan again at the
/// new budget.
bool rescale_plan(Plan& plan, double scale, const std::map<std::string, double>& map_scales = {});

/// A hash of what the plan depends on in the input (vertex and triangle counts, triangles, texture
/// coordinates, materials), so bake_plan can refuse another mesh.
uint64_t input_fingerprint(const TexturedMesh& input);

/// What prepare_mesh made: the repaired mesh's components (Surface::input_face -> input triangle) and,
/// per component, its seams and handle removal (nullopt where that search met an InternalError:
/// map_component meets it again and reports it as the map's fallback).
struct PreparedMesh::State {
  uint64_t input_fingerprint = 0;  // input_fingerprint() of the mesh prepared
  RepairStats repair;
  SetAside set_aside;
  std::vector<Surface> components;
  std::vector<std::optional<CutInputs>> cut_inputs;  // all nullopt where the input is tight (not cut)
  double tight_utilization = 0;                      // tight_utilization(): > 0 where it is one chart per component
  std::vector<StageTiming> timings;                  // "repair", "seams+handles"
};

/// Each component's cut_inputs, computed in parallel (nullopt where it throws InternalError).
std::vector<std::optional<CutInputs>> prepare_cut_inputs(const TexturedMesh& input, const std::vector<Surface>& components);

/// Per triangle of `geometry`, whether it has no texture to bake from (no material, or one without a
/// texture); `list` gets them in order. Throws InputError when no triangle has one: nothing to bake.
std::vector<char> untextured_triangles(const TexturedMesh& geometry, std::vector<uint32_t>& list);

/// Scales each component (one source mesh's surface) by the square root of its source mesh's area
/// scale (TexturedMesh::source_mesh_area_scale): its share of the texels, and its density, follow the
/// area the scene shows of it. The maps are the same up to that similarity; the output keeps the
/// input's own positions.
void scale_to_world_area(const TexturedMesh& geometry, std::vector<Surface>& components);

/// prepare_mesh's work, without the wrapper.
std::unique_ptr<PreparedMesh::State> prepare_state(const TexturedMesh& geometry, const Options& options);

/// plan_charts with test hooks (tests only).
Plan plan_charts(const TexturedMesh& input, const Options& options, const PlanHooks& hooks);

/// plan_charts at `budget` instead of the one `options` ask for, its first part from `prepared` where
/// given (as plan_charts(input, options, prepared) takes it).
Plan plan_charts(const TexturedMesh& input, const Options& options, const TextureBudget& budget, PreparedMesh* prepared = nullptr);

}  // namespace tightex
