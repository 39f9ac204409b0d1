#include "bake/bake.hpp"

#include "core/raster.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace tightex {

namespace {

constexpr int kTile = 64;

Rgba8 to_rgba(const std::array<float, 4>& c) {
  auto q = [](float x) { return uint8_t(std::clamp(x + 0.5f, 0.0f, 255.0f)); };
  return {q(c[0]), q(c[1]), q(c[2]), q(c[3])};
}

}  // namespace

void bake_texture(const TexturedMesh& input, const std::vector<BakeTriangle>& triangles,
                  const std::vector<Rect>& rects, std::vector<Image>& images, BakeStats* stats) {
  std::vector<Rgba8> flat_colour(input.materials.size());
  for (size_t m = 0; m < input.materials.size(); ++m) {
    const auto& kd = input.materials[m].kd;
    flat_colour[m] = to_rgba({float(kd[0] * 255), float(kd[1] * 255), float(kd[2] * 255), 255.f});
  }
  std::atomic<size_t> filled{0}, dilated{0};
  for (uint32_t img = 0; img < images.size(); ++img) {
    Image& out = images[img];
    const int tiles_x = (out.width + kTile - 1) / kTile, tiles_y = (out.height + kTile - 1) / kTile;
    std::vector<std::vector<uint32_t>> bins(size_t(tiles_x) * size_t(tiles_y));
    for (uint32_t t = 0; t < triangles.size(); ++t) {
      const BakeTriangle& tri = triangles[t];
      if (tri.image != img) continue;
      double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
      for (const Vec2& p : tri.target_px) x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x()), y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
      const int tx0 = std::clamp(int(std::floor(x0)) / kTile, 0, tiles_x - 1), tx1 = std::clamp(int(std::floor(x1)) / kTile, 0, tiles_x - 1);
      const int ty0 = std::clamp(int(std::floor(y0)) / kTile, 0, tiles_y - 1), ty1 = std::clamp(int(std::floor(y1)) / kTile, 0, tiles_y - 1);
      for (int ty = ty0; ty <= ty1; ++ty)
        for (int tx = tx0; tx <= tx1; ++tx) bins[size_t(ty) * size_t(tiles_x) + size_t(tx)].push_back(t);
    }
    std::vector<uint8_t, LargeBufferAllocator<uint8_t>> covered(size_t(out.width) * size_t(out.height), 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, bins.size()), [&](const tbb::blocked_range<size_t>& range) {
      size_t local = 0;
      for (size_t b = range.begin(); b < range.end(); ++b) {
        const int bx0 = int(b % size_t(tiles_x)) * kTile, by0 = int(b / size_t(tiles_x)) * kTile;
        const int bx1 = std::min(bx0 + kTile, out.width), by1 = std::min(by0 + kTile, out.height);
        for (uint32_t t : bins[b]) {
          const BakeTriangle& tri = triangles[t];
          const Image* src = nullptr;
          Rgba8 flat{255, 255, 255, 255};
          if (tri.material >= 0) {
            const Material& mat = input.materials[size_t(tri.material)];
            if (mat.texture >= 0 && !input.textures[size_t(mat.texture)].image.empty())
              src = &input.textures[size_t(mat.texture)].image;
            else
              flat = flat_colour[size_t(tri.material)];
          }
          scan_triangle(tri.target_px[0], tri.target_px[1], tri.target_px[2], bx0, bx1, by0, by1, EdgeRule::kInclusive,
                        [&](long x, long y, double w0, double w1, double w2) {
                          Rgba8 c = flat;
                          if (src) {
                            const Vec2 uv = w0 * tri.source_uv[0] + w1 * tri.source_uv[1] + w2 * tri.source_uv[2];
                            c = to_rgba(sample_bilinear(*src, uv.x(), uv.y()));
                          }
                          const size_t idx = size_t(y) * size_t(out.width) + size_t(x);
                          out.pixels[idx] = c;
                          local += !covered[idx];
                          covered[idx] = 1;
                        });
        }
      }
      filled += local;
    });

    // Dilation inside each rectangle, layer by layer (deterministic: a layer reads only earlier layers).
    std::vector<size_t> my_rects;
    for (size_t r = 0; r < rects.size(); ++r)
      if (rects[r].image == int(img)) my_rects.push_back(r);
    tbb::parallel_for(size_t(0), my_rects.size(), [&](size_t ri) {
      const Rect& r = rects[my_rects[ri]];
      std::vector<std::pair<int, int>> frontier, next;
      size_t local = 0;
      auto is_cov = [&](int x, int y) { return covered[size_t(y) * size_t(out.width) + size_t(x)] != 0; };
      for (int y = r.y; y < r.y + r.h; ++y)
        for (int x = r.x; x < r.x + r.w; ++x)
          if (!is_cov(x, y)) frontier.push_back({x, y});
      if (frontier.size() == size_t(r.w) * size_t(r.h)) {  // nothing covered: keep a neutral grey
        for (auto [x, y] : frontier) out.at(x, y) = {128, 128, 128, 255};
        dilated += frontier.size();
        return;
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
        local += updates.size();
        if (updates.empty()) break;
        frontier.swap(next);
      }
      dilated += local;
    });
  }
  if (stats) {
    stats->texels_filled = filled;
    stats->texels_dilated = dilated;
  }
}

}  // namespace tightex
