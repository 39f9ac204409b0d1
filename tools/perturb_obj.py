#!/usr/bin/env python3
"""Make a messy variant of a textured OBJ, as unseen scans come: for robustness sweeps (bench/perturbed.sh).

Usage: tools/perturb_obj.py IN.obj OUT_DIR MODE [SEED]
MODE:
  pepper   0.5% of the triangles removed at random: about as many small holes
  patches  six patches of about 1% of the triangles each removed: six larger holes
  noise    every position jittered by up to 20% of the mean edge length: slivers, near-degenerates
  flip     2% of the triangles wound the other way (their corners reversed, texture coordinates too)
The OBJ is written to OUT_DIR under its own name; the input's other files (MTL, textures) are linked
beside it, so the copy reads as the original does. The input is never touched.
"""
import math
import os
import random
import sys


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    src, out, mode = sys.argv[1], sys.argv[2], sys.argv[3]
    rng = random.Random(int(sys.argv[4]) if len(sys.argv) > 4 else 7)
    os.makedirs(out, exist_ok=True)
    d = os.path.dirname(os.path.abspath(src))
    for f in os.listdir(d):
        if not f.endswith('.obj') and os.path.isfile(os.path.join(d, f)):
            dst = os.path.join(out, f)
            if not os.path.lexists(dst):
                os.symlink(os.path.join(d, f), dst)
    lines = open(src).read().split('\n')
    vlines = [i for i, l in enumerate(lines) if l.startswith('v ')]
    flines = [i for i, l in enumerate(lines) if l.startswith('f ')]

    def corners(i):
        return [int(t.split('/')[0]) for t in lines[i].split()[1:]]

    def vindex(k):  # OBJ index (1-based or negative) -> position list index
        return k - 1 if k > 0 else len(vlines) + k

    drop = set()
    if mode == 'pepper':
        drop = set(rng.sample(flines, max(1, len(flines) // 200)))
    elif mode == 'patches':
        fv = {i: [vindex(k) for k in corners(i)] for i in flines}
        around = {}
        for i in flines:
            for v in fv[i]:
                around.setdefault(v, []).append(i)
        for _ in range(6):
            seed = rng.choice(flines)
            queue, seen, qi = [seed], {seed}, 0
            while qi < len(queue) and len(seen) < len(flines) // 100:
                for v in fv[queue[qi]]:
                    for n in around[v]:
                        if n not in seen:
                            seen.add(n)
                            queue.append(n)
                qi += 1
            drop |= seen
    elif mode == 'noise':
        pos = [list(map(float, lines[i].split()[1:4])) for i in vlines]
        total, n = 0.0, 0
        for i in flines[:2000]:
            c = [vindex(k) for k in corners(i)]
            for k in range(len(c)):
                total += math.dist(pos[c[k]], pos[c[(k + 1) % len(c)]])
                n += 1
        e = 0.2 * total / max(n, 1)
        for i in vlines:
            parts = lines[i].split()
            p = [float(x) + rng.uniform(-e, e) for x in parts[1:4]]
            lines[i] = 'v ' + ' '.join('%.7g' % x for x in p) + ''.join(' ' + x for x in parts[4:])
    elif mode == 'flip':
        for i in rng.sample(flines, len(flines) // 50):
            t = lines[i].split()
            lines[i] = 'f ' + ' '.join(reversed(t[1:]))
    else:
        sys.exit('unknown mode ' + mode)
    with open(os.path.join(out, os.path.basename(src)), 'w') as f:
        f.write('\n'.join(l for i, l in enumerate(lines) if i not in drop))


if __name__ == '__main__':
    main()
