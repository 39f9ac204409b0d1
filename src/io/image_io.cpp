#include "io/image_io.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <new>
#include <optional>
#include <system_error>
#include <utility>
#include <vector>

// jpeglib.h needs FILE and size_t declared before it; jerror.h needs jpeglib.h's configuration.
// clang-format off
#include <jpeglib.h>
#include <jerror.h>
// clang-format on
#include <spng.h>
#include <webp/decode.h>
#include <webp/encode.h>
#include <zlib.h>

#include "core/error.hpp"
#include "io/png_one_pass.hpp"
#include "io/png_parallel.hpp"

// stb_image is the fallback for formats other than PNG and JPEG, which have hardened decoders above.
// STB_IMAGE_STATIC keeps its functions private to this file, so another translation unit that also
// compiles stb cannot clash with it. PNG and JPEG are compiled out because they never reach stb. So is
// Radiance HDR: stb 2.27 loops forever on an RLE count of 0 (found by fuzzing), and a float HDR image
// is no 8-bit texture anyway; and Softimage PIC, which no texture pipeline produces. What remains:
// BMP, TGA, GIF (first frame), PNM, and PSD's header (its pixels are decoded here: see decode_psd).
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_NO_STDIO
#define STBI_NO_PNG
#define STBI_NO_JPEG
#define STBI_NO_HDR
#define STBI_NO_PIC
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#pragma GCC diagnostic ignored "-Wunused-but-set-variable"
#include <stb/stb_image.h>
#pragma GCC diagnostic pop

namespace tightex {

// The decoders write straight into Image::pixels, which must therefore be tightly packed RGBA bytes.
static_assert(sizeof(Rgba8) == 4 && alignof(Rgba8) == 1);

namespace {

// Bigger than any compressed image tightex could accept under the default pixel limit, and a guard
// against reading an endless stream (a FIFO fed from /dev/zero) into memory.
constexpr size_t kMaxFileBytes = size_t(4) << 30;

// libspng keeps ancillary PNG chunks (text, ICC profile, EXIF) in memory; these limits bound that memory
// for hostile files (real chunks are kilobytes; bigger ones are skipped or refused). The image data
// (IDAT) is streamed through zlib and is not subject to them: a PNG whose single IDAT chunk holds
// 75 MB loads fine (checked by hand).
constexpr size_t kPngChunkSizeLimit = size_t(64) << 20;
constexpr size_t kPngChunkCacheLimit = size_t(256) << 20;

// A progressive JPEG may legally hold any number of scans, and each one makes libjpeg re-walk the whole
// coefficient buffer: a tiny hostile file can keep it busy for hours. Real encoders write at most a few
// dozen (libjpeg-turbo's djpeg -maxscans and TurboJPEG's scan limit are the same kind of cap).
constexpr int kMaxJpegScans = 500;

// The fast PNG settings (kPngLevelFast): after the UP filter, photographic data has almost no long
// repeats for LZ77 to find, so Z_RLE skips the mostly useless match search: several times faster than
// level 6, files a few percent larger (docs/decisions.md; BENCHMARKS.md, "Options"). One fixed filter
// also avoids trying all five on every row.
constexpr int kPngFastCompressionLevel = 1;
constexpr int kPngFastCompressionStrategy = Z_RLE;

// From this quality on, JPEG keeps full-resolution chroma (4:4:4). A texture atlas packs unrelated
// charts side by side, so sharp colour edges are everywhere; 4:2:0 averages chroma over 2x2 texels and
// bleeds colour across chart borders and into the gutters. At quality >= 90 that chroma error is the
// largest error left, and a user asking for such a quality wants fidelity; below 90 the luma
// quantisation dominates and 4:2:0's smaller file is the better trade (docs/decisions.md). Huffman-table
// optimisation stays off: several times the encode time for a slightly smaller file.
constexpr int kJpegFullChromaQuality = 90;

std::string errno_message(int error) { return std::generic_category().message(error); }

// True if the data starts with `magic`, or is a file cut off inside it (at least two bytes long), so
// that such a stub is reported as a truncated PNG or JPEG rather than an unknown format.
bool starts_with(const unsigned char* data, size_t size, const unsigned char* magic, size_t magic_size) {
  return size >= std::min<size_t>(2, magic_size) && std::memcmp(data, magic, std::min(size, magic_size)) == 0;
}

bool is_png(const unsigned char* data, size_t size) {
  static constexpr unsigned char kMagic[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return starts_with(data, size, kMagic, sizeof(kMagic));
}

bool is_jpeg(const unsigned char* data, size_t size) {
  static constexpr unsigned char kMagic[] = {0xff, 0xd8, 0xff};
  return starts_with(data, size, kMagic, sizeof(kMagic));
}

/// "RIFF", a size, "WEBP": the container of every WebP file (lossy, lossless, extended).
bool is_webp(const unsigned char* data, size_t size) {
  return size >= 12 && std::memcmp(data, "RIFF", 4) == 0 && std::memcmp(data + 8, "WEBP", 4) == 0;
}

// Rejects empty images and images larger than the caller's limit, before any pixel memory is allocated.
void check_dimensions(const std::string& name, const char* format, uint64_t width, uint64_t height, size_t max_pixels) {
  if (width == 0 || height == 0) fail_input("{}: {} image has zero size ({}x{})", name, format, width, height);
  if (width > uint64_t(INT_MAX) || height > uint64_t(INT_MAX) || width * height > max_pixels) {
    fail_input("{}: {} image is {}x{} pixels, more than the limit of {} pixels", name, format, width, height, max_pixels);
  }
}

// ---------------------------------------------------------------------------------------------------
// Files

class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) : fd_(fd) {}
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

std::vector<unsigned char> read_whole_file(const std::string& path) {
  const FileDescriptor fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (fd.get() < 0) fail_input("{}: cannot open image ({})", path, errno_message(errno));
  struct stat info {};
  if (::fstat(fd.get(), &info) != 0) fail_input("{}: cannot open image ({})", path, errno_message(errno));
  // open() succeeds on a directory; read() would then fail with a less obvious message.
  if (S_ISDIR(info.st_mode)) fail_input("{}: cannot open image ({})", path, errno_message(EISDIR));
  if (S_ISREG(info.st_mode) && uint64_t(info.st_size) > kMaxFileBytes) {
    fail_input("{}: cannot read image (the file is {} bytes, more than the limit of {})", path, uint64_t(info.st_size), kMaxFileBytes);
  }

  // Read until end of file rather than trusting st_size, so pipes and files that change size work too.
  std::vector<unsigned char> data;
  data.resize(S_ISREG(info.st_mode) ? size_t(info.st_size) + 1 : size_t(1) << 20);
  size_t used = 0;
  for (;;) {
    if (used == data.size()) {
      if (data.size() >= kMaxFileBytes) {
        fail_input("{}: cannot read image (more than {} bytes)", path, kMaxFileBytes);
      }
      data.resize(std::min(data.size() * 2, kMaxFileBytes));
    }
    const ssize_t n = ::read(fd.get(), data.data() + used, data.size() - used);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail_input("{}: cannot read image ({})", path, errno_message(errno));
    }
    if (n == 0) break;
    used += size_t(n);
  }
  if (used == 0) fail_input("{}: cannot read image (the file is empty)", path);
  data.resize(used);
  return data;
}

// An output file that is removed again unless commit() succeeds, so a failed save leaves no truncated
// image behind that a later step could mistake for a good one.
class ImageFileBeingWritten {
 public:
  explicit ImageFileBeingWritten(const std::string& path) : path_(path), file_(std::fopen(path.c_str(), "wb")) {
    if (file_ == nullptr) fail_input("{}: cannot open for writing ({})", path, errno_message(errno));
    struct stat info {};
    // Only a regular file we created may be deleted on failure (never a device such as /dev/null).
    is_regular_ = ::fstat(::fileno(file_), &info) == 0 && S_ISREG(info.st_mode);
  }
  ~ImageFileBeingWritten() {
    if (file_ != nullptr) {
      std::fclose(file_);
      discard();
    }
  }
  /// A stream opened by the caller (a memory stream, `name` for messages): never removed.
  ImageFileBeingWritten(std::FILE* stream, const std::string& name) : path_(name), file_(stream) {}
  ImageFileBeingWritten(const ImageFileBeingWritten&) = delete;
  ImageFileBeingWritten& operator=(const ImageFileBeingWritten&) = delete;

