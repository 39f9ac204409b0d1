// A catalogue of hostile and awkward inputs, generated here, each run through the tightex command:
// bad input (and an output folder that cannot be created) must exit 1 (never a signal) with one line that
// names the file, and leave no model behind; awkward but valid input (quads, CRLF, 16-bit, grey and alpha
// textures, spaces in folder and file names, ...) must succeed with no lost and no flipped triangle.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "command_line.hpp"
#include "gltf_builder.hpp"

#include "core/error.hpp"
#include "io/image_io.hpp"
#include "io/obj_reader.hpp"
#include "io/output_files.hpp"
#include "report/metrics.hpp"

namespace fs = std::filesystem;
using namespace tightex;

namespace {

struct Case {
  std::string name;
  std::string obj;            // OBJ text; "mtllib m.mtl" refers to the MTL below
  std::string mtl;            // empty: no MTL file written
  bool texture = true;        // write t.png (a small gradient)
  std::string texture_bytes;  // non-empty: write these bytes as t.png instead (a corrupt or unusual texture)
  bool valid = false;
  std::string folder;  // the model's folder inside the test's own (may contain spaces)
  std::string obj_name = "in.obj", mtl_name = "m.mtl", texture_name = "t.png";
  bool out_under_file = false;  // -o names a path below a regular file: nothing can be written there
  /// Writes what lies outside the model's folder (or links in it), given the test's folder and the model's.
  std::function<void(const fs::path& dir, const fs::path& model)> setup;
  bool allow_outside = false;  // run with --allow-outside-files
  std::string error_mentions;  // a refusal's message must contain this
};

// A 16x16 gradient PNG, the catalogue's texture.
void write_gradient(const fs::path& path, uint8_t blue = 128) {
  Image img(16, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) img.at(x, y) = {uint8_t(x * 16), uint8_t(y * 16), blue, 255};
  save_image(path.string(), img, ImageFormat::kPng);
}

// `text` with every "@DIR@" replaced by `dir`.
std::string with_dir(std::string text, const fs::path& dir) {
  for (size_t p = text.find("@DIR@"); p != std::string::npos; p = text.find("@DIR@", p)) text.replace(p, 5, dir.string());
  return text;
}

// An 8x8 PNG of the fuzz seed corpus (fuzz/corpus/fuzz_image: one file per colour type and bit depth).
std::string seed_png(const std::string& name) {
  std::ifstream in(fs::path(TIGHTEX_FUZZ_CORPUS) / "fuzz_image" / name, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  if (bytes.empty()) throw std::runtime_error("missing seed image " + name);
  return bytes;
}

// A 4x4 grid of quads with UVs, as OBJ text (positions, vt, faces). `face_prefix` lets a case insert
// statements before the faces.
std::string grid_obj(const std::string& header = "mtllib m.mtl\nusemtl a\n", bool quads = false, bool crlf = false) {
  std::string s = header;
  const int n = 5;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) s += "v " + std::to_string(i) + " " + std::to_string(j) + " 0\n";
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) s += "vt " + std::to_string(i / 4.0 * 0.5) + " " + std::to_string(j / 4.0 * 0.5) + "\n";
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i + 1, b = a + 1, c = a + n + 1, d = a + n;
      auto corner = [](int v) { return std::to_string(v) + "/" + std::to_string(v); };
      if (quads)
        s += "f " + corner(a) + " " + corner(b) + " " + corner(c) + " " + corner(d) + "\n";
      else
        s += "f " + corner(a) + " " + corner(b) + " " + corner(c) + "\nf " + corner(a) + " " + corner(c) + " " + corner(d) + "\n";
    }
  if (crlf) {
    std::string t;
    for (char ch : s) {
      if (ch == '\n') t += '\r';
      t += ch;
    }
    return t;
  }
  return s;
}

const std::string kMtl = "newmtl a\nKd 1 1 1\nmap_Kd t.png\n";

