#!/usr/bin/env python3
"""Writes the seed meshes of fuzz/corpus/fuzz_pipeline in the byte format of mesh_from_bytes
(fuzz/targets.hpp): flags, vertex count - 3, triangle count - 1, scale index | map << 3 | splits << 5, [-s/-o bytes],
vertices (3 int8, coordinate = b / 8), triangles (3 indices), corner UVs (2 bytes, byte / 255)."""
import math
import os
import struct

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus", "fuzz_pipeline")
TEXTURED, ONE_TEXEL, PER_COMPONENT, HOLES_CUT, WIDE_UV, SO = 4, 8, 1, 2, 64, 128
SIZE = {64: 0, 16: 16, 8: 32, 128: 48}
MAP = {"detail": 0, "area": 1, "texel": 2, "harmonic": 3}


def write(name, verts, tris, uvs, flags=TEXTURED, size=64, scale=0, so=None, map="detail", splits=0):
    assert 3 <= len(verts) <= 64 and 1 <= len(tris) <= 64 and len(uvs) == 3 * len(tris) and 0 <= splits <= 2
    b = bytes([flags | SIZE[size] | (SO if so else 0), len(verts) - 3, len(tris) - 1, scale | MAP[map] << 3 | splits << 5])
    if so:
        b += struct.pack("4b", *so)
    for v in verts:
        b += struct.pack("3b", *[max(-128, min(127, round(c * 8))) for c in v])
    for t in tris:
        b += bytes(t)
    for u, v in uvs:
        b += bytes([max(0, min(255, round(u * 255))), max(0, min(255, round(v * 255)))])
    with open(os.path.join(OUT, name), "wb") as f:
        f.write(b)


def per_vertex_uv(verts, tris, uv):
    return [uv(verts[i]) for t in tris for i in t]


def grid(n, holes=()):
    verts = [(i, j, 0.25 * ((i * j) % 3)) for j in range(n) for i in range(n)]
    tris = []
    for j in range(n - 1):
        for i in range(n - 1):
            if (i, j) in holes:
                continue
            a = j * n + i
            tris += [(a, a + 1, a + n + 1), (a, a + n + 1, a + n)]
    return verts, tris


def torus(nu, nv, r1=3.0, r2=1.0):
    verts = []
    for j in range(nv):
        for i in range(nu):
            a, b = 2 * math.pi * i / nu, 2 * math.pi * j / nv
            verts.append(((r1 + r2 * math.cos(b)) * math.cos(a), (r1 + r2 * math.cos(b)) * math.sin(a), r2 * math.sin(b)))
    tris = []
    for j in range(nv):
        for i in range(nu):
            a, b, c, d = j * nu + i, j * nu + (i + 1) % nu, ((j + 1) % nv) * nu + (i + 1) % nu, ((j + 1) % nv) * nu + i
            tris += [(a, b, c), (a, c, d)]
    return verts, tris


