// The tightex command: a thin shell over the library and the command (cli/command.hpp). Exit codes: 0 ok, 1 bad input (the message names
// the file and element), 2 internal error.
#include <malloc.h>
#include <CLI/CLI.hpp>
#include <iostream>
#include <limits>
#include <optional>
#include <string>

#include "cli/command.hpp"
#include "core/error.hpp"
#include "report/metrics.hpp"
#include "report/report.hpp"
#include "tightex/tightex.hpp"

using namespace tightex;

namespace {

/// `tightex measure INPUT OUTPUT`: prints the METRICS.md figures of two models as JSON.
int run_measure(int argc, char** argv) {
  CLI::App app{"tightex measure: the figures of METRICS.md for an input model and an output model"};
  std::string in_path, out_path;
  size_t samples = 200000;
  app.add_option("input", in_path, "the original model (OBJ, PLY, glTF or GLB)")->required();
  app.add_option("output", out_path, "the re-textured model (OBJ, PLY, glTF or GLB)")->required();
  app.add_option("--samples", samples, "surface PSNR samples");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 1;
  }
  const TexturedMesh in = read_model(in_path), out = read_model(out_path);
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

/// glibc's allocator told to keep freed memory for the next allocation instead of giving it back to the
/// kernel: the run allocates and frees arrays the size of the surface at every step, and each page taken
/// again from the kernel costs a page fault and its zeroing. Blocks up to 32 MiB (glibc's largest
/// threshold) come from the heap, which is never trimmed and grows 256 MiB at a time (address space,
/// not memory, until written). 854k faces: page faults 0.57 M -> 0.40 M, sys 4.5 -> 3.5 s (BENCHMARKS.md).
void keep_freed_memory_for_reuse() {
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
  mallopt(M_TOP_PAD, 256 << 20);
}

}  // namespace

int main(int argc, char** argv) {
  keep_freed_memory_for_reuse();
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
