// The tightex command: a thin shell over the library's run (tightex/run.hpp) and the command's flags (cli/command.hpp). Exit codes: 0 ok, 1
// bad input (the message names the file and element), 2 internal error.
#include <sys/auxv.h>
#include <unistd.h>
#include <CLI/CLI.hpp>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <string>
#include <string_view>

#include "cli/command.hpp"
#include "core/error.hpp"
#include "report/metrics.hpp"
#include "report/report.hpp"
#include "tightex/run.hpp"
#include "tightex/tightex.hpp"

using namespace tightex;

namespace {

/// `tightex measure INPUT OUTPUT`: prints the docs/metrics.md figures of two models as JSON.
int run_measure(int argc, char** argv) {
  CLI::App app{"tightex measure: the figures of docs/metrics.md for an input model and an output model", "tightex measure"};
  std::string in_path, out_path;
  size_t samples = kPsnrPoints;
  app.add_option("input", in_path, "the original model (OBJ, PLY, glTF or GLB)")->required();
  app.add_option("output", out_path, "the re-textured model (OBJ, PLY, glTF or GLB)")->required();
  app.add_option("--samples", samples, "surface PSNR samples");
  bool allow_outside = false;
  app.add_flag("--allow-outside-files", allow_outside, "read files the models name outside their folders (tightex --help)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 1;
  }
  // A glTF scene beside a model without a scene graph (OBJ, PLY) is compared in world space, as
  // tightex writes a scene to OBJ or PLY; two glTF models each mesh in its own space.
  auto is_gltf = [](const std::string& path) {
    const ModelFormat f = model_format_of(path);
    return f == ModelFormat::kGltf || f == ModelFormat::kGlb;
  };
  ModelReadOptions in_options, out_options;
  in_options.flatten_scene = is_gltf(in_path) && !is_gltf(out_path);
  out_options.flatten_scene = is_gltf(out_path) && !is_gltf(in_path);
  in_options.allow_outside_files = out_options.allow_outside_files = allow_outside;
  const TexturedMesh in = read_model(in_path, in_options), out = read_model(out_path, out_options);
  std::cout << to_json(measure(in, out, samples)).dump(2) << "\n";
  return 0;
}

/// The main command from its arguments to its exit code (0, or 1 for a command-line error).
int run_main(int argc, char** argv) {
  int exit_code = 0;
  const std::optional<cli::CommandLine> line = cli::parse_command_line(argc, argv, exit_code);
  if (!line) return exit_code;
  cli::run_command(*line);
  return 0;
}

/// Starts this program again with glibc's allocator told to ask for transparent huge pages
/// (GLIBC_TUNABLES glibc.malloc.hugetlb=1, which only the environment of a starting process can set):
/// the heap and the blocks mapped on their own are advised as 2 MiB pages, so that a surface-sized
/// array costs one page fault per 2 MiB instead of per 4 KiB, and the solvers' scattered reads miss
/// the TLB less (BENCHMARKS.md). Only a starting process can ask it, so the command does it here; the
/// allocator's other settings are the library's (run: keep_freed_memory_for_reuse), and neither changes
/// a byte of the output. Not done where GLIBC_TUNABLES already says how (as it does in the new
/// process); where execv fails the run goes on as it is. Not done either where the program was started
/// by naming the dynamic loader (`ld-linux-x86-64.so.2 tightex ...`: /proc/self/exe is then the loader,
/// and the kernel gives no interpreter base) or is linked statically.
void restart_with_huge_pages(char** argv) {
  if (::getauxval(AT_BASE) == 0) return;
  constexpr std::string_view kHugePages = "glibc.malloc.hugetlb";
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables != nullptr && std::string_view(tunables).find(kHugePages) != std::string_view::npos) return;
  std::string value = std::string(kHugePages) + "=1";
  if (tunables != nullptr && *tunables != '\0') value += std::string(":") + tunables;
  if (::setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  ::execv("/proc/self/exe", argv);
}

}  // namespace

int main(int argc, char** argv) {
  restart_with_huge_pages(argv);
  try {
    if (argc > 1 && std::string(argv[1]) == "measure") return run_measure(argc - 1, argv + 1);
    return run_main(argc, argv);
  } catch (const InputError& e) {
    fmt::print(stderr, "tightex: error: {}\n", e.what());
    return int(ExitCode::kBadInput);
  } catch (const InternalError& e) {
    fmt::print(stderr, "tightex: internal error: {}\n", e.what());
    return int(ExitCode::kInternal);
  } catch (const std::bad_alloc&) {
    fmt::print(stderr, "tightex: internal error: out of memory\n");
    return int(ExitCode::kInternal);
  } catch (const std::exception& e) {
    fmt::print(stderr, "tightex: internal error: {}\n", e.what());
    return int(ExitCode::kInternal);
  }
}
