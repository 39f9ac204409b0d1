// One description per Options field, shared by the faces that set them: the command's --help and the
// Python module's tightex.Options docstrings.
#pragma once
#include <span>
#include <string_view>

namespace tightex {

struct OptionHelp {
  std::string_view field;  // the Options field (and the Python attribute)
  std::string_view flag;   // the command's flag; empty: none
  std::string_view help;   // what the field chooses, as --help and the docstring say it
};

/// Every Options field a caller sets, in the order --help lists them.
std::span<const OptionHelp> option_helps();

/// The description of `field`. Throws InternalError for a field without one.
std::string_view option_help(std::string_view field);

}  // namespace tightex
