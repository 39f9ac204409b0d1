#include "bake/bake.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "bake/fit.hpp"
#include "bake/sampler.hpp"
#include "core/error.hpp"
#include "core/image.hpp"
#include "core/large_buffer.hpp"
#include "core/progress.hpp"
#include "core/raster.hpp"

namespace tightex {

namespace {

/// Side of the square tiles the output is baked and fitted in (in parallel). At least kFitHalo: a
/// tile's fit reaches into its eight neighbours only.
constexpr int kTile = 64;
static_assert(kTile >= kFitHalo);
/// Progress units of fitting one tile, against one for rasterising it.
constexpr double kFitUnits = 3.0;

/// Per texel of one output image: 1 once some triangle covers it or dilation has filled it.
using CoverageMask = std::vector<uint8_t, LargeBufferAllocator<uint8_t>>;

/// The BakeStats counts, summed over the baking threads.
struct BakeCounters {
  std::atomic<size_t> filled{0}, dilated{0}, filtered{0}, tiles_fitted{0}, tiles_total{0};
};

/// What every step of one bake reads, and where it counts.
struct BakeContext {
  const std::vector<BakeTriangle>& triangles;
  const SamplerMaker& samplers;
  const BakeOptions& options;
  int max_samples;  // options.max_footprint_samples, at least 1
  BakeCounters& counters;
  ProgressCounter& progress;
};

/// The samplers of a base colour bake: each triangle's material's texture where it has one with
/// pixels, else the material's flat colour (white without a material); `linear_light`: filtered in
/// linear light.
SamplerMaker base_colour_samplers(const TexturedMesh& input, const std::vector<BakeTriangle>& triangles, bool linear_light) {
  SamplerMaker maker{triangles, std::vector<MaterialSampling>(input.materials.size() + 1)};
  for (size_t m = 0; m < input.materials.size(); ++m) {
    const Material& mat = input.materials[m];
    MaterialSampling& ms = maker.material[m];
    if (mat.texture >= 0 && !input.textures[size_t(mat.texture)].image.empty()) {
      ms.src = &input.textures[size_t(mat.texture)].image;
      ms.corner_samples = input.textures[size_t(mat.texture)].from_vertex_colours;
    } else {
      auto stored = [&](int k) { return float(linear_to_srgb(mat.kd[size_t(k)]) * 255); };
      ms.flat = to_rgba({stored(0), stored(1), stored(2), 255.f});
    }
  }
  if (linear_light) maker.encoding = SlotEncoding::kSrgbColour;
  return maker;
}

/// The samplers of a bake of `map`: each triangle's material's texture for the map where it has one
/// with pixels; a triangle whose material has none is unread (MaterialSampling::unread); with the map's
/// encoding and the triangle's frames.
SamplerMaker map_samplers(const TexturedMesh& input, const MaterialMapSource& map, const std::vector<BakeTriangle>& triangles) {
  SamplerMaker maker{triangles,
                     std::vector<MaterialSampling>(input.materials.size() + 1, MaterialSampling{nullptr, map.flat, false, true})};
  for (size_t m = 0; m < input.materials.size() && m < map.texture_of_material.size(); ++m) {
    const int tex = map.texture_of_material[m];
    if (tex >= 0 && !input.textures[size_t(tex)].image.empty())
      maker.material[m].src = &input.textures[size_t(tex)].image, maker.material[m].unread = false;
  }
  maker.encoding = map.encoding;
  if (map.encoding == SlotEncoding::kTangentNormal) maker.frames = map.frames;
  return maker;
}

/// The bake's progress units: each tile of each image is rasterised (1 unit) and, with the fit,
/// fitted (kFitUnits).
double bake_progress_units(const std::vector<Image>& images, bool fit) {
  double all_units = 0;
  for (const Image& out : images)
    all_units += double((out.width + kTile - 1) / kTile) * double((out.height + kTile - 1) / kTile) * (fit ? 1 + kFitUnits : 1);
  return all_units;
}

/// The triangles and rectangles of each image (indices, ascending), gathered in one pass over all:
/// the per-component layout can have tens of thousands of images.
struct ImageParts {
  std::vector<std::vector<uint32_t>> triangles;
  std::vector<std::vector<size_t>> rects;
};

ImageParts group_by_image(const std::vector<BakeTriangle>& triangles, const std::vector<Rect>& rects, size_t num_images) {
  ImageParts parts;
  parts.triangles.resize(num_images);
  parts.rects.resize(num_images);
  for (uint32_t t = 0; t < triangles.size(); ++t)
    if (triangles[t].image < num_images) parts.triangles[triangles[t].image].push_back(t);
  for (size_t r = 0; r < rects.size(); ++r)
    if (rects[r].image >= 0 && size_t(rects[r].image) < num_images) parts.rects[size_t(rects[r].image)].push_back(r);
  return parts;
}

/// One output image cut into kTile x kTile tiles, each with the triangles whose bounding box meets it.
struct TileBins {
  int tiles_x = 0, tiles_y = 0;
  std::vector<std::vector<uint32_t>> bins;  // row-major; each in ascending triangle order

