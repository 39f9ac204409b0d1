#!/usr/bin/env bash
# Configures and builds tightex in ./build (Release), and installs the Python module tightex for
# Debian's /usr/bin/python3 (cmake --install, component python: /usr/local/lib/python3.11/dist-packages).
# Installs the Debian packages first if missing.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
if [ ! -f build/CMakeCache.txt ]; then
  cmake -S . -B build "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE=/usr/bin/python3 >/dev/null
fi
cmake --build build --parallel "$(nproc)"
if grep -q '^TIGHTEX_BUILD_PYTHON:BOOL=ON' build/CMakeCache.txt; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO cmake --install build --component python >/dev/null
fi
