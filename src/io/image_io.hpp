// Reading and writing texture images. PNG through libspng, JPEG through libjpeg-turbo, WebP (reading) through libwebp, anything else
// stb_image understands (BMP, TGA, ...) through stb_image as a fallback. Every image is converted to
// 8-bit RGBA on load: grey, grey+alpha, palette, RGB, RGBA, 8 and 16 bits per channel.
#pragma once
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "core/image.hpp"
#include "tightex/io.hpp"

namespace tightex {

/// Decodes an image held in memory (used for fuzzing and for embedded glTF images); `name` is used
/// in error messages.
Image decode_image(const unsigned char* data, size_t size, const std::string& name, size_t max_pixels = size_t(1) << 30);

/// The image as a JPEG file's bytes (RGB, alpha ignored), encoded in memory. Requires a non-empty image
/// and quality in 1..100 (else InternalError); throws std::bad_alloc where memory runs out.
std::string encode_jpeg(const Image& image, int quality);

/// Refuses an encoding save_image would refuse: InputError "PATH: PNG compression level N is outside
/// 0..9" or "PATH: JPEG quality N is outside 1..100" (only the setting of encoding.format is checked).
void check_image_encoding(const ImageEncoding& encoding, const std::string& path);

/// Encodes one image at several settings (a rate search's qualities): what every lossy WebP encoding
/// of it shares, its conversion to YUV 4:2:0 (the costly sharp conversion, 0.6 s for 9 million
/// texels), is made on the first and kept for the others. encode() may run on several threads at once;
/// the image must outlive the encoder and stay unchanged.
class ImageEncoder {
 public:
  ImageEncoder(const Image& image, std::string name);
  ~ImageEncoder();
  ImageEncoder(const ImageEncoder&) = delete;
  ImageEncoder& operator=(const ImageEncoder&) = delete;
  /// The bytes encode_image(image, encoding, name) gives.
  std::string encode(const ImageEncoding& encoding) const;

  struct WebpYuv;

 private:
  const Image& image_;
  std::string name_;
  mutable std::once_flag webp_converted_;
  mutable std::unique_ptr<WebpYuv> webp_;
};

/// Width and height from the file's header alone ({0, 0} when unknown), so memory can be estimated
/// before any pixel is allocated.
std::pair<int, int> image_dimensions(const std::string& path);

/// The same from the first `size` bytes of an image held in memory (an image embedded in a glTF).
std::pair<int, int> image_dimensions(const unsigned char* data, size_t size);

}  // namespace tightex