  TexelTile tile(size_t b, const Image& out) const {
    TexelTile t;
    t.x0 = int(b % size_t(tiles_x)) * kTile, t.y0 = int(b / size_t(tiles_x)) * kTile;
    t.x1 = std::min(t.x0 + kTile, out.width), t.y1 = std::min(t.y0 + kTile, out.height);
    return t;
  }
};

TileBins bin_triangles_by_tile(const Image& out, const std::vector<uint32_t>& image_triangles, const std::vector<BakeTriangle>& triangles) {
  TileBins grid;
  grid.tiles_x = (out.width + kTile - 1) / kTile, grid.tiles_y = (out.height + kTile - 1) / kTile;
  const int tiles_x = grid.tiles_x, tiles_y = grid.tiles_y;
  grid.bins.resize(size_t(tiles_x) * size_t(tiles_y));
  for (uint32_t t : image_triangles) {
    const BakeTriangle& tri = triangles[t];
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    for (const Vec2& p : tri.target_px)
      x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x()), y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
    const int tx0 = std::clamp(int(std::floor(x0)) / kTile, 0, tiles_x - 1), tx1 = std::clamp(int(std::floor(x1)) / kTile, 0, tiles_x - 1);
    const int ty0 = std::clamp(int(std::floor(y0)) / kTile, 0, tiles_y - 1), ty1 = std::clamp(int(std::floor(y1)) / kTile, 0, tiles_y - 1);
    for (int ty = ty0; ty <= ty1; ++ty)
      for (int tx = tx0; tx <= tx1; ++tx) grid.bins[size_t(ty) * size_t(tiles_x) + size_t(tx)].push_back(t);
  }
  return grid;
}

/// Texels counted by one thread's share of the scan conversion.
struct ScanCounts {
  size_t filled = 0;    // texels covered for the first time
  size_t filtered = 0;  // texels given a footprint-filtered colour
};

/// Paper Alg. 3 for one triangle within one tile: every texel centre inside the triangle (edges
/// included) takes the input's colour at the interpolated original UV: the bilinear sample where the
/// input is magnified, the footprint-filtered mean where it is minified, the flat colour without a
/// texture. Marks the texels covered.
void scan_convert_triangle(const BakeTriangle& tri, const TriangleSampler& smp, const TexelTile& tile, int max_samples, Image& out,
                           CoverageMask& covered, ScanCounts& counts) {
  if (smp.unread) return;  // its texels are the neighbours' (dilation)
  const bool minified = smp.footprint_x > 1 || smp.footprint_y > 1;
  scan_triangle(tri.target_px[0], tri.target_px[1], tri.target_px[2], tile.x0, tile.x1, tile.y0, tile.y1, EdgeRule::kInclusive,
                [&](long x, long y, double w0, double w1, double w2) {
                  Rgba8 c = smp.flat;
                  if (smp.src && (smp.encoding != SlotEncoding::kData || smp.frames)) {
                    if (smp.valid) c = to_rgba(smp.footprint_colour(double(x) + 0.5, double(y) + 0.5, 1.0, max_samples));
                    counts.filtered += minified && smp.valid;
                  } else if (smp.src) {
                    if (minified && smp.valid) {
                      c = to_rgba(smp.footprint_colour(double(x) + 0.5, double(y) + 0.5, 1.0, max_samples));
                      ++counts.filtered;
                    } else {
                      const Vec2 uv = w0 * tri.source_uv[0] + w1 * tri.source_uv[1] + w2 * tri.source_uv[2];
                      c = to_rgba(sample_bilinear(*smp.src, uv.x(), uv.y()));
                    }
                  }
                  const size_t idx = size_t(y) * size_t(out.width) + size_t(x);
                  out.pixels[idx] = c;
                  counts.filled += !covered[idx];
                  covered[idx] = 1;
                });
}

/// The scan-line texture generation (Alg. 3) of one image, in parallel over its tiles; each tile takes
/// its triangles in order, so a texel covered twice gets the later triangle's colour whatever the
/// thread count.
void rasterize_texels(const BakeContext& ctx, const TileBins& grid, Image& out, CoverageMask& covered) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, grid.bins.size()), [&](const tbb::blocked_range<size_t>& range) {
    ScanCounts counts;
    for (size_t b = range.begin(); b < range.end(); ++b) {
      const TexelTile tile = grid.tile(b, out);
      const std::vector<uint32_t>& bin = grid.bins[b];
      const std::vector<TriangleSampler> samplers = ctx.samplers.of(bin);
      for (size_t i = 0; i < bin.size(); ++i)
        scan_convert_triangle(ctx.triangles[bin[i]], samplers[i], tile, ctx.max_samples, out, covered, counts);
    }
    ctx.counters.filled += counts.filled;
    ctx.counters.filtered += counts.filtered;
    ctx.progress.advance(double(range.size()));
  });
}

