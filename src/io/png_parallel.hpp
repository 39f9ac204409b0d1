// PNG encoding on every core: rows filtered in parallel, the filtered bytes deflated in slices side by
// side (each slice primed with the 32 KiB before it, as pigz does, so matches reach across slices), the
// slices joined into one zlib stream (sync-flushed at their ends, Adler-32 combined), one IDAT chunk.
#pragma once
#include <string>

#include "core/image.hpp"

namespace tightex {

/// How the rows are filtered before deflate.
enum class PngRowFilter {
  kUp,        // every row against the one above (one pass, what photographs gain most from)
  kAdaptive,  // per row the filter of the five whose bytes have the least sum of absolute values
};

/// The settings of one encoding: zlib's level (0..9) and strategy (Z_DEFAULT_STRATEGY, Z_RLE, ...).
struct PngSettings {
  int level = 6;
  int strategy = 0;
  PngRowFilter filter = PngRowFilter::kAdaptive;
};

/// Whether every pixel's alpha is 255 (an encoder may then store RGB alone).
bool is_opaque(const Image& image);

/// The PNG file of `image`: 8-bit grey where red, green and blue agree in every pixel (a one-channel
/// map takes a third of the samples), else RGB; with alpha where some alpha is not 255. The same pixels as any
/// encoder's; the bytes depend on the settings and the slice size, not on the number of cores.
std::string encode_png(const Image& image, const PngSettings& settings);

}  // namespace tightex
