// Reading and writing texture images. PNG through libspng, JPEG through libjpeg-turbo, anything else
// stb_image understands (BMP, TGA, ...) through stb_image as a fallback. Every image is converted to
// 8-bit RGBA on load: grey, grey+alpha, palette, RGB, RGBA, 8 and 16 bits per channel.
#pragma once
#include <string>
#include <utility>

#include "core/image.hpp"

namespace tightex {

enum class ImageFormat { kPng, kJpeg };

/// Loads an image file. Throws InputError naming the file and the problem (missing, unreadable,
/// truncated, corrupt, unsupported, or larger than max_pixels) -- never crashes on a bad file.
Image load_image(const std::string& path, size_t max_pixels = size_t(1) << 30);

/// Decodes an image held in memory (used for fuzzing and for embedded glTF images); `name` is used
/// in error messages.
Image decode_image(const unsigned char* data, size_t size, const std::string& name,
                   size_t max_pixels = size_t(1) << 30);

/// Width and height from the file's header alone ({0, 0} when unknown), so memory can be estimated
/// before any pixel is allocated.
std::pair<int, int> image_dimensions(const std::string& path);

/// Writes an image (RGB; alpha is dropped when it is 255 everywhere). PNG uses fast compression
/// settings (tightex writes 8K textures; zlib level 9 would dominate the run time). `jpeg_quality`
/// is 1..100. Throws InputError naming the file when it cannot be written.
void save_image(const std::string& path, const Image& image, ImageFormat format, int jpeg_quality = 92);

}  // namespace tightex