/// Fills the texels of rectangle r that no triangle covers from their covered neighbours within r,
/// layer by layer (deterministic: a layer reads only earlier layers); a rectangle with nothing covered
/// becomes neutral grey. Returns the number of texels filled.
size_t dilate_rect(const Rect& r, Image& out, CoverageMask& covered) {
  std::vector<std::pair<int, int>> frontier, next;
  size_t filled = 0;
  auto is_cov = [&](int x, int y) { return covered[size_t(y) * size_t(out.width) + size_t(x)] != 0; };
  for (int y = r.y; y < r.y + r.h; ++y)
    for (int x = r.x; x < r.x + r.w; ++x)
      if (!is_cov(x, y)) frontier.push_back({x, y});
  if (frontier.size() == size_t(r.w) * size_t(r.h)) {
    for (auto [x, y] : frontier) out.at(x, y) = {128, 128, 128, 255};
    return frontier.size();
  }
  while (!frontier.empty()) {
    std::vector<std::pair<std::pair<int, int>, Rgba8>> updates;
    next.clear();
    for (auto [x, y] : frontier) {
      int sum[4] = {0, 0, 0, 0}, n = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if ((dx == 0 && dy == 0) || nx < r.x || ny < r.y || nx >= r.x + r.w || ny >= r.y + r.h || !is_cov(nx, ny)) continue;
          const Rgba8& c = out.at(nx, ny);
          sum[0] += c.r, sum[1] += c.g, sum[2] += c.b, sum[3] += c.a, ++n;
        }
      if (n == 0) {
        next.push_back({x, y});
        continue;
      }
      updates.push_back({{x, y}, Rgba8{uint8_t(sum[0] / n), uint8_t(sum[1] / n), uint8_t(sum[2] / n), uint8_t(sum[3] / n)}});
    }
    for (auto& [p, c] : updates) {
      out.at(p.first, p.second) = c;
      covered[size_t(p.second) * size_t(out.width) + size_t(p.first)] = 1;
    }
    filled += updates.size();
    if (updates.empty()) break;
    frontier.swap(next);
  }
  return filled;
}

/// Dilation of every rectangle of one image (`image_rects`: indices into `rects`), in parallel.
void dilate_uncovered(const std::vector<Rect>& rects, const std::vector<size_t>& image_rects, Image& out, CoverageMask& covered,
                      BakeCounters& counters) {
  tbb::parallel_for(size_t(0), image_rects.size(),
                    [&](size_t ri) { counters.dilated += dilate_rect(rects[image_rects[ri]], out, covered); });
}

/// Whether a tile's fit can change anything: some textured triangle does not magnify the input by 2 or
/// more (where all do, the bilinear bake is already right), or samples its corners (the bilinear
/// bake flattens the peaks of a vertex-coloured input's colours at its vertices).
bool worth_fitting(const std::vector<TriangleSampler>& samplers) {
  bool worth = false;
  for (const TriangleSampler& smp : samplers) {
    worth = worth || (smp.src && smp.valid && (smp.corner_samples || std::max(smp.footprint_x, smp.footprint_y) > 0.5));
  }
  return worth;
}

