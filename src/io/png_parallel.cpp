#include "io/png_parallel.hpp"

#include <tbb/parallel_for.h>
#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "core/error.hpp"

namespace tightex {

namespace {

constexpr size_t kSliceBytes = size_t(1) << 20;  // filtered bytes deflated as one slice
constexpr size_t kWindowBytes = 32768;           // deflate's window: the dictionary a slice is primed with
constexpr size_t kMaxIdatBytes = size_t(1) << 30;

/// Row y's samples: grey (`channels` 1: the red of an image whose red, green and blue agree), grey and
/// alpha (2), RGB (3) or RGBA (4).
void raw_row(const Image& image, size_t y, size_t channels, unsigned char* out) {
  const Rgba8* row = image.pixels.data() + y * size_t(image.width);
  if (channels >= 3) {
    for (size_t x = 0; x < size_t(image.width); ++x) std::memcpy(out + x * channels, &row[x], channels);
  } else {
    for (size_t x = 0; x < size_t(image.width); ++x) {
      out[x * channels] = row[x].r;
      if (channels == 2) out[x * channels + 1] = row[x].a;
    }
  }
}

/// The fewest 8-bit channels that hold every pixel of `image` exactly: 1 (grey) or 2 (grey and alpha)
/// where red, green and blue agree everywhere (an occlusion, roughness, height or greyscale scan), else
/// 3 (RGB) or 4 (RGBA); alpha only where some pixel's is not 255.
size_t channels_needed(const Image& image) {
  const bool grey = std::all_of(image.pixels.begin(), image.pixels.end(), [](const Rgba8& p) { return p.r == p.g && p.g == p.b; });
  return (grey ? 1 : 3) + (is_opaque(image) ? 0 : 1);
}

/// PNG's colour type for `channels` 8-bit channels: grey 0, grey and alpha 4, RGB 2, RGBA 6.
char colour_type(size_t channels) { return char(channels == 1 ? 0 : channels == 2 ? 4 : channels == 3 ? 2 : 6); }

uint8_t paeth(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return uint8_t(pa <= pb && pa <= pc ? a : pb <= pc ? b : c);
}

/// `cur` filtered with PNG filter type `type` (0 none, 1 sub, 2 up, 3 average, 4 paeth) into `out`.
void filter_row(int type, const unsigned char* cur, const unsigned char* prev, size_t n, size_t bpp, unsigned char* out) {
  for (size_t i = 0; i < n; ++i) {
    const int a = i >= bpp ? cur[i - bpp] : 0, b = prev[i], c = i >= bpp ? prev[i - bpp] : 0;
    const int predicted = type == 0 ? 0 : type == 1 ? a : type == 2 ? b : type == 3 ? (a + b) / 2 : paeth(a, b, c);
    out[i] = uint8_t(cur[i] - predicted);
  }
}

/// Sum of the filtered bytes read as signed: the usual guess of how well a row will deflate.
uint64_t signed_sum(const unsigned char* bytes, size_t n) {
  uint64_t sum = 0;
  for (size_t i = 0; i < n; ++i) sum += uint64_t(std::abs(int(int8_t(bytes[i]))));
  return sum;
}

/// Every row with its filter byte in front, as PNG's IDAT data holds them before deflate.
std::vector<unsigned char> filtered_rows(const Image& image, size_t channels, PngRowFilter filter) {
  const size_t stride = size_t(image.width) * channels, rows = size_t(image.height);
  std::vector<unsigned char> out(rows * (stride + 1));
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rows, 64), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<unsigned char> prev(stride, 0), cur(stride), trial(stride);
    if (r.begin() > 0) raw_row(image, r.begin() - 1, channels, prev.data());
    for (size_t y = r.begin(); y < r.end(); ++y) {
      raw_row(image, y, channels, cur.data());
      unsigned char* dst = out.data() + y * (stride + 1);
      if (filter == PngRowFilter::kUp) {
        dst[0] = 2;
        filter_row(2, cur.data(), prev.data(), stride, channels, dst + 1);
      } else {
        uint64_t best = UINT64_MAX;
        for (int type = 0; type < 5; ++type) {
          filter_row(type, cur.data(), prev.data(), stride, channels, trial.data());
          const uint64_t cost = signed_sum(trial.data(), stride);
          if (cost < best) best = cost, dst[0] = uint8_t(type), std::memcpy(dst + 1, trial.data(), stride);
        }
      }
      std::swap(prev, cur);
    }
  });
  return out;
}

