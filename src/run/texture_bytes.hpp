// How the output's texture images are encoded, and what both models' images weigh: the input's codec
// unless the command line names one; for a lossy codec the quality that rate control picks (the
// input's own bytes as the bound by default, or --target-psnr / --max-bytes); the bytes of every image
// the materials bind, and the surface PSNR of the images as written.
#pragma once
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "io/texture_sources.hpp"
#include "report/metrics.hpp"
#include "tightex/io.hpp"
#include "tightex/mesh.hpp"

namespace tightex {

/// What the options ask of the output's images (Options: texture_format, the codecs' settings, target_psnr_db, max_bytes).
struct BytesRequest {
  std::optional<ImageFormat> format;  // --format; nullopt: the input's base colour codec (PNG where none)
  ImageEncoding encoding;             // the levels and qualities as given or defaulted
  bool quality_given = false;         // --jpeg-quality or --webp-quality: kept as it is
  double target_psnr_db = 0;          // --target-psnr (0: none)
  uint64_t max_bytes = 0;             // --max-bytes (0: none)
  /// Where > 0, --target-psnr and --max-bytes choose the texels of the bake's images too (the output's
  /// first `new_pages` textures are its pages; budget_search.hpp); 0: the quality alone.
  size_t new_pages = 0;
  /// Where > 0, the quality rate control expects near the answer (it brackets there first).
  int quality_hint = 0;
  /// --target-psnr: the codec's expected error (mean squared, 8-bit levels) per quality 0..100 (the texel
  /// search's model); rate control then starts where it and the images' own error, measured, meet the
  /// target, instead of at quality_hint. Empty: none.
  std::vector<double> codec_mse_by_quality;
  /// --target-psnr: judges made for an output with the same triangles, corners and vertices as this
  /// one (another bake of the same charts), asked instead of new ones. Null: made here.
  PsnrJudges judges;
  /// Without --format, the lossy codecs that search may choose from (those the output format reads
  /// everywhere).
  std::vector<ImageFormat> codecs;
  /// Told the fraction of the encoding done (rate control's steps, then the final images); may throw
  /// Cancelled to stop it. Empty: none.
  std::function<void(double)> progress;
};

/// The encoding chosen and what it gives: each output texture's encoded file, the surface PSNR of the
/// images as written (decoded back; for a lossless codec the bake's, unset here), and why.
struct EncodingChoice {
  ImageEncoding encoding;
  std::vector<std::string> images;  // per output texture, its file's bytes (for the writer)
  std::vector<uint64_t> bytes;      // per output texture
  std::optional<double> written_psnr_db;
  std::string reason;
  nlohmann::json probes;           // the texel search's probes (null where it did not run)
  double texel_scale = 1;          // the texel search's scale of the baked images' side (1: as baked)
  double bake_error_exponent = 2;  // the texel search's (BudgetSearchResult)
  /// The texel search's model of the codec's error (BudgetSearchResult).
  std::function<double(double scale, int quality)> codec_mse_at;
  /// The judges that measured the images (made for `output`'s triangles; null where none did): the
  /// caller asks them again for the same output's figures, such as its images unencoded.
  PsnrJudges judges;
};

/// Whether images of `bytes_a` bytes at `psnr_a` dB answer --target-psnr (`target_psnr_db` > 0) or else
/// --max-bytes better than `bytes_b` at `psnr_b`: fewer bytes at the target (more PSNR where neither
/// reaches it), more PSNR within the bound (fewer bytes where neither fits).
bool answers_better(double target_psnr_db, uint64_t max_bytes, uint64_t bytes_a, double psnr_a, uint64_t bytes_b, double psnr_b);

/// Per texture of `mesh`, whether some material binds it (as base colour or any other map).
std::vector<char> bound_textures(const TexturedMesh& mesh);

/// The lowest quality in [1, 100] whose surface PSNR (`psnr_at`, rising with the quality) reaches
/// `target`; 101 where none does. `psnr_at` measures a quality and, where not yet known, the one
/// below it (a caller encodes them side by side): where the first is the answer, the second proves
/// it. Starts at `hint` (75 without one), then interpolates between the two sides once both are known,
/// else follows the secant a little beyond: two or three rounds from a hint within ten qualities of
/// the answer. Each quality is measured at most once.
int lowest_quality_reaching(const std::function<std::vector<double>(const std::vector<int>&)>& psnr_at, double target, int hint);

/// Chooses the encoding of `output`'s images (the result of `input`, whose textures are `sources`), and
/// measures what it gives. Leaves `output` as it was.
EncodingChoice choose_encoding(const BytesRequest& request, const TexturedMesh& input, const std::vector<TextureSource>& sources,
                               TexturedMesh& output);

/// report.json's "bytes": per model, the bytes of the images its materials bind, as base colour and per
/// other map slot, and in total; every written image (file, size, slots, codec, quality, bytes, the
/// written PSNR of what it shows); the encoding chosen and why; the surface PSNR as written (`written`:
/// the metrics measured from the files). An output image only slots `format` cannot hold read
/// (OBJ's specular map in a glTF, glTF's occlusion in an MTL) is not written there and not counted.
nlohmann::json bytes_json(const TexturedMesh& input, const std::vector<TextureSource>& sources, const TexturedMesh& output,
                          const EncodingChoice& choice, const Metrics& written, ModelFormat format);

}  // namespace tightex