  std::FILE* get() const { return file_; }

  // Flushes and closes; throws naming the file if anything written so far or the close failed.
  void commit() {
    std::FILE* file = std::exchange(file_, nullptr);
    const int write_errno = errno;  // set by the fwrite that failed, if one did
    const bool write_failed = std::ferror(file) != 0;
    errno = 0;
    if (std::fclose(file) != 0 || write_failed) {
      const int error = errno != 0 ? errno : write_errno;
      discard();
      fail_input("{}: cannot write image ({})", path_, error != 0 ? errno_message(error) : "I/O error");
    }
  }

  // Throws naming the file; `what` says which encoder step failed. The system's reason is added only
  // when a write actually failed, since errno is otherwise left over from something unrelated.
  [[noreturn]] void fail(const std::string& what) {
    const int error = errno;
    std::string reason = what;
    if (file_ != nullptr) {
      if (std::ferror(file_) != 0 && error != 0) reason += "; " + errno_message(error);
      std::fclose(std::exchange(file_, nullptr));
      discard();
    }
    fail_input("{}: cannot write image ({})", path_, reason);
  }

 private:
  void discard() const {
    if (is_regular_) std::remove(path_.c_str());
  }

  std::string path_;
  std::FILE* file_;
  bool is_regular_ = false;
};

// ---------------------------------------------------------------------------------------------------
// PNG (libspng)

struct SpngContextDeleter {
  void operator()(spng_ctx* ctx) const { spng_ctx_free(ctx); }
};
using SpngContext = std::unique_ptr<spng_ctx, SpngContextDeleter>;

SpngContext make_spng_context(int flags) {
  SpngContext ctx(spng_ctx_new(flags));
  if (ctx == nullptr) throw std::bad_alloc();
  return ctx;
}

[[noreturn]] void fail_png(const std::string& name, int error) {
  if (error == SPNG_IO_EOF) fail_input("{}: truncated PNG (the data ends early)", name);
  fail_input("{}: corrupt PNG (spng: {})", name, spng_strerror(error));
}

Image decode_png(const unsigned char* data, size_t size, const std::string& name, size_t max_pixels) {
  // The common kinds in one pass (libdeflate: meshroom_esp32cam's 4096^2 texture in about half the
  // time); every other PNG, and any problem, through libspng.
  if (std::optional<Image> image = decode_png_in_one_pass(data, size, max_pixels, kPngChunkSizeLimit)) return std::move(*image);
  SpngContext ctx = make_spng_context(0);
  spng_set_png_buffer(ctx.get(), data, size);
  spng_set_chunk_limits(ctx.get(), kPngChunkSizeLimit, kPngChunkCacheLimit);

  spng_ihdr ihdr{};
  if (int error = spng_get_ihdr(ctx.get(), &ihdr)) fail_png(name, error);
  check_dimensions(name, "PNG", ihdr.width, ihdr.height, max_pixels);

  size_t size_rgba = 0;
  if (int error = spng_decoded_image_size(ctx.get(), SPNG_FMT_RGBA8, &size_rgba)) fail_png(name, error);
  Image image(int(ihdr.width), int(ihdr.height));
  if (size_rgba != image.pixels.size() * sizeof(Rgba8)) {
    fail_internal("{}: libspng reports {} bytes for a {}x{} RGBA8 image", name, size_rgba, ihdr.width, ihdr.height);
  }
  // SPNG_FMT_RGBA8 converts every colour type and bit depth (16-bit samples are scaled to 8 bits);
  // SPNG_DECODE_TRNS turns a tRNS chunk (transparent colour or palette alpha) into alpha. Gamma (gAMA)
  // is deliberately not applied: texture values are used as stored, as renderers do.
  // Decoding stops at the end of the zlib stream, whose Adler-32 has then verified every pixel; a file
  // that lacks only the trailing IEND chunk is therefore accepted, like a JPEG without its EOI marker.
  if (int error = spng_decode_image(ctx.get(), image.pixels.data(), size_rgba, SPNG_FMT_RGBA8, SPNG_DECODE_TRNS)) {
    fail_png(name, error);
  }
  return image;
}

// The zlib level, strategy and row filter for ImageEncoding::png_level: the fast settings, or that
// level with zlib's default strategy and the adaptive filter (each row tries all five).
PngSettings png_settings(int png_level) {
  if (png_level == kPngLevelFast) return {kPngFastCompressionLevel, kPngFastCompressionStrategy, PngRowFilter::kUp};
  return {png_level, Z_DEFAULT_STRATEGY, PngRowFilter::kAdaptive};
}

void save_png(ImageFileBeingWritten& out, const Image& image, int png_level) {
  if (image.width <= 0 || image.height <= 0) out.fail(fmt::format("a PNG needs pixels ({}x{})", image.width, image.height));
  const std::string bytes = encode_png(image, png_settings(png_level));
  if (std::fwrite(bytes.data(), 1, bytes.size(), out.get()) != bytes.size()) out.fail("fwrite");
}

// ---------------------------------------------------------------------------------------------------
// JPEG (libjpeg-turbo)
//
// libjpeg reports errors through a callback that must not return. Throwing a C++ exception through the
// C library's frames is undefined (it is built without unwind tables), so the callback longjmps back.
// longjmp is only well defined if it skips no C++ destructors, so setjmp lives in the small *_guarded
// functions below, whose frames hold only trivially destructible locals; they return false on error
// and their callers, ordinary C++ code, then throw. libjpeg state is owned by RAII structs outside them.

struct JpegErrorManager {
  jpeg_error_mgr pub;  // first member: libjpeg hands us &pub, which we cast back
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

JpegErrorManager& error_manager(j_common_ptr cinfo) { return *reinterpret_cast<JpegErrorManager*>(cinfo->err); }

[[noreturn]] void jpeg_fail(j_common_ptr cinfo) {
  JpegErrorManager& err = error_manager(cinfo);
  (*err.pub.format_message)(cinfo, err.message);
  std::longjmp(err.jump, 1);
}

// libjpeg treats damaged entropy data as a warning: it fills the rest of the image with grey and carries
// on. A truncated or corrupt texture must not pass silently, so those warnings are made fatal. Benign
// ones (extra bytes between markers, an unknown JFIF revision) are ignored, as is trace output.
void jpeg_message(j_common_ptr cinfo, int msg_level) {
  if (msg_level >= 0) return;
  switch (cinfo->err->msg_code) {
#if JPEG_LIB_VERSION >= 70 || defined(D_ARITH_CODING_SUPPORTED)
    case JWRN_ARITH_BAD_CODE:  // declared by jerror.h only when arithmetic decoding is built in
#endif
    case JWRN_BOGUS_PROGRESSION:
    case JWRN_HIT_MARKER:
    case JWRN_HUFF_BAD_CODE:
    case JWRN_JPEG_EOF:
    case JWRN_MUST_RESYNC:
    case JWRN_NOT_SEQUENTIAL:
      jpeg_fail(cinfo);
    default:
      cinfo->err->num_warnings++;
  }
}

void jpeg_progress(j_common_ptr cinfo) {
  if (!cinfo->is_decompressor) return;
  const int scan = reinterpret_cast<j_decompress_ptr>(cinfo)->input_scan_number;
  if (scan > kMaxJpegScans) {
    JpegErrorManager& err = error_manager(cinfo);
    err.pub.msg_code = 0;
    std::snprintf(err.message, sizeof(err.message), "more than %d progressive scans", kMaxJpegScans);
    std::longjmp(err.jump, 1);
  }
}

void install_error_handlers(JpegErrorManager& err) {
  jpeg_std_error(&err.pub);
  err.pub.error_exit = jpeg_fail;
  err.pub.emit_message = jpeg_message;
  err.message[0] = '\0';
}

struct JpegDecoder {
  jpeg_decompress_struct cinfo{};  // zeroed, so destroying it is safe even if creation failed
  JpegErrorManager err{};
  jpeg_progress_mgr progress{};
  ~JpegDecoder() { jpeg_destroy_decompress(&cinfo); }
};

bool jpeg_read_header_guarded(JpegDecoder& d, const unsigned char* data, size_t size) {
  install_error_handlers(d.err);
  d.cinfo.err = &d.err.pub;
  if (setjmp(d.err.jump)) return false;
  jpeg_create_decompress(&d.cinfo);
  d.progress.progress_monitor = jpeg_progress;
  d.cinfo.progress = &d.progress;
  jpeg_mem_src(&d.cinfo, data, static_cast<unsigned long>(size));
  jpeg_read_header(&d.cinfo, TRUE);
  return true;
}

// Decodes into `out` (width * height pixels). For CMYK/YCCK input the four bytes per pixel are C, M, Y, K
// and the caller converts them.
bool jpeg_decompress_guarded(JpegDecoder& d, Rgba8* out, bool cmyk) {
  if (setjmp(d.err.jump)) return false;
  d.cinfo.out_color_space = cmyk ? JCS_CMYK : JCS_EXT_RGBA;  // libjpeg-turbo sets alpha to 255
  jpeg_start_decompress(&d.cinfo);
  if (d.cinfo.output_width != d.cinfo.image_width || d.cinfo.output_height != d.cinfo.image_height || d.cinfo.output_components != 4) {
    d.err.pub.msg_code = 0;
    std::snprintf(d.err.message, sizeof(d.err.message), "unexpected decoder output layout");
    return false;
  }
  const size_t width = d.cinfo.output_width;
  while (d.cinfo.output_scanline < d.cinfo.output_height) {
    constexpr JDIMENSION kRowsPerCall = 8;
    JSAMPROW rows[kRowsPerCall];
    const JDIMENSION first = d.cinfo.output_scanline;
    const JDIMENSION count = std::min(kRowsPerCall, d.cinfo.output_height - first);
    for (JDIMENSION i = 0; i < count; ++i) rows[i] = reinterpret_cast<JSAMPROW>(out + (size_t(first) + i) * width);
    // A memory source never suspends, so zero rows means the decoder is stuck: stop rather than spin.
    if (jpeg_read_scanlines(&d.cinfo, rows, count) == 0) {
      d.err.pub.msg_code = 0;
      std::snprintf(d.err.message, sizeof(d.err.message), "decoder made no progress");
      return false;
    }
  }
  // jpeg_finish_decompress is skipped on purpose: it only checks that an EOI marker follows the image
  // data, and files that lack it but are otherwise complete are common and harmless.
  return true;
}

// CMYK as Adobe writes it (the only common source) stores inverted values, 255 meaning no ink; libjpeg
// records an Adobe APP14 marker in saw_Adobe_marker. Plain CMYK stores ink amounts. This is the
// naive conversion without a colour profile, the same as browsers use when no ICC profile is given.
void cmyk_to_rgb(Image& image, bool adobe_inverted) {
  for (Rgba8& p : image.pixels) {
    int c = p.r, m = p.g, y = p.b, k = p.a;
    if (!adobe_inverted) {
      c = 255 - c;
      m = 255 - m;
      y = 255 - y;
      k = 255 - k;
    }
    p = Rgba8{uint8_t((c * k + 127) / 255), uint8_t((m * k + 127) / 255), uint8_t((y * k + 127) / 255), 255};
  }
}

[[noreturn]] void fail_jpeg(const std::string& name, const JpegErrorManager& err) {
  const char* what = "corrupt";
  switch (err.pub.msg_code) {
    case JWRN_JPEG_EOF:
      what = "truncated";
      break;
    case JERR_BAD_PRECISION:  // 12-bit samples: this libjpeg-turbo build decodes 8-bit only
    case JERR_NOT_COMPILED:
    case JERR_ARITH_NOTIMPL:
      what = "unsupported";
      break;
    default:
      break;
  }
  fail_input("{}: {} JPEG (libjpeg: {})", name, what, err.message);
}

Image decode_jpeg(const unsigned char* data, size_t size, const std::string& name, size_t max_pixels) {
  JpegDecoder decoder;
  if (!jpeg_read_header_guarded(decoder, data, size)) {
    fail_jpeg(name, decoder.err);
  }
  const jpeg_decompress_struct& cinfo = decoder.cinfo;
  bool cmyk = false;
  switch (cinfo.jpeg_color_space) {
    case JCS_GRAYSCALE:
    case JCS_YCbCr:
    case JCS_RGB:
      break;
    case JCS_CMYK:
    case JCS_YCCK:
      cmyk = true;
      break;
    default:
      fail_input("{}: unsupported JPEG colour space ({} components, colour space {})", name, cinfo.num_components,
                 int(cinfo.jpeg_color_space));
  }
  check_dimensions(name, "JPEG", cinfo.image_width, cinfo.image_height, max_pixels);

  Image image(int(cinfo.image_width), int(cinfo.image_height));
  if (!jpeg_decompress_guarded(decoder, image.pixels.data(), cmyk)) {
    fail_jpeg(name, decoder.err);
  }
  if (cmyk) cmyk_to_rgb(image, cinfo.saw_Adobe_marker != 0);
  return image;
}

struct JpegEncoder {
  jpeg_compress_struct cinfo{};
  JpegErrorManager err{};
  ~JpegEncoder() { jpeg_destroy_compress(&cinfo); }
};

bool jpeg_encode_guarded(JpegEncoder& e, std::FILE* file, const Image& image, int quality) {
  install_error_handlers(e.err);
  e.cinfo.err = &e.err.pub;
  if (setjmp(e.err.jump)) return false;
  jpeg_create_compress(&e.cinfo);
  jpeg_stdio_dest(&e.cinfo, file);
  e.cinfo.image_width = JDIMENSION(image.width);
  e.cinfo.image_height = JDIMENSION(image.height);
  // libjpeg-turbo reads RGBA directly and ignores the fourth byte, so no RGB copy of the image is made.
  e.cinfo.input_components = 4;
  e.cinfo.in_color_space = JCS_EXT_RGBA;
  jpeg_set_defaults(&e.cinfo);  // YCbCr, 4:2:0, standard Huffman tables, accurate integer DCT
  jpeg_set_quality(&e.cinfo, quality, TRUE);
  if (quality >= kJpegFullChromaQuality) {
    e.cinfo.comp_info[0].h_samp_factor = 1;
    e.cinfo.comp_info[0].v_samp_factor = 1;
  }
  jpeg_start_compress(&e.cinfo, TRUE);
  const size_t width = size_t(image.width);
  while (e.cinfo.next_scanline < e.cinfo.image_height) {
    // libjpeg's API takes non-const rows but only reads them.
    JSAMPROW row = reinterpret_cast<JSAMPROW>(const_cast<Rgba8*>(image.pixels.data() + e.cinfo.next_scanline * width));
    jpeg_write_scanlines(&e.cinfo, &row, 1);
  }
  jpeg_finish_compress(&e.cinfo);  // flushes; a failed fwrite raises JERR_FILE_WRITE here
  return true;
}

void save_jpeg(ImageFileBeingWritten& out, const Image& image, int quality) {
  // libjpeg's format limit (JPEG_MAX_DIMENSION); checked here to give a clear message.
  constexpr int kMaxJpegSide = 65500;
  if (image.width > kMaxJpegSide || image.height > kMaxJpegSide) {
    out.fail(fmt::format("{}x{} is larger than JPEG allows ({} pixels a side)", image.width, image.height, kMaxJpegSide));
  }
  JpegEncoder encoder;
  if (!jpeg_encode_guarded(encoder, out.get(), image, quality)) out.fail(fmt::format("libjpeg: {}", encoder.err.message));
}

// ---------------------------------------------------------------------------------------------------
// Everything else (stb_image)

const char* stb_reason() {
  const char* reason = stbi_failure_reason();
  return reason != nullptr ? reason : "unknown error";
}

struct StbImageDeleter {
  void operator()(stbi_uc* pixels) const { stbi_image_free(pixels); }
};

// stb 2.27 reads the numbers of a binary PNM header (P5, P6) into an int without an overflow check:
// a width of ten or more digits is signed overflow, undefined behaviour (found by fuzz_image under UBSan;
// stb 2.28 refuses such numbers). This scans the header the way stb does (blanks, '#' comments up to the
// end of the line, three decimal numbers) and reports a number of more than 9 digits, which cannot
// overflow stb's "value * 10 + digit" and is far beyond any size check_dimensions lets through.
bool pnm_header_number_too_long(const unsigned char* data, size_t size) {
  if (size < 2 || data[0] != 'P' || (data[1] != '5' && data[1] != '6')) return false;
  auto blank = [](unsigned char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\v' || c == '\f' || c == '\r'; };
  size_t i = 2;
  for (int number = 0; number < 3; ++number) {
    for (;;) {
      while (i < size && blank(data[i])) ++i;
      if (i >= size || data[i] != '#') break;
      while (i < size && data[i] != '\n' && data[i] != '\r') ++i;
    }
    size_t digits = 0;
    for (; i < size && data[i] >= '0' && data[i] <= '9'; ++i)
      if (++digits > 9) return true;
  }
  return false;
}

// ---------------------------------------------------------------------------------------------------
// PSD: the merged composite of an RGB file, 8 or 16 bits, raw or RLE; what stb_image reads, read the way
// it reads it. Decoded here rather than by stb 2.27, whose loader removes Photoshop's white matte from
// every pixel of partial alpha with `(unsigned char)(c / a + 255 (1 - 1 / a))`: a colour below the matte
// (any file not written by Photoshop) casts a negative float to a byte, which is undefined behaviour
// (found by fuzz_image under UBSan; fuzz/corpus/fuzz_image/regress-psd-matte-below-zero.psd). Here that
// value is clamped to 0; every pixel stb decodes without undefined behaviour decodes the same.

bool is_psd(const unsigned char* data, size_t size) {
  static constexpr unsigned char kMagic[] = {'8', 'B', 'P', 'S'};
  return size >= 4 && std::memcmp(data, kMagic, 4) == 0;
}

/// Big-endian reads that, like stb's, give 0 past the end; a skip past the end stops at the end.
struct PsdReader {
  const unsigned char* data;
  size_t size, at = 0;
  unsigned get8() { return at < size ? data[at++] : 0u; }
  unsigned get16() { return (get8() << 8) | get8(); }
  uint32_t get32() { return (uint32_t(get16()) << 16) | get16(); }
  void skip(uint64_t n) { at = n >= size - std::min(at, size) ? size : at + size_t(n); }
};

Image decode_psd(const unsigned char* data, size_t size, const std::string& name, size_t max_pixels) {
  PsdReader r{data, size};
  r.skip(4);  // "8BPS"
  if (r.get16() != 1) fail_input("{}: unsupported PSD version", name);
  r.skip(6);
  const unsigned channels = r.get16();
  if (channels > 16) fail_input("{}: PSD image with {} channels (at most 16 are supported)", name, channels);
  const uint32_t height = r.get32(), width = r.get32();
  check_dimensions(name, "PSD", width, height, max_pixels);
  const unsigned depth = r.get16();
  if (depth != 8 && depth != 16) fail_input("{}: PSD image of {} bits per channel (8 or 16 are supported)", name, depth);
  if (r.get16() != 3) fail_input("{}: PSD image not in RGB colour mode", name);
  r.skip(r.get32());  // colour mode data
  r.skip(r.get32());  // image resources
  r.skip(r.get32());  // layers and masks: only the merged composite is read
  const unsigned compression = r.get16();
  if (compression > 1) fail_input("{}: PSD image with unknown compression {}", name, compression);
  Image image{int(width), int(height)};
  const size_t n = image.pixels.size();
  auto channel_byte = [&](Rgba8& p, unsigned c) -> uint8_t& { return c == 0 ? p.r : c == 1 ? p.g : c == 2 ? p.b : p.a; };
  if (compression == 1) {
    r.skip(uint64_t(height) * channels * 2);  // per-row byte counts: not needed
  }
  for (unsigned c = 0; c < 4; ++c) {
    if (c >= channels) {  // missing channels: colour 0, alpha opaque
      for (Rgba8& p : image.pixels) channel_byte(p, c) = c == 3 ? 255 : 0;
      continue;
    }
    if (compression == 0) {
      for (Rgba8& p : image.pixels) channel_byte(p, c) = uint8_t(depth == 16 ? r.get16() >> 8 : r.get8());
      continue;
    }
    // PackBits: n < 128 copies n+1 bytes, n > 128 repeats the next byte 257-n times, 128 does nothing.
    // (As in stb, 16-bit RLE data is unpacked as bytes.)
    for (size_t i = 0; i < n;) {
      const unsigned len = r.get8();
      if (len == 128) continue;
      const size_t count = len < 128 ? len + 1 : 257 - len;
      if (count > n - i) fail_input("{}: corrupt PSD image (bad RLE data)", name);
      if (len < 128) {
        for (size_t k = 0; k < count; ++k) channel_byte(image.pixels[i++], c) = uint8_t(r.get8());
      } else {
        const uint8_t v = uint8_t(r.get8());
        for (size_t k = 0; k < count; ++k) channel_byte(image.pixels[i++], c) = v;
      }
    }
  }
  if (channels >= 4) {  // remove the white matte, in stb's float arithmetic
    for (Rgba8& p : image.pixels) {
      if (p.a == 0 || p.a == 255) continue;
      const float a = float(p.a) / 255.0f, ra = 1.0f / a, inv_a = 255.0f * (1 - ra);
      for (uint8_t* v : {&p.r, &p.g, &p.b}) {
        const float x = float(*v) * ra + inv_a;
        *v = x <= 0.0f ? 0 : uint8_t(x);
      }
    }
  }
  return image;
}

/// The name of an image format that scans and game engines write and tightex does not decode (GPU
/// texture containers, HDR and camera formats), by its magic bytes; nullptr for any other data.
const char* undecoded_format(const unsigned char* data, size_t size) {
  static constexpr unsigned char kKtx[] = {0xAB, 'K', 'T', 'X', ' '};
  if (size >= 8 && std::memcmp(data, kKtx, 5) == 0) return data[5] == '2' ? "KTX2" : "KTX";
  if (size >= 4 && std::memcmp(data, "DDS ", 4) == 0) return "DDS";
  static constexpr unsigned char kExr[] = {0x76, 0x2F, 0x31, 0x01};
  if (size >= 4 && std::memcmp(data, kExr, 4) == 0) return "OpenEXR";
  if (size >= 4 && (std::memcmp(data, "II*\0", 4) == 0 || std::memcmp(data, "MM\0*", 4) == 0)) return "TIFF";
  if (size >= 12 && std::memcmp(data + 4, "ftyp", 4) == 0) {
    if (std::memcmp(data + 8, "avif", 4) == 0 || std::memcmp(data + 8, "avis", 4) == 0) return "AVIF";
    if (std::memcmp(data + 8, "heic", 4) == 0 || std::memcmp(data + 8, "heix", 4) == 0 || std::memcmp(data + 8, "mif1", 4) == 0)
      return "HEIF";
  }
  return nullptr;
}

Image decode_with_stb(const unsigned char* data, size_t size, const std::string& name, size_t max_pixels) {
  if (const char* format = undecoded_format(data, size))
    fail_input(
        "{}: the image is {}, which tightex does not decode (it reads PNG, JPEG and WebP; a glTF can name one as the fallback "
        "of KHR_texture_basisu or MSFT_texture_dds)",
        name, format);
  if (size > size_t(INT_MAX)) fail_input("{}: unrecognised image format", name);
  if (pnm_header_number_too_long(data, size)) fail_input("{}: corrupt PNM header (a number of more than 9 digits)", name);
  int width = 0, height = 0, channels = 0;
  // stbi_info parses only the header, so the size check happens before any pixel memory is allocated.
  if (!stbi_info_from_memory(data, int(size), &width, &height, &channels)) {
    fail_input("{}: unrecognised image format (not PNG, JPEG or WebP, and stb_image cannot read it: {})", name, stb_reason());
  }
  check_dimensions(name, "image", uint64_t(std::max(width, 0)), uint64_t(std::max(height, 0)), max_pixels);
  // stb 2.27 (Debian 12) reads 16-bit PNM samples in the wrong byte order; refusing beats wrong colours.
  if (data[0] == 'P' && stbi_is_16_bit_from_memory(data, int(size))) {
    fail_input("{}: 16-bit PNM images are not supported (convert to PNG)", name);
  }
  // Loaded with the file's own channel count, and widened to RGBA below, rather than asking stb for 4
  // channels: when the counts differ stb 2.27 converts 16-bit data with its 8-bit converter and reads
  // past its buffer (found by fuzzing this function under ASan, with a 16-bit PNM).
  std::unique_ptr<stbi_uc, StbImageDeleter> pixels(stbi_load_from_memory(data, int(size), &width, &height, &channels, 0));
  if (pixels == nullptr) fail_input("{}: corrupt image (stb_image: {})", name, stb_reason());
  check_dimensions(name, "image", uint64_t(std::max(width, 0)), uint64_t(std::max(height, 0)), max_pixels);
  if (channels < 1 || channels > 4) fail_input("{}: unsupported image with {} channels", name, channels);

  Image image(width, height);
  const stbi_uc* in = pixels.get();
  for (Rgba8& p : image.pixels) {
    switch (channels) {
      case 1:
        p = Rgba8{in[0], in[0], in[0], 255};
        break;
      case 2:
        p = Rgba8{in[0], in[0], in[0], in[1]};
        break;
      case 3:
        p = Rgba8{in[0], in[1], in[2], 255};
        break;
      default:
        p = Rgba8{in[0], in[1], in[2], in[3]};
        break;
    }
    in += channels;
  }
  return image;
}

/// WebP through libwebp: the header's size is checked before any pixel is allocated, then the image is
/// decoded straight into the RGBA pixels (animated WebP: libwebp's simple decoder refuses it).
Image decode_webp(const unsigned char* data, size_t size, const std::string& name, size_t max_pixels) {
  int width = 0, height = 0;
  if (!WebPGetInfo(data, size, &width, &height)) fail_input("{}: corrupt or unsupported WebP image (header)", name);
  check_dimensions(name, "WebP", uint64_t(std::max(width, 0)), uint64_t(std::max(height, 0)), max_pixels);
  Image image(width, height);
  const size_t stride = size_t(width) * sizeof(Rgba8);
  if (WebPDecodeRGBAInto(data, size, reinterpret_cast<uint8_t*>(image.pixels.data()), stride * size_t(height), int(stride)) == nullptr)
    fail_input("{}: corrupt or unsupported WebP image (an animated WebP is not a texture)", name);
  return image;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------

Image load_image(const std::string& path, size_t max_pixels) {
  const std::vector<unsigned char> data = read_whole_file(path);
  return decode_image(data.data(), data.size(), path, max_pixels);
}

Image decode_image(const unsigned char* data, size_t size, const std::string& name, size_t max_pixels) {
  if (data == nullptr || size == 0) fail_input("{}: no image data (empty)", name);
  // Detected by content, not by extension: textures named .png that hold JPEG data are common.
  if (is_png(data, size)) return decode_png(data, size, name, max_pixels);
  if (is_jpeg(data, size)) return decode_jpeg(data, size, name, max_pixels);
  if (is_webp(data, size)) return decode_webp(data, size, name, max_pixels);
  if (is_psd(data, size)) return decode_psd(data, size, name, max_pixels);
  return decode_with_stb(data, size, name, max_pixels);
}

void check_image_encoding(const ImageEncoding& encoding, const std::string& path) {
  if (encoding.format == ImageFormat::kPng && encoding.png_level != kPngLevelFast && (encoding.png_level < 0 || encoding.png_level > 9))
    fail_input("{}: PNG compression level {} is outside 0..9", path, encoding.png_level);
  if (encoding.format == ImageFormat::kJpeg && (encoding.jpeg_quality < 1 || encoding.jpeg_quality > 100))
    fail_input("{}: JPEG quality {} is outside 1..100", path, encoding.jpeg_quality);
  if (encoding.format == ImageFormat::kWebp && !encoding.webp_lossless && (encoding.webp_quality < 1 || encoding.webp_quality > 100))
    fail_input("{}: WebP quality {} is outside 1..100", path, encoding.webp_quality);
}

namespace {

constexpr int kMaxWebpSide = 16383;

void check_webp_side(const Image& image, const std::string& name) {
  if (image.width > kMaxWebpSide || image.height > kMaxWebpSide)
    fail_input("{}: {}x{} is larger than WebP allows ({} pixels a side)", name, image.width, image.height, kMaxWebpSide);
}

/// The image's RGB bytes where it is opaque (else empty): WebP then stores no alpha.
std::vector<uint8_t> opaque_rgb(const Image& image) {
  std::vector<uint8_t> rgb;
  if (!is_opaque(image)) return rgb;
  rgb.resize(size_t(image.width) * size_t(image.height) * 3);
  for (size_t i = 0; i < image.pixels.size(); ++i)
    rgb[3 * i] = image.pixels[i].r, rgb[3 * i + 1] = image.pixels[i].g, rgb[3 * i + 2] = image.pixels[i].b;
  return rgb;
}

/// The image as a lossless WebP file's bytes (libwebp's simple API), RGB where it is opaque.
std::string encode_webp_lossless(const Image& image, const std::string& name) {
  check_webp_side(image, name);
  const std::vector<uint8_t> rgb = opaque_rgb(image);
  uint8_t* out = nullptr;
  const size_t size = !rgb.empty() ? WebPEncodeLosslessRGB(rgb.data(), image.width, image.height, image.width * 3, &out)
                                   : WebPEncodeLosslessRGBA(reinterpret_cast<const uint8_t*>(image.pixels.data()), image.width,
                                                            image.height, image.width * 4, &out);
  std::string bytes(reinterpret_cast<const char*>(out), size);
  WebPFree(out);
  if (size == 0) fail_internal("{}: libwebp could not encode a {}x{} image", name, image.width, image.height);
  return bytes;
}

}  // namespace

/// libwebp's picture of an image in YUV 4:2:0 (with alpha where it is not opaque), what its lossy
/// encoder reads.
struct ImageEncoder::WebpYuv {
  WebPPicture picture{};
  WebpYuv() = default;
  WebpYuv(const WebpYuv&) = delete;
  WebpYuv& operator=(const WebpYuv&) = delete;
  ~WebpYuv() { WebPPictureFree(&picture); }
};

namespace {

/// From this mean squared error (8-bit levels, over RGB) of the plain RGB-to-YUV 4:2:0 conversion alone
/// (converted and upsampled back, no coding), an image takes the sharp conversion (webp_yuv).
constexpr double kSharpYuvFromPlainMse = 2.0;

/// The mean squared error (over RGB, of the texels not fully transparent) of `argb` (a picture holding
/// `image` as ARGB) converted to YUV 4:2:0 by libwebp's plain conversion and back as its decoder
/// upsamples it.
double plain_conversion_mse(const WebPPicture& argb, const Image& image) {
  WebPPicture probe;
  if (!WebPPictureInit(&probe) || !WebPPictureCopy(&argb, &probe)) throw std::bad_alloc();
  const bool ok = WebPPictureARGBToYUVA(&probe, is_opaque(image) ? WEBP_YUV420 : WEBP_YUV420A) && WebPPictureYUVAToARGB(&probe);
  double squared = 0;
  size_t texels = 0;
  for (int y = 0; ok && y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const Rgba8 p = image.at(x, y);
      const uint32_t back = probe.argb[size_t(y) * size_t(probe.argb_stride) + size_t(x)];
      const double r = double((back >> 16) & 255) - p.r, g = double((back >> 8) & 255) - p.g, b = double(back & 255) - p.b;
      squared += p.a > 0 ? r * r + g * g + b * b : 0;
      texels += p.a > 0 ? 1 : 0;
    }
  WebPPictureFree(&probe);
  if (!ok) throw std::bad_alloc();
  return texels > 0 ? squared / double(3 * texels) : 0;
}

/// `image` converted for libwebp's lossy encoder. Where 4:2:0 chroma alone loses much (the plain
/// conversion's error above kSharpYuvFromPlainMse: saturated print, colour edges a texel or two wide),
/// the colour goes through libwebp's sharp conversion, an iterative fit of the planes to the RGB as the
/// decoder upsamples them; elsewhere (photographs, grey) its extra luma detail costs more bytes than
/// it gains (docs/decisions.md). Transparent texels are cleaned here, once, as libwebp's encoder would
/// on every call.
std::unique_ptr<ImageEncoder::WebpYuv> webp_yuv(const Image& image, const std::string& name) {
  check_webp_side(image, name);
  auto yuv = std::make_unique<ImageEncoder::WebpYuv>();
  WebPPicture& pic = yuv->picture;
  if (!WebPPictureInit(&pic)) fail_internal("{}: libwebp version mismatch", name);
  pic.width = image.width, pic.height = image.height, pic.use_argb = 1;
  if (!WebPPictureImportRGBA(&pic, reinterpret_cast<const uint8_t*>(image.pixels.data()), image.width * 4)) throw std::bad_alloc();
  const bool sharp = plain_conversion_mse(pic, image) > kSharpYuvFromPlainMse;
  const WebPEncCSP space = is_opaque(image) ? WEBP_YUV420 : WEBP_YUV420A;
  if (!(sharp ? WebPPictureSharpARGBToYUVA(&pic) : WebPPictureARGBToYUVA(&pic, space))) throw std::bad_alloc();
  WebPCleanupTransparentArea(&pic);
  return yuv;
}

/// `yuv` as a lossy WebP file's bytes at `quality`. The picture is only read (a shallow copy carries
/// the writer), so several threads may encode one picture at once.
std::string encode_webp_yuv(const WebPPicture& yuv, float quality, const std::string& name) {
  WebPConfig config;
  if (!WebPConfigInit(&config)) fail_internal("{}: libwebp version mismatch", name);
  config.quality = quality;
  config.exact = 1;  // the transparent texels are already cleaned (webp_yuv)
  WebPPicture pic = yuv;
  WebPMemoryWriter writer;
  WebPMemoryWriterInit(&writer);
  pic.writer = WebPMemoryWrite, pic.custom_ptr = &writer;
  const bool ok = WebPEncode(&config, &pic) != 0;
  std::string bytes(reinterpret_cast<const char*>(writer.mem), ok ? writer.size : 0);
  WebPMemoryWriterClear(&writer);
  if (!ok) {
    if (pic.error_code == VP8_ENC_ERROR_OUT_OF_MEMORY) throw std::bad_alloc();
    fail_internal("{}: libwebp could not encode a {}x{} image (error {})", name, yuv.width, yuv.height, int(pic.error_code));
  }
  return bytes;
}

}  // namespace

bool ImageEncoding::lossy() const {
  auto lossy_format = [&](ImageFormat f) { return f == ImageFormat::kJpeg || (f == ImageFormat::kWebp && !webp_lossless); };
  return lossy_format(format) || std::any_of(formats.begin(), formats.end(), lossy_format);
}

ImageEncoding ImageEncoding::of_texture(size_t i) const {
  ImageEncoding e = *this;
  e.formats.clear();
  if (i < formats.size()) e.format = formats[i];
  return e;
}

const char* image_extension(ImageFormat format) {
  switch (format) {
    case ImageFormat::kJpeg:
      return ".jpg";
    case ImageFormat::kWebp:
      return ".webp";
    case ImageFormat::kPng:
      break;
  }
  return ".png";
}

ImageEncoder::ImageEncoder(const Image& image, std::string name) : image_(image), name_(std::move(name)) {}

ImageEncoder::~ImageEncoder() = default;

std::string ImageEncoder::encode(const ImageEncoding& encoding) const {
  check_image_encoding(encoding, name_);
  if (encoding.format == ImageFormat::kJpeg) return encode_jpeg(image_, encoding.jpeg_quality);
  if (encoding.format == ImageFormat::kWebp && encoding.webp_lossless) return encode_webp_lossless(image_, name_);
  if (encoding.format == ImageFormat::kWebp) {
    std::call_once(webp_converted_, [&] { webp_ = webp_yuv(image_, name_); });
    return encode_webp_yuv(webp_->picture, float(encoding.webp_quality), name_);
  }
  // PNG through a file (libspng writes to a FILE): a memory stream.
  char* buffer = nullptr;
  size_t size = 0;
  std::FILE* stream = open_memstream(&buffer, &size);
  if (stream == nullptr) throw std::bad_alloc();
  {
    ImageFileBeingWritten out(stream, name_);
    save_png(out, image_, encoding.png_level);
    out.commit();
  }
  std::string bytes(buffer != nullptr ? buffer : "", buffer != nullptr ? size : 0);
  std::free(buffer);
  return bytes;
}

std::string encode_image(const Image& image, const ImageEncoding& encoding, const std::string& name) {
  return ImageEncoder(image, name).encode(encoding);
}

void save_image(const std::string& path, const Image& image, const ImageEncoding& encoding) {
  if (image.empty() || image.pixels.size() != size_t(image.width) * size_t(image.height)) {
    fail_internal("{}: cannot save a {}x{} image with {} pixels", path, image.width, image.height, image.pixels.size());
  }
  check_image_encoding(encoding, path);
  ImageFileBeingWritten out(path);
  switch (encoding.format) {
    case ImageFormat::kPng:
      save_png(out, image, encoding.png_level);
      break;
    case ImageFormat::kJpeg:
      save_jpeg(out, image, encoding.jpeg_quality);
      break;
    case ImageFormat::kWebp: {
      const std::string bytes = encode_image(image, encoding, path);
      if (std::fwrite(bytes.data(), 1, bytes.size(), out.get()) != bytes.size()) out.fail("write failed");
      break;
    }
  }
  out.commit();
}

void save_image(const std::string& path, const Image& image, ImageFormat format, int jpeg_quality) {
  save_image(path, image, ImageEncoding(format, kDefaultPngLevel, jpeg_quality));
}

std::string encode_jpeg(const Image& image, int quality) {
  if (image.empty() || image.pixels.size() != size_t(image.width) * size_t(image.height) || quality < 1 || quality > 100)
    fail_internal("encode_jpeg: a {}x{} image with {} pixels at quality {}", image.width, image.height, image.pixels.size(), quality);
  char* buffer = nullptr;
  size_t size = 0;
  std::FILE* stream = open_memstream(&buffer, &size);
  if (stream == nullptr) throw std::bad_alloc();
  JpegEncoder encoder;
  const bool ok = jpeg_encode_guarded(encoder, stream, image, quality);
  std::fclose(stream);  // sets buffer and size
  std::string bytes(buffer != nullptr ? buffer : "", buffer != nullptr ? size : 0);
  std::free(buffer);
  if (!ok) fail_internal("encode_jpeg: libjpeg: {}", encoder.err.message);
  return bytes;
}

}  // namespace tightex

namespace tightex {

std::pair<int, int> image_dimensions(const std::string& path) {
  // Only the header is read: the size of a texture is known before its pixels are allocated.
  std::ifstream f(path, std::ios::binary);
  if (!f) return {0, 0};
  std::vector<unsigned char> head(64 * 1024);
  f.read(reinterpret_cast<char*>(head.data()), std::streamsize(head.size()));
  head.resize(size_t(f.gcount()));
  return image_dimensions(head.data(), head.size());
}

std::pair<int, int> image_dimensions(const unsigned char* head, size_t n) {
  auto be32 = [&](size_t i) {
    return (uint32_t(head[i]) << 24) | (uint32_t(head[i + 1]) << 16) | (uint32_t(head[i + 2]) << 8) | head[i + 3];
  };
  static const unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (n >= 24 && std::equal(kPng, kPng + 8, head)) {
    const uint32_t w = be32(16), h = be32(20);
    return {int(std::min<uint32_t>(w, INT_MAX)), int(std::min<uint32_t>(h, INT_MAX))};
  }
  if (n >= 4 && head[0] == 0xFF && head[1] == 0xD8) {  // JPEG: walk the markers to a start-of-frame
    size_t i = 2;
    while (i + 9 < n) {
      if (head[i] != 0xFF) return {0, 0};
      const unsigned char m = head[i + 1];
      const size_t len = (size_t(head[i + 2]) << 8) | head[i + 3];
      if (m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC)
        return {int((head[i + 7] << 8) | head[i + 8]), int((head[i + 5] << 8) | head[i + 6])};
      i += 2 + len;
    }
    return {0, 0};
  }
  int w = 0, h = 0, c = 0;
  if (is_webp(head, n)) return WebPGetInfo(head, n, &w, &h) ? std::pair<int, int>{w, h} : std::pair<int, int>{0, 0};
  n = std::min<size_t>(n, INT_MAX);
  if (pnm_header_number_too_long(head, n)) return {0, 0};
  if (stbi_info_from_memory(head, int(n), &w, &h, &c)) return {w, h};
  return {0, 0};
}

}  // namespace tightex
