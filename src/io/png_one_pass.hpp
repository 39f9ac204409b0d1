// The common PNG textures decoded in one pass: the whole zlib stream inflated at once by libdeflate
// (several times faster than zlib's streaming inflate, which libspng uses), then unfiltered row by row
// into the RGBA pixels, in the image's own memory.
#pragma once
#include <cstddef>
#include <optional>

#include "core/image.hpp"

namespace tightex {

/// The image of a PNG whose samples are 8-bit grey, grey+alpha, RGB or RGBA, not interlaced, without
/// a tRNS chunk (what scanners and photogrammetry write), as RGBA (grey spread to red, green and blue;
/// alpha 255 where the image has none): the pixels libspng gives for SPNG_FMT_RGBA8. nullopt for any
/// other PNG and for anything unexpected (a chunk's CRC, a chunk larger than `max_chunk_bytes`, the
/// zlib stream or its size, a row's filter type, more than `max_pixels` pixels): the caller then
/// decodes with libspng, which names the problem. Reads nothing outside [data, data + size); allocates
/// the image (a quarter pixel a row more, for the inflated rows), two rows, and a copy of the
/// compressed data where it spans several chunks.
std::optional<Image> decode_png_in_one_pass(const unsigned char* data, size_t size, size_t max_pixels, size_t max_chunk_bytes);

}  // namespace tightex
