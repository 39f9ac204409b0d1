#!/usr/bin/env python3
"""Draws the texture layout of tightex outputs as an SVG, one panel per model, each triangle at its
output uv filled by its angle distortion (docs/metrics.md: sigma_max / sigma_min of its 3D-to-UV Jacobian;
white = conformal, dark red = 8 or more, log scale). Used for docs/corners.md; no dependencies.

  tools/uv_distortion_svg.py OUT.svg "TITLE=OUTDIR/model.obj" ["TITLE=..." ...]
"""
import math
import sys


def read_obj(path):
    v, vt, faces = [], [], []
    with open(path) as f:
        for line in f:
            p = line.split()
            if not p:
                continue
            if p[0] == "v":
                v.append(tuple(map(float, p[1:4])))
            elif p[0] == "vt":
                vt.append(tuple(map(float, p[1:3])))
            elif p[0] == "f":
                corners = [c.split("/") for c in p[1:4]]
                faces.append(([int(c[0]) - 1 for c in corners], [int(c[1]) - 1 for c in corners]))
    return v, vt, faces


def distortion(p, q):
    """sigma_max / sigma_min of the affine map taking 3D triangle p onto uv triangle q."""
    e1 = [p[1][i] - p[0][i] for i in range(3)]
    e2 = [p[2][i] - p[0][i] for i in range(3)]
    l1 = math.sqrt(sum(x * x for x in e1))
    if l1 == 0:
        return float("inf")
    x = [c / l1 for c in e1]
    a = sum(e2[i] * x[i] for i in range(3))
    y = [e2[i] - a * x[i] for i in range(3)]
    b = math.sqrt(sum(c * c for c in y))
    if b == 0:
        return float("inf")
    # local 2D: P = [[l1, a], [0, b]]; uv edges: Q = [[du1, du2], [dv1, dv2]]; J = Q P^-1
    du1, dv1 = q[1][0] - q[0][0], q[1][1] - q[0][1]
    du2, dv2 = q[2][0] - q[0][0], q[2][1] - q[0][1]
    j11, j21 = du1 / l1, dv1 / l1
    j12, j22 = (du2 - a * j11) / b, (dv2 - a * j21) / b
    fro = j11 * j11 + j12 * j12 + j21 * j21 + j22 * j22
    det = abs(j11 * j22 - j12 * j21)
    if det == 0:
        return float("inf")
    disc = math.sqrt(max(fro * fro / 4 - det * det, 0))
    smax, smin = math.sqrt(fro / 2 + disc), math.sqrt(max(fro / 2 - disc, 0))
    return smax / smin if smin > 0 else float("inf")


def colour(d):
    t = min(math.log2(max(d, 1.0)) / 3.0, 1.0)  # 1 -> 0, 8 -> 1
    r = 255 - int(105 * t)
    g = b = 255 - int(255 * t)
    return f"#{r:02x}{g:02x}{b:02x}"


def main():
    out, panels = sys.argv[1], sys.argv[2:]
    size, pad, title_h = 320, 16, 40
    width = len(panels) * (size + pad) + pad
    svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{size + title_h + pad}" '
           f'font-family="sans-serif" font-size="13">', f'<rect width="{width}" height="{size + title_h + pad}" fill="white"/>']
    for k, panel in enumerate(panels):
        title, path = panel.split("=", 1)
        v, vt, faces = read_obj(path)
        x0 = pad + k * (size + pad)
        total_area = weighted = 0.0
        polys = []
        for fv, ft in faces:
            p = [v[i] for i in fv]
            q = [vt[i] for i in ft]
            d = distortion(p, q)
            e1 = [p[1][i] - p[0][i] for i in range(3)]
            e2 = [p[2][i] - p[0][i] for i in range(3)]
            c = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
            area = 0.5 * math.sqrt(sum(x * x for x in c))
            if math.isfinite(d):
                total_area += area
                weighted += area * d
            pts = " ".join(f"{x0 + u * size:.1f},{title_h + (1 - w) * size:.1f}" for u, w in q)
            polys.append(f'<polygon points="{pts}" fill="{colour(d)}" stroke="{colour(d)}" stroke-width="0.3"/>')
        mean = weighted / total_area if total_area else float("nan")
        svg.append(f'<text x="{x0}" y="16">{title}</text>')
        svg.append(f'<text x="{x0}" y="32" fill="#555">angle distortion, area-weighted mean {mean:.2f}</text>')
        svg.extend(polys)
        svg.append(f'<rect x="{x0}" y="{title_h}" width="{size}" height="{size}" fill="none" stroke="black" stroke-width="0.5"/>')
    svg.append("</svg>")
    with open(out, "w") as f:
        f.write("\n".join(svg) + "\n")


if __name__ == "__main__":
    main()
