// Reading Wavefront OBJ + MTL, with every texture image the materials name.
//
// tightex parses OBJ itself rather than through tinyobjloader: a pipeline that runs unattended over
// thousands of scans needs every malformed line refused with its file and line number, which
// tinyobjloader's loader does not give for bad indices or numbers.
#pragma once
#include <string>
#include <vector>

#include "core/mesh.hpp"
#include "tightex/io.hpp"

namespace tightex {

/// read_obj's stretch of the file parsed as one task: large enough that a stretch's own arrays cost
/// nothing against its parsing, small enough that a scan of a few MB uses every core.
constexpr size_t kObjChunkBytes = size_t(1) << 20;

/// read_obj with the file cut into stretches of about chunk_bytes (whole lines), parsed on every core.
/// The mesh, the stats and the error do not depend on chunk_bytes (tests compare 1 with the default).
TexturedMesh read_obj_in_chunks(const std::string& path, const ModelReadOptions& options, ModelReadStats* stats, size_t chunk_bytes);

}  // namespace tightex
