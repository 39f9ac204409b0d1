#!/usr/bin/env python3
"""Greedy edge cover of a fuzz run's grown corpus: which of its inputs to check in as cov-* files.

    scripts/fuzz_cover.py HARNESS [MIN_NEW_EDGES=3] [--copy]

Runs build-fuzz/fuzz/HARNESS once over the checked-in corpus (fuzz/corpus/HARNESS) and the grown one
(build-fuzz/corpus/HARNESS) in libFuzzer's merge mode with a control file (-merge=1, counters, CMP and
value profile off, so a feature is an edge), then, starting from the edges the checked-in inputs reach,
repeatedly takes the grown input that adds the most edges not yet reached, while it adds at least
MIN_NEW_EDGES (FUZZING.md: 3 for fuzz_obj and fuzz_image, 5 for fuzz_pipeline). Prints one line per
input taken; --copy copies them into fuzz/corpus/HARNESS as cov-<sha1 prefix>. Build the harness first
(scripts/fuzz.sh 0 HARNESS).
"""
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile


def parse_control(path):
    """Per file index: its path and the set of edges (COV lines) libFuzzer recorded for it."""
    with open(path) as f:
        lines = f.read().splitlines()
    n = int(lines[0])
    first = int(lines[1])
    files = lines[2:2 + n]
    edges = {}
    for line in lines[2 + n:]:
        parts = line.split()
        if parts and parts[0] == "COV":
            edges[int(parts[1])] = set(int(x) for x in parts[2:])
    return files, first, edges


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    if not args:
        sys.exit(__doc__)
    harness = args[0]
    min_new = int(args[1]) if len(args) > 1 else 3
    copy = "--copy" in sys.argv
    os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    binary = f"build-fuzz/fuzz/{harness}"
    seeds, grown = f"fuzz/corpus/{harness}", f"build-fuzz/corpus/{harness}"
    for p in (binary, seeds, grown):
        if not os.path.exists(p):
            sys.exit(f"fuzz_cover: {p}: missing (build and run the harness first: scripts/fuzz.sh)")
    with tempfile.TemporaryDirectory() as tmp:
        # The merge's output folder starts as a copy of the seeds: its files are the "initial" ones.
        initial = os.path.join(tmp, "initial")
        shutil.copytree(seeds, initial)
        control = os.path.join(tmp, "control")
        env = dict(os.environ, ASAN_OPTIONS="detect_leaks=0:allocator_may_return_null=1",
                   TIGHTEX_FUZZ_FINDINGS=os.path.join(tmp, "findings"))
        subprocess.run([binary, "-merge=1", f"-merge_control_file={control}", "-use_counters=0", "-use_cmp=0",
                        "-use_value_profile=0", "-timeout=10", "-rss_limit_mb=2048", initial, grown],
                       env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
        if not os.path.exists(control):
            sys.exit(f"fuzz_cover: {binary}: the merge wrote no control file (run it by hand to see why)")
        files, first, edges = parse_control(control)
    reached = set()
    for i in range(first):
        reached |= edges.get(i, set())
    candidates = {i: edges.get(i, set()) - reached for i in range(first, len(files))}
    print(f"{harness}: {first} checked-in inputs reach {len(reached)} edges; {len(files) - first} grown inputs")
    taken = []
    while candidates:
        best = max(candidates, key=lambda i: (len(candidates[i]), -os.path.getsize(files[i])))
        gain = candidates.pop(best)
        if len(gain) < min_new:
            break
        reached |= gain
        taken.append(best)
        for i in candidates:
            candidates[i] -= gain
        print(f"  +{len(gain)} edges  {os.path.getsize(files[best])} bytes  {files[best]}")
    print(f"{len(taken)} inputs taken; {len(reached)} edges reached")
    if copy:
        for i in taken:
            data = open(files[i], "rb").read()
            dest = os.path.join(seeds, "cov-" + hashlib.sha1(data).hexdigest()[:12])
            with open(dest, "wb") as f:
                f.write(data)
            print(f"  wrote {dest}")


if __name__ == "__main__":
    main()
