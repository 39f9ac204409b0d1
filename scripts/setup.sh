#!/usr/bin/env bash
# Installs everything tightex needs to build and test on Debian 12 (run as root, or with sudo available).
set -euo pipefail
pkgs=(build-essential cmake ninja-build pkg-config
      libeigen3-dev libsuitesparse-dev libopenblas0-pthread libtbb-dev
      libtinyobjloader-dev nlohmann-json3-dev
      libspng-dev libdeflate-dev libjpeg62-turbo-dev libwebp-dev libstb-dev zlib1g-dev
      libcli11-dev libfmt-dev libgtest-dev libgmock-dev libbenchmark-dev
      pybind11-dev python3-dev python3-numpy python3-distributed python3-pytest python3-venv python3-pip python3-setuptools python3-open3d python3-pil
      libjs-three chromium clang-format blender)
# python3-open3d: tests only, a real client of the Python module (tests/python/test_open3d.py).
# python3-pil: tools/webp_rotation_cost.py only (a measurement of BENCHMARKS.md).
# clang-format: scripts/check_format.sh, the house format's check.
# blender: tests only, the add-on's headless test (Blender.AddOn; skipped without it).
# libjs-three: the three.js that report.html packs (at build time). chromium: the browser test of
# report.html. Tests only: Node.js drives it, and runs the Khronos glTF-Validator and three.js on
# written glTF (scripts/gltf-checks.sh); a node installed otherwise (nodesource, nvm) is used as it is.
# blender (3.4.1, on the system's Python 3.11; about 550 MB installed): the add-on's headless test
# (tests/blender); without it that test is skipped.
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then pkgs+=(nodejs npm); fi
missing=()
for p in "${pkgs[@]}"; do dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
