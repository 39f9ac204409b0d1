// --target-psnr and --max-bytes with tightex's own texel budget: the texels and the quality chosen
// together. The baked atlas is shrunk to a few scales and each encoded at a few qualities (probes,
// never a re-bake); bytes and surface PSNR are interpolated between the probes over the quality, the
// best (scale, quality) chosen from that model, then checked and nudged on the images as written.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io/image_io.hpp"
#include "report/metrics.hpp"
#include "tightex/io.hpp"
#include "tightex/mesh.hpp"

namespace tightex {

/// What the search asks for: the fewest bytes at `target_psnr_db`, or the most PSNR within `max_bytes`.
struct BudgetSearchRequest {
  double target_psnr_db = 0;  // 0: none
  uint64_t max_bytes = 0;     // 0: none
  size_t new_pages = 0;       // the output's first textures that are the bake's pages
  /// false: a scale below 1 is returned as the model chose it, unchecked and without images (the caller
  /// plans and bakes at that budget again and chooses its quality there).
  bool check_shrunk = true;
  /// Judges made for this output (another codec's search), asked instead of new ones. Null: made here.
  PsnrJudges judges;
  /// Told the fraction of the search done; may throw Cancelled. Empty: none.
  std::function<void(double)> progress;
};

/// The search's choice: the quality (set into the encoding), the scale of the baked images and the
/// images at that scale, their encoded files and the surface PSNR as written, and the probes.
struct BudgetSearchResult {
  int quality = 0;  // the model's alone where `images` is empty (BudgetSearchRequest::check_shrunk)
  double scale = 1;
  std::vector<Image> scaled;        // per texture of the output, its image at `scale` (empty: as it is)
  std::vector<std::string> images;  // per texture of the output, its file's bytes
  double written_psnr_db = 0;
  std::string reason;
  nlohmann::json probes = nlohmann::json::array();
  /// The model's codec error (mean squared, 8-bit levels) at a scale of the side and a quality, where
  /// the images come back unchecked (BudgetSearchRequest::check_shrunk), and where no quality reaches a
  /// target at the bake's size (then scaled by what the checks there measured; asked above 1 too, of a
  /// bake at more texels): with a re-bake's own error it tells the quality to start its search at.
  /// Empty otherwise.
  std::function<double(double scale, int quality)> codec_mse_at;
  /// How fast the bake's own error grows as the side shrinks: log2 of its mean squared error at half the
  /// side over its error at the full side (measured unencoded; 2 where it is not measured). A target the
  /// full side does not reach takes this to tell how many more texels may reach it.
  double bake_error_exponent = 2;
  PsnrJudges judges;  // those the search made (`all` null where it checked nothing)
};

/// An encoder (ImageEncoder) per texture image of a model, for encoding them all at several settings:
/// the conversions every lossy WebP encoding of an image shares are made once.
class TextureEncoders {
 public:
  /// For each texture of `mesh` with an image (and, where `only` is given, marked in it): its image, or
  /// the one `replaced` holds at its index where that is not empty. The images must outlive it.
  explicit TextureEncoders(const TexturedMesh& mesh, const std::vector<Image>& replaced = {}, const std::vector<char>& only = {});
  /// Each image encoded as encoding.of_texture(i) says (on every core; empty where there is no encoder,
  /// and, with `lossy_only`, where its encoding is lossless).
  std::vector<std::string> encode(const ImageEncoding& encoding, bool lossy_only = false) const;

 private:
  std::vector<std::unique_ptr<ImageEncoder>> encoders_;
};

/// Per texture of `output`, whether a material binds it as its base colour: the images the surface PSNR
/// reads (the other maps change the bytes alone).
std::vector<char> colour_textures(const TexturedMesh& output);

/// The mean squared error (8-bit levels, per channel) that a surface PSNR stands for.
double mse_of_psnr(double psnr);

/// The surface PSNR (`judge`'s points) of `output` with its base colour images (`colour`) as `files`
/// decode (swapped in, then back).
double psnr_as_written(const SurfacePsnrOfImages& judge, const std::vector<char>& colour, TexturedMesh& output,
                       const std::vector<std::string>& files);

/// Searches the scale of `output`'s baked images (the new pages and the maps of the materials that
/// bind them) and the lossy quality of `encoding` together. `output` is left as it was (its images are
/// swapped out and back while measured); `input` is the model it was made from.
BudgetSearchResult search_texels_and_quality(const BudgetSearchRequest& request, const TexturedMesh& input, TexturedMesh& output,
                                             ImageEncoding& encoding);

/// `image` made `width` x `height` (no larger) by the mean of its texels over each new texel's
/// footprint, counting only the texels `inside` marks where the footprint holds any, so a chart's
/// border does not take its gutter's colour.
Image shrink_image(const Image& image, const std::vector<uint8_t>& inside, int width, int height);

}  // namespace tightex
