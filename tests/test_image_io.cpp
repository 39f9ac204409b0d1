// Image reading and writing: exact PNG round trips, approximate JPEG round trips, every PNG colour
// type and bit depth, and bad files (missing, directory, empty, truncated, garbage, too large) that must
// give an InputError naming the file instead of a crash.
#include <gtest/gtest.h>
#include <unistd.h>

// The test builds its own odd PNGs and JPEGs with the same libraries tightex links.
#include <cstdio>
// clang-format off
#include <jpeglib.h>
// clang-format on
#include <spng.h>
#include <webp/encode.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "io/image_io.hpp"
#include "io/png_one_pass.hpp"

namespace tightex {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<unsigned char>;

class ImageIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::random_device rd;
    dir_ = fs::temp_directory_path() / ("tightex_image_io_" + std::to_string(::getpid()) + "_" + std::to_string(rd()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

Bytes read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const std::string& path, const Bytes& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

// A smooth image with some structure in every channel, as a photo or a baked texture has.
Image gradient_image(int width, int height, bool with_alpha) {
  Image image(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double u = double(x) / width, v = double(y) / height;
      image.at(x, y) = Rgba8{uint8_t(40 + 180 * u), uint8_t(30 + 190 * v), uint8_t(128 + 100 * std::sin(6 * u + 4 * v)),
                             uint8_t(with_alpha ? (x * 7 + y * 3) % 256 : 255)};
    }
  }
  return image;
}

Image noise_image(int width, int height, bool with_alpha, unsigned seed) {
  std::mt19937 rng(seed);
  Image image(width, height);
  for (Rgba8& p : image.pixels) {
    p = Rgba8{uint8_t(rng()), uint8_t(rng()), uint8_t(rng()), uint8_t(with_alpha ? rng() : 255)};
  }
  return image;
}

double psnr_rgb(const Image& a, const Image& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  double sum = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    const double dr = a.pixels[i].r - b.pixels[i].r, dg = a.pixels[i].g - b.pixels[i].g, db = a.pixels[i].b - b.pixels[i].b;
    sum += dr * dr + dg * dg + db * db;
  }
  const double mse = sum / (3.0 * double(a.pixels.size()));
  return mse == 0 ? 99.0 : 10 * std::log10(255.0 * 255.0 / mse);
}

// PNG colour type, from the IHDR chunk at byte 25 of every PNG.
int png_color_type(const Bytes& png) { return png.size() > 25 ? png[25] : -1; }

// Encodes raw samples (PNG layout, host-endian for 16 bits) with libspng.
Bytes encode_png(const spng_ihdr& ihdr, const void* samples, size_t size, const spng_plte* plte = nullptr, const spng_trns* trns = nullptr,
                 int filter_choice = SPNG_FILTER_CHOICE_ALL) {
  spng_ctx* ctx = spng_ctx_new(SPNG_CTX_ENCODER);
  spng_set_option(ctx, SPNG_ENCODE_TO_BUFFER, 1);
  spng_set_option(ctx, SPNG_FILTER_CHOICE, filter_choice);
  spng_ihdr header = ihdr;
  EXPECT_EQ(spng_set_ihdr(ctx, &header), 0);
  if (plte != nullptr) {
    spng_plte p = *plte;
    EXPECT_EQ(spng_set_plte(ctx, &p), 0);
  }
  if (trns != nullptr) {
    spng_trns t = *trns;
    EXPECT_EQ(spng_set_trns(ctx, &t), 0);
  }
  EXPECT_EQ(spng_encode_image(ctx, samples, size, SPNG_FMT_PNG, SPNG_ENCODE_FINALIZE), 0);
  size_t length = 0;
  int error = 0;
  auto* buffer = static_cast<unsigned char*>(spng_get_png_buffer(ctx, &length, &error));
  EXPECT_EQ(error, 0);
  Bytes png(buffer, buffer + length);
  std::free(buffer);
  spng_ctx_free(ctx);
  return png;
}

spng_ihdr make_ihdr(uint32_t width, uint32_t height, uint8_t bit_depth, uint8_t color_type) {
  spng_ihdr ihdr{};
  ihdr.width = width;
  ihdr.height = height;
  ihdr.bit_depth = bit_depth;
  ihdr.color_type = color_type;
  return ihdr;
}

// Encodes a greyscale or CMYK JPEG, which save_image never writes. For CMYK, libjpeg stores the samples
// as given and marks the file Adobe; Adobe's convention is inverted (255 = no ink), as Photoshop writes.
Bytes encode_jpeg(int width, int height, int components, J_COLOR_SPACE space, const Bytes& samples) {
  jpeg_compress_struct cinfo{};
  jpeg_error_mgr err{};
  cinfo.err = jpeg_std_error(&err);
  jpeg_create_compress(&cinfo);
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&cinfo, &buffer, &size);
  cinfo.image_width = JDIMENSION(width);
  cinfo.image_height = JDIMENSION(height);
  cinfo.input_components = components;
  cinfo.in_color_space = space;
  jpeg_set_defaults(&cinfo);
  jpeg_set_quality(&cinfo, 95, TRUE);
  jpeg_start_compress(&cinfo, TRUE);
  while (cinfo.next_scanline < cinfo.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(samples.data() + size_t(cinfo.next_scanline) * size_t(width * components));
    jpeg_write_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_compress(&cinfo);
  jpeg_destroy_compress(&cinfo);
  Bytes jpeg(buffer, buffer + size);
  std::free(buffer);
  return jpeg;
}

// A 24-bit bottom-up BMP, to exercise the stb_image fallback.
Bytes encode_bmp(const Image& image) {
  const uint32_t row_bytes = (uint32_t(image.width) * 3 + 3) & ~3u;
  const uint32_t data_size = row_bytes * uint32_t(image.height);
  Bytes bmp;
  auto put16 = [&](uint32_t v) { bmp.push_back(uint8_t(v)), bmp.push_back(uint8_t(v >> 8)); };
  auto put32 = [&](uint32_t v) { put16(v & 0xffff), put16(v >> 16); };
  bmp.push_back('B'), bmp.push_back('M');
  put32(54 + data_size), put32(0), put32(54);                              // file header
  put32(40), put32(uint32_t(image.width)), put32(uint32_t(image.height));  // BITMAPINFOHEADER
  put16(1), put16(24), put32(0), put32(data_size), put32(2835), put32(2835), put32(0), put32(0);
  for (int y = image.height - 1; y >= 0; --y) {
    for (int x = 0; x < image.width; ++x) {
      const Rgba8 p = image.at(x, y);
      bmp.push_back(p.b), bmp.push_back(p.g), bmp.push_back(p.r);
    }
    for (uint32_t i = uint32_t(image.width) * 3; i < row_bytes; ++i) bmp.push_back(0);
  }
  return bmp;
}

// PNG chunk CRC (CRC-32, polynomial 0xedb88320), for hand-written chunks.
uint32_t png_crc(const unsigned char* data, size_t size) {
  uint32_t crc = 0xffffffffu;
  for (size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return crc ^ 0xffffffffu;
}

// A PNG signature and a valid RGB8 IHDR chunk, nothing else.
Bytes png_header_only(uint32_t width, uint32_t height) {
  Bytes png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R'};
  for (uint32_t v : {width, height}) {
    for (int shift : {24, 16, 8, 0}) png.push_back(uint8_t(v >> shift));
  }
  png.insert(png.end(), {8, 2, 0, 0, 0});             // 8-bit RGB, deflate, no interlace
  const uint32_t crc = png_crc(png.data() + 12, 17);  // over chunk type and data
  for (int shift : {24, 16, 8, 0}) png.push_back(uint8_t(crc >> shift));
  return png;
}

// Runs `f`, expecting an InputError whose message contains `needle`; returns the message.
template <typename F>
std::string expect_input_error(F&& f, const std::string& needle) {
  try {
    f();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << "message: " << e.what();
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InputError, got: " << e.what();
    return {};
  }
  ADD_FAILURE() << "expected InputError containing '" << needle << "', nothing was thrown";
  return {};
}

// GPU texture containers, HDR and camera formats: refused by name, with what is read instead.
TEST(ImageDecode, FormatsItDoesNotDecodeAreNamed) {
  const std::vector<std::pair<Bytes, std::string>> cases = {
      {{0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n', 0, 0, 0, 0}, "the image is KTX2,"},
      {{0xAB, 'K', 'T', 'X', ' ', '1', '1', 0xBB, '\r', '\n', 0x1A, '\n', 0, 0, 0, 0}, "the image is KTX,"},
      {{'D', 'D', 'S', ' ', 124, 0, 0, 0}, "the image is DDS,"},
      {{0x76, 0x2F, 0x31, 0x01, 2, 0, 0, 0}, "the image is OpenEXR,"},
      {{'I', 'I', '*', 0, 8, 0, 0, 0}, "the image is TIFF,"},
      {{0, 0, 0, 0x1C, 'f', 't', 'y', 'p', 'a', 'v', 'i', 'f', 0, 0, 0, 0}, "the image is AVIF,"},
      {{0, 0, 0, 0x18, 'f', 't', 'y', 'p', 'h', 'e', 'i', 'c', 0, 0, 0, 0}, "the image is HEIF,"},
  };
  for (const auto& [bytes, needle] : cases) {
    const std::string message = expect_input_error([&] { decode_image(bytes.data(), bytes.size(), "images[1]"); }, needle);
    EXPECT_NE(message.find("images[1]: "), std::string::npos) << message;
    EXPECT_NE(message.find("PNG, JPEG and WebP"), std::string::npos) << message;
  }
  const Bytes noise = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  expect_input_error([&] { decode_image(noise.data(), noise.size(), "noise.bin"); }, "unrecognised image format (not PNG, JPEG or WebP");
}

// ---------------------------------------------------------------------------------------------------
// Round trips

TEST_F(ImageIoTest, PngRgbRoundTripIsExactAndDropsAlpha) {
  const Image image = noise_image(67, 41, false, 1);
  save_image(path("rgb.png"), image, ImageFormat::kPng);
  EXPECT_EQ(png_color_type(read_bytes(path("rgb.png"))), 2);  // RGB: alpha was 255 everywhere
  const Image loaded = load_image(path("rgb.png"));
  ASSERT_EQ(loaded.width, image.width);
  ASSERT_EQ(loaded.height, image.height);
  EXPECT_TRUE(loaded.pixels == image.pixels);
}

TEST_F(ImageIoTest, PngRgbaRoundTripIsExact) {
  const Image image = noise_image(50, 33, true, 2);
  save_image(path("rgba.png"), image, ImageFormat::kPng);
  EXPECT_EQ(png_color_type(read_bytes(path("rgba.png"))), 6);  // RGBA
  const Image loaded = load_image(path("rgba.png"));
  ASSERT_EQ(loaded.width, image.width);
  ASSERT_EQ(loaded.height, image.height);
  EXPECT_TRUE(loaded.pixels == image.pixels);
}

TEST_F(ImageIoTest, PngOfAGreyImageIsGreyAndExact) {
  // An occlusion or roughness map: red, green and blue agree everywhere. One sample a pixel, not three.
  Image image = noise_image(61, 37, false, 3);
  for (Rgba8& p : image.pixels) p.g = p.b = p.r;
  save_image(path("grey.png"), image, ImageFormat::kPng);
  EXPECT_EQ(png_color_type(read_bytes(path("grey.png"))), 0);
  EXPECT_TRUE(load_image(path("grey.png")).pixels == image.pixels);
  // With alpha: grey and alpha.
  image.pixels[5].a = 17;
  save_image(path("grey_alpha.png"), image, ImageFormat::kPng);
  EXPECT_EQ(png_color_type(read_bytes(path("grey_alpha.png"))), 4);
  EXPECT_TRUE(load_image(path("grey_alpha.png")).pixels == image.pixels);
  // One pixel whose blue differs: RGB again.
  image.pixels[5].a = 255, image.pixels[9].b = uint8_t(image.pixels[9].r ^ 1);
  save_image(path("almost_grey.png"), image, ImageFormat::kPng);
  EXPECT_EQ(png_color_type(read_bytes(path("almost_grey.png"))), 2);
  EXPECT_TRUE(load_image(path("almost_grey.png")).pixels == image.pixels);
}

TEST_F(ImageIoTest, PngOnePixelAndOneRowRoundTrip) {
  for (const auto& [w, h] : {std::pair{1, 1}, std::pair{300, 1}, std::pair{1, 300}}) {
    const Image image = noise_image(w, h, true, 3);
    save_image(path("small.png"), image, ImageFormat::kPng);
    EXPECT_TRUE(load_image(path("small.png")).pixels == image.pixels) << w << "x" << h;
  }
}

TEST_F(ImageIoTest, SaveOverwritesAnExistingFile) {
  write_bytes(path("old.png"), Bytes(100000, 'x'));
  const Image image = gradient_image(8, 8, false);
  save_image(path("old.png"), image, ImageFormat::kPng);
  EXPECT_TRUE(load_image(path("old.png")).pixels == image.pixels);
}

TEST_F(ImageIoTest, JpegRoundTripIsClose) {
  const Image image = gradient_image(256, 160, false);
  for (int quality : {92, 75}) {  // 4:4:4 and 4:2:0 chroma
    const std::string file = path("q" + std::to_string(quality) + ".jpg");
    save_image(file, image, ImageFormat::kJpeg, quality);
    const Image loaded = load_image(file);
    ASSERT_EQ(loaded.width, image.width);
    ASSERT_EQ(loaded.height, image.height);
    EXPECT_GT(psnr_rgb(image, loaded), 35.0) << "quality " << quality;
    for (const Rgba8& p : loaded.pixels) ASSERT_EQ(p.a, 255);
  }
}

TEST_F(ImageIoTest, JpegOddSizeAndDroppedAlpha) {
  const Image image = gradient_image(17, 13, true);  // alpha is dropped, colours kept
  save_image(path("odd.jpg"), image, ImageFormat::kJpeg, 95);
  const Image loaded = load_image(path("odd.jpg"));
  ASSERT_EQ(loaded.width, 17);
  ASSERT_EQ(loaded.height, 13);
  EXPECT_GT(psnr_rgb(image, loaded), 35.0);
}

TEST_F(ImageIoTest, HigherJpegQualityKeepsMoreDetail) {
  const Image image = noise_image(64, 64, false, 4);
  save_image(path("lo.jpg"), image, ImageFormat::kJpeg, 30);
  save_image(path("hi.jpg"), image, ImageFormat::kJpeg, 98);
  EXPECT_GT(psnr_rgb(image, load_image(path("hi.jpg"))), psnr_rgb(image, load_image(path("lo.jpg"))) + 5);
  EXPECT_GT(read_bytes(path("hi.jpg")).size(), read_bytes(path("lo.jpg")).size());
}

TEST_F(ImageIoTest, FormatIsDetectedByContentNotExtension) {
  const Image image = gradient_image(32, 32, false);
  save_image(path("really_a_jpeg.png"), image, ImageFormat::kJpeg, 95);
  EXPECT_GT(psnr_rgb(image, load_image(path("really_a_jpeg.png"))), 35.0);
  save_image(path("really_a_png.jpg"), image, ImageFormat::kPng);
  EXPECT_TRUE(load_image(path("really_a_png.jpg")).pixels == image.pixels);
}

TEST_F(ImageIoTest, PngEveryLevelRoundTripsExactlyAndLevelNineIsTheSmallest) {
  for (const bool alpha : {false, true}) {
    const Image image = gradient_image(96, 80, alpha);
    auto size_at = [&](int level) {
      const std::string file = path("level" + std::to_string(level) + ".png");
      save_image(file, image, ImageEncoding(ImageFormat::kPng, level, kDefaultJpegQuality));
      EXPECT_TRUE(load_image(file).pixels == image.pixels) << "level " << level << (alpha ? " RGBA" : " RGB");
      return read_bytes(file).size();
    };
    const size_t fast = size_at(kPngLevelFast), stored = size_at(0), best = size_at(9);
    size_at(6);
    EXPECT_LE(best, fast) << (alpha ? "RGBA" : "RGB");
    EXPECT_LT(best, stored) << (alpha ? "RGBA" : "RGB");
  }
  // The ImageFormat overload is the default setting, byte for byte.
  const Image image = noise_image(40, 30, false, 5);
  save_image(path("format.png"), image, ImageFormat::kPng);
  save_image(path("encoding.png"), image, ImageEncoding(ImageFormat::kPng));
  EXPECT_TRUE(read_bytes(path("format.png")) == read_bytes(path("encoding.png")));
}

TEST_F(ImageIoTest, PngDeflatedInSlicesIsOneZlibStream) {
  // 1200 x 900 RGBA: 4.3 MB of filtered rows, deflated as five slices side by side.
  const Image image = noise_image(1200, 900, true, 7);
  for (const int level : {kPngLevelFast, 1, 6}) {
    const std::string file = path("sliced.png");
    save_image(file, image, ImageEncoding(ImageFormat::kPng, level, kDefaultJpegQuality));
    const Bytes png = read_bytes(file);
    // The IDAT data inflated by zlib itself (not the decoder tightex reads with): every row, a valid
    // Adler-32, nothing after the stream's end.
    Bytes idat;
    for (size_t at = 8; at + 8 <= png.size();) {
      const size_t length = size_t(png[at]) << 24 | size_t(png[at + 1]) << 16 | size_t(png[at + 2]) << 8 | png[at + 3];
      if (std::memcmp(&png[at + 4], "IDAT", 4) == 0)
        idat.insert(idat.end(), png.begin() + long(at + 8), png.begin() + long(at + 8 + length));
      at += 12 + length;
    }
    Bytes rows(size_t(900) * (1200 * 4 + 1) + 1);
    uLongf rows_size = uLongf(rows.size());
    EXPECT_EQ(uncompress(rows.data(), &rows_size, idat.data(), uLong(idat.size())), Z_OK) << level;
    EXPECT_EQ(rows_size, size_t(900) * (1200 * 4 + 1)) << level;
    EXPECT_TRUE(load_image(file).pixels == image.pixels) << level;
  }
}

TEST_F(ImageIoTest, PngLevelOutOfRangeIsRefusedBeforeTheFileIsCreated) {
  for (const int level : {-2, 10}) {
    expect_input_error([&] { save_image(path("l.png"), Image(2, 2), ImageEncoding(ImageFormat::kPng, level, kDefaultJpegQuality)); },
                       "compression level");
    EXPECT_FALSE(fs::exists(path("l.png")));
  }
  // Only the setting of the format written is checked.
  save_image(path("q.png"), Image(2, 2), ImageEncoding(ImageFormat::kPng, 9, 0));
  EXPECT_TRUE(fs::exists(path("q.png")));
}

// ---------------------------------------------------------------------------------------------------
// PNG colour types and bit depths

TEST_F(ImageIoTest, DecodesGreyPng) {
  const Bytes grey = {0, 64, 128, 255, 1, 2};
  const Bytes png = encode_png(make_ihdr(3, 2, 8, SPNG_COLOR_TYPE_GRAYSCALE), grey.data(), grey.size());
  const Image image = decode_image(png.data(), png.size(), "grey.png");
  ASSERT_EQ(image.width, 3);
  ASSERT_EQ(image.height, 2);
  for (size_t i = 0; i < grey.size(); ++i) EXPECT_EQ(image.pixels[i], (Rgba8{grey[i], grey[i], grey[i], 255}));
}

TEST_F(ImageIoTest, DecodesLowBitDepthGreyPng) {
  // 2 bits per sample, 4 pixels in one byte: 0, 1, 2, 3 -> 0, 85, 170, 255.
  const Bytes packed = {0b00011011};
  const Bytes png = encode_png(make_ihdr(4, 1, 2, SPNG_COLOR_TYPE_GRAYSCALE), packed.data(), packed.size());
  const Image image = decode_image(png.data(), png.size(), "grey2.png");
  ASSERT_EQ(image.width, 4);
  const uint8_t expected[] = {0, 85, 170, 255};
  for (int x = 0; x < 4; ++x) EXPECT_EQ(image.at(x, 0), (Rgba8{expected[x], expected[x], expected[x], 255}));
}

TEST_F(ImageIoTest, DecodesGreyAlphaPng) {
  const Bytes grey_alpha = {10, 255, 200, 0, 90, 128, 255, 7};
  const Bytes png = encode_png(make_ihdr(2, 2, 8, SPNG_COLOR_TYPE_GRAYSCALE_ALPHA), grey_alpha.data(), grey_alpha.size());
  const Image image = decode_image(png.data(), png.size(), "ga.png");
  ASSERT_EQ(image.width, 2);
  for (size_t i = 0; i < 4; ++i) {
    const uint8_t g = grey_alpha[2 * i], a = grey_alpha[2 * i + 1];
    EXPECT_EQ(image.pixels[i], (Rgba8{g, g, g, a}));
  }
}

TEST_F(ImageIoTest, Decodes16BitPngs) {
  // 16-bit samples are reduced to their high byte (0x1234 -> 0x12); spng rounds, so allow +-1.
  const std::vector<uint16_t> rgba16 = {0x0000, 0x1234, 0xffff, 0x8000, 0xfedc, 0x0101, 0x7f80, 0x4000};
  const Bytes png = encode_png(make_ihdr(2, 1, 16, SPNG_COLOR_TYPE_TRUECOLOR_ALPHA), rgba16.data(), rgba16.size() * sizeof(uint16_t));
  const Image image = decode_image(png.data(), png.size(), "rgba16.png");
  ASSERT_EQ(image.width, 2);
  const uint8_t* bytes = &image.pixels[0].r;
  for (size_t i = 0; i < rgba16.size(); ++i) EXPECT_NEAR(bytes[i], rgba16[i] / 257.0, 1.0) << i;

  const std::vector<uint16_t> grey16 = {0x0000, 0xffff, 0x8080};
  const Bytes grey_png = encode_png(make_ihdr(3, 1, 16, SPNG_COLOR_TYPE_GRAYSCALE), grey16.data(), grey16.size() * sizeof(uint16_t));
  const Image grey = decode_image(grey_png.data(), grey_png.size(), "grey16.png");
  EXPECT_EQ(grey.at(0, 0), (Rgba8{0, 0, 0, 255}));
  EXPECT_EQ(grey.at(1, 0), (Rgba8{255, 255, 255, 255}));
  EXPECT_EQ(grey.at(2, 0), (Rgba8{128, 128, 128, 255}));

  const std::vector<uint16_t> rgb16 = {0xffff, 0x0000, 0x8080};
  const Bytes rgb_png = encode_png(make_ihdr(1, 1, 16, SPNG_COLOR_TYPE_TRUECOLOR), rgb16.data(), rgb16.size() * sizeof(uint16_t));
  EXPECT_EQ(decode_image(rgb_png.data(), rgb_png.size(), "rgb16.png").at(0, 0), (Rgba8{255, 0, 128, 255}));
}

TEST_F(ImageIoTest, DecodesPalettePngWithTransparency) {
  spng_plte plte{};
  plte.n_entries = 3;
  plte.entries[0] = {255, 0, 0, 0};
  plte.entries[1] = {0, 255, 0, 0};
  plte.entries[2] = {0, 0, 255, 0};
  spng_trns trns{};
  trns.n_type3_entries = 2;  // entries past the list are opaque
  trns.type3_alpha[0] = 0;
  trns.type3_alpha[1] = 100;
  const Bytes indices = {0, 1, 2, 2};
  const Bytes png = encode_png(make_ihdr(4, 1, 8, SPNG_COLOR_TYPE_INDEXED), indices.data(), indices.size(), &plte, &trns);
  const Image image = decode_image(png.data(), png.size(), "palette.png");
  ASSERT_EQ(image.width, 4);
  EXPECT_EQ(image.at(0, 0), (Rgba8{255, 0, 0, 0}));
  EXPECT_EQ(image.at(1, 0), (Rgba8{0, 255, 0, 100}));
  EXPECT_EQ(image.at(2, 0), (Rgba8{0, 0, 255, 255}));
}

TEST_F(ImageIoTest, DecodesRgbPngWithTransparentColour) {
  const Bytes rgb = {1, 2, 3, 9, 9, 9};
  spng_trns trns{};
  trns.red = 9, trns.green = 9, trns.blue = 9;
  const Bytes png = encode_png(make_ihdr(2, 1, 8, SPNG_COLOR_TYPE_TRUECOLOR), rgb.data(), rgb.size(), nullptr, &trns);
  const Image image = decode_image(png.data(), png.size(), "trns.png");
  EXPECT_EQ(image.at(0, 0), (Rgba8{1, 2, 3, 255}));
  EXPECT_EQ(image.at(1, 0).a, 0);
}

// ---------------------------------------------------------------------------------------------------
// JPEG colour spaces and the stb_image fallback

// ---------------------------------------------------------------------------------------------------
// PNG in one pass (libdeflate), against libspng's own decode

// libspng's RGBA8 pixels of a PNG, as decode_png asked for them before the one-pass decoder.
Bytes spng_rgba8(const Bytes& png) {
  spng_ctx* ctx = spng_ctx_new(0);
  spng_set_png_buffer(ctx, png.data(), png.size());
  size_t size = 0;
  EXPECT_EQ(spng_decoded_image_size(ctx, SPNG_FMT_RGBA8, &size), 0);
  Bytes out(size);
  EXPECT_EQ(spng_decode_image(ctx, out.data(), out.size(), SPNG_FMT_RGBA8, SPNG_DECODE_TRNS), 0);
  spng_ctx_free(ctx);
  return out;
}

Bytes pixel_bytes(const Image& image) {
  const auto* p = reinterpret_cast<const unsigned char*>(image.pixels.data());
  return Bytes(p, p + image.pixels.size() * sizeof(Rgba8));
}

// The chunks of a PNG (type, data), in order.
std::vector<std::pair<std::string, Bytes>> png_chunks(const Bytes& png) {
  std::vector<std::pair<std::string, Bytes>> chunks;
  for (size_t p = 8; p + 12 <= png.size();) {
    const uint32_t length = uint32_t(png[p]) << 24 | uint32_t(png[p + 1]) << 16 | uint32_t(png[p + 2]) << 8 | png[p + 3];
    chunks.emplace_back(std::string(png.begin() + std::ptrdiff_t(p + 4), png.begin() + std::ptrdiff_t(p + 8)),
                        Bytes(png.begin() + std::ptrdiff_t(p + 8), png.begin() + std::ptrdiff_t(p + 8 + length)));
    p += 12 + length;
  }
  return chunks;
}

// A PNG of the given chunks, each with its length and CRC.
Bytes png_of(const std::vector<std::pair<std::string, Bytes>>& chunks) {
  Bytes png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  for (const auto& [type, data] : chunks) {
    for (int shift : {24, 16, 8, 0}) png.push_back(uint8_t(data.size() >> shift));
    const size_t start = png.size();
    png.insert(png.end(), type.begin(), type.end());
    png.insert(png.end(), data.begin(), data.end());
    const uint32_t crc = png_crc(png.data() + start, png.size() - start);
    for (int shift : {24, 16, 8, 0}) png.push_back(uint8_t(crc >> shift));
  }
  return png;
}

// The filtered rows of a PNG (each a filter type byte, then its samples), inflated by zlib.
Bytes png_raw_rows(const Bytes& png, size_t raw_size) {
  Bytes stream;
  for (const auto& [type, data] : png_chunks(png))
    if (type == "IDAT") stream.insert(stream.end(), data.begin(), data.end());
  Bytes raw(raw_size);
  uLongf size = raw_size;
  EXPECT_EQ(uncompress(raw.data(), &size, stream.data(), stream.size()), Z_OK);
  EXPECT_EQ(size, raw_size);
  return raw;
}

// 8-bit samples with smooth parts and noise, `channels` a pixel.
Bytes mixed_samples(uint32_t width, uint32_t height, int channels) {
  std::mt19937 rng(21);
  Bytes samples(size_t(width) * height * size_t(channels));
  for (size_t i = 0; i < samples.size(); ++i) {
    const size_t pixel = i / size_t(channels);
    const uint32_t x = uint32_t(pixel % width), y = uint32_t(pixel / width);
    samples[i] = (x + y) % 5 == 0 ? uint8_t(rng()) : uint8_t(x * 7 + y * 3 + i % size_t(channels) * 50);
  }
  return samples;
}

TEST(PngOnePass, EveryFilterOfEveryCommonKindDecodesAsLibspng) {
  const uint32_t width = 37, height = 29;
  std::vector<int> filters_seen(5, 0);
  for (const auto& [colour_type, channels] : {std::pair{0, 1}, {4, 2}, {2, 3}, {6, 4}}) {
    const Bytes samples = mixed_samples(width, height, channels);
    for (int choice : {int(SPNG_DISABLE_FILTERING), int(SPNG_FILTER_CHOICE_SUB), int(SPNG_FILTER_CHOICE_UP), int(SPNG_FILTER_CHOICE_AVG),
                       int(SPNG_FILTER_CHOICE_PAETH), int(SPNG_FILTER_CHOICE_ALL)}) {
      SCOPED_TRACE(::testing::Message() << "colour type " << colour_type << ", filter choice " << choice);
      const Bytes png =
          encode_png(make_ihdr(width, height, 8, uint8_t(colour_type)), samples.data(), samples.size(), nullptr, nullptr, choice);
      const Bytes raw = png_raw_rows(png, size_t(height) * (1 + size_t(width) * size_t(channels)));
      for (uint32_t y = 0; y < height; ++y) ++filters_seen.at(raw[size_t(y) * (1 + size_t(width) * size_t(channels))]);
      const std::optional<Image> image = decode_png_in_one_pass(png.data(), png.size(), size_t(1) << 30, size_t(64) << 20);
      ASSERT_TRUE(image.has_value());
      EXPECT_EQ(image->width, int(width));
      EXPECT_EQ(image->height, int(height));
      EXPECT_EQ(pixel_bytes(*image), spng_rgba8(png));
      EXPECT_EQ(pixel_bytes(decode_image(png.data(), png.size(), "kind.png")), spng_rgba8(png));
    }
  }
  for (int type = 0; type < 5; ++type) EXPECT_GT(filters_seen[size_t(type)], 0) << "filter type " << type << " never written";
}

TEST(PngOnePass, SeveralImageDataChunksAreOneStream) {
  const Image image = noise_image(300, 200, true, 22);
  const Bytes one = encode_png(make_ihdr(300, 200, 8, 6), image.pixels.data(), image.pixels.size() * 4);
  // The same stream cut into IDAT chunks of 1000 bytes, and an ancillary chunk before them.
  std::vector<std::pair<std::string, Bytes>> chunks;
  Bytes stream;
  for (const auto& [type, data] : png_chunks(one)) {
    if (type == "IDAT") stream.insert(stream.end(), data.begin(), data.end());
    if (type == "IHDR") chunks.emplace_back(type, data), chunks.emplace_back("tEXt", Bytes{'a', 0, 'b'});
  }
  for (size_t p = 0; p < stream.size(); p += 1000)
    chunks.emplace_back("IDAT",
                        Bytes(stream.begin() + std::ptrdiff_t(p), stream.begin() + std::ptrdiff_t(std::min(stream.size(), p + 1000))));
  chunks.emplace_back("IEND", Bytes{});
  ASSERT_GT(chunks.size(), 10u);
  const Bytes png = png_of(chunks);
  const std::optional<Image> decoded = decode_png_in_one_pass(png.data(), png.size(), size_t(1) << 30, size_t(64) << 20);
  ASSERT_TRUE(decoded.has_value());
  EXPECT_TRUE(decoded->pixels == image.pixels);
}

TEST(PngOnePass, OtherKindsAreLeftToLibspng) {
  const auto declined = [](const Bytes& png) {
    return !decode_png_in_one_pass(png.data(), png.size(), size_t(1) << 30, size_t(64) << 20).has_value();
  };
  const Bytes rgb = mixed_samples(16, 8, 3);
  const Bytes plain = encode_png(make_ihdr(16, 8, 8, 2), rgb.data(), rgb.size());
  ASSERT_FALSE(declined(plain));
  std::vector<uint16_t> wide(16 * 8 * 3, 0x1234);
  EXPECT_TRUE(declined(encode_png(make_ihdr(16, 8, 16, 2), wide.data(), wide.size() * 2)));  // 16-bit
  spng_plte plte{};
  plte.n_entries = 2;
  const Bytes indices(16 * 8, 1);
  EXPECT_TRUE(declined(encode_png(make_ihdr(16, 8, 8, 3), indices.data(), indices.size(), &plte)));  // palette
  spng_trns trns{};
  trns.red = 7;
  EXPECT_TRUE(declined(encode_png(make_ihdr(16, 8, 8, 2), rgb.data(), rgb.size(), nullptr, &trns)));  // a transparent colour
  const Bytes grey4(16 * 8 / 2, 0x5a);
  EXPECT_TRUE(declined(encode_png(make_ihdr(16, 8, 4, 0), grey4.data(), grey4.size())));  // 4-bit grey
  std::vector<std::pair<std::string, Bytes>> chunks = png_chunks(plain);
  chunks[0].second[12] = 1;  // interlaced (Adam7), told by the header alone
  EXPECT_TRUE(declined(png_of(chunks)));
  EXPECT_TRUE(!decode_png_in_one_pass(plain.data(), plain.size(), 16 * 8 - 1, size_t(64) << 20).has_value());  // too many pixels
}

TEST(PngOnePass, DamageIsLeftToLibspngWhichNamesIt) {
  const Bytes rgb = mixed_samples(16, 8, 3);
  const Bytes plain = encode_png(make_ihdr(16, 8, 8, 2), rgb.data(), rgb.size());
  const auto check = [](const Bytes& png, const std::string& what) {
    SCOPED_TRACE(what);
    EXPECT_FALSE(decode_png_in_one_pass(png.data(), png.size(), size_t(1) << 30, size_t(64) << 20).has_value());
    expect_input_error([&] { decode_image(png.data(), png.size(), "damaged.png"); }, "damaged.png");
  };
  Bytes flipped = plain;
  flipped[flipped.size() - 20] ^= 0x40;  // inside the image data: its CRC fails
  check(flipped, "a flipped bit");
  check(Bytes(plain.begin(), plain.begin() + std::ptrdiff_t(plain.size() / 2)), "cut in half");
  // Rows whose filter type is 5 (there are five, 0..4), and a stream one row short, each with sound CRCs.
  Bytes raw = png_raw_rows(plain, 8 * (1 + 16 * 3));
  for (const auto& [rows, filter] : {std::pair{8, 5}, {7, 0}}) {
    Bytes cut(raw.begin(), raw.begin() + rows * (1 + 16 * 3));
    for (int y = 0; y < rows; ++y) cut[size_t(y) * (1 + 16 * 3)] = uint8_t(filter);
    Bytes stream(compressBound(uLong(cut.size())));
    uLongf size = stream.size();
    ASSERT_EQ(compress(stream.data(), &size, cut.data(), uLong(cut.size())), Z_OK);
    stream.resize(size);
    std::vector<std::pair<std::string, Bytes>> chunks = png_chunks(plain);
    chunks = {chunks.front(), {"IDAT", stream}, {"IEND", Bytes{}}};
    check(png_of(chunks), rows == 8 ? "filter type 5" : "a row short");
  }
}

TEST_F(ImageIoTest, DecodesGreyJpeg) {
  Bytes grey(40 * 30);
  for (size_t i = 0; i < grey.size(); ++i) grey[i] = uint8_t(40 + (i % 40) * 4);
  const Bytes jpeg = encode_jpeg(40, 30, 1, JCS_GRAYSCALE, grey);
  const Image image = decode_image(jpeg.data(), jpeg.size(), "grey.jpg");
  ASSERT_EQ(image.width, 40);
  ASSERT_EQ(image.height, 30);
  for (size_t i = 0; i < grey.size(); ++i) {
    const Rgba8 p = image.pixels[i];
    ASSERT_EQ(p.r, p.g);
    ASSERT_EQ(p.r, p.b);
    ASSERT_EQ(p.a, 255);
    ASSERT_NEAR(p.r, grey[i], 4);
  }
}

TEST_F(ImageIoTest, DecodesAdobeCmykJpeg) {
  // Inverted CMYK, as Photoshop writes it: (C, M, Y, K) = (0, 100%, 100%, 0) is stored as 255, 0, 0, 255.
  Bytes cmyk;
  for (int i = 0; i < 16 * 16; ++i) cmyk.insert(cmyk.end(), {255, 0, 0, 255});
  const Bytes jpeg = encode_jpeg(16, 16, 4, JCS_CMYK, cmyk);
  const Image image = decode_image(jpeg.data(), jpeg.size(), "cmyk.jpg");
  ASSERT_EQ(image.width, 16);
  for (const Rgba8& p : image.pixels) {
    ASSERT_NEAR(p.r, 255, 3);
    ASSERT_NEAR(p.g, 0, 3);
    ASSERT_NEAR(p.b, 0, 3);
    ASSERT_EQ(p.a, 255);
  }
}

TEST_F(ImageIoTest, DecodesBmpThroughStb) {
  const Image image = noise_image(13, 7, false, 5);
  write_bytes(path("image.bmp"), encode_bmp(image));
  const Image loaded = load_image(path("image.bmp"));
  ASSERT_EQ(loaded.width, 13);
  ASSERT_EQ(loaded.height, 7);
  EXPECT_TRUE(loaded.pixels == image.pixels);
}

TEST_F(ImageIoTest, Refuses16BitPpmClearly) {
  // stb_image 2.27 overran its buffer on 16-bit PNMs when asked for 4 channels, and reads their samples
  // in the wrong byte order; they must give a clear error, not a crash or wrong colours.
  Bytes ppm = {'P', '6', '\n', '3', ' ', '2', '\n', '6', '5', '5', '3', '5', '\n'};
  for (int i = 0; i < 3 * 2 * 3; ++i) ppm.push_back(uint8_t(i * 37)), ppm.push_back(uint8_t(i));
  expect_input_error([&] { decode_image(ppm.data(), ppm.size(), "deep.ppm"); }, "deep.ppm: 16-bit PNM");

  // 8-bit PNM is fine.
  Bytes ppm8 = {'P', '6', '\n', '2', ' ', '1', '\n', '2', '5', '5', '\n', 1, 2, 3, 250, 251, 252};
  const Image image = decode_image(ppm8.data(), ppm8.size(), "plain.ppm");
  ASSERT_EQ(image.width, 2);
  EXPECT_EQ(image.at(0, 0), (Rgba8{1, 2, 3, 255}));
  EXPECT_EQ(image.at(1, 0), (Rgba8{250, 251, 252, 255}));
}

// ---------------------------------------------------------------------------------------------------
// Bad input

TEST_F(ImageIoTest, MissingFileNamesTheFile) {
  const std::string message = expect_input_error([&] { load_image(path("nope.png")); }, path("nope.png"));
  EXPECT_NE(message.find("No such file or directory"), std::string::npos) << message;
}

TEST_F(ImageIoTest, DirectoryIsRefused) {
  expect_input_error([&] { load_image(dir_.string()); }, dir_.string());
}

TEST_F(ImageIoTest, EmptyFileIsRefused) {
  write_bytes(path("empty.png"), {});
  expect_input_error([&] { load_image(path("empty.png")); }, path("empty.png"));
  expect_input_error([&] { decode_image(nullptr, 0, "nothing.png"); }, "nothing.png");
}

TEST_F(ImageIoTest, TruncatedPngNamesTheFile) {
  const Image image = noise_image(64, 64, false, 6);
  save_image(path("full.png"), image, ImageFormat::kPng);
  const Bytes png = read_bytes(path("full.png"));
  // Cuts inside the signature, the header and the image data.
  for (size_t cut : {png.size() / 2, size_t(40), size_t(20), size_t(8), size_t(3), png.size() - 17}) {
    SCOPED_TRACE(cut);
    write_bytes(path("cut.png"), Bytes(png.begin(), png.begin() + std::ptrdiff_t(cut)));
    const std::string message = expect_input_error([&] { load_image(path("cut.png")); }, path("cut.png"));
    EXPECT_NE(message.find("truncated PNG"), std::string::npos) << message;
  }
  // Losing only what follows the image data (the IEND chunk) loses no pixels; that file is accepted.
  const Bytes no_iend(png.begin(), png.end() - 12);
  EXPECT_TRUE(decode_image(no_iend.data(), no_iend.size(), "no_iend.png").pixels == image.pixels);
}

TEST_F(ImageIoTest, TruncatedJpegNamesTheFile) {
  save_image(path("full.jpg"), noise_image(64, 64, false, 7), ImageFormat::kJpeg, 90);
  const Bytes jpeg = read_bytes(path("full.jpg"));
  for (size_t cut : {jpeg.size() / 2, size_t(300), size_t(100), size_t(4)}) {
    SCOPED_TRACE(cut);
    write_bytes(path("cut.jpg"), Bytes(jpeg.begin(), jpeg.begin() + std::ptrdiff_t(cut)));
    const std::string message = expect_input_error([&] { load_image(path("cut.jpg")); }, path("cut.jpg"));
    EXPECT_NE(message.find("truncated JPEG"), std::string::npos) << message;
  }
}

TEST_F(ImageIoTest, CorruptPngDataIsRefused) {
  save_image(path("good.png"), noise_image(32, 32, false, 8), ImageFormat::kPng);
  Bytes png = read_bytes(path("good.png"));
  png[png.size() / 2] ^= 0x55;  // inside the image data: the CRC no longer matches
  expect_input_error([&] { decode_image(png.data(), png.size(), "flipped.png"); }, "flipped.png");
}

TEST_F(ImageIoTest, CorruptJpegDataIsRefusedOrDecodedWithoutCrashing) {
  save_image(path("good.jpg"), noise_image(64, 64, false, 9), ImageFormat::kJpeg, 90);
  const Bytes jpeg = read_bytes(path("good.jpg"));
  // Bit flips in entropy-coded data often decode to a valid (wrong) image, which JPEG cannot detect;
  // what matters is that every variant either decodes or throws an InputError, never crashes.
  std::mt19937 rng(10);
  for (int trial = 0; trial < 200; ++trial) {
    Bytes damaged = jpeg;
    for (int k = 0; k < 4; ++k) damaged[2 + rng() % (damaged.size() - 2)] = uint8_t(rng());
    try {
      const Image image = decode_image(damaged.data(), damaged.size(), "damaged.jpg");
      EXPECT_FALSE(image.empty());
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("damaged.jpg"), std::string::npos) << e.what();
    }
  }
}

TEST_F(ImageIoTest, GarbageIsRefused) {
  std::mt19937 rng(11);
  Bytes garbage(5000);
  for (unsigned char& b : garbage) b = uint8_t(rng());
  garbage[0] = 'G';  // not a TGA header by chance (stb guesses TGA from loose header checks)
  garbage[1] = 'X';
  write_bytes(path("garbage.png"), garbage);
  expect_input_error([&] { load_image(path("garbage.png")); }, path("garbage.png"));

  const std::string text = "this is a text file, not an image\n";
  write_bytes(path("text.jpg"), Bytes(text.begin(), text.end()));
  expect_input_error([&] { load_image(path("text.jpg")); }, path("text.jpg"));

  // Right magic bytes, garbage after them.
  for (Bytes magic : {Bytes{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'}, Bytes{0xff, 0xd8, 0xff}}) {
    magic.insert(magic.end(), garbage.begin(), garbage.end());
    expect_input_error([&] { decode_image(magic.data(), magic.size(), "magic.bin"); }, "magic.bin");
  }
}

TEST_F(ImageIoTest, RandomBytesNeverCrash) {
  // Fuzz-style smoke test: short random buffers, including ones starting with each magic number.
  std::mt19937 rng(12);
  const std::vector<Bytes> prefixes = {{}, {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'}, {0xff, 0xd8, 0xff}, {'B', 'M'}};
  for (int trial = 0; trial < 400; ++trial) {
    Bytes data = prefixes[size_t(trial) % prefixes.size()];
    const size_t extra = 1 + rng() % 300;
    for (size_t i = 0; i < extra; ++i) data.push_back(uint8_t(rng()));
    try {
      decode_image(data.data(), data.size(), "fuzz.bin", size_t(1) << 20);
    } catch (const InputError&) {
    }
  }
}

TEST_F(ImageIoTest, RadianceHdrDoesNotHang) {
  // An RLE scanline whose run count is 0 made stb_image 2.27 loop forever; HDR is not read at all.
  const std::string header = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 8\n";
  Bytes hdr(header.begin(), header.end());
  hdr.insert(hdr.end(), {2, 2, 0, 8, 0, 0, 0, 0});
  expect_input_error([&] { decode_image(hdr.data(), hdr.size(), "sky.hdr"); }, "sky.hdr");
}

TEST_F(ImageIoTest, PnmHeaderNumberTooLongIsRefused) {
  // stb_image 2.27 parses PNM header numbers into an int without an overflow check: a 10-digit width was
  // signed overflow (found by fuzz_image under UBSan; the input is fuzz/corpus/fuzz_image/
  // regress-pnm-width-overflow.ppm). Refused before stb sees it, also by the header-only size query.
  const std::string header = "P6\n# comment\n8866666666 2\n255\n";
  Bytes ppm(header.begin(), header.end());
  ppm.insert(ppm.end(), 12, 7);
  expect_input_error([&] { decode_image(ppm.data(), ppm.size(), "wide.ppm"); }, "wide.ppm: corrupt PNM header");
  write_bytes(path("wide.ppm"), ppm);
  EXPECT_EQ(image_dimensions(path("wide.ppm")), (std::pair<int, int>{0, 0}));
  // Nine digits still reach the size check.
  const std::string nine = "P5 999999999 1 255\n";
  expect_input_error([&] { decode_image(reinterpret_cast<const unsigned char*>(nine.data()), nine.size(), "nine.pgm", size_t(1) << 20); },
                     "999999999x1 pixels, more than the limit");
}

// A PSD of `channels` 8-bit planes, raw, `w` x `h`, each plane given in full.
Bytes raw_psd(int w, int h, const std::vector<Bytes>& planes) {
  Bytes b = {'8', 'B', 'P', 'S', 0, 1, 0, 0, 0, 0, 0, 0, 0, uint8_t(planes.size())};
  for (uint32_t v : {uint32_t(h), uint32_t(w)})
    for (int s = 24; s >= 0; s -= 8) b.push_back(uint8_t(v >> s));
  b.insert(b.end(), {0, 8, 0, 3});  // 8 bits, RGB mode
  b.insert(b.end(), 12, 0);         // no colour mode data, image resources or layers
  b.insert(b.end(), {0, 0});        // raw
  for (const Bytes& p : planes) b.insert(b.end(), p.begin(), p.end());
  return b;
}

TEST_F(ImageIoTest, PsdWithColourBelowTheWhiteMatteDecodesClamped) {
  // stb_image 2.27 removes Photoshop's white matte from partly transparent PSD pixels with a float to
  // byte cast that is undefined behaviour when the colour lies below the matte (found by fuzz_image
  // under UBSan; the input is fuzz/corpus/fuzz_image/regress-psd-matte-below-zero.psd). tightex decodes
  // PSD itself, the same way, with that value clamped to 0.
  const Bytes psd = raw_psd(3, 1, {{10, 200, 40}, {0, 255, 90}, {255, 100, 0}, {128, 128, 255}});
  const Image img = decode_image(psd.data(), psd.size(), "matte.psd");
  ASSERT_EQ(img.width, 3);
  ASSERT_EQ(img.height, 1);
  // Pixel 0 (alpha 128): 10 and 0 lie below the matte -> 0; 255 -> 255 * 1.99 - 253.0 = 255.
  EXPECT_EQ(img.at(0, 0).r, 0);
  EXPECT_EQ(img.at(0, 0).g, 0);
  EXPECT_EQ(img.at(0, 0).b, 255);
  EXPECT_EQ(img.at(0, 0).a, 128);
  // Pixel 1 (alpha 128): 200 -> 145.4 -> 145, as stb computes it; 255 -> 255; 100 -> 0.
  EXPECT_EQ(img.at(1, 0).r, 145);
  EXPECT_EQ(img.at(1, 0).g, 255);
  EXPECT_EQ(img.at(1, 0).b, 0);
  // Pixel 2 (opaque): as stored.
  EXPECT_EQ(img.at(2, 0).r, 40);
  EXPECT_EQ(img.at(2, 0).g, 90);
  EXPECT_EQ(img.at(2, 0).b, 0);
  EXPECT_EQ(img.at(2, 0).a, 255);
  write_bytes(path("matte.psd"), psd);
  EXPECT_EQ(image_dimensions(path("matte.psd")), (std::pair<int, int>{3, 1}));
  // The fuzzer's input: 1x3 pixels, 8 channels, nothing but the matte to remove.
  const Bytes found = read_bytes(std::string(TIGHTEX_FUZZ_CORPUS) + "/fuzz_image/regress-psd-matte-below-zero.psd");
  const Image f = decode_image(found.data(), found.size(), "found.psd");
  EXPECT_EQ(f.width * f.height, 3);
}

TEST_F(ImageIoTest, PsdMissingChannelsAndBadHeadersAreRefusedOrFilled) {
  // One plane: red only, green and blue 0, opaque (as stb reads it).
  const Bytes one = raw_psd(2, 1, {{7, 9}});
  const Image img = decode_image(one.data(), one.size(), "one.psd");
  EXPECT_EQ(img.at(1, 0).r, 9);
  EXPECT_EQ(img.at(1, 0).g, 0);
  EXPECT_EQ(img.at(1, 0).a, 255);
  Bytes bad_mode = one;
  bad_mode[25] = 1;  // greyscale
  expect_input_error([&] { decode_image(bad_mode.data(), bad_mode.size(), "grey.psd"); }, "grey.psd: PSD image not in RGB");
  Bytes bad_rle = one;
  bad_rle[39] = 1;  // RLE: row counts, then a run longer than the plane
  bad_rle.resize(40);
  bad_rle.insert(bad_rle.end(), {0, 0, 0xFD, 1});
  expect_input_error([&] { decode_image(bad_rle.data(), bad_rle.size(), "rle.psd"); }, "rle.psd: corrupt PSD image (bad RLE data)");
  Bytes huge = one;
  huge[14] = 0x7F;  // height 2^30 + ...
  expect_input_error([&] { decode_image(huge.data(), huge.size(), "huge.psd", size_t(1) << 20); }, "more than the limit");
}

TEST_F(ImageIoTest, ZeroSizePngIsRefused) {
  // spng's encoder refuses to write a zero width, so the header is written by hand.
  const Bytes png = png_header_only(0, 1);
  expect_input_error([&] { decode_image(png.data(), png.size(), "zero.png"); }, "zero.png");
}

TEST_F(ImageIoTest, PixelLimitIsEnforcedForEveryFormat) {
  const Image image = gradient_image(100, 50, false);  // 5000 pixels
  save_image(path("limit.png"), image, ImageFormat::kPng);
  save_image(path("limit.jpg"), image, ImageFormat::kJpeg);
  write_bytes(path("limit.bmp"), encode_bmp(image));
  for (const char* name : {"limit.png", "limit.jpg", "limit.bmp"}) {
    EXPECT_NO_THROW(load_image(path(name), 5000)) << name;
    const std::string message = expect_input_error([&] { load_image(path(name), 4999); }, path(name));
    EXPECT_NE(message.find("100x50"), std::string::npos) << message;
  }
}

TEST_F(ImageIoTest, HugeDeclaredSizeIsRefusedBeforeAllocating) {
  // 100000 x 100000 is 10^10 pixels, 40 GB as RGBA; the default limit must refuse it at once.
  const Bytes png = png_header_only(100000, 100000);
  expect_input_error([&] { decode_image(png.data(), png.size(), "huge.png"); }, "more than the limit");
}

// ---------------------------------------------------------------------------------------------------
// Write failures

TEST_F(ImageIoTest, UnwritablePathNamesTheFile) {
  const std::string target = path("no_such_dir/out.png");
  expect_input_error([&] { save_image(target, gradient_image(4, 4, false), ImageFormat::kPng); }, target);
}

TEST_F(ImageIoTest, FullDiskIsReported) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const Image image = noise_image(256, 256, false, 13);  // larger than stdio's buffer
  expect_input_error([&] { save_image("/dev/full", image, ImageFormat::kPng); }, "/dev/full");
  expect_input_error([&] { save_image("/dev/full", image, ImageFormat::kJpeg); }, "/dev/full");
  EXPECT_TRUE(fs::exists("/dev/full"));  // a failed save removes only regular files it created
}

TEST_F(ImageIoTest, FailedJpegSaveLeavesNoFile) {
  // Wider than JPEG allows (65500 pixels a side).
  expect_input_error([&] { save_image(path("wide.jpg"), Image(65501, 1), ImageFormat::kJpeg); }, path("wide.jpg"));
  EXPECT_FALSE(fs::exists(path("wide.jpg")));
}

TEST_F(ImageIoTest, JpegQualityOutOfRangeIsRefused) {
  expect_input_error([&] { save_image(path("q.jpg"), Image(2, 2), ImageFormat::kJpeg, 0); }, "quality");
  expect_input_error([&] { save_image(path("q.jpg"), Image(2, 2), ImageFormat::kJpeg, 101); }, "quality");
}

#ifdef TIGHTEX_SHARED_DATA
TEST_F(ImageIoTest, LoadsRealTexture) {
  const std::string file = std::string(TIGHTEX_SHARED_DATA) + "/meshroom_esp32cam/texture_1001.png";
  if (!fs::exists(file)) GTEST_SKIP() << file << " not present";
  const Image image = load_image(file);
  EXPECT_EQ(image.width, 4096);
  EXPECT_EQ(image.height, 4096);
}
#endif

// WebP (glTF scans carry it through EXT_texture_webp): a lossless one decodes to its exact pixels,
// its header gives the size, and a truncated one is refused on one line.
TEST(ImageIo, DecodesWebp) {
  const int w = 7, h = 5;
  std::vector<uint8_t> rgba(size_t(w * h * 4));
  for (size_t i = 0; i < rgba.size(); ++i) rgba[i] = uint8_t(i * 37 % 256);
  for (size_t i = 3; i < rgba.size(); i += 4) rgba[i] = 255;
  uint8_t* encoded = nullptr;
  const size_t size = WebPEncodeLosslessRGBA(rgba.data(), w, h, w * 4, &encoded);
  ASSERT_GT(size, 0u);
  const std::vector<uint8_t> bytes(encoded, encoded + size);
  WebPFree(encoded);
  const Image img = decode_image(bytes.data(), bytes.size(), "t.webp");
  ASSERT_EQ(img.width, w);
  ASSERT_EQ(img.height, h);
  EXPECT_EQ(std::memcmp(img.pixels.data(), rgba.data(), rgba.size()), 0);
  EXPECT_EQ(image_dimensions(bytes.data(), bytes.size()), std::make_pair(w, h));
  EXPECT_THROW(decode_image(bytes.data(), bytes.size() / 2, "t.webp"), InputError);
  EXPECT_THROW(decode_image(bytes.data(), bytes.size(), "t.webp", 10), InputError);  // more pixels than allowed
}

/// The PSNR (dB, over RGB) of `bytes` decoded against `image`.
double webp_psnr(const std::string& bytes, const Image& image) {
  const Image decoded = decode_image(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), "t.webp");
  double se = 0;
  for (size_t i = 0; i < image.pixels.size(); ++i) {
    const Rgba8 a = image.pixels[i], b = decoded.pixels[i];
    se += double((a.r - b.r) * (a.r - b.r) + (a.g - b.g) * (a.g - b.g) + (a.b - b.b) * (a.b - b.b));
  }
  return 10 * std::log10(255.0 * 255.0 / std::max(se / double(3 * image.pixels.size()), 1e-9));
}

/// `image` through libwebp's simple lossy API (its plain RGB-to-YUV conversion) at `quality`.
std::string plain_webp(const Image& image, int quality) {
  std::vector<uint8_t> rgb;
  for (const Rgba8& p : image.pixels) rgb.insert(rgb.end(), {p.r, p.g, p.b});
  uint8_t* out = nullptr;
  const size_t size = WebPEncodeRGB(rgb.data(), image.width, image.height, image.width * 3, float(quality), &out);
  std::string bytes(reinterpret_cast<const char*>(out), size);
  WebPFree(out);
  return bytes;
}

/// Printed matter: lines of letters (strokes two texels wide in cells of 12 x 18), red and blue by
/// turns, on yellow.
Image printed_colour(int side) {
  Image img(side, side, Rgba8{240, 210, 30, 255});
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      const int u = x / 2 % 6, v = y / 2 % 9, glyph = int((uint32_t(x / 12) * 2654435761u + uint32_t(y / 18) * 40503u) >> 7) % 4;
      const bool stroke = u < 5 && v < 8 &&
                          (glyph == 0   ? u == 0 || v == 0
                           : glyph == 1 ? u == 2 || v == 7
                           : glyph == 2 ? v == 3 || u == 4
                                        : u == v / 2);
      if (stroke) img.at(x, y) = (y / 18) % 2 ? Rgba8{200, 20, 30, 255} : Rgba8{20, 40, 190, 255};
    }
  return img;
}

// Lossy WebP converts saturated print to YUV 4:2:0 by libwebp's sharp conversion: 3.5-3.9 dB more
// than the plain conversion at the same bytes or more (the plain one's lowest quality that takes at
// least as many). An image whose chroma varies slowly (a photograph's smooth colour under luma
// detail, or grey) takes the plain conversion: the same bytes as libwebp's simple API.
TEST(ImageIo, LossyWebpConvertsSaturatedPrintSharplyAndPhotographsPlainly) {
  const Image print = printed_colour(128);
  const ImageEncoding webp(ImageFormat::kWebp);
  for (const int quality : {60, 90}) {
    ImageEncoding e = webp;
    e.webp_quality = quality;
    const std::string sharp = encode_image(print, e);
    int q = 1;
    while (q < 100 && plain_webp(print, q).size() < sharp.size()) ++q;
    const double sharp_db = webp_psnr(sharp, print), plain_db = webp_psnr(plain_webp(print, q), print);
    EXPECT_GT(sharp_db, plain_db + 2) << "quality " << quality << ": " << sharp_db << " vs " << plain_db << " dB; " << quality << ": sharp "
                                      << sharp.size() << " bytes; plain quality " << q;
  }
  Image grey = print, photo(128, 128);
  for (Rgba8& p : grey.pixels) p.r = p.g = p.b = uint8_t((p.r + 2 * p.g + p.b) / 4);
  std::mt19937 rng(3);
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x) {
      const int light = int(rng() % 60);
      photo.at(x, y) = Rgba8{uint8_t(90 + x / 2 + light), uint8_t(70 + y / 3 + light), uint8_t(60 + (x + y) / 8 + light), 255};
    }
  EXPECT_EQ(encode_image(grey, webp), plain_webp(grey, webp.webp_quality));
  EXPECT_EQ(encode_image(photo, webp), plain_webp(photo, webp.webp_quality));
}

// One ImageEncoder encodes its image at several qualities, on several threads at once, to the bytes
// encode_image gives for each; an image with transparent texels keeps its alpha exactly (WebP's alpha
// plane is lossless) and its opaque colour close.
TEST(ImageIo, OneImageEncoderServesEveryQualityOnEveryThread) {
  Image img = printed_colour(96);
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 20; ++x) img.at(x, y) = Rgba8{0, 0, 0, 0};
  const ImageEncoder encoder(img, "t.webp");
  const std::vector<int> qualities = {30, 70, 95, 70};
  std::vector<std::string> bytes(qualities.size());
  std::vector<std::thread> threads;
  for (size_t i = 0; i < qualities.size(); ++i)
    threads.emplace_back([&, i] {
      ImageEncoding e(ImageFormat::kWebp);
      e.webp_quality = qualities[i];
      bytes[i] = encoder.encode(e);
    });
  for (std::thread& t : threads) t.join();
  for (size_t i = 0; i < qualities.size(); ++i) {
    ImageEncoding e(ImageFormat::kWebp);
    e.webp_quality = qualities[i];
    EXPECT_EQ(bytes[i], encode_image(img, e)) << "quality " << qualities[i];
  }
  EXPECT_LT(bytes[0].size(), bytes[1].size());
  const Image decoded = decode_image(reinterpret_cast<const unsigned char*>(bytes[2].data()), bytes[2].size(), "t.webp");
  double se = 0;
  size_t opaque = 0;
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    ASSERT_EQ(decoded.pixels[i].a, img.pixels[i].a) << "texel " << i;
    if (img.pixels[i].a == 0) continue;
    ++opaque;
    se += std::pow(decoded.pixels[i].r - img.pixels[i].r, 2) + std::pow(decoded.pixels[i].g - img.pixels[i].g, 2) +
          std::pow(decoded.pixels[i].b - img.pixels[i].b, 2);
  }
  EXPECT_GT(10 * std::log10(255.0 * 255.0 / (se / double(3 * opaque))), 20.0);  // 23.9 dB; colour lost: under 10
}

}  // namespace
}  // namespace tightex

// A NaN or infinite texture coordinate reads no texel (converting NaN to an index is undefined
// behaviour; UBSan flags it): transparent black, and finite wrapped coordinates still sample.
TEST(SampleBilinear, NonFiniteCoordinatesReadNothing) {
  tightex::Image img(4, 4, tightex::Rgba8{200, 100, 50, 255});
  for (double bad : {std::nan(""), double(INFINITY), -double(INFINITY)}) {
    const auto a = tightex::sample_bilinear(img, bad, 0.5), b = tightex::sample_bilinear(img, 0.5, bad);
    for (int c = 0; c < 4; ++c) {
      EXPECT_EQ(a[size_t(c)], 0.0f);
      EXPECT_EQ(b[size_t(c)], 0.0f);
    }
  }
  EXPECT_FLOAT_EQ(tightex::sample_bilinear(img, 7.3, -2.1)[0], 200.0f);
}
