#!/usr/bin/env python3
"""What turning a texture's content costs WebP: a window of an image is rotated about its centre by each
angle (bicubic), the central part that every rotation fills is encoded at WebP qualities 50..100, and the
bytes at a given image PSNR are interpolated on each angle's curve. Used for BENCHMARKS.md "Bytes" (why a
re-baked atlas of printed packaging costs more than its axis-aligned input). Needs python3-pil.

  tools/webp_rotation_cost.py IMAGE X0,Y0,X1,Y1 [PSNR_DB ...]     (default PSNRs: 36 38)
"""
import io
import math
import sys

import numpy as np
from PIL import Image

ANGLES = (0, 5, 15, 30, 45)
QUALITIES = range(50, 101, 5)


def encode(image, quality):
    """Bytes of `image` as lossy WebP at `quality`, and the decoded image's PSNR against it."""
    buffer = io.BytesIO()
    image.save(buffer, "WEBP", quality=quality)
    size = buffer.tell()
    buffer.seek(0)
    decoded = np.asarray(Image.open(buffer).convert("RGB"), float)
    mse = ((np.asarray(image, float) - decoded) ** 2).mean()
    return size, 10 * math.log10(255.0**2 / max(mse, 1e-12))


def bytes_at(curve, psnr):
    """The curve's bytes at `psnr` (linear between its qualities), or NaN outside it."""
    for (b0, p0), (b1, p1) in zip(curve, curve[1:]):
        if min(p0, p1) <= psnr <= max(p0, p1) and p0 != p1:
            return b0 + (b1 - b0) * (psnr - p0) / (p1 - p0)
    return float("nan")


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    window = Image.open(sys.argv[1]).convert("RGB").crop(tuple(int(v) for v in sys.argv[2].split(",")))
    targets = [float(v) for v in sys.argv[3:]] or [36.0, 38.0]
    w, h = window.size
    centre = (w // 2 - w // 3, h // 2 - h // 3, w // 2 + w // 3, h // 2 + h // 3)
    print("angle | " + " | ".join("KiB at %.1f dB" % t for t in targets))
    baseline = None
    for angle in ANGLES:
        turned = window.rotate(angle, resample=Image.BICUBIC).crop(centre)
        curve = [encode(turned, q) for q in QUALITIES]
        sizes = [bytes_at(curve, t) / 1024 for t in targets]
        baseline = baseline or sizes
        print("%d | " % angle + " | ".join("%.0f (%.2fx)" % (s, s / b) for s, b in zip(sizes, baseline)))


if __name__ == "__main__":
    main()
