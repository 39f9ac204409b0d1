// tightex.Options and tightex.Report as Python classes: the library's own types, each field a typed
// attribute with the description the command's --help gives it (run/option_help.hpp).
#pragma once
#include <pybind11/pybind11.h>

namespace tightex {

/// Adds the class Options to `m`: every field but `progress` as an attribute (choices as their names,
/// "auto"-like defaults as None), each documented from option_help.
void bind_options(pybind11::module_& m);

/// Adds option_flags() (the table the command's --help and Options' docstrings come from) and
/// check_options(options).
void bind_option_table(pybind11::module_& m);

/// Adds the class Report to `m`: the main figures as read-only attributes, to_dict() for the whole
/// report, and report["key"] for its sections, as report.json holds them.
void bind_report(pybind11::module_& m);

}  // namespace tightex