// References out of the model's folder ("scan", inside the test's folder, where the files named lie):
// refused with one line naming the way out unless --allow-outside-files; one found inside the folder by
// a tail of the path as written (a Windows exporter's absolute path) is read. @DIR@: the test's folder.
void add_outside_cases(std::vector<Case>& c) {
  auto outside = [&c](std::string name, std::string obj, std::string mtl, bool valid, auto setup, bool allow = false) {
    Case k{std::move(name), std::move(obj), std::move(mtl), false, "", valid, "scan"};
    k.setup = setup;
    k.allow_outside = allow;
    if (!valid) k.error_mentions = "--allow-outside-files";
    c.push_back(k);
  };
  auto secret = [](const fs::path& dir, const fs::path&) { write_gradient(dir / "secret.png", 7); };
  for (bool allow : {false, true}) {
    const std::string v = allow ? "valid_allowed_" : "";
    outside(v + "map_kd_leads_out", grid_obj(), "newmtl a\nmap_Kd ../secret.png\n", allow, secret, allow);
    outside(v + "map_kd_absolute", grid_obj(), "newmtl a\nmap_Kd @DIR@/secret.png\n", allow, secret, allow);
    outside(v + "map_kd_file_uri", grid_obj(), "newmtl a\nmap_Kd file://@DIR@/secret.png\n", allow, secret, allow);
    outside(
        v + "mtllib_leads_out", grid_obj("mtllib ../m.mtl\nusemtl a\n"), "", allow,
        [](const fs::path& dir, const fs::path&) {
          std::ofstream(dir / "m.mtl") << kMtl;
          write_gradient(dir / "t.png");
        },
        allow);
    outside(
        v + "texture_is_a_symlink_out", grid_obj(), kMtl, allow,
        [](const fs::path& dir, const fs::path& model) {
          write_gradient(dir / "secret.png", 7);
          fs::create_symlink("../secret.png", model / "t.png");
        },
        allow);
    outside(
        v + "folder_is_a_symlink_out", grid_obj(), "newmtl a\nmap_Kd tex/t.png\n", allow,
        [](const fs::path& dir, const fs::path& model) {
          fs::create_directories(dir / "elsewhere");
          write_gradient(dir / "elsewhere" / "t.png", 7);
          fs::create_directory_symlink(dir / "elsewhere", model / "tex");
        },
        allow);
  }
  outside("map_bump_leads_out", grid_obj(), kMtl + "map_Bump ../secret.png\n", false, [secret](const fs::path& dir, const fs::path& model) {
    secret(dir, model);
    write_gradient(model / "t.png");
  });
  // Found inside the folder by a tail of the path as written, though a file of that path exists outside.
  outside("valid_windows_absolute_path_found_inside", grid_obj(), "newmtl a\nmap_Kd C:\\Users\\me\\scan\\t.png\n", true,
          [](const fs::path&, const fs::path& model) { write_gradient(model / "t.png"); });
  outside("valid_leading_out_but_found_inside", grid_obj(), "newmtl a\nmap_Kd ../textures/t.png\n", true,
          [](const fs::path& dir, const fs::path& model) {
            fs::create_directories(model / "textures");
            write_gradient(model / "textures" / "t.png");
            fs::create_directories(dir / "textures");
            write_gradient(dir / "textures" / "t.png", 7);
          });
}

