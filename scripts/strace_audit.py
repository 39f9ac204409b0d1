#!/usr/bin/env python3
"""The cases and the audit of scripts/check_untrusted_io.sh.

    strace_audit.py TRACE WATCHED IN OUT       what an strace log (open, openat, creat, rename*) shows:
                                               exit 1 if a file under WATCHED was read outside IN or OUT
                                               or created outside OUT (symbolic links followed)
    strace_audit.py --make-cases AREA          hostile models under AREA/cases/<case>/scan, the files
                                               they name beside scan/ (from AREA/src: boxes, gltf, ply)
    strace_audit.py --make-tileset AREA VENDOR a hostile tileset VENDOR/in, its outside files in VENDOR
"""
import json
import os
import re
import shutil
import subprocess
import sys

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SYSTEM = ("/usr/", "/lib", "/etc/", "/proc/", "/sys/", "/dev/", "/run/")


def under(path, root):
    return path == root or path.startswith(root.rstrip("/") + "/")


def accesses(trace):
    """(read, written): the real paths opened for reading, and those created, opened for writing or renamed into."""
    read, written = set(), set()
    for line in open(trace):
        if "= -1" in line:
            continue
        m = re.search(r'(open|openat|creat)\((?:AT_FDCWD, |\d+, )?"([^"]*)"(?:, ([A-Z_|]+))?', line)
        if m:
            writes = m.group(1) == "creat" or re.search(r"O_WRONLY|O_RDWR|O_CREAT", m.group(3) or "")
            (written if writes else read).add(os.path.realpath(m.group(2)))
        m = re.search(r'rename(?:at2?)?\((?:AT_FDCWD, |\d+, )?"[^"]*", (?:AT_FDCWD, |\d+, )?"([^"]*)"', line)
        if m:
            written.add(os.path.realpath(m.group(1)))
    return read, written


def audit(trace, watched, inp, out):
    watched, inp, out = (os.path.realpath(p) for p in (watched, inp, out))
    read, written = accesses(trace)
    bad_reads = sorted(p for p in read if under(p, watched) and not under(p, inp) and not under(p, out) and not os.path.isdir(p))
    bad_writes = sorted(p for p in written if under(p, watched) and not under(p, out))
    others = sorted(p for p in read | written if not under(p, watched) and not p.startswith(SYSTEM) and not under(p, REPO))
    print(f"   opened {len(read)} paths for reading ({sum(under(p, inp) for p in read)} in the input's folder), "
          f"created or renamed {len(written)}")
    print(f"   read outside the input's folder: {bad_reads or 'none'}; created outside the output's: {bad_writes or 'none'}")
    if others:
        print(f"   elsewhere (not the cases' files: the tools' own): {others[:8]}{' ...' if len(others) > 8 else ''}")
    return 1 if bad_reads or bad_writes else 0


def make_cases(area):
    src, cases = os.path.join(area, "src"), os.path.join(area, "cases")

    def case(name, folder, model_files):
        d = os.path.join(cases, name)
        os.makedirs(os.path.join(d, "scan"))
        shutil.copy(os.path.join(src, "boxes", "boxes.png"), os.path.join(d, "secret.png"))
        for f in model_files:
            shutil.copy(os.path.join(src, folder, f), os.path.join(d, "scan", f))
        return d

    mtl = [l for l in open(os.path.join(src, "boxes", "boxes.mtl")) if not l.lower().startswith("map_kd")]
    for name, line in (("obj_dotdot", "map_Kd ../secret.png"), ("obj_absolute", "map_Kd {d}/secret.png"),
                       ("obj_file_uri", "map_Kd file://{d}/secret.png"), ("obj_link", "map_Kd boxes.png")):
        d = case(name, "boxes", ["boxes.obj"])
        with open(os.path.join(d, "scan", "boxes.mtl"), "w") as f:
            f.write("".join(mtl) + line.format(d=d) + "\n")
    os.symlink("../secret.png", os.path.join(cases, "obj_link", "scan", "boxes.png"))
    d = case("obj_mtllib", "boxes", ["boxes.obj"])
    subprocess.run(["sed", "-i", "s|^mtllib .*|mtllib ../boxes.mtl|", os.path.join(d, "scan", "boxes.obj")], check=True)
    shutil.copy(os.path.join(src, "boxes", "boxes.mtl"), d)
    shutil.copy(os.path.join(src, "boxes", "boxes.png"), d)
    for name, field, uri in (("gltf_buffer", "buffers", "../secret.bin"), ("gltf_image", "images", "{d}/secret.png")):
        d = case(name, "gltf", os.listdir(os.path.join(src, "gltf")))
        shutil.copy(os.path.join(src, "gltf", "boxes.bin"), os.path.join(d, "secret.bin"))
        path = os.path.join(d, "scan", "boxes.gltf")
        doc = json.load(open(path))
        doc[field][0]["uri"] = uri.format(d=d)
        json.dump(doc, open(path, "w"))
    d = case("ply_dotdot", "ply", [])
    head, body = open(os.path.join(src, "ply", "boxes.ply"), "rb").read().split(b"end_header\n", 1)
    lines = [b"comment TextureFile ../secret.png" if l.startswith(b"comment TextureFile") else l for l in head.split(b"\n")]
    open(os.path.join(d, "scan", "boxes.ply"), "wb").write(b"\n".join(lines) + b"end_header\n" + body)


def make_tileset(area, vendor):
    for sub in ("in/tiles", "in/sub", "outer"):
        os.makedirs(os.path.join(vendor, sub))
    shutil.copytree(os.path.join(area, "src", "boxes"), os.path.join(vendor, "in", "tiles", "t0"))
    shutil.copytree(os.path.join(area, "src", "boxes"), os.path.join(vendor, "evil"))
    os.symlink("../../evil", os.path.join(vendor, "in", "tiles", "link"))
    open(os.path.join(vendor, "in", "tiles", "p.pnts"), "w").write("pnts")
    box = {"box": [0, 0, 0, 100, 0, 0, 0, 100, 0, 0, 0, 10]}

    def tileset(path, uris):
        children = [{"boundingVolume": box, "geometricError": 0, "content": {"uri": u}} for u in uris]
        json.dump({"asset": {"version": "1.1"}, "geometricError": 100,
                   "root": {"boundingVolume": box, "geometricError": 50, "refine": "ADD", "children": children}}, open(path, "w"))

    tileset(os.path.join(vendor, "in", "sub", "tileset.json"), ["../../evil/boxes.obj"])
    tileset(os.path.join(vendor, "outer", "tileset.json"), ["../evil/boxes.obj"])
    evil = os.path.join(vendor, "evil", "boxes.obj")
    tileset(os.path.join(vendor, "in", "tileset.json"), ["tiles/t0/boxes.obj", "sub/tileset.json", "tiles/p.pnts", "../evil/boxes.obj", evil,
                                                          "file://" + evil, "tiles/link/boxes.obj", "../outer/tileset.json",
                                                          "http://example.com/t.glb", "https://example.com/t.b3dm"])


if __name__ == "__main__":
    if sys.argv[1] == "--make-cases":
        make_cases(sys.argv[2])
    elif sys.argv[1] == "--make-tileset":
        make_tileset(sys.argv[2], sys.argv[3])
    else:
        sys.exit(audit(*sys.argv[1:5]))
