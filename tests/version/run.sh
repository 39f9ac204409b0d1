#!/bin/sh
# One version: `tightex --version` shows git describe of the source tree (the project version alone
# outside a git checkout, no SOURCE_DIR/.git, as cmake/version.cmake decides), report.json's
# "tightex_version" and tightex.__version__ are the same string, and pyproject.toml's version is
# CMakeLists.txt's project version.
# Arguments: TIGHTEX SOURCE_DIR PROJECT_VERSION [PYTHON PYTHONPATH] (the Python check where given).
set -eu
tightex=$1 src=$2 project_version=$3
fail() { echo "version: $*" >&2; exit 1; }
version=$("$tightex" --version)
[ -n "$version" ] || fail "tightex --version printed nothing"
if [ -e "$src/.git" ] && command -v git >/dev/null && described=$(git -C "$src" describe --tags --always 2>/dev/null); then
  # Without --dirty: the build (which refreshes the string) may predate an edit to the tree.
  case "$version" in *"$described"*) ;; *) fail "tightex --version says '$version', git describe '$described' (rebuild?)" ;; esac
else
  [ "$version" = "$project_version" ] || fail "outside git, tightex --version says '$version', not $project_version"
fi
case "$version" in "$project_version"*|v*|[0-9]*) ;; *) fail "'$version' starts with neither the project version nor a tag" ;; esac
grep -q "^version = \"$project_version\"" "$src/pyproject.toml" || fail "pyproject.toml's version is not $project_version"
out=$(pwd)/version_run
rm -rf "$out"
"$tightex" "$src/tests/data/fuze/fuze.obj" -o "$out" --size 64 --no-html --quiet
in_report=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["tightex_version"])' "$out/report.json")
[ "$in_report" = "$version" ] || fail "report.json says '$in_report', tightex --version '$version'"
rm -rf "$out"
if [ $# -ge 5 ]; then
  in_python=$(PYTHONPATH=$5 "$4" -c 'import tightex; print(tightex.__version__)')
  [ "$in_python" = "$version" ] || fail "tightex.__version__ is '$in_python', tightex --version '$version'"
fi
echo "version: $version everywhere"
