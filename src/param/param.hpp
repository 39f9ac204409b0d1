// The map of a disk onto the unit square (paper §4.2): Alg. 1 boundary, Alg. 2 harmonic map.
#pragma once
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "cut/cut.hpp"

namespace tightex {

/// From this many unknowns on, a map's linear systems are factorised supernodally (dense BLAS kernels
/// on column blocks); below it, simplicially. Measured (BENCHMARKS.md, "Large models"), cut+map
/// seconds, default map, simplicial -> supernodal with Debian's OpenBLAS (pthread): a vase of 44k
/// triangles 14.5 -> 5.8, of 225k 48.8 -> 14.9, of 896k 571 -> 77. With the reference BLAS the
/// supernodal one still wins at 225k (41.8 s). Below 40k the simplicial one is as fast, and it keeps
/// meshroom's harmonic systems (26k unknowns) as they were: its crowding rounds are sensitive to
/// rounding (42.22 -> 41.71 dB with those supernodal). Its 53k-unknown symmetric Dirichlet systems are
/// supernodal: 42.2233 dB either way; every model in ../shared/data keeps its PSNR.
constexpr long kSupernodalFrom = 40000;

struct SquareMapOptions {
  // Size of the texel rectangle the square will be stretched to. Used only to size the boundary bumps
  // (see map_to_square) in texels; the map itself is computed on the unit square.
  int rect_width = 1024, rect_height = 1024;
  // Maps with a density target (face_target given) also take the rectangle's shape into account: the
  // corners share the boundary out as the rectangle's perimeter (choose_corners' aspect), and the
  // symmetric Dirichlet refinement measures each triangle in texels, so a triangle isometric to its
  // target in a 2:1 rectangle is isometric in the texture, not in the unit square. The paper's harmonic
  // map keeps the quarters. Measured (session 7, ycb_005_tomato_soup_can, the detail map at the input's
  // budget in a 2024 x 4048 texture): quarters and unit-square refinement 47.94 dB, corners by shape
  // 48.29, both 49.00.
  double bump_texels = 0.3;  // < 0.5: a bump stays inside the chart's own outermost texels
  // The largest texel coordinate the rectangle reaches in its texture (0: the rectangle's own size):
  // what the written texture coordinates' rounding is relative to (see map_to_square's collapse test).
  double texel_extent = 0;
  CornerRule corners = CornerRule::kEqualArcs;

