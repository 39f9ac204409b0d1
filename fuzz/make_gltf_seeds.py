#!/usr/bin/env python3
"""Writes the seeds of fuzz/corpus/fuzz_gltf: small glTF models as run_gltf (fuzz/targets.hpp) reads them,
GLB and .gltf text, each using another part of the format (indices or none, strips and fans, an embedded
PNG or the harness folder's t.png, data URIs, COLOR_0, KHR_texture_transform, normalized UVs, byteStride,
points beside triangles, nested nodes, a sampler, a scene of copies, mirrored and untextured parts and
KTX2 textures) and a few that lie."""
import base64
import json
import os
import struct
import zlib

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus", "fuzz_gltf")


def png(w=2, h=2):
    raw = b"".join(b"\0" + bytes([(x * 97 + y * 31) % 256 for x in range(w) for _ in range(3)]) for y in range(h))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")


class Doc:
    def __init__(self):
        self.j = {"asset": {"version": "2.0"}, "bufferViews": [], "accessors": [], "buffers": []}
        self.bin = b""

    def view(self, data, stride=None):
        self.bin += b"\0" * (-len(self.bin) % 4)
        v = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if stride:
            v["byteStride"] = stride
        self.bin += data
        self.j["bufferViews"].append(v)
        return len(self.j["bufferViews"]) - 1

    def accessor(self, fmt, values, ctype, kind, normalized=False, stride=None):
        data = b"".join(struct.pack("<" + fmt, *v) if isinstance(v, tuple) else struct.pack("<" + fmt, v) for v in values)
        a = {"bufferView": self.view(data, stride), "componentType": ctype, "count": len(values), "type": kind}
        if normalized:
            a["normalized"] = True
        if kind == "VEC3" and ctype == 5126:
            a["min"] = [min(v[i] for v in values) for i in range(3)]
            a["max"] = [max(v[i] for v in values) for i in range(3)]
        self.j["accessors"].append(a)
        return len(self.j["accessors"]) - 1

    def glb(self):
        j = dict(self.j)
        j["buffers"] = [{"byteLength": len(self.bin)}]
        text = json.dumps(j).encode()
        text += b" " * (-len(text) % 4)
        b = self.bin + b"\0" * (-len(self.bin) % 4)
        body = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(b), 0x004E4942) + b
        return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body

    def gltf(self):
        j = dict(self.j)
        j["buffers"] = [{"byteLength": len(self.bin), "uri": "data:application/octet-stream;base64," + base64.b64encode(self.bin).decode()}]
        return json.dumps(j).encode()


def quad(d, uv_fmt=("ff", 5126, False), **prim):
    pos = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 1.0, 0.0)]
    uvs = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    if uv_fmt[1] != 5126:
        uvs = [tuple(int(c * 255) for c in uv) for uv in uvs]
    attributes = {"POSITION": d.accessor("fff", pos, 5126, "VEC3"), "TEXCOORD_0": d.accessor(uv_fmt[0], uvs, uv_fmt[1], "VEC2", uv_fmt[2])}
    p = {"attributes": attributes, "material": 0}
    p.update(prim)
    return p