/// The triangles of tile (tx, ty) and of its eight neighbours (the fit's halo reaches into them),
/// each once, ascending.
std::vector<uint32_t> triangles_near_tile(const TileBins& grid, int tx, int ty) {
  std::vector<uint32_t> tris;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int nx = tx + dx, ny = ty + dy;
      if (nx < 0 || ny < 0 || nx >= grid.tiles_x || ny >= grid.tiles_y) continue;
      const auto& bin = grid.bins[size_t(ny) * size_t(grid.tiles_x) + size_t(nx)];
      tris.insert(tris.end(), bin.begin(), bin.end());
    }
  std::sort(tris.begin(), tris.end());
  tris.erase(std::unique(tris.begin(), tris.end()), tris.end());
  return tris;
}

/// The least-squares fit (fit_tile) of every tile of one image worth fitting, in parallel; every tile
/// reads the same copy of the plain bake, so the result does not depend on the order.
void fit_tiles(const BakeContext& ctx, const TileBins& grid, Image& out) {
  const Image base = out;
  tbb::parallel_for(size_t(0), grid.bins.size(), [&](size_t b) {
    if (!grid.bins[b].empty()) ++ctx.counters.tiles_total;
    if (!grid.bins[b].empty() && worth_fitting(ctx.samplers.of(grid.bins[b]))) {
      const std::vector<uint32_t> nearby = triangles_near_tile(grid, int(b % size_t(grid.tiles_x)), int(b / size_t(grid.tiles_x)));
      fit_tile(FitTileInput{base, ctx.triangles, ctx.samplers.of(nearby), nearby}, grid.tile(b, out), ctx.options, out);
      ++ctx.counters.tiles_fitted;
    }
    ctx.progress.advance(kFitUnits);
  });
}

/// The bake of every image through the samplers `samplers` makes.
void bake_with_samplers(const SamplerMaker& samplers, const std::vector<BakeTriangle>& triangles, const std::vector<Rect>& rects,
                        std::vector<Image>& images, BakeStats* stats, const BakeOptions& options) {
  BakeCounters counters;
  ProgressCounter progress(options.progress, bake_progress_units(images, options.fit), options.progress_interval_s);
  const BakeContext ctx{triangles, samplers, options, std::max(1, options.max_footprint_samples), counters, progress};
  const ImageParts parts = group_by_image(triangles, rects, images.size());
  for (uint32_t img = 0; img < images.size(); ++img) {
    Image& out = images[img];
    const TileBins grid = bin_triangles_by_tile(out, parts.triangles[img], triangles);
    CoverageMask covered(size_t(out.width) * size_t(out.height), 0);
    rasterize_texels(ctx, grid, out, covered);
    dilate_uncovered(rects, parts.rects[img], out, covered, counters);
    if (options.fit) fit_tiles(ctx, grid, out);
  }
  if (stats) {
    stats->texels_filled = counters.filled;
    stats->texels_dilated = counters.dilated;
    stats->texels_footprint_filtered = counters.filtered;
    stats->tiles_fitted = counters.tiles_fitted;
    stats->tiles = counters.tiles_total;
  }
}

}  // namespace

void bake_texture(const TexturedMesh& input, const std::vector<BakeTriangle>& triangles, const std::vector<Rect>& rects,
                  std::vector<Image>& images, BakeStats* stats, const BakeOptions& options) {
  bake_with_samplers(base_colour_samplers(input, triangles, options.linear_light_colour), triangles, rects, images, stats, options);
}

void bake_material_map(const TexturedMesh& input, const MaterialMapSource& map, const std::vector<BakeTriangle>& triangles,
                       const std::vector<Rect>& rects, std::vector<Image>& images, BakeStats* stats, const BakeOptions& options) {
  if (map.encoding == SlotEncoding::kTangentNormal && (!map.frames || map.frames->size() != triangles.size()))
    fail_internal("bake_material_map: a normal map needs one frame per triangle ({} for {})", map.frames ? map.frames->size() : 0,
                  triangles.size());
  bake_with_samplers(map_samplers(input, map, triangles), triangles, rects, images, stats, options);
}

}  // namespace tightex
