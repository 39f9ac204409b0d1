#!/usr/bin/env python3
"""Lists the function and lambda bodies in C++ sources that are longer than a limit (lines from the
opening to the closing brace). Exits 1 if any is over --max (default 150), so a check can use it.

    python3 scripts/long_functions.py [--max N] [--over N] PATH...

--over N lists everything over N lines (default: --max) without changing the exit status rule.
"""
import argparse
import pathlib
import re
import sys

CONTROL = {"if", "for", "while", "switch", "catch", "return", "sizeof", "decltype", "alignof", "noexcept"}


def strip(text):
    """The source with comments, strings and characters blanked (newlines kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i)); i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j])); i = j
        elif text[i] in "\"'":
            q, j = text[i], i + 1
            while j < n and text[j] != q:
                j += 2 if text[j] == "\\" else 1
            out.append(" " * (j + 1 - i)); i = j + 1
        else:
            out.append(text[i]); i += 1
    return "".join(out)


def bodies(text):
    """(name, first line, line count) of every function or lambda body."""
    s = strip(text)
    stack, found = [], []
    for i, ch in enumerate(s):
        if ch == "{":
            stack.append(i)
        elif ch == "}" and stack:
            start = stack.pop()
            head = s[max(0, start - 300):start].rstrip()
            head = re.sub(r"(\b(const|mutable|noexcept|override|final)\b|->\s*[\w:<>,\s&*]+)\s*$", "", head).rstrip()
            if not head.endswith(")"):
                continue
            depth, j = 0, len(head) - 1
            while j >= 0:
                depth += head[j] == ")"
                depth -= head[j] == "("
                if depth == 0:
                    break
                j -= 1
            before = head[:j].rstrip()
            m = re.search(r"([\w:~<>]+|\])\s*$", before)
            name = m.group(1) if m else "?"
            if name in CONTROL:
                continue
            first = s.count("\n", 0, start) + 1
            last = s.count("\n", 0, i) + 1
            found.append(("lambda" if name == "]" else name, first, last - first + 1))
    return found


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--max", type=int, default=150)
    ap.add_argument("--over", type=int)
    ap.add_argument("paths", nargs="+")
    a = ap.parse_args()
    over = a.over if a.over is not None else a.max
    files = []
    for p in map(pathlib.Path, a.paths):
        files += sorted(p.rglob("*.[ch]pp")) if p.is_dir() else [p]
    worst = 0
    for f in files:
        for name, line, count in bodies(f.read_text()):
            worst = max(worst, count)
            if count > over:
                print(f"{f}:{line}: {name} {count} lines")
    return 1 if worst > a.max else 0


if __name__ == "__main__":
    sys.exit(main())