def textured(d, image):
    d.j["images"] = [image]
    d.j["textures"] = [{"source": 0}]
    d.j["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "baseColorFactor": [1, 0.5, 0.5, 1]}}]


def scene(d, meshes=1):
    d.j["nodes"] = [{"mesh": m} for m in range(meshes)]
    d.j["scenes"] = [{"nodes": list(range(meshes))}]
    d.j["scene"] = 0


def main():
    os.makedirs(OUT, exist_ok=True)
    seeds = {}
    d = Doc()
    p = quad(d)
    p["indices"] = d.accessor("H", [0, 1, 2, 0, 2, 3], 5123, "SCALAR")
    textured(d, {"bufferView": d.view(png()), "mimeType": "image/png"})
    d.j["meshes"] = [{"primitives": [p]}]
    scene(d)
    seeds["indexed_embedded_png.glb"] = d.glb()
    seeds["indexed_data_uri.gltf"] = d.gltf()

    d = Doc()
    p = quad(d, ("BB", 5121, True), mode=6)
    p["attributes"]["COLOR_0"] = d.accessor("HHHH", [(65535, 0, 0, 65535)] * 4, 5123, "VEC4", True)
    textured(d, {"uri": "t.png"})
    d.j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = {"KHR_texture_transform": {"offset": [0.5, 0], "scale": [0.5, 1]}}
    d.j["extensionsUsed"] = ["KHR_texture_transform"]
    d.j["samplers"] = [{"wrapS": 33648, "wrapT": 33071}]
    d.j["textures"][0]["sampler"] = 0
    pts = {"attributes": {"POSITION": d.accessor("fff", [(0.0, 0.0, 1.0)], 5126, "VEC3")}, "mode": 0}
    d.j["meshes"] = [{"primitives": [p, pts]}]
    d.j["nodes"] = [{"children": [1], "translation": [1, 2, 3]}, {"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}]
    d.j["scenes"] = [{"nodes": [0]}]
    seeds["fan_colour_transform_points.glb"] = d.glb()

    d = Doc()
    pos = [(float(i % 3), float(i // 3), 0.0, 0.0) for i in range(6)]
    a = d.accessor("ffff", pos, 5126, "VEC3", stride=16)
    d.j["accessors"][a]["count"] = 6
    uv = d.accessor("HH", [(i * 9000, i * 7000) for i in range(6)], 5123, "VEC2", True)
    textured(d, {"uri": "t.jpg"})
    d.j["meshes"] = [{"primitives": [{"attributes": {"POSITION": a, "TEXCOORD_0": uv}, "mode": 5, "material": 0}]}]
    d.j["nodes"] = [{"mesh": 0}]
    seeds["strided_strip_no_scene.glb"] = d.glb()

    # A scene: two meshes on one POSITION accessor with their own texture coordinates, one shown twice
    # (once mirrored), an untextured primitive, an empty children array, a KTX2 texture with a PNG
    # fallback; then the same KTX2 texture without one.
    d = Doc()
    p = quad(d)
    copy = dict(p, attributes=dict(p["attributes"], TEXCOORD_0=d.accessor("ff", [(0.5, 0.5), (1.0, 0.5), (1.0, 1.0), (0.5, 1.0)], 5126, "VEC2")))
    plain = {"attributes": {"POSITION": d.accessor("fff", [(0.0, 0.0, 1.0), (1.0, 0.0, 1.0), (0.0, 1.0, 1.0)], 5126, "VEC3")}, "material": 1}
    textured(d, {"bufferView": d.view(png()), "mimeType": "image/png"})
    d.j["images"].append({"bufferView": d.view(b"\xabKTX 20\xbb\r\n\x1a\n"), "mimeType": "image/ktx2"})
    d.j["textures"][0]["extensions"] = {"KHR_texture_basisu": {"source": 1}}
    d.j["materials"].append({"pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.6, 1]}})
    d.j["extensionsUsed"] = ["KHR_texture_basisu"]
    d.j["meshes"] = [{"primitives": [p]}, {"primitives": [copy, plain]}]
    d.j["nodes"] = [{"mesh": 0, "children": []}, {"mesh": 1, "scale": [-1, 1, 1], "translation": [3, 0, 0]}, {"mesh": 1, "children": [0]}]
    d.j["scenes"] = [{"nodes": [1, 2]}]
    d.j["scene"] = 0
    seeds["scene_copies_mirror_untextured_ktx2.glb"] = d.glb()
    del d.j["textures"][0]["source"]
    seeds["scene_ktx2_without_fallback.glb"] = d.glb()

    d = Doc()
    p = quad(d)
    p["indices"] = d.accessor("B", [0, 1, 2, 0, 2, 7], 5121, "SCALAR")
    textured(d, {"bufferView": d.view(png()), "mimeType": "image/png"})
    d.j["meshes"] = [{"primitives": [p]}]
    scene(d)
    seeds["lie_index_out_of_range.glb"] = d.glb()
    g = bytearray(d.glb())
    struct.pack_into("<I", g, 12, len(g))
    seeds["lie_json_chunk_length.glb"] = bytes(g)
    d.j["accessors"][0]["count"] = 4000000000
    seeds["lie_accessor_count.glb"] = d.glb()
    for name, data in seeds.items():
        with open(os.path.join(OUT, name), "wb") as f:
            f.write(data)


main()
