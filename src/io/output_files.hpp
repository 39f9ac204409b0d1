// What the model writers (OBJ, PLY) share: a set of files that appears in its folder all together or
// not at all, a file written from a string, and the names the texture files take.
#pragma once
#include <array>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "tightex/io.hpp"

namespace tightex {

/// One file of a set: its name inside the folder, and what writes its content to the path it is given
/// (a temporary one).
struct OutputFile {
  std::string name;
  std::function<void(const std::filesystem::path&)> write;
};

/// Creates `folder` if needed, writes every file under a hidden temporary name beside its final one
/// (".NAME.tmpPID", so a rename never crosses file systems and a reader never sees half a file), in
/// parallel (each `write` is called once, from any thread), and only once all are complete renames them
/// into place in order (the model last, so a model file that exists is complete with its textures). On any failure the temporary files are
/// removed and the exception is rethrown, so a failed run leaves no model behind. Each name is checked
/// first (check_inside_output).
/// Throws InputError naming the folder or file that cannot be created, written or renamed.
void write_files_atomically(const std::string& folder, const std::vector<OutputFile>& files);

/// Refuses (InputError naming the folder and the name) to write `name` into `folder` unless it is one
/// plain file name, so that every writer renames only into the folder it was given.
void check_inside_output(const std::string& folder, const std::string& name);

/// Refuses, before any work, an output folder that write_files_atomically could not create or write
/// into: a path that exists and is not a folder, or whose nearest existing ancestor is not a folder this
/// process may write into. Creates nothing. Throws InputError naming the folder and why.
void check_output_folder(const std::string& folder);

/// Writes `bytes` to `path` as they are. Throws InputError naming the path (and the system's reason).
void write_whole_file(const std::filesystem::path& path, const std::string& bytes);

/// Writes `pieces` to `path` one after the other (a text made in pieces on every core, never joined
/// in memory). Throws InputError naming the path (and the system's reason).
void write_whole_file(const std::filesystem::path& path, std::span<const std::string> pieces);

/// The name a texture is written under: Texture::path (the file stem inside the output folder) and the
/// extension of `format` (.png or .jpg).
std::string texture_file_name(const Texture& texture, ImageFormat format);

/// Rounds `mesh`'s texture coordinates to what a model file of `format` stores and its reader reads
/// back (glTF: the float of 1 - v; PLY: floats; OBJ: shortest round-trip text, unchanged), on every
/// triangle whose material has no texture scale or offset (those store the transformed coordinate).
/// Measured after it, a map's figures (flipped, degenerate, coverage) are those of the written file.
void round_uvs_as_stored(TexturedMesh& mesh, ModelFormat format);

/// Per texture of a model, its file's bytes where the caller has encoded it already as the writer's
/// encoding says (rate control measured them); written as they are. An empty entry, or a missing one,
/// is encoded when written.
using EncodedImages = std::vector<std::string>;

/// One OutputFile per texture of `mesh`, in its order, named by texture_file_name and writing the image
/// as `encoding` says (or `encoded`'s bytes). The writers refer to `mesh` and `encoded`, which must
/// outlive them.
/// Throws InputError for an encoding save_image refuses (check_image_encoding), before anything is written.
std::vector<OutputFile> texture_output_files(const TexturedMesh& mesh, const ImageEncoding& encoding, const EncodedImages& encoded = {});

/// write_obj, write_ply and write_gltf (tightex/io.hpp) with the images that are encoded already.
std::vector<std::string> write_obj(const TexturedMesh& mesh, const std::string& outdir, const std::string& name,
                                   const ImageEncoding& encoding, const EncodedImages& encoded);
std::vector<std::string> write_ply(const TexturedMesh& mesh, const std::string& outdir, const std::string& name,
                                   const ImageEncoding& encoding, const EncodedImages& encoded);
std::vector<std::string> write_gltf(const TexturedMesh& mesh, const std::string& outdir, const std::string& name,
                                    const ImageEncoding& encoding, GltfContainer container, const EncodedImages& encoded);

/// What a writer leaves out of a model's materials: one sentence per map slot that some material of
/// `mesh` binds and `written` says the format does not carry ("the occlusion map of material \"m\" is
/// not bound in the output (REASON)"; "of N materials" when more than one), in slot order.
/// Throws: nothing but std::bad_alloc.
std::vector<std::string> unbound_maps(const TexturedMesh& mesh, const std::function<bool(const Material&, MaterialSlot)>& written,
                                      const std::string& reason);

}  // namespace tightex
