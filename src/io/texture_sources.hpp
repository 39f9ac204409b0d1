// What a model's texture images are on disk: their encoded bytes and codec, for the report's bytes and
// for an output that follows the input's codec.
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include "tightex/io.hpp"
#include "tightex/mesh.hpp"

namespace tightex {

/// One input texture as stored: its encoded bytes (its file's size, or a glTF image's bytes) and its
/// codec (nullopt for one tightex does not write, or one made from vertex colours: 0 bytes).
struct TextureSource {
  uint64_t bytes = 0;
  std::optional<ImageFormat> format;
};

/// Per texture of `mesh` (as a reader made it), its source.
std::vector<TextureSource> texture_sources(const TexturedMesh& mesh);

/// The codec of the images a model's materials bind as their base colour, where they all share one
/// (JPEG, WebP or PNG); nullopt where they differ, none is bound, or one is made from vertex colours.
std::optional<ImageFormat> base_colour_format(const TexturedMesh& mesh, const std::vector<TextureSource>& sources);

/// The same for the images a model's materials bind to `slot`.
std::optional<ImageFormat> material_map_format(const TexturedMesh& mesh, const std::vector<TextureSource>& sources, MaterialSlot slot);

}  // namespace tightex
