#!/usr/bin/env bash
# Untrusted input stays inside its folders (docs/architecture.md, "Files a model names"), checked from
# the outside: hostile OBJ, glTF and PLY models (a texture, library or buffer named by '..', an absolute
# path, a file: URI, a symbolic link out) and a hostile tileset run under strace; for each, what was
# opened outside the input's folder (system files aside) and what was created outside the output's.
#
#   bash scripts/check_untrusted_io.sh [BUILD_DIR]     (default build; needs strace, exit 77 without it)
#
# Prints one block per case; exits 1 if a case did not exit 1, or anything was read from the cases'
# folders outside the input or written there outside the output (Dask's own scratch files are listed,
# not counted), or the control run (--allow-outside-files) shows no read outside.
set -uo pipefail
cd "$(dirname "$0")/.."
command -v strace >/dev/null || { echo "strace is not installed"; exit 77; }
build=$(realpath "${1:-build}")
cli=$build/tightex
area=$(mktemp -d /tmp/tightex-untrusted-XXXXXX)
trace() { strace -f -e trace=open,openat,creat,rename,renameat,renameat2 -o "$1" "${@:2}"; }
audit() { python3 scripts/strace_audit.py "$@" || failed=1; }
failed=0

python3 tools/make_boxes.py 6 "$area/src/boxes" --seed 3 >/dev/null
"$cli" "$area/src/boxes/boxes.obj" -o "$area/src/gltf" --output-format gltf --size 64 --quiet --no-html
"$cli" "$area/src/boxes/boxes.obj" -o "$area/src/ply" --output-format ply --size 64 --quiet --no-html
python3 scripts/strace_audit.py --make-cases "$area"
for case in "$area"/cases/*/; do
  model=$(ls "$case"scan/boxes.* | grep -E '\.(obj|gltf|ply)$')
  trace "$case/trace.txt" "$cli" "$model" -o "$case/out" --size 64 --no-html 2> "$case/stderr.txt"
  status=$?
  echo "== $(basename "$case"): exit $status ($(cat "$case/stderr.txt"))"
  [ "$status" = 1 ] || failed=1
  audit "$case/trace.txt" "$case" "$case/scan" "$case/out"
done
# The control: with --allow-outside-files the audit must see the read outside.
case=$area/cases/obj_dotdot
trace "$case/allowed.txt" "$cli" "$case/scan/boxes.obj" -o "$case/allowed" --size 64 --no-html --quiet --allow-outside-files
echo "== obj_dotdot --allow-outside-files (control): exit $?"
python3 scripts/strace_audit.py "$case/allowed.txt" "$case" "$case/scan" "$case/allowed" && failed=1

vendor=$area/vendor
python3 scripts/strace_audit.py --make-tileset "$area" "$vendor"
(cd "$area" && PYTHONPATH=$build/python trace "$area/tiles.txt" /usr/bin/python3 -m tightex.tiles "$vendor/in/tileset.json" \
  "$vendor/out/a/b" --workers 1 --size 64 2> "$area/tiles.err")
status=$?
[ "$status" = 1 ] || failed=1
echo "== tileset: exit $status ($(grep -c '^tightex.tiles: \(refused\|remote\|unreadable\)' "$area/tiles.err") contents listed; $(tail -1 "$area/tiles.err"))"
audit "$area/tiles.txt" "$vendor" "$vendor/in" "$vendor/out/a/b"
rm -rf "$area"
exit $failed
