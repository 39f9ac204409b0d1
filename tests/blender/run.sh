#!/bin/sh
# The Blender add-on's headless test (test_addon.py, run inside Blender). Exit 77 (ctest: skipped) with
# the reason where blender is not installed.
# Usage: run.sh BUILD_DIR SOURCE_DIR
build=$1 source=$2
if ! command -v blender >/dev/null 2>&1; then
  echo "SKIP: blender is not installed (scripts/setup.sh installs Debian's)"
  exit 77
fi
work="$build/blender_test"
rm -rf "$work" && mkdir -p "$work"
# The add-on is installed into the test's own folder, not the user's Blender configuration.
export BLENDER_USER_CONFIG="$work/config" BLENDER_USER_SCRIPTS="$work/scripts"
exec blender -b --factory-startup --python-exit-code 1 --python "$source/tests/blender/test_addon.py" -- "$build" "$source" "$work"
