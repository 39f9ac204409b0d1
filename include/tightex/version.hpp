// The version of the tightex build: the output of `git describe --tags --always --dirty` at build time
// where that names a tag, else the project version with the commit (0.9.0+gabc1234, with -dirty for
// uncommitted changes), or the project version alone outside a git checkout (cmake/version.cmake).
// `tightex --version`, report.json's "tightex_version" and tightex.__version__ all show this string.
#pragma once
#include <string_view>

namespace tightex {

std::string_view version();

}  // namespace tightex
