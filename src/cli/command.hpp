// The tightex command: its flags (one CLI11 definition, mapped onto the library's Options) and what it
// prints around the library's run (tightex/run.hpp).
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "tightex/options.hpp"
#include "tightex/report.hpp"

namespace tightex::cli {

/// What the command line asks for.
struct CommandLine {
  std::string input, outdir;
  Options options;
  bool quiet = false, verbose = false;
};

/// Parses the main command's arguments, as the command line has them after the program's name (e.g.
/// {"in.obj", "-o", "out", "--size", "512"}). Guarantees: every value passed the flags' checks (ranges,
/// names, exclusions). Throws InputError with CLI11's one-line message for an unknown option, a missing
/// or bad value, and for --help (there is no terminal to print it to).
CommandLine parse_arguments(const std::vector<std::string>& args);

/// parse_arguments for main(): nullopt where the command ends here (--help printed, or a parse error
/// CLI11 has printed), with the exit code in `exit_code`.
std::optional<CommandLine> parse_command_line(int argc, char** argv, int& exit_code);

/// Runs the main command: the library's run with a progress line where stderr is a terminal, then its
/// warnings and notes on stderr and the summary line on stdout (nothing but errors with --quiet).
/// Throws as run does.
Report run_command(const CommandLine& line);

}  // namespace tightex::cli