std::vector<Case> catalogue() {
  std::vector<Case> c;
  c.push_back({"valid_grid", grid_obj(), kMtl, true, "", true});
  c.push_back({"valid_quads", grid_obj("mtllib m.mtl\nusemtl a\n", true), kMtl, true, "", true});
  c.push_back({"valid_crlf", grid_obj("mtllib m.mtl\nusemtl a\n", false, true), kMtl, true, "", true});
  c.push_back({"valid_map_options", grid_obj(), "newmtl a\nmap_Kd -s 2 2 1 -o 0.1 0 0 -bm 1 t.png\n", true, "", true});
  c.push_back({"valid_uv_outside_unit_square",
               [] {
                 std::string s = grid_obj();
                 for (size_t p = s.find("vt "); p != std::string::npos; p = s.find("vt ", p + 1)) s.replace(p, 3, "vt 3");
                 return s;
               }(),
               kMtl, true, "", true});
  // No material, no texture, no vertex colours: nothing to bake, refused.
  c.push_back({"no_material_nothing_to_bake", grid_obj(""), "", false, "", false});
  for (const char* png : {"rgb16", "rgba16", "grey16", "grey8", "greyalpha8", "rgba8"})
    c.push_back({std::string("valid_texture_") + png, grid_obj(), kMtl, true, seed_png(std::string(png) + ".png"), true});
  c.push_back({"valid_spaces_in_names", grid_obj("mtllib my materials.mtl\nusemtl a\n"), "newmtl a\nmap_Kd my texture.png\n", true, "",
               true, "my scans", "my model.obj", "my materials.mtl", "my texture.png"});
  c.push_back({"empty_file", "", "", false, "", false});
  c.push_back({"only_comments", "# nothing\n\n", "", false, "", false});
  c.push_back({"no_texture_coordinates", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "", false, "", false});
  c.push_back({"index_out_of_range", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 4/1\n", "", false, "", false});
  c.push_back({"zero_index", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 0/1 2/1 3/1\n", "", false, "", false});
  c.push_back({"negative_index_too_far", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf -1/1 -2/1 -9/1\n", "", false, "", false});
  c.push_back({"nan_coordinate", "v 0 0 nan\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n", "", false, "", false});
  c.push_back({"inf_coordinate", "v 0 0 inf\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n", "", false, "", false});
  c.push_back({"overflowing_coordinate", "v 0 0 1e300\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n", "", false, "", false});
  c.push_back({"malformed_number", "v 0 0 abc\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n", "", false, "", false});
  c.push_back({"two_corner_face", "v 0 0 0\nv 1 0 0\nvt 0 0\nf 1/1 2/1\n", "", false, "", false});
  c.push_back({"only_degenerate_triangles", "v 0 0 0\nv 1 0 0\nv 2 0 0\nvt 0 0\nf 1/1 2/1 3/1\nf 1/1 1/1 2/1\n", "", false, "", false});
  c.push_back({"missing_mtl", grid_obj(), "", false, "", false});
  c.push_back({"missing_material", grid_obj("mtllib m.mtl\nusemtl nope\n"), kMtl, true, "", false});
  c.push_back({"missing_texture", grid_obj(), kMtl, false, "", false});
  c.push_back({"corrupt_texture", grid_obj(), kMtl, false, "\x89PNG\r\n\x1a\n garbage garbage", false});
  // A 68-byte PNG whose header declares 200000 x 200000 pixels: refused from its header, before anything
  // is sized by it.
  static const char kHugePng[] =
      "\x89\x50\x4e\x47\x0d\x0a\x1a\x0a\x00\x00\x00\x0d\x49\x48\x44\x52\x00\x03\x0d\x40\x00\x03\x0d\x40\x08\x02\x00\x00\x00\x76\x59\x1f\x5d"
      "\x00\x00\x00\x0b\x49\x44\x41\x54\x78\x9c\x63\x60\x80\x01\x00\x00\x0a\x00\x01\x7f\x80\x74\x5e\x00\x00\x00\x00\x49\x45\x4e\x44\xae\x42"
      "\x60\x82";
  c.push_back({"texture_header_declares_200000_squared", grid_obj(), kMtl, false, std::string(kHugePng, sizeof kHugePng - 1), false});
  c.push_back({"mtllib_is_a_device", grid_obj("mtllib /dev/zero\nusemtl a\n"), "", false, "", false});
  c.push_back({"texture_is_a_device", grid_obj(), "newmtl a\nmap_Kd /dev/zero\n", false, "", false});
  c.push_back({"binary_garbage", std::string("\x00\x01\x02\xff\xfe", 5) + "v 1 2", "", false, "", false});
  {
    Case k{"output_under_a_file", grid_obj(), kMtl, true, "", false};
    k.out_under_file = true;
    c.push_back(k);
  }
  add_outside_cases(c);
  return c;
}

class HostileCli : public ::testing::TestWithParam<Case> {};

TEST_P(HostileCli, RefusedCleanlyOrProcessedCorrectly) {
  const Case& k = GetParam();
  const fs::path dir = fs::temp_directory_path() / ("tightex_hostile_" + k.name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const fs::path model = dir / k.folder;
  fs::create_directories(model);
  std::ofstream(model / k.obj_name, std::ios::binary) << with_dir(k.obj, dir);
  if (!k.mtl.empty()) std::ofstream(model / k.mtl_name, std::ios::binary) << with_dir(k.mtl, dir);
  if (!k.texture_bytes.empty()) {
    std::ofstream(model / k.texture_name, std::ios::binary) << k.texture_bytes;
  } else if (k.texture) {
    write_gradient(model / k.texture_name);
  }
  if (k.setup) k.setup(dir, model);
  if (k.out_under_file) std::ofstream(dir / "blocker") << "a file, not a folder";
  const fs::path out = k.out_under_file ? dir / "blocker" / "out" : dir / (k.folder.empty() ? "out" : k.folder + " out");
  const std::string cmd = std::string(TIGHTEX_CLI) + " '" + (model / k.obj_name).string() + "' -o '" + out.string() +
                          "' --size 64 --quiet" + (k.allow_outside ? " --allow-outside-files" : "") + " 2> '" +
                          (dir / "stderr.txt").string() + "'";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status)) << "killed by a signal";
  std::ifstream err_file(dir / "stderr.txt");
  const std::string err((std::istreambuf_iterator<char>(err_file)), {});
  if (k.valid) {
    ASSERT_EQ(WEXITSTATUS(status), 0) << err;
    ModelReadOptions read_options;
    read_options.allow_outside_files = k.allow_outside;
    const TexturedMesh in = read_obj((model / k.obj_name).string(), read_options);
    const TexturedMesh result = read_obj((out / k.obj_name).string());
    const Metrics m = measure(in, result, 20000);
    EXPECT_EQ(m.lost_triangles, 0u);
    EXPECT_EQ(m.flipped, 0u);
  } else {
    EXPECT_EQ(WEXITSTATUS(status), 1) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;  // one line
    EXPECT_NE(err.find("error"), std::string::npos) << err;
    EXPECT_TRUE(err.find("in.obj") != std::string::npos || err.find("m.mtl") != std::string::npos ||
                err.find("t.png") != std::string::npos || (k.out_under_file && err.find("blocker/out") != std::string::npos))
        << "the message names no file: " << err;
    EXPECT_FALSE(fs::exists(out / k.obj_name)) << "a failed run left a model behind";
    if (!k.error_mentions.empty()) EXPECT_NE(err.find(k.error_mentions), std::string::npos) << err;
  }
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Catalogue, HostileCli, ::testing::ValuesIn(catalogue()),
                         [](const ::testing::TestParamInfo<Case>& info) { return info.param.name; });

}  // namespace

namespace {

// The outputs are named after the input: -o naming the input's own folder would replace the input
// model. Refused with one line and exit 1, the input byte for byte as it was.
TEST(HostileCliOutput, OutputIntoTheInputsOwnFolderIsRefusedAndTheInputUntouched) {
  const fs::path dir = fs::temp_directory_path() / ("tightex_samedir_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string obj = grid_obj();
  std::ofstream(dir / "in.obj", std::ios::binary) << obj;
  std::ofstream(dir / "m.mtl", std::ios::binary) << kMtl;
  Image img(16, 16, Rgba8{10, 20, 30, 255});
  save_image((dir / "t.png").string(), img, ImageFormat::kPng);
  for (const std::string& out : {dir.string(), dir.string() + "/.", dir.string() + "/../" + dir.filename().string()}) {
    SCOPED_TRACE(out);
    const std::string cmd = std::string(TIGHTEX_CLI) + " '" + (dir / "in.obj").string() + "' -o '" + out + "' --size 64 --quiet 2> '" +
                            (dir / "stderr.txt").string() + "'";
    const int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 1);
    std::ifstream err_file(dir / "stderr.txt");
    const std::string err((std::istreambuf_iterator<char>(err_file)), {});
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_NE(err.find("in.obj"), std::string::npos) << err;
    std::ifstream in(dir / "in.obj", std::ios::binary);
    EXPECT_EQ(std::string((std::istreambuf_iterator<char>(in)), {}), obj);
    EXPECT_FALSE(fs::exists(dir / "report.json"));
    EXPECT_FALSE(fs::exists(dir / "in_tightex.png"));
  }
  fs::remove_all(dir);
}

// The command restarts itself with glibc's huge-page tunable unless GLIBC_TUNABLES names it or the
// dynamic loader was named to start it: the same texture whichever way it ran.
TEST(HostileCliOutput, TheSameTextureWhicheverWayTheCommandStarts) {
  const fs::path dir = fs::temp_directory_path() / ("tightex_starts_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "in.obj", std::ios::binary) << grid_obj();
  std::ofstream(dir / "m.mtl", std::ios::binary) << kMtl;
  Image img(16, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) img.at(x, y) = {uint8_t(x * 16), uint8_t(y * 16), 128, 255};
  save_image((dir / "t.png").string(), img, ImageFormat::kPng);
  std::vector<std::string> starts = {"", "GLIBC_TUNABLES=glibc.malloc.hugetlb=0 ", "GLIBC_TUNABLES=glibc.malloc.check=0 "};
  const fs::path loader = "/lib64/ld-linux-x86-64.so.2";
  // Started through the loader, LeakSanitizer (the sanitizer build) reports the loader's own
  // bookkeeping (dl-open's global scope) as a leak: not tightex's, so not checked there.
  if (fs::exists(loader)) starts.push_back("ASAN_OPTIONS=\"${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0\" " + loader.string() + " ");
  std::vector<std::string> textures;
  for (size_t i = 0; i < starts.size(); ++i) {
    SCOPED_TRACE(starts[i]);
    const fs::path out = dir / ("out" + std::to_string(i));
    const std::string cmd = starts[i] + TIGHTEX_CLI + " '" + (dir / "in.obj").string() + "' -o '" + out.string() + "' --size 64 --quiet";
    const int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status));
    ASSERT_EQ(WEXITSTATUS(status), 0);
    std::ifstream png(out / "in_tightex.png", std::ios::binary);
    textures.push_back(std::string((std::istreambuf_iterator<char>(png)), {}));
    EXPECT_FALSE(textures.back().empty());
    EXPECT_EQ(textures.back(), textures.front());
  }
  fs::remove_all(dir);
}

TEST(HostileCliOutput, AnOutputFolderThatCannotBeCreatedIsRefusedBeforeAnyWorkAndNothingIsCreated) {
  const fs::path dir = fs::temp_directory_path() / ("tightex_outcheck_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "blocker") << "a file, not a folder";
  EXPECT_THROW(check_output_folder((dir / "blocker").string()), InputError);
  EXPECT_THROW(check_output_folder((dir / "blocker" / "out" / "deeper").string()), InputError);
  EXPECT_NO_THROW(check_output_folder(dir.string()));
  EXPECT_NO_THROW(check_output_folder((dir / "new" / "nested").string()));
  EXPECT_FALSE(fs::exists(dir / "new"));  // checked, not created: a failed run leaves no folder behind
  fs::remove_all(dir);
}

}  // namespace

namespace {

// glTF and PLY models whose buffer, image or TextureFile leads out of the model's folder: refused with
// one line naming the model, the element and the way out, nothing written; with --allow-outside-files
// read as before. The test's folder holds the model's folder "scan" and the files named outside it.
struct Outside {
  fs::path dir, model, out;
  explicit Outside(const std::string& name)
      : dir(tightex::testing::scratch_folder("outside_" + name)), model(dir / "scan"), out(dir / "out") {
    fs::create_directories(model);
  }
  // Runs the command on scan/FILE; its exit status, stderr in `err`.
  int run(const std::string& file, const std::string& flags, std::string& err) const {
    const int status = tightex::testing::run_tightex("'" + (model / file).string() + "' -o '" + out.string() + "' --size 64 --quiet " +
                                                     flags + " 2> '" + (dir / "stderr.txt").string() + "'");
    err = tightex::testing::read_whole(dir / "stderr.txt");
    return status;
  }
};

// The glTF grid with its buffer and base colour image named by these URIs (@DIR@: the test's folder).
std::string grid_gltf_naming(const std::string& buffer_uri, const std::string& image_uri, const fs::path& dir) {
  tightex::testing::GridGltf g = tightex::testing::grid_gltf();
  g.doc["buffers"][0]["uri"] = with_dir(buffer_uri, dir);
  g.doc["images"][0] = {{"uri", with_dir(image_uri, dir)}};
  return g.doc.dump();
}

TEST(HostileCliReferences, GltfBuffersAndImagesOutOfTheFolderAreRefusedUnlessAllowed) {
  const std::string bin = tightex::testing::grid_gltf().bin;
  struct Ref {
    std::string buffer, image, element;
  };
  const std::vector<Ref> refs = {{"../secret.bin", "t.png", "buffers[0]"},
                                 {"g.bin", "../secret.png", "images[0]"},
                                 {"@DIR@/secret.bin", "t.png", "buffers[0]"},
                                 {"g.bin", "@DIR@/secret.png", "images[0]"},
                                 {"file://@DIR@/secret.bin", "t.png", "buffers[0]"},
                                 {"g.bin", "file://@DIR@/secret.png", "images[0]"},
                                 {"g.bin", "link.png", "images[0]"},
                                 {"sub/g.bin", "t.png", "buffers[0]"}};
  for (const Ref& ref : refs) {
    SCOPED_TRACE(ref.buffer + " " + ref.image);
    Outside o("gltf");
    tightex::testing::write_whole(o.model / "g.bin", bin);
    tightex::testing::write_whole(o.dir / "secret.bin", bin);
    write_gradient(o.model / "t.png");
    write_gradient(o.dir / "secret.png", 7);
    fs::create_symlink("../secret.png", o.model / "link.png");
    fs::create_directory_symlink(o.dir, o.model / "sub");  // scan/sub/g.bin is the test folder's g.bin
    tightex::testing::write_whole(o.dir / "g.bin", bin);
    tightex::testing::write_whole(o.model / "m.gltf", grid_gltf_naming(ref.buffer, ref.image, o.dir));
    std::string err;
    EXPECT_EQ(o.run("m.gltf", "", err), 1) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_NE(err.find("m.gltf: " + ref.element), std::string::npos) << err;
    EXPECT_NE(err.find("--allow-outside-files"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(o.out / "m.gltf")) << "a refused model left a model behind";
    EXPECT_EQ(o.run("m.gltf", "--allow-outside-files", err), 0) << err;
    EXPECT_TRUE(fs::exists(o.out / "m.gltf")) << err;
  }
}

// The OBJ grid as an ascii PLY whose texture is named by `texture`.
std::string grid_ply(const std::string& texture) {
  std::vector<std::string> v, vt, f;
  std::istringstream obj(grid_obj(""));
  for (std::string line; std::getline(obj, line);) (line[0] == 'f' ? f : line[1] == 't' ? vt : v).push_back(line);
  std::string s = "ply\nformat ascii 1.0\ncomment TextureFile " + texture + "\nelement vertex " + std::to_string(v.size()) +
                  "\nproperty float x\nproperty float y\nproperty float z\nproperty float s\nproperty float t\nelement face " +
                  std::to_string(f.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  for (size_t i = 0; i < v.size(); ++i) s += v[i].substr(2) + " " + vt[i].substr(3) + "\n";
  for (const std::string& face : f) {
    std::istringstream corners(face.substr(2));
    s += "3";
    for (std::string c; corners >> c;) s.append(" ").append(std::to_string(std::stoi(c) - 1));
    s += "\n";
  }
  return s;
}

TEST(HostileCliReferences, PlyTextureFilesOutOfTheFolderAreRefusedUnlessAllowed) {
  for (const std::string texture : {"../secret.png", "@DIR@/secret.png", "file://@DIR@/secret.png"}) {
    SCOPED_TRACE(texture);
    Outside o("ply");
    write_gradient(o.dir / "secret.png", 7);
    tightex::testing::write_whole(o.model / "m.ply", grid_ply(with_dir(texture, o.dir)));
    std::string err;
    EXPECT_EQ(o.run("m.ply", "", err), 1) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_NE(err.find("m.ply:3: texture"), std::string::npos) << err;
    EXPECT_NE(err.find("--allow-outside-files"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(o.out / "m.ply"));
    EXPECT_EQ(o.run("m.ply", "--allow-outside-files", err), 0) << err;
    EXPECT_TRUE(fs::exists(o.out / "m.ply")) << err;
  }
}

// Every writer renames only into the folder it was given: a name that is not one plain file name is
// refused before anything is written.
TEST(HostileCliReferences, WritersRenameOnlyIntoTheirFolder) {
  const fs::path dir = tightex::testing::scratch_folder("writers_folder");
  for (const std::string name : {"../x.obj", "/tmp/x.obj", "a/x.obj", "..", "."}) {
    SCOPED_TRACE(name);
    bool written = false;
    EXPECT_THROW(write_files_atomically((dir / "out").string(), {{name, [&](const fs::path&) { written = true; }}}), InputError);
    EXPECT_FALSE(written);
  }
  EXPECT_NO_THROW(check_inside_output((dir / "out").string(), "model.obj"));
  EXPECT_FALSE(fs::exists(dir / "x.obj"));
}

}  // namespace
