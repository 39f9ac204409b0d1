// The texture's shape (Options::aspect): the corners share the boundary out as the
// rectangle's perimeter, the refinement is measured in texels, the auto shape follows the surface, and
// a chart covers every texel centre of its rectangle whatever the texture's size.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "cut/cut.hpp"
#include "mesh_catalogue.hpp"
#include "param/param.hpp"
#include "pipeline/aspect.hpp"
#include "pipeline/map_component.hpp"
#include "prepare/components.hpp"
#include "prepare/repair.hpp"
#include "report/metrics.hpp"
#include "report/report.hpp"
#include "tightex/tightex.hpp"

namespace tightex {
namespace {

namespace cat = tightex::testing;

/// A flat sheet of (nu-1) x (nv-1) unit squares whose texture coordinates copy it without distortion
/// into the texture (at `scale` uv per unit, from (0.05, 0.05)), textured with per-pixel noise: every
/// texel of the input matters, so a map that distorts it loses fidelity at once.
TexturedMesh noisy_sheet(int nu, int nv, double scale, int tex = 256) {
  const cat::Geometry g = cat::param_grid(nu, nv, false, false, [](int i, int j) { return Vec3(i, j, 0.0); });
  Image img(tex, tex);
  uint32_t state = 12345;
  for (Rgba8& p : img.pixels) {
    state = state * 1664525u + 1013904223u;
    p = Rgba8{uint8_t(state >> 24), uint8_t(state >> 16), uint8_t(state >> 8), 255};
  }
  TexturedMesh m = cat::make_textured("sheet", g.positions, g.triangles, std::move(img));
  for (size_t t = 0; t < m.num_triangles(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = m.positions[m.triangles[t][size_t(k)]];
      m.corner_uv[3 * t + size_t(k)] = Vec2(0.05 + scale * p.x(), 0.05 + scale * p.y());
    }
  return m;
}

Disk sheet_disk(int nu, int nv) {
  const cat::Geometry g = cat::param_grid(nu, nv, false, false, [](int i, int j) { return Vec3(i, j, 0.0); });
  const auto comps = split_components(prepare_surface(cat::make_textured("grid", g.positions, g.triangles), nullptr));
  EXPECT_EQ(comps.size(), 1u);
  return cut_to_disk(comps.at(0), {.holes = HoleMode::kFill}, nullptr);
}

// Equal arcs for a w:h rectangle: the four arcs between the corners are w, h, w, h shares of the
// boundary length (within one edge), for the square's quarters and for other shapes alike.
TEST(Aspect, EqualArcCornersShareTheLengthAsTheRectanglesPerimeter) {
  const Disk disk = sheet_disk(25, 9);
  const auto& b = disk.boundary;
  std::vector<double> arc(b.size() + 1, 0.0);
  for (size_t i = 0; i < b.size(); ++i)
    arc[i + 1] = arc[i] + (disk.mesh.positions[b[(i + 1) % b.size()]] - disk.mesh.positions[b[i]]).norm();
  const double total = arc.back();
  for (double aspect : {1.0, 3.0, 0.5}) {
    SCOPED_TRACE(aspect);
    const auto idx = choose_corners(disk, arc, CornerRule::kEqualArcs, aspect);
    const double share[4] = {aspect, 1, aspect, 1};
    for (int k = 0; k < 4; ++k) {
      const double len = std::fmod(arc[idx[size_t((k + 1) % 4)]] - arc[idx[size_t(k)]] + total, total);
      EXPECT_NEAR(len, total * share[k] / (2 * (aspect + 1)), 1.0 + 1e-9) << "arc " << k;
    }
  }
}

/// Area-weighted mean of sigma_max / sigma_min of the map measured in texels of a w x h rectangle.
double mean_anisotropy(const Disk& disk, const std::vector<Vec2>& uv, int w, int h) {
  double sum = 0, area = 0;
  for (const Tri& f : disk.mesh.triangles) {
    const Vec3 &p0 = disk.mesh.positions[f[0]], &p1 = disk.mesh.positions[f[1]], &p2 = disk.mesh.positions[f[2]];
    const double a3 = triangle_area(p0, p1, p2);
    Eigen::Matrix2d P, T;  // flat sheet: 3D x, y are the surface's own coordinates
    P << (p1 - p0).x(), (p2 - p0).x(), (p1 - p0).y(), (p2 - p0).y();
    T << (uv[f[1]] - uv[f[0]]).x() * (w - 1), (uv[f[2]] - uv[f[0]]).x() * (w - 1), (uv[f[1]] - uv[f[0]]).y() * (h - 1),
        (uv[f[2]] - uv[f[0]]).y() * (h - 1);
    const Eigen::JacobiSVD<Eigen::Matrix2d> svd(T * P.inverse());
    sum += a3 * svd.singularValues()(0) / svd.singularValues()(1);
    area += a3;
  }
  return sum / area;
}

// A flat 2:1 ellipse with uniform density mapped into a 2:1 or 1:2 texel rectangle: the refinement
// lowers the shear measured in texels, not in the unit square. Measured: mean sigma_max / sigma_min in
// texels 1.38 (2:1) / 1.37 (1:2), as low as in a square texture (1.39); refined in the unit square and
// then stretched, 1.62 / 1.61. (A rectangular sheet would not tell: its map is affine either way.)
TEST(Aspect, AMapIntoARectangleOfTheSurfacesShapeIsLessAnisotropicInTexels) {
  cat::Geometry g = cat::disk_geometry(12, 48);
  for (Vec3& p : g.positions) p.x() *= 2;
  const auto comps = split_components(prepare_surface(cat::make_textured("ellipse", g.positions, g.triangles), nullptr));
  ASSERT_EQ(comps.size(), 1u);
  const Disk disk = cut_to_disk(comps[0], {.holes = HoleMode::kFill}, nullptr);
  auto anisotropy = [&](int w, int h) {
    SquareMapOptions mo;
    mo.rect_width = w, mo.rect_height = h;
    for (const Tri& f : disk.mesh.triangles)
      mo.face_target.push_back(triangle_area(disk.mesh.positions[f[0]], disk.mesh.positions[f[1]], disk.mesh.positions[f[2]]));
    mo.refine_keeps_density = false;
    mo.refine_iterations = 30;
    SquareMapStats st;
    const auto uv = map_to_square(disk, mo, &st);
    EXPECT_EQ(count_folds(disk.mesh, uv), 0u);
    return mean_anisotropy(disk, uv, w, h);
  };
  const double square = anisotropy(200, 200), wide = anisotropy(282, 141), tall = anisotropy(141, 282);
  EXPECT_LT(wide, 1.45);
  EXPECT_LT(tall, 1.45);
  EXPECT_LT(std::min(wide, tall), square + 0.05);
}

// The stretch that decides whether other shapes are probed: a 2:1 sheet mapped affinely into a square
// has texels twice as long along x as along y (4 in squares); into a 2:1 rectangle, square texels.
TEST(Aspect, TexelStretchRatioOfASheetMappedAffinely) {
  Mapped m;
  m.disk = sheet_disk(25, 13);  // 24 x 12 units
  for (const Vec3& p : m.disk.mesh.positions) m.uv.push_back(Vec2(p.x() / 24, p.y() / 12));
  m.rect = Rect{0, 0, 0, 100, 100};
  EXPECT_NEAR(texel_stretch_ratio(m), 4.0, 1e-9);
  m.rect = Rect{0, 0, 0, 200, 100};
  EXPECT_NEAR(texel_stretch_ratio(m), 1.0, 1e-9);
  m.rect = Rect{0, 0, 0, 50, 100};
  EXPECT_NEAR(texel_stretch_ratio(m), 16.0, 1e-9);
}

// Options::aspect 0 (auto): a long sheet gets a long texture, which keeps more of its (noise) texture
// than the square at the same budget; a square sheet keeps the square. The report says what was probed.
TEST(Aspect, AutoShapeFollowsTheSurfaceAndKeepsMoreOfTheTexture) {
  const TexturedMesh longsheet = noisy_sheet(49, 17, 0.9 / 48);  // 3:1, 0.9 x 0.3 of the texture
  Options opt;
  const Result aut = optimize(longsheet, opt);
  const double chosen = report_json(aut.report)["aspect"]["chosen"];
  EXPECT_NE(chosen, 1.0);
  EXPECT_EQ(report_json(aut.report)["aspect"]["probes"].size(), 3u);
  const double long_stretch = report_json(aut.report)["aspect"]["square_texel_stretch"];  // < 1: the long side along y
  EXPECT_GT(std::max(long_stretch, 1 / long_stretch), kAspectProbeStretch);
  // The square and the shape on the stretch's side are mapped and estimated, the third is not.
  for (const auto& p : report_json(aut.report)["aspect"]["probes"]) {
    const double a = p["aspect"];
    if (a == 1.0 || (a > 1) == (long_stretch > 1))
      EXPECT_GT(p["estimated_psnr_db"].get<double>(), 0.0) << p;
    else
      EXPECT_EQ(p["estimated_psnr_db"].get<double>(), -1.0) << p;
  }
  EXPECT_EQ(chosen > 1, long_stretch > 1);
  const Image& img = aut.output.textures.at(0).image;
  EXPECT_EQ(chosen > 1, img.width > img.height);
  opt.aspect = 1;
  const Result sq = optimize(longsheet, opt);
  EXPECT_EQ(sq.output.textures.at(0).image.width, sq.output.textures.at(0).image.height);
  EXPECT_EQ(report_json(sq.report)["aspect"]["probes"].size(), 0u);
  const double p_auto = report_json(aut.report)["metrics"]["surface_psnr_db"],
               p_square = report_json(sq.report)["metrics"]["surface_psnr_db"];
  EXPECT_GT(p_auto, p_square + 1.0);
  EXPECT_EQ(report_json(aut.report)["metrics"]["flipped"].get<size_t>(), 0u);

  const TexturedMesh squaresheet = noisy_sheet(33, 33, 0.9 / 32);
  const Result sq2 = optimize(squaresheet, Options{});
  EXPECT_EQ(report_json(sq2.report)["aspect"]["chosen"].get<double>(), 1.0);
  // Its square map's texels are about as long as wide, so the other shapes are not mapped at all, and
  // with nothing to compare the square with, nothing is estimated.
  const double stretch = report_json(sq2.report)["aspect"]["square_texel_stretch"];
  EXPECT_LT(stretch, kAspectProbeStretch);
  EXPECT_GT(stretch, 1 / kAspectProbeStretch);
  for (const auto& p : report_json(sq2.report)["aspect"]["probes"]) EXPECT_EQ(p["estimated_psnr_db"].get<double>(), -1.0) << p;
  // The harmonic map is the paper's square, and so is any map in the paper's per-component layout.
  Options h;
  h.map = MapKind::kHarmonic;
  EXPECT_EQ(report_json(optimize(longsheet, h).report)["aspect"]["chosen"].get<double>(), 1.0);
}

// A component whose probes would be multilevel (over 32k triangles) is not probed: a coarse copy's map
// gives the stretch, and the square's and the stretch-side shape's own maps are estimated and chosen
// between. A 3:1 sheet of 38k triangles takes the long texture on its own map's estimate.
TEST(Aspect, ALargeComponentsShapeIsChosenBetweenOwnMaps) {
  const TexturedMesh longsheet = noisy_sheet(241, 81, 0.9 / 240);
  ASSERT_TRUE(probes_would_be_multilevel(longsheet.num_triangles()));
  const Result r = optimize(longsheet, Options{});
  const nlohmann::json& aspect = report_json(r.report)["aspect"];
  const double stretch = aspect["square_texel_stretch"];
  ASSERT_GT(std::max(stretch, 1 / stretch), kShapeLookStretch);
  double square = -1, side = -1;
  for (const auto& p : aspect["probes"]) {
    EXPECT_EQ(p["estimated_psnr_db"].get<double>(), -1.0) << p;  // no probe
    const double a = p["aspect"];
    if (a != 1.0 && (a > 1) != (stretch > 1)) {
      EXPECT_TRUE(p["full_map_estimated_psnr_db"].is_null()) << p;  // the shape the stretch does not point to
      continue;
    }
    ASSERT_FALSE(p["full_map_estimated_psnr_db"].is_null()) << p;
    (a == 1.0 ? square : side) = p["full_map_estimated_psnr_db"].get<double>();
  }
  EXPECT_GT(side, square + 0.22);
  const double chosen = aspect["chosen"];
  EXPECT_EQ(chosen > 1, stretch > 1);
  EXPECT_NE(chosen, 1.0);
  const Image& img = r.output.textures.at(0).image;
  EXPECT_EQ(chosen > 1, img.width > img.height);
  EXPECT_EQ(report_json(r.report)["metrics"]["flipped"].get<size_t>(), 0u);
  EXPECT_EQ(report_json(r.report)["metrics"]["lost_triangles"].get<size_t>(), 0u);
}

// At tiny sizes a long shape rounds to the square (sides are multiples of 4, at least 8): such a probe
// is skipped, so the reported shape is always the texture's.
TEST(Aspect, TheReportedShapeIsTheTexturesAtAnySize) {
  const TexturedMesh longsheet = noisy_sheet(49, 17, 0.9 / 48);
  for (int size : {8, 12, 16, 24}) {
    SCOPED_TRACE(size);
    Options opt;
    opt.size = size;
    opt.aspect = kAspectAuto;  // chosen, though a size is given
    const Result r = optimize(longsheet, opt);
    const Image& img = r.output.textures.at(0).image;
    const double chosen = report_json(r.report)["aspect"]["chosen"];
    EXPECT_EQ(chosen == 1.0, img.width == img.height);
    for (const auto& p : report_json(r.report)["aspect"]["probes"])
      if (p["estimated_psnr_db"].get<double>() != -1.0 && p["aspect"].get<double>() != 1.0) EXPECT_NE(p["width"], p["height"]);
  }
}

// A shape out of range (a library caller's; the CLI checks its own) is refused with InputError, not
// turned into an absurd texture.
TEST(Aspect, AnAspectOutOfRangeIsRefused) {
  const TexturedMesh sheet = noisy_sheet(5, 5, 0.9 / 4);
  for (double a : {-2.0, -0.5, 1e-3, 17.0, 1e300, std::nan("")}) {  // -1 is kAspectAuto
    Options opt;
    opt.aspect = a;
    EXPECT_THROW(optimize(sheet, opt), InputError) << a;
  }
}

// Every texel centre of a chart's rectangle is inside the chart as docs/metrics.md measures it from the
// stored texture coordinates, for sizes that are not powers of two and for long textures (the corner
// texel centres sit on the chart's edge up to kChartInset; exactly on it, u * W could miss by an ulp).
TEST(Aspect, ChartsCoverEveryTexelCentreAtAnySize) {
  const TexturedMesh sheet = noisy_sheet(17, 17, 0.9 / 16);
  for (int size : {92, 180, 368}) {
    for (double aspect : {1.0, 2.0}) {
      SCOPED_TRACE(std::to_string(size) + " aspect " + std::to_string(aspect));
      Options opt;
      opt.size = size;
      opt.aspect = aspect;
      opt.map = MapKind::kArea;
      const Result r = optimize(sheet, opt);
      EXPECT_EQ(report_json(r.report)["metrics"]["output"]["utilization"].get<double>(), 1.0);
    }
  }
}

}  // namespace
}  // namespace tightex
