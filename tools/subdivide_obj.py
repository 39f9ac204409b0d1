#!/usr/bin/env python3
"""Subdivide a textured OBJ: each triangle into four at its edges' midpoints (positions and texture
coordinates alike), LEVELS times, so a real scan grows 4x per level with the same surface and texture:
for scaling runs (bench/scale.sh). Normals are dropped; polygons are split into fans first.

Usage: tools/subdivide_obj.py IN.obj OUT_DIR LEVELS
The OBJ is written to OUT_DIR under its own name; the input's other files (MTL, textures) are linked
beside it, so the copy reads as the original does. The input is never touched.
"""
import os
import sys


def read_obj(path):
    """Positions, texture coordinates and the other lines in order, faces as lists of (v, vt) 0-based."""
    pos, tex, items = [], [], []
    with open(path) as f:
        for line in f:
            if line.startswith('v '):
                pos.append(line.split()[1:4])
            elif line.startswith('vt '):
                tex.append(line.split()[1:3])
            elif line.startswith('f '):
                corners = []
                for c in line.split()[1:]:
                    p = c.split('/')
                    v = int(p[0])
                    t = int(p[1]) if len(p) > 1 and p[1] else 0
                    corners.append((v - 1 if v > 0 else len(pos) + v, t - 1 if t > 0 else (len(tex) + t if t < 0 else -1)))
                for k in range(1, len(corners) - 1):
                    items.append((corners[0], corners[k], corners[k + 1]))
            elif not line.startswith('vn ') and line.strip():
                items.append(line)
    return [tuple(map(float, p)) for p in pos], [tuple(map(float, t)) for t in tex], items


def subdivide(pos, tex, items):
    """One level of 1:4 midpoint subdivision."""
    mid_v, mid_t = {}, {}

    def midpoint(table, points, a, b):
        if a < 0 or b < 0:
            return -1
        key = (a, b) if a < b else (b, a)
        i = table.get(key)
        if i is None:
            pa, pb = points[a], points[b]
            i = table[key] = len(points)
            points.append(tuple((x + y) * 0.5 for x, y in zip(pa, pb)))
        return i

    out = []
    for it in items:
        if isinstance(it, str):
            out.append(it)
            continue
        (v0, t0), (v1, t1), (v2, t2) = it
        m01 = (midpoint(mid_v, pos, v0, v1), midpoint(mid_t, tex, t0, t1))
        m12 = (midpoint(mid_v, pos, v1, v2), midpoint(mid_t, tex, t1, t2))
        m20 = (midpoint(mid_v, pos, v2, v0), midpoint(mid_t, tex, t2, t0))
        out += [((v0, t0), m01, m20), (m01, (v1, t1), m12), (m20, m12, (v2, t2)), (m01, m12, m20)]
    return out


def write_obj(path, pos, tex, items):
    with open(path, 'w') as f:
        f.write(''.join('v %.7g %.7g %.7g\n' % p for p in pos))
        f.write(''.join('vt %.7g %.7g\n' % t for t in tex))
        for it in items:
            if isinstance(it, str):
                f.write(it if it.endswith('\n') else it + '\n')
            else:
                f.write('f ' + ' '.join('%d/%d' % (v + 1, t + 1) if t >= 0 else '%d' % (v + 1) for v, t in it) + '\n')


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    src, out, levels = sys.argv[1], sys.argv[2], int(sys.argv[3])
    os.makedirs(out, exist_ok=True)
    d = os.path.dirname(os.path.abspath(src))
    for f in os.listdir(d):
        if not f.endswith('.obj') and os.path.isfile(os.path.join(d, f)):
            dst = os.path.join(out, f)
            if not os.path.lexists(dst):
                os.symlink(os.path.join(d, f), dst)
    pos, tex, items = read_obj(src)
    for _ in range(levels):
        items = subdivide(pos, tex, items)
    write_obj(os.path.join(out, os.path.basename(src)), pos, tex, items)


if __name__ == '__main__':
    main()