def main():
    os.makedirs(OUT, exist_ok=True)
    v, t = grid(5)
    uv = lambda p: (p[0] / 4, p[1] / 4)
    write("grid", v, t, per_vertex_uv(v, t, uv))
    write("grid_per_component_cut_so", v, t, per_vertex_uv(v, t, uv), TEXTURED | PER_COMPONENT | HOLES_CUT, 16, so=(32, 16, 8, -8))
    v, t = grid(6, holes={(1, 1), (3, 3), (3, 1)})
    write("grid_holes", v, t, per_vertex_uv(v, t, lambda p: (p[0] / 5, p[1] / 5)), TEXTURED | WIDE_UV, 128)
    write("grid_tiny_scale", *grid(4), per_vertex_uv(*grid(4), lambda p: (p[0] / 3, p[1] / 3)), TEXTURED, 8, scale=7)
    write("grid_huge_scale", *grid(4), per_vertex_uv(*grid(4), lambda p: (p[0] / 3, p[1] / 3)), 0, 64, scale=6)
    tet_v = [(0, 0, 0), (4, 0, 0), (0, 4, 0), (0, 0, 4)]
    tet_t = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)]
    write("tetrahedron", tet_v, tet_t, [(0.1, 0.1), (0.9, 0.1), (0.5, 0.9)] * 4, TEXTURED | ONE_TEXEL)
    cube_v = [(x, y, z) for z in (0, 4) for y in (0, 4) for x in (0, 4)]
    cube_t = [(0, 2, 3), (0, 3, 1), (4, 5, 7), (4, 7, 6), (0, 1, 5), (0, 5, 4), (2, 6, 7), (2, 7, 3), (0, 4, 6), (0, 6, 2), (1, 3, 7), (1, 7, 5)]
    uvs = []
    for k in range(12):
        x0, y0 = (k // 2 % 3) / 3, (k // 6) / 2
        uvs += [(x0, y0), (x0 + 0.3, y0), (x0 + 0.3, y0 + 0.45)] if k % 2 == 0 else [(x0, y0), (x0 + 0.3, y0 + 0.45), (x0, y0 + 0.45)]
    write("cube_charts", cube_v, cube_t, uvs)
    v, t = torus(6, 4)
    write("torus", v, t, per_vertex_uv(v, t, lambda p: ((math.atan2(p[1], p[0]) + math.pi) / (2 * math.pi), (p[2] + 1) / 2)))
    # Bowtie (two triangles sharing one vertex) and a floating triangle.
    v = [(0, 0, 0), (2, 0, 0), (1, 2, 0), (3, 2, 0), (4, 0, 0), (8, 8, 8), (9, 8, 8), (8, 9, 8)]
    t = [(0, 1, 2), (2, 3, 4), (5, 6, 7)]
    write("bowtie_floater", v, t, per_vertex_uv(v, t, lambda p: ((p[0] % 5) / 5, (p[1] % 5) / 5)), 0)
    # Mobius strip: 6 segments.
    n = 6
    v = []
    for i in range(n):
        a = 2 * math.pi * i / n
        for s in (-1, 1):
            w = s * math.cos(a / 2)
            v.append(((4 + w) * math.cos(a), (4 + w) * math.sin(a), s * math.sin(a / 2)))
    t = []
    for i in range(n):
        a, b = 2 * i, 2 * i + 1
        c, d = (2 * i + 2, 2 * i + 3) if i + 1 < n else (1, 0)
        t += [(a, c, b), (b, c, d)]
    write("mobius", v, t, per_vertex_uv(v, t, lambda p: ((math.atan2(p[1], p[0]) + math.pi) / (2 * math.pi), 0.5 + p[2] / 2)))
    # Three triangles on one edge (non-manifold), a duplicate, and a zero-area triangle.
    v = [(0, 0, 0), (4, 0, 0), (2, 3, 0), (2, -3, 0), (2, 0, 3), (6, 0, 0)]
    t = [(0, 1, 2), (1, 0, 3), (0, 1, 4), (0, 1, 2), (0, 1, 5)]
    write("non_manifold", v, t, per_vertex_uv(v, t, lambda p: (p[0] / 6, (p[1] + 3) / 6)))
    v = [(0, 0, 0), (1, 0, 0), (2, 0, 0)]
    write("only_degenerate", v, [(0, 1, 2)], [(0, 0), (0.5, 0), (1, 1)])
    # The other maps, on meshes split to 128..1024 triangles (the area map's density-equalising flow
    # starts at 100 faces; holes cut into the boundary make its reweighting stall).
    v, t = grid(6, holes={(1, 1), (3, 3), (3, 1)})
    uv = per_vertex_uv(v, t, lambda p: (p[0] / 5, p[1] / 5))
    write("grid_holes_cut_area_split2", v, t, uv, TEXTURED | HOLES_CUT, 128, map="area", splits=2)
    write("grid_holes_texel_split1", v, t, uv, TEXTURED, 64, map="texel", splits=1)
    v, t = torus(8, 4)
    uv = per_vertex_uv(v, t, lambda p: ((math.atan2(p[1], p[0]) + math.pi) / (2 * math.pi), (p[2] + 1) / 2))
    write("torus_area_split2", v, t, uv, TEXTURED, 128, map="area", splits=2)
    write("torus_harmonic_split1", v, t, uv, TEXTURED, 64, map="harmonic", splits=1)


main()
