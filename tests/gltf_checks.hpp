// The written glTF files through the Khronos glTF-Validator and three.js's GLTFLoader (tests/gltf,
// installed by scripts/gltf-checks.sh; skipped, saying so, where node or the packages are missing).
#pragma once
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "command_line.hpp"

namespace tightex::testing {

/// True when `node` exists and tests/gltf's packages are installed (scripts/gltf-checks.sh: npm ci,
/// pinned by the lockfile; the test scripts run it before the tests).
inline bool node_checks_ready() {
  static const bool ready = [] {
    const std::filesystem::path modules = std::filesystem::path(TIGHTEX_GLTF_CHECKS) / "node_modules";
    return std::system("command -v node >/dev/null 2>&1") == 0 && std::filesystem::exists(modules / "gltf-validator") &&
           std::filesystem::exists(modules / "three");
  }();
  return ready;
}

/// Runs tests/gltf/check_gltf.mjs on `file`: its JSON line (errors, warnings, meshes, triangles).
inline nlohmann::json node_check(const std::filesystem::path& file) {
  const std::filesystem::path out = file.parent_path() / "check.json";
  std::system(
      ("node '" + std::string(TIGHTEX_GLTF_CHECKS) + "/check_gltf.mjs' '" + file.string() + "' > '" + out.string() + "' 2>&1").c_str());
  try {
    return nlohmann::json::parse(read_whole(out));
  } catch (const nlohmann::json::exception&) {
    return {{"unparsed", read_whole(out)}};
  }
}

inline void expect_valid_and_loading(const std::filesystem::path& file, size_t triangles) {
  if (!node_checks_ready()) {
    std::cout << "[  SKIPPED ] glTF-Validator and three.js: node or tests/gltf/node_modules is missing (bash scripts/gltf-checks.sh)\n";
    return;
  }
  const nlohmann::json r = node_check(file);
  EXPECT_EQ(r.value("errors", -1), 0) << r.dump();
  EXPECT_EQ(r.value("warnings", -1), 0) << r.dump();
  EXPECT_FALSE(r.contains("load_error")) << r.dump();
  EXPECT_EQ(r.value("triangles", 0.0), double(triangles)) << r.dump();
}

}  // namespace tightex::testing
