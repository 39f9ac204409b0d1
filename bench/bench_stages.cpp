// Per-stage benchmarks on generated meshes of 10k..1M triangles: a bumpy sphere (closed, genus 0,
// cut along one path) and the same with holes, a bumpy torus for the handle search, its coarse copy for the multilevel map, and reading it
// back from an OBJ (in stretches on every core, and as one stretch), a scan texture's PNG decoded, and a baked atlas shrunk as the rate
// search does. Speed is measured here, never asserted in tests. Run: build/bench/tightex_bench --benchmark_repetitions=3
// --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <random>

#include <spng.h>

#include "bake/bake.hpp"
#include "cut/cut.hpp"
#include "io/image_io.hpp"
#include "io/obj_reader.hpp"
#include "layout/layout.hpp"
#include "param/coarsen.hpp"
#include "param/param.hpp"
#include "prepare/components.hpp"
#include "prepare/handles.hpp"
#include "prepare/repair.hpp"
#include "run/budget_search.hpp"

using namespace tightex;

namespace {

/// A UV sphere with a bumpy radius: about `triangles` triangles, a fragmented atlas (every quad of the
/// grid its own chart, as the worst photogrammetry output), one 1024x1024 texture.
TexturedMesh bumpy_sphere(int triangles) {
  const int n = std::max(8, int(std::sqrt(triangles / 2.0)));
  TexturedMesh m;
  m.source = "bench";
  auto index = [&](int i, int j) { return uint32_t(i * n + (j % n)); };
  for (int i = 0; i < n; ++i) {
    const double th = std::numbers::pi * (i + 0.5) / n;
    for (int j = 0; j < n; ++j) {
      const double ph = 2 * std::numbers::pi * j / n;
      const double r = 1.0 + 0.1 * std::sin(5 * th) * std::cos(3 * ph);
      m.positions.push_back(r * Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
    }
  }
  const uint32_t north = uint32_t(m.positions.size()), south = north + 1;
  m.positions.push_back(Vec3(0, 0, 1.05));
  m.positions.push_back(Vec3(0, 0, -1.05));
  auto add = [&](Tri t) {
    m.triangles.push_back(t);
    for (int k = 0; k < 3; ++k) {
      const double u = double(m.triangles.size() % 97) / 97.0, v = double(m.triangles.size() % 89) / 89.0;
      m.corner_uv.push_back(Vec2(u + 0.005 * k, v + 0.005 * (k == 2)));
    }
    m.face_material.push_back(0);
  };
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j < n; ++j) {
      add({index(i, j), index(i + 1, j), index(i + 1, j + 1)});
      add({index(i, j), index(i + 1, j + 1), index(i, j + 1)});
    }
  for (int j = 0; j < n; ++j) {
    add({north, index(0, j), index(0, j + 1)});
    add({south, index(n - 1, j + 1), index(n - 1, j)});
  }
  Material mat;
  mat.name = "m";
  mat.texture = 0;
  m.materials.push_back(mat);
  Texture tex;
  tex.path = "bench.png";
  tex.image = Image(1024, 1024);
  for (int y = 0; y < 1024; ++y)
    for (int x = 0; x < 1024; ++x) tex.image.at(x, y) = {uint8_t(x), uint8_t(y), uint8_t(x ^ y), 255};
  m.textures.push_back(std::move(tex));
  return m;
}

const TexturedMesh& mesh_for(int triangles) {
  static std::map<int, TexturedMesh> cache;
  auto it = cache.find(triangles);
  if (it == cache.end()) it = cache.emplace(triangles, bumpy_sphere(triangles)).first;
  return it->second;
}

/// A bumpy torus of about `triangles` triangles: one handle for the handle search, prepared as one
/// component.
Surface bumpy_torus(int triangles) {
  const int n = std::max(8, int(std::sqrt(triangles / 2.0)));
  TexturedMesh m;
  m.source = "bench";
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double u = 2 * std::numbers::pi * i / n, v = 2 * std::numbers::pi * j / n;
      const double r = 0.3 * (1 + 0.1 * std::sin(5 * u) * std::cos(3 * v));
      m.positions.push_back(Vec3((1 + r * std::cos(v)) * std::cos(u), (1 + r * std::cos(v)) * std::sin(u), r * std::sin(v)));
    }
  auto index = [&](int i, int j) { return uint32_t((i % n) * n + (j % n)); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      m.triangles.push_back({index(i, j), index(i + 1, j), index(i + 1, j + 1)});
      m.triangles.push_back({index(i, j), index(i + 1, j + 1), index(i, j + 1)});
    }
  m.corner_uv.assign(3 * m.triangles.size(), Vec2::Zero());
  m.face_material.assign(m.triangles.size(), 0);
  m.materials.push_back(Material{});
  return split_components(prepare_surface(m, nullptr))[0];
}

