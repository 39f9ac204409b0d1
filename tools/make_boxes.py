#!/usr/bin/env python3
"""A city tile of N separate boxes (12 triangles each) sharing one 512x512 texture: a stress model for
many components (GIS tiles, a scan's floaters). Each box face has its own 8x8-texel chart at a random
place in the texture (charts of different boxes overlap), so the input uses far fewer texels than its
faces sample. Deterministic for a seed.

Usage: tools/make_boxes.py N OUTDIR [--seed 3] [--extent 300]
Writes OUTDIR/boxes.obj, boxes.mtl, boxes.png (BENCHMARKS.md, "Scale").
"""
import argparse
import os
import random
import struct
import zlib


def write_png(path, w, h, pixel):
    rows = []
    for y in range(h):
        row = bytearray([0])
        for x in range(w):
            row += bytes(pixel(x, y))
        rows.append(bytes(row))

    def chunk(kind, data):
        return struct.pack('>I', len(data)) + kind + data + struct.pack('>I', zlib.crc32(kind + data) & 0xffffffff)

    with open(path, 'wb') as f:
        f.write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0)) +
                chunk(b'IDAT', zlib.compress(b''.join(rows), 6)) + chunk(b'IEND', b''))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('n', type=int)
    ap.add_argument('outdir')
    ap.add_argument('--seed', type=int, default=3)
    ap.add_argument('--extent', type=float, default=300.0, help='the boxes lie in an extent x extent square')
    a = ap.parse_args()
    if a.n < 1:
        ap.error('N must be at least 1')
    os.makedirs(a.outdir, exist_ok=True)
    write_png(os.path.join(a.outdir, 'boxes.png'), 512, 512, lambda x, y: ((x * 7 + y * 3) % 256, (x ^ y) % 256, (x * y // 64) % 256))
    with open(os.path.join(a.outdir, 'boxes.mtl'), 'w') as f:
        f.write('newmtl a\nmap_Kd boxes.png\n')
    rnd = random.Random(a.seed)
    out = ['mtllib boxes.mtl', 'usemtl a']
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    s = 0.015  # a face's chart: 7.7 texels square
    for i in range(a.n):
        cx, cy = rnd.uniform(0, a.extent), rnd.uniform(0, a.extent)
        sx, sy, sz = [rnd.uniform(0.5, 3) for _ in range(3)]
        for dx in (0, 1):
            for dy in (0, 1):
                for dz in (0, 1):
                    out.append('v %f %f %f' % (cx + dx * sx, cy + dy * sy, dz * sz))
        u0, v0 = rnd.uniform(0, 0.9), rnd.uniform(0, 0.9)
        for k, q in enumerate(faces):
            u, v = u0 + (k % 3) * s, v0 + (k // 3) * s
            out += ['vt %f %f' % p for p in [(u, v), (u + s, v), (u + s, v + s), (u, v + s)]]
            vi = [8 * i + q[j] + 1 for j in range(4)]
            ti = [24 * i + 4 * k + j + 1 for j in range(4)]
            out.append('f %d/%d %d/%d %d/%d' % (vi[0], ti[0], vi[1], ti[1], vi[2], ti[2]))
            out.append('f %d/%d %d/%d %d/%d' % (vi[0], ti[0], vi[2], ti[2], vi[3], ti[3]))
    with open(os.path.join(a.outdir, 'boxes.obj'), 'w') as f:
        f.write('\n'.join(out) + '\n')


if __name__ == '__main__':
    main()
