#!/usr/bin/env bash
# The whole test suite: unit and stage tests on generated meshes, and real scans through the CLI:
# the repository's own (tests/data/fuze) always, every model of ../shared/data where it is present.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
bash scripts/gltf-checks.sh
ctest --test-dir build --output-on-failure --timeout 900 -j "$(nproc)"