/// The bumpy sphere of `triangles` written as an OBJ (once per size, removed at exit).
const std::string& obj_for(int triangles) {
  struct Folders {
    std::map<int, std::filesystem::path> dir;
    std::map<int, std::string> obj;
    ~Folders() {
      std::error_code ec;
      for (const auto& [size, d] : dir) std::filesystem::remove_all(d, ec);
    }
  };
  static Folders written;
  if (!written.obj.contains(triangles)) {
    const auto dir =
        std::filesystem::temp_directory_path() / ("tightex_bench_" + std::to_string(::getpid()) + "_" + std::to_string(triangles));
    written.dir[triangles] = dir;
    write_obj(mesh_for(triangles), dir.string(), "sphere", ImageEncoding{});
    written.obj[triangles] = (dir / "sphere.obj").string();
  }
  return written.obj[triangles];
}

/// read_obj's geometry (no texture decoding); range(1) 0: the default stretches on every core, else
/// one stretch (the file parsed from start to end on one core).
void BM_ReadObj(benchmark::State& state) {
  const std::string& path = obj_for(int(state.range(0)));
  ModelReadOptions options;
  options.load_textures = false;
  const size_t chunk_bytes = state.range(1) == 0 ? kObjChunkBytes : std::numeric_limits<size_t>::max();
  for (auto _ : state) benchmark::DoNotOptimize(read_obj_in_chunks(path, options, nullptr, chunk_bytes));
  state.counters["MB/s"] =
      benchmark::Counter(double(std::filesystem::file_size(path)) / 1e6, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_PrepareSurface(benchmark::State& state) {
  const TexturedMesh& m = mesh_for(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(prepare_surface(m, nullptr));
  state.counters["triangles"] = double(m.num_triangles());
}

/// The handle search and cut (remove_handles) on a torus of range(0) triangles.
void BM_RemoveHandles(benchmark::State& state) {
  const Surface s = bumpy_torus(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(remove_handles(s, nullptr));
  state.counters["triangles"] = double(s.num_faces());
}

void BM_CutToDisk(benchmark::State& state) {
  const Surface s = prepare_surface(mesh_for(int(state.range(0))), nullptr);
  const auto comps = split_components(s);
  for (auto _ : state) benchmark::DoNotOptimize(cut_to_disk(comps[0], {.holes = HoleMode::kFill}, nullptr));
}

void BM_MapToSquare(benchmark::State& state) {
  const Surface s = prepare_surface(mesh_for(int(state.range(0))), nullptr);
  const Disk d = cut_to_disk(split_components(s)[0], {.holes = HoleMode::kFill}, nullptr);
  for (auto _ : state) benchmark::DoNotOptimize(map_to_square(d, {}, nullptr));
}

/// The multilevel map's coarse copy: the disk of range(0) triangles down to 30000 vertices (uniform targets).
void BM_CoarsenDisk(benchmark::State& state) {
  const Surface s = prepare_surface(mesh_for(int(state.range(0))), nullptr);
  const Disk d = cut_to_disk(split_components(s)[0], {.holes = HoleMode::kFill}, nullptr);
  const std::vector<double> target(d.mesh.num_faces(), 1.0);
  for (auto _ : state) benchmark::DoNotOptimize(coarsen_disk(d, target, 30000));
  state.counters["triangles"] = double(d.mesh.num_faces());
}
void BM_BakeTexture(benchmark::State& state) {
  const TexturedMesh& m = mesh_for(int(state.range(0)));
  const Surface s = prepare_surface(m, nullptr);
  const Disk d = cut_to_disk(split_components(s)[0], {.holes = HoleMode::kFill}, nullptr);
  const int size = int(state.range(1));
  SquareMapOptions mo;
  mo.rect_width = mo.rect_height = size;
  const auto uv = map_to_square(d, mo, nullptr);
  std::vector<BakeTriangle> tris;
  for (uint32_t f = 0; f < d.mesh.num_faces(); ++f) {
    if (d.mesh.face_parent[f] == kNone) continue;
    const uint32_t t = s.face_parent[d.mesh.face_parent[f]];
    BakeTriangle bt;
    bt.material = 0;
    for (int k = 0; k < 3; ++k) {
      const Vec2& p = uv[d.mesh.triangles[f][k]];
      bt.target_px[k] = Vec2(0.5 + p.x() * (size - 1), 0.5 + (1 - p.y()) * (size - 1));
      bt.source_uv[k] = m.corner_uv[3 * t + size_t(k)];
    }
    tris.push_back(bt);
  }
  const std::vector<Rect> rects{Rect{0, 0, 0, size, size}};
  for (auto _ : state) {
    std::vector<Image> images{Image(size, size)};
    bake_texture(m, tris, rects, images, nullptr);
    benchmark::DoNotOptimize(images);
  }
  state.counters["texels/s"] = benchmark::Counter(double(size) * size, benchmark::Counter::kIsIterationInvariantRate);
}

/// A scan's texture of side x side texels as its PNG file: square charts of smooth colour and noise on
/// black (about half the texels), encoded as scanners' exporters do (libspng's defaults: zlib level 6,
/// each row's best filter).
const std::vector<unsigned char>& scan_texture_png(int side) {
  static std::map<int, std::vector<unsigned char>> cache;
  auto [it, inserted] = cache.try_emplace(side);
  if (!inserted) return it->second;
  std::mt19937 rng(5);
  std::vector<unsigned char> rgb(size_t(side) * size_t(side) * 3, 0);
  const int chart = std::max(8, side / 16);
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      if ((x / chart + y / chart) % 2 == 1) continue;
      unsigned char* p = &rgb[(size_t(y) * size_t(side) + size_t(x)) * 3];
      for (int c = 0; c < 3; ++c) p[c] = static_cast<unsigned char>(60 + (x * (c + 1) + y * (3 - c)) % 120 + rng() % 24);
    }
  spng_ctx* ctx = spng_ctx_new(SPNG_CTX_ENCODER);
  spng_set_option(ctx, SPNG_ENCODE_TO_BUFFER, 1);
  spng_ihdr ihdr{};
  ihdr.width = ihdr.height = uint32_t(side);
  ihdr.bit_depth = 8;
  ihdr.color_type = SPNG_COLOR_TYPE_TRUECOLOR;
  spng_set_ihdr(ctx, &ihdr);
  spng_encode_image(ctx, rgb.data(), rgb.size(), SPNG_FMT_PNG, SPNG_ENCODE_FINALIZE);
  size_t length = 0;
  int error = 0;
  auto* buffer = static_cast<unsigned char*>(spng_get_png_buffer(ctx, &length, &error));
  it->second.assign(buffer, buffer + length);
  std::free(buffer);
  spng_ctx_free(ctx);
  return it->second;
}

/// Decoding a scan's RGB texture (argument 0: its side): `decode_image` (one pass: libdeflate's inflate,
/// then the rows unfiltered into the image) against libspng's streaming decode (argument 1: 0), which
/// it used before and still uses for other kinds of PNG.
void BM_DecodePng(benchmark::State& state) {
  const std::vector<unsigned char>& png = scan_texture_png(int(state.range(0)));
  for (auto _ : state) {
    if (state.range(1) == 1) {
      benchmark::DoNotOptimize(decode_image(png.data(), png.size(), "bench.png"));
      continue;
    }
    spng_ctx* ctx = spng_ctx_new(0);
    spng_set_png_buffer(ctx, png.data(), png.size());
    size_t size = 0;
    spng_decoded_image_size(ctx, SPNG_FMT_RGBA8, &size);
    Image image(int(state.range(0)), int(state.range(0)));
    spng_decode_image(ctx, image.pixels.data(), size, SPNG_FMT_RGBA8, SPNG_DECODE_TRNS);
    spng_ctx_free(ctx);
    benchmark::DoNotOptimize(image);
  }
}

/// The rate search's shrink of a baked atlas (argument: its side) to the eight scales its model reads
/// (kSteps 4 a halving, from 2^-1/4 down to 1/4): random texels, six of seven inside charts (bands 50
/// texels wide), as a bake between charts leaves them.
void BM_ShrinkAtlas(benchmark::State& state) {
  const int side = int(state.range(0));
  Image atlas(side, side);
  std::vector<uint8_t> inside(atlas.pixels.size());
  std::mt19937 rng(1);
  for (size_t i = 0; i < atlas.pixels.size(); ++i) {
    atlas.pixels[i] = {uint8_t(rng()), uint8_t(rng()), uint8_t(rng()), 255};
    inside[i] = (i / size_t(side) / 50 + i % size_t(side) / 50) % 7 != 0;
  }
  for (auto _ : state)
    for (int step = 1; step <= 8; ++step) {
      const int scaled = int(std::lround(side * std::pow(2.0, -step / 4.0)));
      benchmark::DoNotOptimize(shrink_image(atlas, inside, scaled, scaled));
    }
}

}  // namespace

BENCHMARK(BM_ReadObj)->Args({1000000, 0})->Args({1000000, 1})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PrepareSurface)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RemoveHandles)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CutToDisk)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MapToSquare)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CoarsenDisk)->Arg(200000)->Arg(1000000)->Arg(2000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BakeTexture)->Args({100000, 2048})->Args({100000, 4096})->Args({1000000, 8192})->Unit(benchmark::kMillisecond);

BENCHMARK(BM_DecodePng)->Args({4096, 0})->Args({4096, 1})->Args({8192, 0})->Args({8192, 1})->Unit(benchmark::kMillisecond);

BENCHMARK(BM_ShrinkAtlas)->Arg(3044)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
