// The lines a user should read after a run: where the result is not what was asked (components kept as
// they were, triangles with nothing to bake, exact repeats, a default budget grown), and what the
// output format cannot carry of the input.
#pragma once
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "io/obj_reader.hpp"
#include "tightex/options.hpp"
#include "tightex/tightex.hpp"

namespace tightex {

/// Sets the report's "warnings" and "notes", one line each: what `plan` (made from `input`; the report
/// holds its figures) and the write (`written`: the model format, nullopt where nothing was written;
/// `removed`: what the writer left out) leave a user to know.
void add_warnings(const Plan& plan, const TexturedMesh& input, const ModelReadStats& read_stats, std::optional<ModelFormat> written,
                  const std::vector<std::string>& removed, nlohmann::json& report);

/// Adds to the report's "warnings" where --target-psnr or --max-bytes (`options`) is not met by the
/// images as written (report "bytes"): how far, and what would reach further.
void add_rate_warnings(const Options& options, nlohmann::json& report);

}  // namespace tightex
