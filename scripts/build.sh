#!/usr/bin/env bash
# Configures and builds tightex in ./build (Release), with the Python module tightex in build/python
# (PYTHONPATH=build/python imports it; the tests do so). It installs nothing outside the checkout but
# the Debian packages scripts/setup.sh adds where missing. To install the module for Debian's
# /usr/bin/python3: `cmake --install build --component python` (into /usr/local/lib/python3.11/
# dist-packages), or `pip install --no-build-isolation .` into a virtual environment.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
if [ ! -f build/CMakeCache.txt ]; then
  cmake -S . -B build "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE=/usr/bin/python3 >/dev/null
fi
cmake --build build --parallel "$(nproc)"
