// tightex: global-parameterization texture space optimization (Chen, Ren, Lei, Luo, Gu; arXiv 2406.04115).
//
// The library's public entry point: take a textured mesh with a loose, fragmented UV atlas and return
// the same geometry with one chart per connected surface, each filling its own rectangle of texture.
// Everything here and in the headers it includes is installed; nothing comes from tightex's sources.
#pragma once
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "tightex/error.hpp"
#include "tightex/io.hpp"
#include "tightex/mesh.hpp"
#include "tightex/options.hpp"
#include "tightex/report.hpp"

namespace tightex {

struct Result {
  TexturedMesh output;  // geometry of the input (same corner positions), new UVs, new textures
  Report report;        // what was done and measured (see docs/metrics.md)
};

/// The geometric half of the method (repair, components, handles, holes, cut, layout, map): it needs
/// the input's geometry and UVs, not its texture pixels, so a caller can decode textures meanwhile.
/// Opaque: made by plan_charts, used by bake_plan.
class Plan {
 public:
  struct State;
  Plan();
  explicit Plan(std::unique_ptr<State> state);
  Plan(Plan&&) noexcept;
  Plan& operator=(Plan&&) noexcept;
  ~Plan();

  /// What was done so far (options used, preparation, each component's cut and map, timings).
  Report report() const;
  /// Width and height of each texture the output will have.
  std::vector<std::pair<int, int>> texture_sizes() const;
  /// Components that could not be mapped and keep their input texture coordinates and material(s)
  /// (neither the full method nor the plain fallback mapped them), their triangles, and the first
  /// one's reason; 0, 0, "" normally.
  size_t kept_components() const;
  size_t kept_triangles() const;
  std::string first_kept_reason() const;

 private:
  friend const State& plan_state(const Plan& plan);  // tightex's own stages and tests
  friend State& mutable_plan_state(Plan& plan);      // tightex's own run, which frees what it has baked

  std::unique_ptr<State> state_;
};

/// Plans the charts of `input` (see Plan). Requires a mesh whose indices, materials and coordinates
/// are valid (as read_obj returns); throws InputError naming the element otherwise, or when nothing is
/// left after dropping degenerate triangles or the options are out of range; Cancelled when the
/// progress callback asks.
Plan plan_charts(const TexturedMesh& input, const Options& options);

/// The part of plan_charts that needs neither the texture pixels nor the map's options: the repair
/// (§4.1), the connected components, each one's texture seams and handle removal. The detail map and
/// the shape choice need the pixels before the rest of the plan; a caller can make this from the
/// geometry alone (pixels absent) while it decodes the textures. Opaque: made by prepare_mesh, used up
/// by plan_charts.
class PreparedMesh {
 public:
  struct State;
  PreparedMesh();
  explicit PreparedMesh(std::unique_ptr<State> state);
  PreparedMesh(PreparedMesh&&) noexcept;
  PreparedMesh& operator=(PreparedMesh&&) noexcept;
  ~PreparedMesh();

  std::unique_ptr<State> take();  // for plan_charts; empty afterwards

 private:
  std::unique_ptr<State> state_;
};

/// Prepares `geometry` (see PreparedMesh); throws as plan_charts does.
PreparedMesh prepare_mesh(const TexturedMesh& geometry, const Options& options);

/// plan_charts(input, options) with its first part taken from `prepared`, which must have been made
/// from the same mesh (same triangles, texture coordinates and materials), now with its pixels where
/// the plan needs them; another mesh, or a preparation used already, is an InputError.
Plan plan_charts(const TexturedMesh& input, const Options& options, PreparedMesh&& prepared);

/// The texture half: output model, bake (§4.3), metrics. `input` must be the mesh the plan was made
/// from (same triangles, texture coordinates and materials), now with its textures loaded; another
/// mesh is an InputError.
Result bake_plan(const Plan& plan, const TexturedMesh& input, const Options& options);

/// Runs the whole method on a mesh in memory, as run() does from a file but writing nothing: refuses a
/// run whose estimated memory is above Options::max_memory_mib (InputError), then
/// bake_plan(plan_charts(input, options), input, options), with the wall time and peak memory in the
/// report. Requires a mesh whose textures are loaded.
Result optimize(const TexturedMesh& input, const Options& options);

/// The texture side that holds `texels` texels in one square: sqrt rounded up to a multiple of 4
/// (block-compression friendly), at least 64.
int size_for_texels(double texels);

/// Texels the input model actually uses (texel centres covered by some triangle, over all its
/// textures; docs/metrics.md "used texels"). Needs only the textures' sizes, not their pixels.
double input_used_texels(const TexturedMesh& input);

/// Texels the default budget gives each vertex-coloured triangle: a triangle's colours are linear
/// across it, so its texels reproduce them ever more closely (figures: docs/decisions.md).
constexpr double kTexelsPerColouredTriangle = 8.0;

/// The default budget in texels: the input's used texels in the textures read from files, plus
/// kTexelsPerColouredTriangle for each triangle whose texture was made from vertex colours.
double default_texels(const TexturedMesh& input);

/// The default texture side (Options::size 0): size_for_texels of default_texels rounded up to a
/// multiple of 4 (1024 if no texture has a known size), at most max_side (by default
/// kDefaultSizeMax, 1 GiB of RGBA; beyond only with Options::allow_large_textures).
constexpr int kDefaultSizeMax = 16384;
int default_size(const TexturedMesh& input, int max_side = kDefaultSizeMax);

}  // namespace tightex
