#!/usr/bin/python3
"""Error of linear renders against a reference render of the same scene (docs/accuracy.md, "Render denoising").

  render_error.py [--box N] [--gradient] REF.exr RUN.exr...

Each EXR is a `solo night --render-exr` output (linear XYZ, render units) with its light-id AOV
beside it (STEM.lightid.npy). Over the pixels whose light id is 0 in both images, on the
luminance Y: relative RMSE sqrt(sum (y - r)^2 / sum r^2) and mean ratio sum y / sum r, unclipped
and clipped at the reference's white W (95th percentile of its Y / 0.8, the clip level of the
render error in docs/accuracy.md). With --box N, also the clipped error at low spatial frequency:
the same relative RMSE over the means of N x N pixel boxes (tiled from the top-left corner; a
box's mean over its kept pixels, each box weighted by their count). With --gradient, also the
clipped error at the highest spatial frequency: sqrt(sum (dt - dr)^2 / sum r^2) over the
differences d of horizontally and vertically adjacent kept pixels (blocks and grids a filter
prints raise it; a smooth error does not). Needs oiiotool (openimageio-tools, in tools/setup.sh) and
numpy (Debian python3-numpy, not needed by the build or the tests).
"""
import os
import subprocess
import sys
import tempfile

import numpy as np


def read_exr(path):
    """H x W x C float64 array of an EXR, through oiiotool's FITS writer (rows bottom-up there)."""
    with tempfile.TemporaryDirectory() as tmp:
        fits = os.path.join(tmp, "image.fits")
        subprocess.run(["oiiotool", path, "-d", "float", "-o", fits], check=True)
        raw = open(fits, "rb").read()
    header, offset = {}, 0
    while True:
        cards = [raw[offset + i:offset + i + 80].decode() for i in range(0, 2880, 80)]
        offset += 2880
        for card in cards:
            if card[8:10] == "= ":
                header[card[:8].strip()] = card[10:].split("/")[0].strip()
        if any(card.startswith("END") for card in cards):
            break
    dims = [int(header["NAXIS%d" % (i + 1)]) for i in range(int(header["NAXIS"]))]
    count = int(np.prod(dims))
    image = np.frombuffer(raw[offset:offset + 4 * count], dtype=">f4").astype(np.float64).reshape(dims[::-1])
    return image[::-1]


def load(exr):
    stem = exr[:-len(".exr")]
    return read_exr(exr)[..., 1], np.load(stem + ".lightid.npy")


def box_error(test, ref, keep, box):
    """Relative RMSE of the box means of `test` against `ref` over the kept pixels."""
    h, w = ref.shape
    hb, wb = -(-h // box), -(-w // box)
    def sums(a):
        padded = np.zeros((hb * box, wb * box))
        padded[:h, :w] = a
        return padded.reshape(hb, box, wb, box).sum(axis=(1, 3))
    n = sums(keep.astype(np.float64))
    used = n > 0
    mt = sums(np.where(keep, test, 0.0))[used] / n[used]
    mr = sums(np.where(keep, ref, 0.0))[used] / n[used]
    return np.sqrt((n[used] * (mt - mr) ** 2).sum() / (n[used] * mr ** 2).sum())


def gradient_error(test, ref, keep):
    """Relative RMSE of the differences of adjacent kept pixels of `test` against `ref`."""
    num = 0.0
    for axis in (0, 1):
        pair = np.logical_and(np.delete(keep, 0, axis), np.delete(keep, -1, axis))
        diff = np.diff(test, axis=axis) - np.diff(ref, axis=axis)
        num += (diff[pair] ** 2).sum()
    return np.sqrt(num / (ref[keep] ** 2).sum())


def main(argv):
    box, gradient = 0, False
    while len(argv) > 1 and argv[1] in ("--box", "--gradient"):
        if argv[1] == "--box":
            box = int(argv[2])
            argv = argv[:1] + argv[3:]
        else:
            gradient = True
            argv = argv[:1] + argv[2:]
    if len(argv) < 3:
        sys.exit(__doc__)
    ref_y, ref_id = load(argv[1])
    white = np.percentile(ref_y[ref_id == 0], 95) / 0.8
    print(f"reference {argv[1]}: white W = {white:.4g}")
    print("run".ljust(28) + "rel.RMSE  mean ratio  rel.RMSE(clip W)  mean ratio(clip W)" +
          (f"  boxes {box}x{box} (clip W)" if box else "") + ("  gradient (clip W)" if gradient else ""))
    for exr in argv[2:]:
        y, light_id = load(exr)
        keep = (light_id == 0) & (ref_id == 0)
        r, t = ref_y[keep], y[keep]
        rc, tc = np.minimum(r, white), np.minimum(t, white)
        rmse = np.sqrt(((t - r) ** 2).sum() / (r ** 2).sum())
        rmse_clipped = np.sqrt(((tc - rc) ** 2).sum() / (rc ** 2).sum())
        line = (f"{os.path.basename(exr)[:27]:28s}{rmse:8.4f}  {t.sum() / r.sum():10.4f}  {rmse_clipped:16.4f}  "
                f"{tc.sum() / rc.sum():18.4f}")
        if box:
            both = (light_id == 0) & (ref_id == 0)
            line += f"  {box_error(np.minimum(y, white), np.minimum(ref_y, white), both, box):20.4f}"
        if gradient:
            line += f"  {gradient_error(np.minimum(y, white), np.minimum(ref_y, white), keep):18.4f}"
        print(line)


if __name__ == "__main__":
    main(sys.argv)
