// The input's own rate-distortion curve: every texture a model's materials bind re-encoded in a codec at
// each quality, decoded back, and measured against the model as it is (docs/metrics.md surface PSNR, the same
// points as tightex's report). What a re-encode without repacking (gltf-transform, gltfpack) would give,
// for bench/bytes.sh beside tightex's own curve. webp: tightex's own encoder (the sharp RGB-to-YUV
// conversion); webp-plain: libwebp's simple API with its plain conversion, as Pillow, cwebp without
// -sharp_yuv and gltf-transform (sharp/libvips) encode by default.
// Usage: tightex_reencode_curve MODEL webp|webp-plain|jpg Q1 [Q2 ...]   prints "quality bytes psnr_db" per line.
#include <fmt/format.h>
#include <webp/encode.h>

#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

#include "io/image_io.hpp"
#include "report/metrics.hpp"
#include "tightex/io.hpp"

using namespace tightex;

/// `image` through libwebp's simple lossy API at `quality` (RGB where it is opaque).
std::string plain_webp(const Image& image, int quality) {
  const bool opaque = std::all_of(image.pixels.begin(), image.pixels.end(), [](const Rgba8& p) { return p.a == 255; });
  std::vector<uint8_t> rgb;
  for (const Rgba8& p : image.pixels) rgb.insert(rgb.end(), {p.r, p.g, p.b});
  uint8_t* out = nullptr;
  const size_t size = opaque ? WebPEncodeRGB(rgb.data(), image.width, image.height, image.width * 3, float(quality), &out)
                             : WebPEncodeRGBA(reinterpret_cast<const uint8_t*>(image.pixels.data()), image.width, image.height,
                                              image.width * 4, float(quality), &out);
  std::string bytes(reinterpret_cast<const char*>(out), size);
  WebPFree(out);
  return bytes;
}

int main(int argc, char** argv) {
  if (argc < 4) {
    fmt::print(stderr, "usage: {} MODEL webp|webp-plain|jpg QUALITY...\n", argv[0]);
    return 2;
  }
  const TexturedMesh input = read_model(argv[1]);
  const std::string codec = argv[2];
  ImageEncoding encoding(codec == "jpg" ? ImageFormat::kJpeg : ImageFormat::kWebp);
  for (int a = 3; a < argc; ++a) {
    const int q = std::atoi(argv[a]);
    encoding.jpeg_quality = encoding.webp_quality = q;
    TexturedMesh reencoded = input;
    uint64_t bytes = 0;
    for (Texture& t : reencoded.textures) {
      if (t.image.empty() || t.from_vertex_colours) continue;
      const std::string b = codec == "webp-plain" ? plain_webp(t.image, q) : encode_image(t.image, encoding, t.path);
      bytes += b.size();
      t.image = decode_image(reinterpret_cast<const unsigned char*>(b.data()), b.size(), t.path);
    }
    fmt::print("{} {} {:.3f}\n", q, bytes, surface_psnr(input, reencoded));
  }
  return 0;
}
