#include "io/png_one_pass.hpp"

#include <libdeflate.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <utility>
#include <vector>

namespace tightex {

namespace {

constexpr size_t kSignatureBytes = 8;
constexpr uint32_t kMaxChunkLength = 0x7fffffffu;  // PNG's own limit on a chunk's length

uint32_t big_endian_32(const unsigned char* p) { return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3]; }

/// One chunk of the file: its four-letter type and its data, both inside the file.
struct Chunk {
  const unsigned char* type = nullptr;
  const unsigned char* data = nullptr;
  size_t size = 0;
  bool is(const char* name) const { return std::memcmp(type, name, 4) == 0; }
};

/// The chunk at `offset`, if it lies inside the file, its type is four letters and its CRC matches.
std::optional<Chunk> chunk_at(const unsigned char* file, size_t file_size, size_t offset) {
  if (offset > file_size || file_size - offset < 12) return std::nullopt;
  const unsigned char* p = file + offset;
  const uint32_t length = big_endian_32(p);
  if (length > kMaxChunkLength || length > file_size - offset - 12) return std::nullopt;
  for (int k = 4; k < 8; ++k)
    if (!((p[k] >= 'A' && p[k] <= 'Z') || (p[k] >= 'a' && p[k] <= 'z'))) return std::nullopt;
  if (libdeflate_crc32(0, p + 4, size_t(length) + 4) != big_endian_32(p + 8 + length)) return std::nullopt;
  return Chunk{p + 4, p + 8, length};
}

/// The header's figures this decoder needs.
struct Header {
  uint32_t width = 0, height = 0;
  int channels = 0;  // 1 grey, 2 grey+alpha, 3 RGB, 4 RGBA
};

/// The header, if the image is one this decoder takes: 8-bit samples, no palette, not interlaced.
std::optional<Header> supported_header(const Chunk& ihdr) {
  if (!ihdr.is("IHDR") || ihdr.size != 13) return std::nullopt;
  const unsigned char* d = ihdr.data;
  Header h{big_endian_32(d), big_endian_32(d + 4), 0};
  const int bit_depth = d[8], colour_type = d[9], compression = d[10], filter = d[11], interlace = d[12];
  if (h.width == 0 || h.height == 0 || h.width > kMaxChunkLength || h.height > kMaxChunkLength) return std::nullopt;
  if (bit_depth != 8 || compression != 0 || filter != 0 || interlace != 0) return std::nullopt;
  // Samples a pixel by colour type: 0 grey, 2 RGB, 4 grey+alpha, 6 RGBA; 3 (palette) and others are not taken.
  static constexpr int kChannels[7] = {1, 0, 3, 0, 2, 0, 4};
  h.channels = colour_type < 7 ? kChannels[colour_type] : 0;
  if (h.channels == 0) return std::nullopt;
  return h;
}

/// The zlib stream: the data of the consecutive IDAT chunks, in `joined` where there are several.
/// nullopt where a chunk before them is one this decoder does not take (tRNS, which makes some colour
/// transparent; a palette for a grey image; an unknown critical chunk; one larger than the limit).
std::optional<std::pair<const unsigned char*, size_t>> image_data(const unsigned char* file, size_t size, size_t offset,
                                                                  const Header& header, size_t max_chunk_bytes,
                                                                  std::vector<unsigned char>& joined) {
  std::optional<Chunk> chunk = chunk_at(file, size, offset);
  for (; chunk && !chunk->is("IDAT"); chunk = chunk_at(file, size, offset)) {
    const bool critical = chunk->type[0] <= 'Z';
    if (chunk->is("tRNS") || chunk->size > max_chunk_bytes) return std::nullopt;
    if (critical && !(chunk->is("PLTE") && header.channels >= 3)) return std::nullopt;  // IEND, IHDR again, unknown
    offset += 12 + chunk->size;
  }
  if (!chunk) return std::nullopt;
  // The run of IDAT chunks, measured first so that a stream of many is copied once into its place.
  const size_t first = offset;
  size_t chunks = 0, bytes = 0;
  for (; chunk && chunk->is("IDAT"); chunk = chunk_at(file, size, offset)) {
    ++chunks, bytes += chunk->size;
    offset += 12 + chunk->size;
  }
  if (chunks == 1) return std::make_pair(file + first + 8, bytes);
  joined.reserve(bytes);
  for (offset = first; joined.size() < bytes; offset += 12 + big_endian_32(file + offset))
    joined.insert(joined.end(), file + offset + 8, file + offset + 8 + big_endian_32(file + offset));
  return std::make_pair(joined.data(), joined.size());
}

/// The Paeth predictor (PNG §9.4): of left, above and upper left, the one nearest left + above - upper left.
/// Without branches: on photographs the choice is unpredictable, and mispredicted branches made the
/// rows unfilter slower than libspng's.
inline unsigned char paeth(int a, int b, int c) {
  const int pa = std::abs(b - c), pb = std::abs(a - c), pc = std::abs(a + b - 2 * c);
  const int b_or_c = pb <= pc ? b : c;
  return static_cast<unsigned char>((pa <= pb) & (pa <= pc) ? a : b_or_c);
}

/// Undoes one row's filter in place (PNG §9): `row` (its filter's bytes) becomes the reconstructed
/// samples, `above` is the row above reconstructed (zeros above the first row), `Bpp` bytes a pixel.
/// False for an unknown filter type.
template <size_t Bpp>
bool unfilter_row(unsigned char type, unsigned char* row, const unsigned char* above, size_t bytes) {
  switch (type) {
    case 0:
      return true;
    case 1:
      for (size_t i = Bpp; i < bytes; ++i) row[i] = static_cast<unsigned char>(row[i] + row[i - Bpp]);
      return true;
    case 2:
      for (size_t i = 0; i < bytes; ++i) row[i] = static_cast<unsigned char>(row[i] + above[i]);
      return true;
    case 3:
      for (size_t i = 0; i < Bpp; ++i) row[i] = static_cast<unsigned char>(row[i] + above[i] / 2);
      for (size_t i = Bpp; i < bytes; ++i) row[i] = static_cast<unsigned char>(row[i] + (row[i - Bpp] + above[i]) / 2);
      return true;
    case 4:
      for (size_t i = 0; i < Bpp; ++i) row[i] = static_cast<unsigned char>(row[i] + above[i]);
      for (size_t i = Bpp; i < bytes; ++i) row[i] = static_cast<unsigned char>(row[i] + paeth(row[i - Bpp], above[i], above[i - Bpp]));
      return true;
    default:
      return false;
  }
}

/// One reconstructed row of `Channels` samples a pixel as RGBA pixels.
template <size_t Channels>
void expand_row(const unsigned char* row, uint32_t width, Rgba8* out) {
  for (uint32_t x = 0; x < width; ++x, row += Channels) {
    if constexpr (Channels == 1) out[x] = Rgba8{row[0], row[0], row[0], 255};
    if constexpr (Channels == 2) out[x] = Rgba8{row[0], row[0], row[0], row[1]};
    if constexpr (Channels == 3) out[x] = Rgba8{row[0], row[1], row[2], 255};
    if constexpr (Channels == 4) out[x] = Rgba8{row[0], row[1], row[2], row[3]};
  }
}

/// Unfilters the rows of `raw` (each a filter type byte, then the row's samples) into `image`, whose
/// pixels may share memory with `raw` as long as each row's pixels end at or before the next raw row
/// begins: each raw row is copied out before its pixels are written. False for an unknown filter type.
template <size_t Channels>
bool unfilter_into(const unsigned char* raw, Image& image) {
  const uint32_t width = uint32_t(image.width);
  const size_t bytes = size_t(width) * Channels;
  std::vector<unsigned char> above(bytes, 0), row(bytes);
  for (int y = 0; y < image.height; ++y, raw += bytes + 1) {
    const unsigned char type = raw[0];
    std::memcpy(row.data(), raw + 1, bytes);
    if (!unfilter_row<Channels>(type, row.data(), above.data(), bytes)) return false;
    expand_row<Channels>(row.data(), width, image.pixels.data() + size_t(y) * width);
    std::swap(row, above);
  }
  return true;
}

/// unfilter_into for the image's samples a pixel.
bool unfilter_rows(int channels, const unsigned char* raw, Image& image) {
  if (channels == 1) return unfilter_into<1>(raw, image);
  if (channels == 2) return unfilter_into<2>(raw, image);
  if (channels == 3) return unfilter_into<3>(raw, image);
  return unfilter_into<4>(raw, image);
}

struct DecompressorDeleter {
  void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};

}  // namespace

