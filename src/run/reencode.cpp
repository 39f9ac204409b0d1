#include "run/reencode.hpp"

#include <tbb/parallel_for.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "io/image_io.hpp"
#include "report/metrics.hpp"
#include "run/budget_search.hpp"
#include "run/texture_bytes.hpp"

namespace tightex {

namespace {

/// Per texture of `mesh`, whether a material binds it (bound_textures) and it holds an image of its
/// own (not vertex colours).
std::vector<char> bound_images(const TexturedMesh& mesh) {
  std::vector<char> bound = bound_textures(mesh);
  for (size_t i = 0; i < bound.size(); ++i) bound[i] = bound[i] && !mesh.textures[i].image.empty() && !mesh.textures[i].from_vertex_colours;
  return bound;
}

/// `mesh` without its images (the textures' other fields kept): the side of the comparison that the
/// re-encoded images are swapped into, while `mesh` keeps its own.
TexturedMesh without_images(TexturedMesh& mesh) {
  std::vector<Image> images(mesh.textures.size());
  for (size_t i = 0; i < images.size(); ++i) std::swap(images[i], mesh.textures[i].image);
  TexturedMesh copy = mesh;
  for (size_t i = 0; i < images.size(); ++i) std::swap(images[i], mesh.textures[i].image);
  return copy;
}

}  // namespace

ReencodeFigures reencode_at_psnr(TexturedMesh& input, ImageFormat codec, double psnr_db) {
  const std::vector<char> bound = bound_images(input);
  const std::vector<char> colour = colour_textures(input);
  TexturedMesh reencoded = without_images(input);
  const SurfacePsnrOfImages judge(input, reencoded);
  std::map<int, std::pair<uint64_t, double>> measured;  // quality -> bytes, PSNR
  const TextureEncoders encoders(input, {}, bound);
  // Each quality's images encoded side by side with the other's (one core an image), then measured.
  auto psnr_at = [&](const std::vector<int>& qualities) {
    std::vector<std::vector<std::string>> files(qualities.size());
    tbb::parallel_for(size_t(0), qualities.size(), [&](size_t q) {
      ImageEncoding encoding(codec);
      encoding.jpeg_quality = encoding.webp_quality = qualities[q];
      files[q] = encoders.encode(encoding);
    });
    std::vector<double> psnr;
    for (size_t q = 0; q < qualities.size(); ++q) {
      uint64_t bytes = 0;
      for (const std::string& f : files[q]) bytes += f.size();
      psnr.push_back(psnr_as_written(judge, colour, reencoded, files[q]));
      measured[qualities[q]] = {bytes, psnr.back()};
    }
    return psnr;
  };
  ReencodeFigures r;
  r.quality = lowest_quality_reaching(psnr_at, psnr_db, 0);
  for (const auto& [q, m] : measured) r.probes.push_back({{"quality", q}, {"bytes", m.first}, {"psnr_db", m.second}});
  const auto at = measured.find(std::min(r.quality, 100));
  r.bytes = at->second.first, r.reached_psnr_db = at->second.second;
  r.bytes_at_psnr = double(r.bytes);
  const auto below = measured.find(r.quality - 1);
  if (r.quality <= 100 && below != measured.end() && at->second.second > below->second.second) {
    const double t = (psnr_db - below->second.second) / (at->second.second - below->second.second);
    r.bytes_at_psnr =
        std::exp(std::log(double(below->second.first)) + t * (std::log(double(r.bytes)) - std::log(double(below->second.first))));
  }
  return r;
}

}  // namespace tightex
