#include "io/output_files.hpp"

#include <tbb/parallel_for.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <utility>

#include "core/error.hpp"
#include "io/image_io.hpp"

namespace tightex {

namespace fs = std::filesystem;

void check_inside_output(const std::string& folder, const std::string& name) {
  // One plain file name: nothing a model names ("../x", "/x", "a/b") can place a file elsewhere. (A
  // symbolic link already at that name is replaced by the rename, not written through.)
  const fs::path p(name);
  if (name.empty() || name == "." || name == ".." || p.has_root_path() || p.has_parent_path())
    fail_input("{}: refusing to write '{}': not one file name inside the output folder", folder, name);
}

void write_files_atomically(const std::string& folder, const std::vector<OutputFile>& files) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (!fs::is_directory(folder)) fail_input("{}: cannot create output directory", folder);
  const std::string tag = fmt::format(".tmp{}", ::getpid());
  std::vector<std::pair<fs::path, fs::path>> pending;  // temporary -> final, in rename order
  for (const OutputFile& file : files) {
    check_inside_output(folder, file.name);
    pending.push_back({fs::path(folder) / ("." + file.name + tag), fs::path(folder) / file.name});
  }
  try {
    // The files are independent (a model and its texture pages): written in parallel. A failure
    // anywhere is rethrown here once every write has stopped.
    tbb::parallel_for(size_t(0), files.size(), [&](size_t i) { files[i].write(pending[i].first); });
    for (auto& [tmp, final_path] : pending) {
      fs::rename(tmp, final_path, ec);
      if (ec) fail_input("{}: cannot rename into place ({})", final_path.string(), ec.message());
    }
  } catch (...) {
    for (auto& [tmp, final_path] : pending) fs::remove(tmp, ec);
    throw;
  }
}

void check_output_folder(const std::string& folder) {
  std::error_code ec;
  fs::path existing = fs::absolute(fs::path(folder), ec);
  if (ec) fail_input("{}: cannot create output directory ({})", folder, ec.message());
  while (!fs::exists(existing, ec) && existing.has_parent_path() && existing != existing.parent_path()) existing = existing.parent_path();
  if (!fs::is_directory(existing, ec)) fail_input("{}: cannot create output directory ({} is not a directory)", folder, existing.string());
  if (::access(existing.c_str(), W_OK | X_OK) != 0)
    fail_input("{}: cannot create output directory ({}: {})", folder, existing.string(), std::strerror(errno));
}

void write_whole_file(const fs::path& path, const std::string& bytes) { write_whole_file(path, std::span<const std::string>(&bytes, 1)); }

void write_whole_file(const fs::path& path, std::span<const std::string> pieces) {
  std::ofstream f(path, std::ios::binary);
  if (!f) fail_input("{}: cannot write ({})", path.string(), std::strerror(errno));
  for (const std::string& bytes : pieces) f.write(bytes.data(), std::streamsize(bytes.size()));
  f.close();
  if (!f) fail_input("{}: write failed ({})", path.string(), std::strerror(errno));
}

std::string texture_file_name(const Texture& texture, ImageFormat format) { return texture.path + image_extension(format); }

void round_uvs_as_stored(TexturedMesh& mesh, ModelFormat format) {
  if (format == ModelFormat::kObj) return;
  const bool gltf = format == ModelFormat::kGltf || format == ModelFormat::kGlb;
  for (size_t t = 0; t < mesh.num_triangles(); ++t) {
    const int32_t m = mesh.face_material[t];
    if (m >= 0) {
      const Material& mat = mesh.materials[size_t(m)];
      if (mat.uv_scale[0] != 1 || mat.uv_scale[1] != 1 || mat.uv_offset[0] != 0 || mat.uv_offset[1] != 0) continue;
    }
    for (int c = 0; c < 3; ++c) {
      Vec2& uv = mesh.corner_uv[3 * t + size_t(c)];
      const float u = float(uv.x()), v = float(gltf ? 1.0 - uv.y() : uv.y());
      uv = Vec2(double(u), gltf ? 1.0 - double(v) : double(v));
    }
  }
}

std::vector<OutputFile> texture_output_files(const TexturedMesh& mesh, const ImageEncoding& encoding, const EncodedImages& encoded) {
  std::vector<OutputFile> files;
  for (size_t i = 0; i < mesh.textures.size(); ++i) {
    const Texture& tex = mesh.textures[i];
    const ImageEncoding own = encoding.of_texture(i);
    const std::string name = texture_file_name(tex, own.format);
    check_image_encoding(own, name);
    if (i < encoded.size() && !encoded[i].empty())
      files.push_back({name, [bytes = &encoded[i]](const fs::path& tmp) { write_whole_file(tmp, *bytes); }});
    else
      files.push_back({name, [&tex, own](const fs::path& tmp) { save_image(tmp.string(), tex.image, own); }});
  }
  return files;
}

std::vector<std::string> unbound_maps(const TexturedMesh& mesh, const std::function<bool(const Material&, MaterialSlot)>& written,
                                      const std::string& reason) {
  std::vector<std::string> lines;
  for (size_t s = 0; s < kMaterialSlots; ++s) {
    std::vector<const Material*> dropped;
    for (const Material& m : mesh.materials)
      if (m.maps[s] >= 0 && !written(m, MaterialSlot(s))) dropped.push_back(&m);
    if (dropped.empty()) continue;
    const std::string of =
        dropped.size() == 1 ? fmt::format("material \"{}\"", dropped[0]->name) : fmt::format("{} materials", dropped.size());
    lines.push_back(fmt::format("the {} map of {} is not bound in the output ({})", material_slot_name(MaterialSlot(s)), of, reason));
  }
  return lines;
}

}  // namespace tightex
