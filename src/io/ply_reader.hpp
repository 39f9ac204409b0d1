// Reading PLY (read_ply, tightex/io.hpp): the block size of its ascii elements, for tests.
#pragma once
#include <cstdint>
#include <string>

#include "tightex/io.hpp"

namespace tightex {

/// read_ply's ascii vertex and face elements of at least two blocks are read in blocks of this many
/// entries (lines), each on any core; a smaller element is read in one pass.
constexpr uint64_t kPlyBlockEntries = 16384;

/// read_ply with blocks of `block_entries` entries (at least 1). The mesh, the stats and the error do
/// not depend on block_entries (tests compare small blocks, the default and one pass).
TexturedMesh read_ply_in_blocks(const std::string& path, const ModelReadOptions& options, ModelReadStats* stats, uint64_t block_entries);

}  // namespace tightex
