// Reading and writing texture images. PNG through libspng, JPEG through libjpeg-turbo, WebP (reading) through libwebp, anything else
// stb_image understands (BMP, TGA, ...) through stb_image as a fallback. Every image is converted to
// 8-bit RGBA on load: grey, grey+alpha, palette, RGB, RGBA, 8 and 16 bits per channel.
#pragma once
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

/// Width and height from the file's header alone ({0, 0} when unknown), so memory can be estimated
/// before any pixel is allocated.
std::pair<int, int> image_dimensions(const std::string& path);

/// The same from the first `size` bytes of an image held in memory (an image embedded in a glTF).
std::pair<int, int> image_dimensions(const unsigned char* data, size_t size);

}  // namespace tightex
