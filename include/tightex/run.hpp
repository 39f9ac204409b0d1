// A whole run, from a model file to the files a user opens: what the `tightex` command and the Python
// module's `optimize` do, for any caller.
#pragma once
#include <string>

#include "tightex/error.hpp"
#include "tightex/options.hpp"
#include "tightex/report.hpp"

namespace tightex {

/// The model format a file's extension names (without case): .ply, .gltf, .glb, else OBJ.
ModelFormat model_format_of(const std::string& path);

/// Throws InputError naming the option (as the command spells it) for a value out of range or two
/// options that go against each other; run and optimize check them first.
void check_options(const Options& options);

/// Optimizes the model at `input_path` into `output_dir`: reads its geometry, refuses a run whose
/// estimated memory is above Options::max_memory_mib before any pixel is allocated, decodes the
/// textures beside the repair, plans, bakes, chooses the images' codec and quality (Options: the
/// input's codec by default, rate control for a lossy one), writes the model (named after the input, in
/// Options::model_format) with its textures, measures it (docs/metrics.md), and writes report.json and
/// report.html (and the preview where asked). Every file is written under a temporary name and renamed
/// into place; the input is never written to.
/// Returns the report as written, with the warnings and notes a user should read.
/// Options::progress hears every stage through the last file renamed into place ("done" comes after it).
/// Throws InputError (a bad model or option, an output folder that is the input's, a run above the
/// memory limit), Cancelled (Options::progress returned false, at any stage before "done"; nothing is
/// written), InternalError (a bug).
Report run(const std::string& input_path, const std::string& output_dir, const Options& options = {});

/// The memory in bytes the run's guard estimates for this model and options (decoded input textures,
/// the mesh and its stages, the atlas texture at the side the run will use), from the model's geometry
/// and its images' headers alone: what a scheduler reserves for the run. The per-component layout's
/// textures are not known before the plan and are estimated as one atlas of the same side.
/// Throws InputError for a model that cannot be read, as run would.
double estimate_memory(const std::string& input_path, const Options& options = {});

}  // namespace tightex
