#!/usr/bin/env bash
# The whole test suite: unit and stage tests on generated meshes, and every model in ../shared/data
# through the CLI (those skip cleanly when ../shared/data is absent).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
bash scripts/gltf-checks.sh
ctest --test-dir build --output-on-failure --timeout 900 -j "$(nproc)"
