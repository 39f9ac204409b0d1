// tightex: global-parameterization texture space optimization (Chen, Ren, Lei, Luo, Gu; arXiv 2406.04115).
//
// The library's public entry point: take a textured mesh with a loose, fragmented UV atlas and return
// the same geometry with one chart per connected surface, each filling its own rectangle of texture.
#pragma once
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "tightex/options.hpp"
#include "core/error.hpp"
#include "core/mesh.hpp"
#include "io/image_io.hpp"
#include "io/obj_reader.hpp"
#include "io/obj_writer.hpp"
#include "layout/layout.hpp"
#include "param/param.hpp"
#include "cut/cut.hpp"

namespace tightex {

struct Options {
  /// Atlas: the texture's side; per-component: the largest texture's side. 0 (default): default_size(input),
  /// as the CLI: as many texels as the input uses, so the output keeps the input's information (per
  /// component: in all the textures together, see default_budget).
  int size = 0;
  /// `size` is the default budget (the input's used texels; always so for `size` 0), not a side the
  /// caller asked for. The CLI sets it when neither --size nor --texels is given. Then:
  /// - the atlas grows where `size` cannot hold a 4 x 4 rectangle for every component (a city tile of
  ///   thousands of buildings, a scan's thousands of floaters, whose used texels are fewer than 16 a
  ///   component): to the side that holds `size`^2 texels and 16 more per component, or more if the
  ///   layout needs it (report "options": "size_grown_from"); an asked-for size that cannot hold them
  ///   is an InputError that names the sizes;
  /// - the per-component textures hold `size`^2 texels together (an asked-for size is the largest's side).
  bool default_budget = false;
  /// Width/height of the texture, which then holds about size x size texels (sides multiples of 4).
  /// 0 (default): chosen per model for the area, texel and detail maps in the atlas layout: the
  /// component that holds most of the texture is mapped into a square, a 1:2 and a 2:1 texture, each
  /// map baked without the fit and compared with the input at up to 1M surface points, and the square
  /// kept unless another shape's error is at least 5% lower (report "aspect"; costs two more maps of
  /// that component, which is not probed beyond 100k triangles). Otherwise 1, the paper's square. The CLI's --size asks for a square (1)
  /// unless --aspect is given. Measured: a soup can (ycb_005_tomato_soup_can) 47.66 -> 48.97 dB surface
  /// PSNR at the same budget in a 1:2 texture; the other scans of ../shared/data keep the square but
  /// meshroom_esp32cam (2:1, 42.25 -> 42.11, within its sampling noise).
  double aspect = 0;
  Layout layout = Layout::kAtlas;
  HoleMode holes = HoleMode::kFill;
  /// Default kDetail, as the CLI's: the highest surface PSNR of the four maps on every model of
  /// ../shared/data at the input's budget (BENCHMARKS.md, "Surface PSNR per map").
  MapKind map = MapKind::kDetail;
  /// Angle/area trade-off of the area, texel and detail maps: 0 = the harmonic map's density (least
  /// angle distortion), 1 = the target density exactly; between, the geometric blend of the two.
  double balance = 1.0;
  /// Which boundary vertices become the square's corners. Default kEqualArcs: better surface PSNR than
  /// kTurningAngle on 7 of the 9 models of ../shared/data with the area map (docs/corners.md).
  CornerRule corners = CornerRule::kEqualArcs;
  /// Least-squares fit of the baked texels to the input under bilinear read-back (BakeOptions::fit).
  bool fit = true;
  /// The fit on a 4 x 4 grid of points per texel (pull 0.3) instead of 2 x 2 (pull 1), except on tiles
  /// minified beyond 12 input pixels per texel: +0.1..0.3 dB surface PSNR on every model of
  /// ../shared/data with the detail map (harmonic: 0..+0.3), at about twice the bake time; the texture
  /// coordinates do not change (BENCHMARKS.md, "Fine fit"). Ignored without `fit`.
  bool fine_fit = false;
  /// Compute the METRICS.md figures into report["metrics"]. A caller that writes the result can turn
  /// this off and run measure() beside the write (the CLI does).
  bool measure = true;
  /// Called with a stage name and the fraction [0,1] done (an estimate within "cut+map" and "bake", at
  /// most every 0.2 s there). Calls never overlap and never go backwards within a stage, but within
  /// "cut+map" and "bake" they may come from any thread working for the call (components are mapped,
  /// tiles baked in parallel).
  std::function<void(std::string_view stage, double fraction)> progress;
  /// Test only (tests/test_kept_component.cpp): components, by index in plan order, whose cut+map is made
  /// to throw InternalError both in the full method and in the plain fallback, so the last resort (see
  /// Plan::kept) can be exercised on any mesh. Leave empty.
  std::vector<size_t> test_fail_components;
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
  /// Per component: empty when it was mapped; otherwise why it could not be (the full method and the
  /// plain fallback both threw, or the fallback's map folds). Such a component is the last resort's:
  /// its disk and uv are empty, and bake_plan outputs its triangles with their input texture
  /// coordinates and a copy of their input material(s) and texture(s), so no triangle is ever dropped.
  std::vector<std::string> kept;
  nlohmann::json report;                 // what was done so far
};
Plan plan_charts(const TexturedMesh& input, const Options& options);

/// The texture half: output model, bake, metrics. `input` must be the mesh the plan was made from
/// (same triangles and UVs), now with its textures loaded.
Result bake_plan(const Plan& plan, const TexturedMesh& input, const Options& options);

/// The texture side that holds `texels` texels in one square: sqrt rounded up to a multiple of 4
/// (block-compression friendly), at least 64.
int size_for_texels(double texels);

/// Texels the input model actually uses (texel centres covered by some triangle, over all its
/// textures; METRICS.md "used texels"). Needs only the textures' sizes, not their pixels.
double input_used_texels(const TexturedMesh& input);

/// The default texture side (Options::size 0, the CLI without --size or --texels): size_for_texels of the
/// input's used texels rounded up to a multiple of 4 (1024² if no texture has a known size), at most
/// max_side (by default kDefaultSizeMax, 1 GiB of RGBA; the CLI goes beyond only with --force).
constexpr int kDefaultSizeMax = 16384;
int default_size(const TexturedMesh& input, int max_side = kDefaultSizeMax);

/// Runs the whole method: repair, components, holes, cut, harmonic map, layout, bake, metrics.
/// Requires a mesh as returned by read_obj (validated). Throws InputError for input it cannot handle
/// (e.g. nothing left after dropping degenerate triangles) and InternalError for broken invariants.
Result optimize(const TexturedMesh& input, const Options& options);

}  // namespace tightex
