// The input's own rate-distortion curve: every texture a model's materials bind re-encoded in a codec at
// each quality, decoded back, and measured against the model as it is (docs/metrics.md surface PSNR, the same
// points as tightex's report). What a re-encode without repacking (gltf-transform, gltfpack) would give,
// for bench/bytes.sh beside tightex's own curve.
// Usage: tightex_reencode_curve MODEL webp|jpg Q1 [Q2 ...]   prints "quality bytes psnr_db" per line.
#include <fmt/format.h>

#include <cstdlib>
#include <string>

#include "io/image_io.hpp"
#include "report/metrics.hpp"
#include "tightex/io.hpp"

using namespace tightex;

int main(int argc, char** argv) {
  if (argc < 4) {
    fmt::print(stderr, "usage: {} MODEL webp|jpg QUALITY...\n", argv[0]);
    return 2;
  }
  const TexturedMesh input = read_model(argv[1]);
  ImageEncoding encoding(std::string(argv[2]) == "jpg" ? ImageFormat::kJpeg : ImageFormat::kWebp);
  for (int a = 3; a < argc; ++a) {
    const int q = std::atoi(argv[a]);
    encoding.jpeg_quality = encoding.webp_quality = q;
    TexturedMesh reencoded = input;
    uint64_t bytes = 0;
    for (Texture& t : reencoded.textures) {
      if (t.image.empty() || t.from_vertex_colours) continue;
      const std::string b = encode_image(t.image, encoding, t.path);
      bytes += b.size();
      t.image = decode_image(reinterpret_cast<const unsigned char*>(b.data()), b.size(), t.path);
    }
    fmt::print("{} {} {:.3f}\n", q, bytes, surface_psnr(input, reencoded));
  }
  return 0;
}