std::optional<Image> decode_png_in_one_pass(const unsigned char* data, size_t size, size_t max_pixels, size_t max_chunk_bytes) {
  const std::optional<Chunk> ihdr = chunk_at(data, size, kSignatureBytes);
  if (!ihdr) return std::nullopt;
  const std::optional<Header> header = supported_header(*ihdr);
  if (!header || uint64_t(header->width) * header->height > max_pixels) return std::nullopt;
  std::vector<unsigned char> joined;
  const auto stream = image_data(data, size, kSignatureBytes + 12 + ihdr->size, *header, max_chunk_bytes, joined);
  if (!stream) return std::nullopt;

  // The inflated rows are written to the end of the pixels' own memory, and unfiltered from its start:
  // a row's pixels (4 bytes each) then end before the next raw row (1 + channels bytes a pixel)
  // begins, given a quarter pixel a row to spare (1 byte a row).
  const size_t pixels = size_t(header->width) * header->height;
  const size_t raw_bytes = size_t(header->height) * (1 + size_t(header->width) * size_t(header->channels));
  Image image;
  image.width = int(header->width);
  image.height = int(header->height);
  image.pixels.resize(pixels + (header->height + 3) / 4);
  unsigned char* memory = reinterpret_cast<unsigned char*>(image.pixels.data());
  unsigned char* raw = memory + image.pixels.size() * sizeof(Rgba8) - raw_bytes;
  const std::unique_ptr<libdeflate_decompressor, DecompressorDeleter> inflater(libdeflate_alloc_decompressor());
  if (!inflater) throw std::bad_alloc();
  if (libdeflate_zlib_decompress(inflater.get(), stream->first, stream->second, raw, raw_bytes, nullptr) != LIBDEFLATE_SUCCESS)
    return std::nullopt;
  if (!unfilter_rows(header->channels, raw, image)) return std::nullopt;
  image.pixels.resize(pixels);
  return image;
}

}  // namespace tightex
