// One component cut to a disk and mapped onto its rectangle (§4.2), with the fallbacks that make every
// component one chart: the full method, then the plain cut graph, then (last resort) its input UVs.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "core/progress.hpp"
#include "cut/cut.hpp"
#include "cut/seams.hpp"
#include "layout/layout.hpp"
#include "param/density_targets.hpp"
#include "param/param.hpp"
#include "prepare/components.hpp"
#include "prepare/handles.hpp"
#include "tightex/options.hpp"

namespace tightex {

/// Test hooks of the pipeline (never set by the library's callers): components, by index in plan
/// order, whose full method and plain fallback are made to fail, so that the last resort can be
/// exercised on any mesh.
struct PlanHooks {
  std::vector<size_t> fail_components;
};

/// One component cut and mapped for the texel rectangle `rect`.
struct Mapped {
  Rect rect;
  Disk disk;
  std::vector<Vec2> uv;  // per disk vertex, in the unit square
  CutStats cut;
  SquareMapStats map;
  std::string kept;  // non-empty: neither the full method nor the fallback mapped it (why)
};

/// What the cut needs of a component whatever its rectangle: the input's texture seams (cuts prefer
/// them) and, if it has handles, the handle removal (once, whatever the rounds or the shapes probed).
struct CutInputs {
  std::vector<char> seams;
  std::optional<Denoised> denoised;
};
CutInputs cut_inputs(const TexturedMesh& input, const Surface& component);

/// How the longest hole is treated: kAuto finds out whether it is small (small_longest_hole) and then
/// compares; kCompare maps it both ways and keeps the better; kKeep / kCap as already decided for
/// another shape of the same component.
enum class CapChoice { kAuto, kCompare, kKeep, kCap };

/// What every map of one run shares.
struct MapContext {
  const TexturedMesh& input;
  const Options& options;
  const std::vector<Surface>& components;
  const std::vector<ComponentDensity>& density;
  ProgressCounter& progress;  // in triangles mapped
  bool have_pixels;           // the textures' pixels are loaded (the estimates need them)
  const PlanHooks& hooks;
  /// Per component: 1 where it is a piece of a component split for pages (split_into_parts). Its
  /// border has real corners where the split lines meet the boundary, and a long thin piece's equal
  /// arcs would put a short end on a side, squeezed flat: such a piece takes the turning-angle corners.
  /// Empty: none is.
  const std::vector<char>& split_piece;
};

/// A shape probe (`probe` in map_component) maps its disk multilevel from this many vertices, on a coarse
/// copy of at most kProbeCoarseVertices: the probes compare shapes, and the shape chosen is mapped again
/// as any component is. Chosen by measurement: BENCHMARKS.md.
constexpr size_t kProbeMultilevelFrom = 16000, kProbeCoarseVertices = 8000;

/// Whether a component of `faces` faces would be probed multilevel (a disk has about half as many
/// vertices as faces): such a component's shape is chosen on own maps instead (choose_aspect).
inline bool probes_would_be_multilevel(size_t faces) { return faces > 2 * kProbeMultilevelFrom; }

/// Cuts and maps component c for `rect` (see the file comment). `pre`: cut_inputs(c) if known. `probe`:
/// a shape probe's map (multilevel from kProbeMultilevelFrom vertices). Never throws InternalError: a
/// component whose full method and fallback both fail is returned with Mapped::kept saying why.
Mapped map_component(const MapContext& ctx, size_t c, const Rect& rect, const CutInputs* pre, CapChoice choice, bool probe = false);

/// Component c with its input texture coordinates, material(s) and image(s), not mapped (as the last
/// resort keeps a component): `why` in Mapped::kept.
Mapped kept_with_input_uvs(const MapContext& ctx, size_t c, const Rect& rect, std::string why);

/// Component c cut as map_component cuts it (the longest hole kept), its disk coarsened to at most
/// `vertices` vertices (coarsen_disk) and that copy mapped for `rect`, as multilevel_map maps its coarse
/// copy: a cheap look at the shape the component's map takes (its texel stretch), not a map to bake.
/// Mapped::disk is the coarse copy; Mapped::kept says why there is no map (the cut or the map failed).
Mapped map_coarse_copy(const MapContext& ctx, size_t c, const Rect& rect, const CutInputs* pre, size_t vertices);

/// Whether component c is also to be mapped with its longest hole capped: that hole has fewer than
/// kSmallKeptLoop edges and its cap fits the budget; not for the paper's map, which keeps the paper's
/// cut; only where the texture's pixels are known (the estimate needs them), and not beyond
/// kProbeMaxFaces (each try is a whole map). One cut, without a map.
bool small_longest_hole(const MapContext& ctx, size_t c, const CutInputs& ci);

/// Beyond this many faces a component is not mapped more than once (aspect probes, both cuts of a
/// small longest hole): each such map costs as much as the component's own.
constexpr size_t kProbeMaxFaces = 100000;

/// The estimated colour error of a mapped component baked into its rectangle (resampling_mse at up to
/// 1M surface points, 4 per texel); < 0: no estimate (no pixels).
double estimate_mse(const TexturedMesh& input, const Mapped& m);

/// Whether map a (estimated error mse_a; < 0: not mapped) beats map b by the factor `gain` (<= 1: a
/// must be that much better). The area map promises its density first: a map that keeps P5..P95 of
/// log2(area / target) within +-1 beats one that does not, and among maps that all miss, the nearest
/// wins. The one rule by which the aspect probes and the two cuts of a small hole are chosen.
bool better_map(MapKind kind, const SquareMapStats& a, double mse_a, const SquareMapStats& b, double mse_b, double gain);

}  // namespace tightex