  // Beyond the paper (issue 4): the texel density. Empty: the paper's harmonic map. Otherwise a target
  // UV area for every disk face (any common scale; > 0), e.g. its 3D area (uniform density) or the
  // texels the input gave it. The harmonic map is then only the start: see map_to_square.
  std::vector<double> face_target;
  /// The trade-off between angle and area distortion: 0 keeps the harmonic map's density (least angle
  /// distortion), 1 aims at face_target exactly; in between, the target is the geometric blend
  /// harmonic^(1-balance) * target^balance per face.
  double balance = 1.0;
  int max_iterations = 60;
  double tolerance_log2 = 0.15;  // stop once P5..P95 of log2(area / target) lies within +-this
  /// Symmetric Dirichlet steps after the reweighting (refine_map). Measured on meshroom_esp32cam, area
  /// map, --size 1024: 0 steps 40.98 dB, 2: 41.37, 4: 41.36, 8 (converged): 41.35; each step costs one
  /// factorisation of twice the interior's size.
  int refine_iterations = 4;
  /// true: the refinement is undone if it widens the density error by more than 0.1 (log2) — a map
  /// whose promise is its density (area). false: it runs to convergence (up to refine_iterations),
  /// trading density for shear wherever that lowers the energy.
  bool refine_keeps_density = true;
  /// The boundary's vertices (all but the four corners and chord bumps) slide along their side of the
  /// square: between reweighting steps each boundary edge grows or shrinks with the square root of its
  /// face's target/area, and the refinement moves them along the side. Measured (surface PSNR at the
  /// input's budget, area map then 30 refinement steps, fixed / sliding): meshroom_esp32cam 41.50 /
  /// 41.95, danish_dancinggirl area map density P5 -1.02 / -0.85.
  bool slide_boundary = true;
  /// Rounds of target correction after that (each: the targets scaled by target/area, 2 more steps).
  /// Off by default: measured on ../shared/data it narrowed no model's density error once the best
  /// reweighting iterate is kept, and cost meshroom_esp32cam 0.2 dB (41.17 vs 41.36 at --size 1024).
  int correction_rounds = 0;
  /// After the reweighting, where it stalled short of tolerance_log2: the density-equalising flow
  /// (flow_density), kept if it narrows the density error. The area map's (set_face_targets).
  bool density_flow = false;
  /// Linear systems of this many unknowns or more are factorised supernodally, smaller ones
  /// simplicially (see kSupernodalFrom). Tests set it low to run the supernodal path on small meshes.
  long supernodal_from = kSupernodalFrom;
  /// Optional: called from the mapping thread with an estimate of the fraction of this map done (the
  /// density reweighting up to 0.4, the symmetric Dirichlet steps from there; each step counts as if
  /// the reweighting took 20 and the steps 15, so the estimate may jump to 1 at the end).
  std::function<void(double)> progress;
};

struct SquareMapStats {
  std::string weights;          // "cotangent", "clamped-cotangent" or "uniform": the first that gave no fold
  size_t flipped = 0;           // triangles with UV area <= 0 in the returned map (0 unless every weight failed)
  size_t negative_weights = 0;  // interior edges whose cotangent weight was negative
  std::array<uint32_t, 4> corners{};  // boundary vertices at (0,0), (1,0), (1,1), (0,1)
  std::vector<size_t> folds_per_attempt;  // folded triangles of each weighting tried, in order
  size_t bumped_vertices = 0;
  /// A vertex of a triangle that folded even with positive weights: the map crowded a region below
  /// floating-point precision there (harmonic maps crowd exponentially in protrusions). kNone if none.
  uint32_t crowded_vertex = kNone;
  // Density iterations (face_target given): P5/P95 of log2(area / target), weighted by target, before
  // (the harmonic map with the density-placed boundary) and after.
  int iterations = 0;
  double spread_before_p5 = 0, spread_before_p95 = 0, spread_p5 = 0, spread_p95 = 0;
  std::string stopped;  // "converged", "iterations", "stalled" or "fold" (the last fold-free iterate is kept)
  std::vector<double> blended_target;  // internal: the targets the iterations aimed at (cleared on return)
  int refine_iterations = 0, correction_rounds = 0;
  double refine_energy_before = 0, refine_energy = 0;
  std::string refine_stopped;
  int flow_steps = 0;
  int flow_lead_steps = 0;   // symmetric Dirichlet steps before the flow (kFlowLeadSteps, fewer if they converged)
  int flow_shape_steps = 0;  // symmetric Dirichlet steps towards the flowed shapes (0: each flowed map was kept as it was)
  std::string flow_stopped;  // FlowStats::stopped, ", reverted" added if it was undone; empty if not run
};

/// The four boundary positions (indices into disk.boundary, in boundary order, distinct unless the
/// boundary has 3 vertices: {0, 1, 2, 2}) that map_to_square sends to (0,0), (1,0), (1,1), (0,1).
/// `arc`: cumulative boundary length, arc[i] at boundary vertex i, arc[nb] the total (map_to_square
/// passes density-scaled lengths when it has a density target).
/// kEqualArcs: the vertices that share the length out as a rectangle of width/height `aspect` shares
/// its perimeter (the quarters for the square, aspect 1), from the first "ear" (a boundary vertex
/// with a single triangle, which must sit on a corner or its triangle collapses) or vertex 0, snapped to
/// an ear within 5% of the length. kTurningAngle: the vertices where the boundary turns most (pi minus
/// the interior angle sum, integrated over +-2.5% of the length with tent weights, so zigzags cancel),
/// ears first, greedily, skipping any closer than 10% of the length to one already chosen (`aspect` is
/// not used: the turning decides).
std::array<size_t, 4> choose_corners(const Disk& disk, const std::vector<double>& arc, CornerRule rule, double aspect = 1.0);

/// Maps a topological disk onto the unit square, boundary counter-clockwise.
/// Corners: choose_corners with options.corners. Boundary: arc length between corners (Alg. 1). Interior: harmonic with cotangent weights, boundary rows eliminated, one CHOLMOD
/// factorisation for u and v (Alg. 2).
/// Fold-free guarantee: if any triangle folds (cotangent weights go negative on obtuse triangles), the
/// map is recomputed with the negative weights clamped positive, which gives a bijection onto a convex
/// boundary (Tutte/Floater); uniform weights are the last resort for numerically extreme meshes.
/// A chord (interior edge between two boundary vertices on one side of the square) would squash every
/// triangle beyond it onto the side; the boundary between its ends is lifted outward by a sine bump of
/// `bump_texels`, so those triangles keep positive area.
///
/// Density (options.face_target given): the boundary is placed by target length instead of arc length
/// (each boundary edge's 3D length times the square root of its face's target density, so the sides
/// slide to where the density wants them), and the interior is re-solved with reweighted positive
/// edge weights: an iteratively reweighted Tutte embedding (in the spirit of Yoshizawa, Belyaev and
/// Seidel 2004's stretch minimisation). Each step multiplies an edge's weight by the square root of
/// the area ratio (UV area / target) of its two faces: a squeezed region's springs slacken and it
/// expands. Every step is a convex-combination map onto the convex square, so by Tutte/Floater it
/// cannot fold; a step that folds numerically is rejected and the last fold-free map kept. The
/// sparsity pattern never changes: the symbolic factorisation is reused by every step.
std::vector<Vec2> map_to_square(const Disk& disk, const SquareMapOptions& options, SquareMapStats* stats);

struct SlimStats {
  int iterations = 0;
  double energy_before = 0, energy = 0;  // area-weighted symmetric Dirichlet energy (2 per unit area = isometric)
  std::string stopped;                   // "converged", "iterations", "no descent" or "solver"
  int capped_steps = 0;                  // steps whose system solved only with its weights capped
};

/// A triangle's shape in the plane (its corners in the face's order; position and rotation do not matter).
using FaceShape = std::array<Vec2, 3>;

/// Lowers the symmetric Dirichlet energy |J|^2 + |J^-1|^2 of every face, measured against its target
/// shape (the 3D triangle scaled to area target[f]; a face of zero 3D area keeps its start shape and
/// area; `shapes`, optional: face f's shapes[f] instead, where that has a positive area), weighted by
/// target area; fixed[v] bit 0 holds the vertex's u, bit 1 its v (3: the vertex stays; 1 or 2: it
/// slides along a side). uv must be fold-free; it stays fold-free (the line search stops short of any
/// triangle's collapse). SLIM (Rabinovich et al. 2017): a reweighted proxy solved with CHOLMOD, pattern
/// analysed once.
SlimStats refine_map(const Surface& mesh, const std::vector<char>& fixed, const std::vector<double>& target, int iterations,
                     std::vector<Vec2>& uv, long supernodal_from = kSupernodalFrom,
                     const std::function<void(int step)>& on_step = {}, const std::vector<FaceShape>* shapes = nullptr);

struct FlowOptions {
  int grid = 0;             // cells along the rectangle's mean side; 0: 2 sqrt(faces), within 32..256
  int max_steps = 300;
  double tolerance = 0.02;  // stop once the diffused density is within +-this of its mean everywhere
  double time_scale = 1.0;  // diffusion time, in units of the rectangle's longer side squared
  double start_cells = 1;   // the density starts diffused over this many cells (time: its square x a cell's)
  /// true: a step is taken only if every face keeps more than half its area. false: the vertices follow
  /// the flow whatever becomes of the faces between them (a face spanning many cells of a field that
  /// bends across it can fold): the result is a shape to aim at (refine_map's `shapes`), not a map.
  bool fold_free = true;
};

struct FlowStats {
  int steps = 0;
  std::string stopped;  // "converged", "time", "steps" or "fold" (no step short enough kept every face)
};

/// The density-equalising flow of Gastner & Newman (2004) in the texel rectangle of width/height
/// `aspect` (uv in the unit square): each face's target is its population, the density diffuses with
/// zero flux through the sides, and the vertices move with -grad(rho)/rho until the density is even,
/// so each face tends to its target area. fixed[v] as for refine_map (bit 0 holds u, bit 1 v); side
/// vertices slide along their side. Fold-free: a step is taken only if every face keeps more than half
/// its area (else it is halved), and the flow stops ("fold") where no step would; unless
/// options.fold_free is false. See density_flow.cpp.
/// `tracers` (optional, unit square like uv): further points carried by the same flow, unconstrained.
FlowStats flow_density(const Surface& mesh, const std::vector<char>& fixed, const std::vector<double>& target, double aspect,
                       std::vector<Vec2>& uv, const FlowOptions& options = {}, std::vector<Vec2>* tracers = nullptr);

/// The cells along the flow grid's mean side for a map of `faces` faces (FlowOptions::grid, or its default).
int flow_grid(size_t faces, const FlowOptions& options = {});

/// Number of triangles whose UV signed area is not strictly positive.
size_t count_folds(const Surface& mesh, const std::vector<Vec2>& uv);

/// Triangles of a unit-square map that would not survive being written: placed in options' rectangle,
/// their area in texels is below what rounding the texture coordinates (2^-52 of the texel extent)
/// can move per unit of their perimeter, so a reader may find them folded or empty. Folded ones count
/// too. `worst_vertex` (optional) gets a vertex of the worst one; untouched when none.
size_t count_collapsed(const Surface& mesh, const std::vector<Vec2>& uv, const SquareMapOptions& options,
                       uint32_t* worst_vertex = nullptr);

}  // namespace tightex
