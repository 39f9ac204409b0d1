#!/usr/bin/env bash
# Checks that the C++ sources follow the repository's .clang-format, changing nothing: lists each file
# that differs and exits non-zero if any does. Usage: bash scripts/check_format.sh [clang-format binary]
# (default: clang-format, from Debian's clang-format package, which scripts/setup.sh installs).
# To apply the format to one file: clang-format -i FILE.
set -euo pipefail
cd "$(dirname "$0")/.."
tool="${1:-${CLANG_FORMAT:-clang-format}}"
if ! command -v "$tool" >/dev/null; then
  echo "check_format: $tool not found (apt-get install clang-format, as scripts/setup.sh does)" >&2
  exit 2
fi
mapfile -t files < <(git ls-files -- 'src/*' 'include/*' 'tests/*' 'tools/*' 'bench/*' 'fuzz/*' 'examples/*' |
                     grep -E '\.(cpp|hpp|h|cc)$')
differ=()
for f in "${files[@]}"; do
  "$tool" --style=file --dry-run -Werror "$f" >/dev/null 2>&1 || differ+=("$f")
done
if [ ${#differ[@]} -gt 0 ]; then
  printf '%s\n' "${differ[@]}"
  echo "check_format: ${#differ[@]} of ${#files[@]} C++ files differ from .clang-format ($("$tool" --version))" >&2
  exit 1
fi
echo "check_format: all ${#files[@]} C++ files follow .clang-format"