/// Slice [begin, end) of `data` as raw deflate, primed with the window before it; sync-flushed (ending
/// on a byte boundary) unless it is the last.
std::string deflate_slice(const std::vector<unsigned char>& data, size_t begin, size_t end, const PngSettings& settings) {
  z_stream z{};
  if (deflateInit2(&z, settings.level, Z_DEFLATED, -15, 8, settings.strategy) != Z_OK) fail_internal("deflateInit2 failed");
  const size_t window = std::min(begin, kWindowBytes);
  if (window > 0) deflateSetDictionary(&z, data.data() + begin - window, uInt(window));
  std::string out(deflateBound(&z, uLong(end - begin)) + 16, '\0');
  z.next_in = const_cast<unsigned char*>(data.data() + begin);
  z.avail_in = uInt(end - begin);
  z.next_out = reinterpret_cast<unsigned char*>(out.data());
  z.avail_out = uInt(out.size());
  const bool last = end == data.size();
  const int status = deflate(&z, last ? Z_FINISH : Z_SYNC_FLUSH);
  const size_t written = out.size() - z.avail_out;
  deflateEnd(&z);
  if (status != (last ? Z_STREAM_END : Z_OK) || z.avail_in != 0) fail_internal("deflate of a PNG slice failed ({})", status);
  out.resize(written);
  return out;
}

/// The zlib stream of `data`: header, the slices' deflate streams in order, Adler-32.
std::string zlib_stream(const std::vector<unsigned char>& data, const PngSettings& settings) {
  const size_t slices = std::max<size_t>(1, (data.size() + kSliceBytes - 1) / kSliceBytes);
  std::vector<std::string> parts(slices);
  std::vector<uLong> adler(slices);
  tbb::parallel_for(size_t(0), slices, [&](size_t k) {
    const size_t begin = k * kSliceBytes, end = std::min(data.size(), begin + kSliceBytes);
    parts[k] = deflate_slice(data, begin, end, settings);
    adler[k] = adler32(adler32(0, nullptr, 0), data.data() + begin, uInt(end - begin));
  });
  uLong checksum = adler[0];
  for (size_t k = 1; k < slices; ++k)
    checksum = adler32_combine(checksum, adler[k], z_off_t(std::min(kSliceBytes, data.size() - k * kSliceBytes)));
  // CMF 0x78: deflate with a 32 KiB window; FLG: the level class, no dictionary, check bits.
  const int level_class = settings.level <= 1 ? 0 : settings.level <= 5 ? 1 : settings.level == 6 ? 2 : 3;
  unsigned flg = unsigned(level_class) << 6;
  flg += 31 - (0x78u * 256 + flg) % 31;
  std::string out{char(0x78), char(flg)};
  for (const std::string& p : parts) out += p;
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(char((checksum >> shift) & 0xFF));
  return out;
}

void append_u32(std::string& out, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(char((v >> shift) & 0xFF));
}

/// One PNG chunk: length, type, data, CRC over type and data.
void append_chunk(std::string& out, const char* type, const char* data, size_t size) {
  append_u32(out, uint32_t(size));
  const size_t type_at = out.size();
  out.append(type, 4);
  if (size > 0) out.append(data, size);
  const uLong crc = crc32(crc32(0, nullptr, 0), reinterpret_cast<const unsigned char*>(out.data() + type_at), uInt(size + 4));
  append_u32(out, uint32_t(crc));
}

}  // namespace

bool is_opaque(const Image& image) {
  return std::all_of(image.pixels.begin(), image.pixels.end(), [](const Rgba8& p) { return p.a == 255; });
}

std::string encode_png(const Image& image, const PngSettings& settings) {
  if (image.width <= 0 || image.height <= 0) fail_internal("encode_png of a {}x{} image", image.width, image.height);
  const size_t channels = channels_needed(image);
  const std::string idat = zlib_stream(filtered_rows(image, channels, settings.filter), settings);
  std::string png("\x89PNG\r\n\x1a\n", 8);
  std::string ihdr;
  append_u32(ihdr, uint32_t(image.width));
  append_u32(ihdr, uint32_t(image.height));
  ihdr += {char(8), colour_type(channels), char(0), char(0), char(0)};  // 8 bits a channel
  append_chunk(png, "IHDR", ihdr.data(), ihdr.size());
  for (size_t at = 0; at < idat.size(); at += kMaxIdatBytes)
    append_chunk(png, "IDAT", idat.data() + at, std::min(kMaxIdatBytes, idat.size() - at));
  append_chunk(png, "IEND", nullptr, 0);
  return png;
}

}  // namespace tightex
