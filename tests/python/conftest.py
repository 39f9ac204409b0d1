"""Fixtures of the Python module's tests: generated models (tools/make_boxes.py: N boxes, one chart
per box face, one texture) and a bad one. The tests skip when the module was not built."""
import os
import shutil
import subprocess
import sys

import pytest

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SHARED_DATA = os.environ.get("TIGHTEX_SHARED_DATA", os.path.join(REPO, "..", "shared", "data"))


@pytest.fixture(scope="session")
def tightex():
    return pytest.importorskip("tightex", reason="the Python module tightex was not built (TIGHTEX_BUILD_PYTHON)")


def make_boxes(folder, count, seed):
    """OUTDIR/boxes.obj, .mtl, .png: `count` boxes (as many components), a chart per box face."""
    subprocess.run([sys.executable, os.path.join(REPO, "tools", "make_boxes.py"), str(count), str(folder), "--seed", str(seed)],
                   check=True, stdout=subprocess.DEVNULL)
    return os.path.join(folder, "boxes.obj")


def make_two_pages(folder, count, seed):
    """A boxes model whose second half of faces uses a second texture page (a copy of the first)."""
    model = make_boxes(folder, count, seed)
    shutil.copyfile(os.path.join(folder, "boxes.png"), os.path.join(folder, "page2.png"))
    with open(os.path.join(folder, "boxes.mtl"), "a") as f:
        f.write("newmtl b\nmap_Kd page2.png\n")
    with open(model) as f:
        lines = f.read().splitlines()
    faces = [i for i, line in enumerate(lines) if line.startswith("f ")]
    lines.insert(faces[len(faces) // 2], "usemtl b")
    with open(model, "w") as f:
        f.write("\n".join(lines) + "\n")
    return model


def make_bad_obj(path):
    """An OBJ whose face names a vertex that does not exist."""
    os.makedirs(os.path.dirname(str(path)), exist_ok=True)
    with open(path, "w") as f:
        f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 7/3\n")
    return str(path)


@pytest.fixture(scope="session")
def boxes_model(tmp_path_factory):
    return make_boxes(tmp_path_factory.mktemp("boxes"), 12, 5)
