#include "report/preview.hpp"

#include <algorithm>

namespace tightex {

// Box-filtered (every source texel counts): a fragmented atlas shrunk by point sampling would show
// noise instead of its charts and gaps.
Image box_shrink(const Image& src, int height) {
  const int h = std::max(1, std::min(height, src.height));
  const int w = std::max(1, int(double(src.width) * h / src.height + 0.5));
  Image dst(w, h);
  for (int y = 0; y < h; ++y) {
    const int y0 = int(long(y) * src.height / h), y1 = std::max(y0 + 1, int(long(y + 1) * src.height / h));
    for (int x = 0; x < w; ++x) {
      const int x0 = int(long(x) * src.width / w), x1 = std::max(x0 + 1, int(long(x + 1) * src.width / w));
      long sum[3] = {0, 0, 0}, n = 0;
      for (int yy = y0; yy < y1; ++yy)
        for (int xx = x0; xx < x1; ++xx) {
          const Rgba8& c = src.at(xx, yy);
          sum[0] += c.r, sum[1] += c.g, sum[2] += c.b, ++n;
        }
      dst.at(x, y) = {uint8_t(sum[0] / n), uint8_t(sum[1] / n), uint8_t(sum[2] / n), 255};
    }
  }
  return dst;
}

Image make_preview(const TexturedMesh& input, const TexturedMesh& output, int height) {
  std::vector<Image> left, right;
  for (const Texture& t : input.textures)
    if (!t.image.empty()) left.push_back(box_shrink(t.image, height));
  for (const Texture& t : output.textures)
    if (!t.image.empty()) right.push_back(box_shrink(t.image, height));
  const int gap = height / 16 + 4;
  int width = gap;
  for (const auto* side : {&left, &right})
    for (const Image& im : *side) width += im.width + gap / 4;
  width += gap;
  Image out(width, height + 2 * (gap / 4), Rgba8{24, 24, 24, 255});
  int x = gap / 4;
  auto blit = [&](const Image& im) {
    for (int y = 0; y < im.height; ++y)
      for (int i = 0; i < im.width; ++i) out.at(x + i, gap / 4 + y) = im.at(i, y);
    x += im.width + gap / 4;
  };
  for (const Image& im : left) blit(im);
  x += gap - gap / 4;
  for (const Image& im : right) blit(im);
  return out;
}

}  // namespace tightex
