#!/usr/bin/env python3
"""Checks docs/architecture.md's layering over the #include lines: each folder of src/ includes only
itself, the public headers (include/tightex/) and the folders before it in the data flow's order; the
report's headers include only core's, the report's own and the public ones (the stages' records live in
core/stage_stats.hpp); the public headers include one another and the C++ standard library's headers
only, and (with --compiler) each compiles alone with include/ as its one include path.
Prints each include that breaks a rule and exits 1 if any does.

    python3 scripts/check_layers.py [--compiler CXX] [ROOT]
"""
import pathlib
import re
import subprocess
import sys

#: The stage folders in the order data flows; each may include the ones before it.
ORDER = ["core", "io", "prepare", "cut", "param", "layout", "bake", "report", "pipeline", "run", "cli", "python"]
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')


def includes(path):
    """(line number, delimiter, header) of each #include of a file."""
    for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
        m = INCLUDE.match(line)
        if m:
            yield number, m.group(1), m.group(2)


def stage_breaks(root):
    """Each include of a later stage's header by an earlier stage."""
    for folder in ORDER:
        for path in sorted((root / "src" / folder).rglob("*.[ch]pp")):
            for number, _, header in includes(path):
                stage = header.split("/")[0]
                if stage in ORDER and ORDER.index(stage) > ORDER.index(folder):
                    yield f"{path.relative_to(root)}:{number}: {folder} includes {header}, a later stage"


#: Folders whose headers may include only core's, their own and the public headers.
CORE_ONLY_HEADERS = ["report"]


def header_breaks(root):
    """Each include of a stage's header (but core's and its own) by a header of CORE_ONLY_HEADERS."""
    for folder in CORE_ONLY_HEADERS:
        for path in sorted((root / "src" / folder).glob("*.hpp")):
            for number, delimiter, header in includes(path):
                stage = header.split("/")[0]
                if delimiter == '"' and stage in ORDER and stage not in ("core", folder):
                    yield f"{path.relative_to(root)}:{number}: a {folder} header includes {header}, a stage's interface"


def public_breaks(root):
    """Each include of src/, of a third-party or of a system header by a public header: they include
    one another and the C++ standard library's headers only."""
    for path in sorted((root / "include" / "tightex").glob("*.hpp")):
        for number, delimiter, header in includes(path):
            if delimiter == '"' and not header.startswith("tightex/"):
                yield f"{path.relative_to(root)}:{number}: a public header includes {header}, not a public one"
            if delimiter == "<" and ("/" in header or header.endswith(".h")):
                yield f"{path.relative_to(root)}:{number}: a public header includes <{header}>, not a standard C++ header"


def standalone_breaks(root, compiler):
    """Each public header that does not compile alone with include/ as its one include path beside the
    system's (where Eigen is not: Debian keeps it under /usr/include/eigen3)."""
    for path in sorted((root / "include" / "tightex").glob("*.hpp")):
        run = subprocess.run([compiler, "-std=c++20", "-fsyntax-only", "-Wno-pragma-once-outside-header", "-I", str(root / "include"), "-x", "c++", str(path)],
                             capture_output=True, text=True)
        if run.returncode != 0:
            errors = [line for line in run.stderr.splitlines() if "error" in line] or ["(no message)"]
            yield f"{path.relative_to(root)}: does not compile alone: {errors[0]}"


def main():
    args = sys.argv[1:]
    compiler = None
    if "--compiler" in args:
        i = args.index("--compiler")
        compiler = args[i + 1]
        del args[i:i + 2]
    root = pathlib.Path(args[0] if args else pathlib.Path(__file__).resolve().parent.parent)
    breaks = list(stage_breaks(root)) + list(header_breaks(root)) + list(public_breaks(root))
    if compiler:
        breaks += list(standalone_breaks(root, compiler))
    for b in breaks:
        print(b)
    print(f"check_layers: {len(breaks)} include(s) against the layering")
    return 1 if breaks else 0


if __name__ == "__main__":
    sys.exit(main())
