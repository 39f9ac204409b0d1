#!/usr/bin/env bash
# docs/cli.md, the command-line reference, from a build's own help (the option table of
# src/run/option_help.cpp as src/cli/command.cpp gives it to CLI11): `tightex --help` and
# `tightex measure --help`, each in a fenced block.
#   bash scripts/gen_cli_doc.sh [TIGHTEX]            rewrite docs/cli.md (TIGHTEX: default build/tightex)
#   bash scripts/gen_cli_doc.sh TIGHTEX --check      exit 1, with the difference, where docs/cli.md is not
#                                                    what TIGHTEX generates (the test Docs.CliReference)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
tightex=${1:-$root/build/tightex}
generate() {
  echo "# Command-line reference"
  echo
  echo "Generated from the command's own help by \`bash scripts/gen_cli_doc.sh\`: do not edit by hand (the test"
  echo "\`Docs.CliReference\` fails when this file is not what the current build prints). The options in"
  echo "words: README.md and docs/usage.md; the figures the report holds: docs/metrics.md."
  echo
  echo '## tightex'
  echo
  echo '```text'
  "$tightex" --help
  echo '```'
  echo
  echo '## tightex measure'
  echo
  echo '```text'
  "$tightex" measure --help
  echo '```'
}
if [ "${2:-}" = "--check" ]; then
  if ! diff -u "$root/docs/cli.md" <(generate) >&2; then
    echo "docs/cli.md is not the current build's help: regenerate it with bash scripts/gen_cli_doc.sh $tightex" >&2
    exit 1
  fi
  echo "docs/cli.md is current"
else
  generate >"$root/docs/cli.md.new"
  mv "$root/docs/cli.md.new" "$root/docs/cli.md"
fi
