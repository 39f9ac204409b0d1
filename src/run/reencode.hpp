// What tightex saves: the input's own images re-encoded in the output's codec, without repacking (what
// gltf-transform or gltfpack would do), at the surface PSNR tightex's written images reach.
#pragma once
#include <cstdint>
#include <nlohmann/json.hpp>

#include "tightex/io.hpp"
#include "tightex/mesh.hpp"

namespace tightex {

/// The re-encode of `input` (its textures as loaded) at `psnr_db`. `quality` is the lowest whose
/// written images reach it (101 where even 100 does not), with their `bytes` and `reached_psnr_db`;
/// `bytes_at_psnr` the bytes interpolated (log bytes, linear in PSNR) between it and the quality below
/// where that was measured, else `bytes`. `probes`: every quality measured, with its bytes and PSNR.
struct ReencodeFigures {
  int quality = 0;
  uint64_t bytes = 0;
  double reached_psnr_db = 0;
  double bytes_at_psnr = 0;
  nlohmann::json probes = nlohmann::json::array();
};

/// Every texture that `input`'s materials bind (not those made of vertex colours), encoded in `codec`
/// (JPEG or lossy WebP) at one quality, decoded back and measured as docs/metrics.md's surface PSNR
/// against `input` as it is (its own points, kPsnrPoints); the lowest quality that reaches `psnr_db`
/// found by lowest_quality_reaching. `input` is left as it was (its
/// images are moved out and back while it is copied).
ReencodeFigures reencode_at_psnr(TexturedMesh& input, ImageFormat codec, double psnr_db);

}  // namespace tightex
