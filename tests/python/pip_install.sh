#!/bin/sh
# pip install . from the checkout into a fresh virtual environment (--system-site-packages: Debian's
# NumPy; --no-build-isolation: the environment's own setuptools, only Debian's packages are reachable),
# reusing BUILD's CMake build; the module's tests run from that environment against the package
# installed there; pip wheel . gives a wheel that installs into a second fresh environment.
# Usage: pip_install.sh BUILD SOURCE
set -eu
build=$1
src=$2
work=$build/pip_install
rm -rf "$work"
mkdir -p "$work"
export TIGHTEX_CMAKE_BUILD_DIR="$build" PIP_NO_INDEX=1 PIP_DISABLE_PIP_VERSION_CHECK=1
/usr/bin/python3 -m venv --system-site-packages "$work/venv"
"$work/venv/bin/pip" install -q --no-build-isolation "$src"
unset PYTHONPATH
cd "$src/tests/python"
"$work/venv/bin/python" -c "import sys, tightex; assert tightex.__file__.startswith(sys.prefix), tightex.__file__; print('installed:', tightex.__file__)"
"$work/venv/bin/python" -m pytest -q -p no:cacheprovider test_module.py
"$work/venv/bin/pip" wheel -q --no-build-isolation --no-deps -w "$work/wheels" "$src"
/usr/bin/python3 -m venv --system-site-packages "$work/venv2"
"$work/venv2/bin/pip" install -q "$work"/wheels/tightex-*.whl
cd "$work"
"$work/venv2/bin/python" -c "import sys, tightex; assert tightex.__file__.startswith(sys.prefix), tightex.__file__; print('wheel installed:', tightex.__file__)"
