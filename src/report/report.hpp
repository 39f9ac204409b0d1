// The report of one run, typed: what each stage did and cost, filled by the stages and the CLI and
// written as JSON in one place (to_json). Every figure here is one of report.json's; the JSON key each
// field becomes is named beside it where it differs from the field's name.
#pragma once
#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/stage_stats.hpp"
#include "core/surface.hpp"
#include "report/metrics.hpp"
#include "tightex/io.hpp"
#include "tightex/options.hpp"
#include "tightex/report.hpp"

namespace tightex {

/// "input": the model as read.
struct InputSummary {
  std::string file;  // TexturedMesh::source
  size_t vertices = 0, triangles = 0, materials = 0, textures = 0;
  /// What the OBJ reader did beyond plain reading ("polygons_triangulated", "paths_found"); the CLI
  /// sets it (the library is given a mesh already read). `lines` is not written.
  std::optional<ModelReadStats> reader;
};

/// "options": the choices the run was made with, after defaults were resolved.
struct OptionsUsed {
  int size = 0;             // the texture side used (atlas) or the largest texture's (per-component)
  int size_grown_from = 0;  // the default budget's side before it grew to hold every component; 0: not grown (null)
  Layout layout = Layout::kAtlas;
  HoleMode holes = HoleMode::kFill;
  MapKind map = MapKind::kDetail;
  double balance = 1.0;
  bool fit = true;
  bool fine_fit = false;  // in effect: false without `fit`
  CornerRule corners = CornerRule::kEqualArcs;
  double aspect = 0;                   // as asked (Options::aspect); 0: "auto"
  double material_map_budget_db = 51;  // Options::material_map_budget_db
};

/// One shape the auto aspect tried ("aspect"/"probes").
struct AspectProbe {
  double aspect = 1.0;        // width / height
  int width = 0, height = 0;  // the texture's size at that shape
  /// resampling_mse of the probed map; written as "estimated_psnr_db". < 0: not estimated (not mapped:
  /// the square's texels were not stretched, or stretched towards the other shape; see
  /// square_texel_stretch).
  double estimated_mse = -1;
  /// resampling_mse of the shape's own (full) map, where the component is large enough for its probes
  /// to be multilevel: the shapes are then chosen on own maps (the square's and the one its coarse
  /// copy's texel stretch points to), not probed; written as "full_map_estimated_psnr_db". < 0: not
  /// made (null).
  double full_map_estimated_mse = -1;
};

/// "aspect": the texture's shape, as asked and as chosen.
struct AspectChoice {
  double requested = 0;  // Options::aspect; 0: "auto"
  double chosen = 1.0;
  size_t probed_component = kNone;  // the component the probes mapped; kNone: none probed (null)
  std::vector<AspectProbe> probes;  // in probe order; empty unless probed
  /// texel_stretch_ratio of the square probe's map, which decides whether the other shapes are probed
  /// (kAspectProbeStretch); < 0: none (null).
  double square_texel_stretch = -1;
};

/// "pages": the texture pages of the atlas and why there is more than one.
struct Pages {
  int max_side = 0;             // Options::max_page_side (0: no cap, null)
  size_t max_piece_faces = 0;   // Options::max_piece_faces (0: no cap, null)
  size_t count = 1;             // texture pages written
  size_t components_split = 0;  // components split into pieces: one alone was more than a page holds or max_piece_faces
  size_t pieces = 0;            // the pieces they became
  std::string reason;           // why more than one page; empty for one
  /// Components of a million triangles or more (kLargeMapFaces) mapped one after another, the memory
  /// limit leaving no room for all of them at once (0: at once, or fewer than two).
  size_t large_maps_one_after_another = 0;
};

/// "preparation": the repair's counts and totals over all components (the listed ones are a subset).
struct Preparation {
  RepairStats repair;  // written under the keys of the report (e.g. "zero_area_dropped", "vertices_sliced")
  size_t components = 0;
  size_t holes_filled = 0, holes_cut = 0;
  size_t components_with_fallback = 0;        // CutStats::fallback_reason non-empty
  size_t components_longest_hole_capped = 0;  // CutStats::longest_loop_capped
  size_t components_kept_original_uvs = 0;    // Plan::kept non-empty
  size_t untextured_kept = 0;                 // triangles with nothing to bake (no texture), written as they came
  bool already_tight = false;                 // every component kept: one chart each filling the texture (already_tight)
  // "components_listed" is ReportData::components.size().
};

/// One entry of "components": a component as cut, mapped and placed.
struct ComponentEntry {
  size_t index = 0;         // in plan order
  size_t triangles = 0;     // of the component
  double area = 0;          // its 3D area
  CutStats cut;             // "euler", "genus", "boundary_loops" from cut.before; "cut" is cut.method, ...
  SquareMapStats map;       // "weights", "flipped_in_map", "density_*", "refine_*", "flow_*", ...
  std::string kept_reason;  // non-empty: kept its input UVs ("kept_original_uvs" true), and why
  Rect rect;                // where its square went
};

/// One entry of "timings".
struct StageTiming {
  std::string stage;
  double seconds = 0;
  std::optional<double> peak_rss_mib;  // peak RSS at the stage's end; not written when unset
  // The process's CPU time while the stage ran (all threads: what ran beside it counts too), in the
  // program and in the kernel; not written when unset.
  std::optional<double> user_seconds, sys_seconds;
};

/// "maps": one output map besides the base colour (bake_material_maps).
struct MaterialMapEntry {
  std::string name;                        // the first slot's name (material_slot_name)
  std::vector<std::string> slots;          // every slot it serves ("metallic_roughness", "occlusion")
  std::string encoding;                    // "srgb_colour", "data" or "tangent_normal"
  std::vector<std::pair<int, int>> sizes;  // per page
  double scale = 1;                        // each side is the base colour's times this (below 1: reduced)
  double seconds = 0;                      // its bake and the choice of its size
};

/// "output": where the CLI wrote the model.
struct OutputFiles {
  std::string directory;
  std::string model;  // the model file's name within `directory` (OBJ or PLY)
  std::string html;   // the report page's name within `directory`; empty: none written (not written)
  /// What the model file leaves out (write_gltf's removed parts, write_obj's and write_ply's unbound
  /// maps), one sentence each; not written when empty.
  std::vector<std::string> not_written;
};

/// The whole report. Sections that only some callers fill are optional and not written when unset:
/// a plan alone has no bake, metrics or peak RSS; only the CLI writes output files and wall time.
struct ReportData {
  InputSummary input;
  OptionsUsed options;
  AspectChoice aspect;
  Pages pages;
  Preparation preparation;
  std::vector<ComponentEntry> components;  // the listed ones, in plan order
  std::vector<StageTiming> timings;        // in the order the stages ran
  std::optional<BakeStats> bake;
  std::vector<MaterialMapEntry> maps;  // written only when not empty
  std::optional<Metrics> metrics;
  std::optional<double> peak_rss_mib;
  std::optional<double> wall_seconds;
  std::optional<OutputFiles> output;
};

/// PSNR in dB of an estimated colour error (resampling_mse): 99 for no error, -1 where none was made
/// (mse < 0). The probes' and the cuts' figures in the report.
double estimated_psnr_db(double mse);

/// The report as JSON: one key per field as named above ("aspect" and "requested" hold "auto" for 0,
/// absent optional sections are left out). Never throws but for allocation.
nlohmann::json to_json(const ReportData& report);

/// What tightex keeps behind a public Report: its every figure as JSON. Mutable so that a reader may
/// index a key the report lacks (nlohmann's operator[] adds it as null), as tests do.
struct ReportDetail {
  mutable nlohmann::json json;
};

/// The public Report of a report's JSON and the output model it describes (its triangles and the
/// sizes of its first `new_textures` textures; none for a plan): the main figures, warnings and notes
/// read from the JSON, its text, and the JSON kept behind it (report_json).
Report public_report(nlohmann::json json, const TexturedMesh& output = {}, size_t new_textures = 0);

/// The whole report behind `report` (an empty object for a default Report). It lives as long as a
/// Report holding it: `report_json(plan.report())[...]` is read within its expression.
nlohmann::json& report_json(const Report& report);

/// One "timings" entry as JSON (the CLI adds its own stages to a report the library wrote).
nlohmann::json to_json(const StageTiming& timing);

/// "output" as JSON.
nlohmann::json to_json(const OutputFiles& files);

/// The reader's figures that "input" holds ("polygons_triangulated", "paths_found", and "not_read"
/// where the reader left parts of the model as they were).
nlohmann::json reader_json(const ModelReadStats& stats);

}  // namespace tightex
