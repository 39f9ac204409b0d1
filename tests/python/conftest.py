"""Fixtures of the Python module's tests: generated models (tools/make_boxes.py: N boxes, one chart
per box face, one texture) and a bad one. The tests skip when the module was not built."""
import json
import os
import shutil
import struct
import subprocess
import sys

import pytest

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
#: The repository's own real scan (tests/data/fuze); ../shared/data holds the larger ones where present.
REPO_DATA = os.path.join(REPO, "tests", "data")
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


def _glb_parts(glb):
    """The JSON document and the BIN chunk of a GLB's bytes."""
    json_length = struct.unpack_from("<I", glb, 12)[0]
    bin_start = 20 + json_length + 8
    return json.loads(glb[20:20 + json_length]), bytearray(glb[bin_start:bin_start + struct.unpack_from("<I", glb, bin_start - 8)[0]])


def _triangle_primitives(doc):
    return [p for mesh in doc["meshes"] for p in mesh["primitives"] if p.get("mode", 4) == 4]


def _positions(doc, binary, primitive):
    accessor = doc["accessors"][primitive["attributes"]["POSITION"]]
    view = doc["bufferViews"][accessor["bufferView"]]
    start, stride = view.get("byteOffset", 0) + accessor.get("byteOffset", 0), view.get("byteStride", 12)
    return [struct.unpack_from("<3f", binary, start + i * stride) for i in range(accessor["count"])]


def batch_of(position, batches):
    """The batch a test tile puts a vertex in: a function of its position, so that vertices at the same
    place (split along seams) share it."""
    return int(abs(position[0] * 7 + position[1] * 3 + position[2] * 5) * 10) % batches


def glb_with_batch_ids(glb, batches):
    """``glb`` (bytes of a GLB with one buffer, the BIN chunk) with a 3D Tiles ``_BATCHID`` on every
    triangle primitive: an unsigned short per vertex, ``batch_of`` its position (a stride of 4, as glTF
    aligns vertex attributes)."""
    doc, binary = _glb_parts(glb)
    for primitive in _triangle_primitives(doc):
        ids = [batch_of(p, batches) for p in _positions(doc, binary, primitive)]
        binary += b"\0" * (-len(binary) % 4)
        doc["bufferViews"].append({"buffer": 0, "byteOffset": len(binary), "byteLength": 4 * len(ids), "byteStride": 4, "target": 34962})
        binary += b"".join(struct.pack("<HH", i, 0) for i in ids)
        doc["accessors"].append({"bufferView": len(doc["bufferViews"]) - 1, "componentType": 5123, "count": len(ids), "type": "SCALAR"})
        primitive["attributes"]["_BATCHID"] = len(doc["accessors"]) - 1
    binary += b"\0" * (-len(binary) % 4)
    doc["buffers"][0]["byteLength"] = len(binary)
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    return (struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(text) + 8 + len(binary)) + struct.pack("<II", len(text), 0x4E4F534A) + text +
            struct.pack("<II", len(binary), 0x004E4942) + bytes(binary))


def batch_id_errors(glb, batches):
    """The vertices of ``glb``'s triangle primitives whose _BATCHID is not ``batch_of`` their position
    (a primitive without _BATCHID counts all its vertices), and the vertices checked."""
    doc, binary = _glb_parts(glb)
    wrong = checked = 0
    for primitive in _triangle_primitives(doc):
        positions = _positions(doc, binary, primitive)
        checked += len(positions)
        if "_BATCHID" not in primitive["attributes"]:
            wrong += len(positions)
            continue
        accessor = doc["accessors"][primitive["attributes"]["_BATCHID"]]
        view = doc["bufferViews"][accessor["bufferView"]]
        start, stride = view.get("byteOffset", 0) + accessor.get("byteOffset", 0), view.get("byteStride", 2)
        for i, p in enumerate(positions):
            wrong += struct.unpack_from("<H", binary, start + i * stride)[0] != batch_of(p, batches)
    return wrong, checked
