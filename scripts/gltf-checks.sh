#!/usr/bin/env bash
# Installs the test-only npm packages of tests/gltf (the Khronos glTF-Validator and three.js, pinned by
# package-lock.json) with which the tests check every glTF they write. Without node and npm it says so
# and the tests skip those checks.
set -uo pipefail
cd "$(dirname "$0")/../tests/gltf"
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  echo "gltf-checks: node/npm not found: the glTF-Validator and three.js checks will be skipped"
  exit 0
fi
[ -d node_modules/gltf-validator ] && [ -d node_modules/three ] && exit 0
npm ci --no-audit --no-fund --silent || echo "gltf-checks: npm ci failed: the glTF-Validator and three.js checks will be skipped"
exit 0
