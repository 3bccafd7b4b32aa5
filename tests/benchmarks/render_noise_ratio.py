#!/usr/bin/python3
"""Render noise against the camera's noise in a night image (docs/rendering.md, "Rendering below
the image size").

  render_noise_ratio.py A_NO_NOISE.png B_NO_NOISE.png A_NOISE.png

A_NO_NOISE and B_NO_NOISE are `solo night --no-noise` images of one scene, light record and
exposure (`--lights`, `--sensor-white`) at two seeds (`--seed`: with the light record given, it
changes the render's samples and the sensor noise only); A_NOISE is A's run
with the sensor noise. On the 8-bit luma Y' = 0.299 R' + 0.587 G' + 0.114 B' of the pixels whose
luma lies between 2 and 250 in all three: the render noise (A - B) / sqrt 2 and the camera noise
A_NOISE - A, their RMS and its ratio, and over 16x16 pixel blocks the median of the blocks'
ratios and the share of blocks whose render noise is below the camera's. Needs oiiotool
(openimageio-tools, in tools/setup.sh) and numpy (Debian python3-numpy).
"""
import os
import subprocess
import sys
import tempfile

import numpy as np


def read_luma(path):
    """H x W 8-bit luma of an sRGB PNG, through oiiotool's binary PPM writer."""
    with tempfile.TemporaryDirectory() as tmp:
        ppm = os.path.join(tmp, "image.ppm")
        subprocess.run(["oiiotool", path, "--ch", "R,G,B", "-d", "uint8", "-o", ppm], check=True)
        raw = open(ppm, "rb").read()
    fields, offset = [], 0
    while len(fields) < 4:  # P6, width, height, maxval
        while raw[offset:offset + 1].isspace():
            offset += 1
        end = offset
        while not raw[end:end + 1].isspace():
            end += 1
        fields.append(raw[offset:end])
        offset = end
    width, height = int(fields[1]), int(fields[2])
    rgb = np.frombuffer(raw[offset + 1:offset + 1 + 3 * width * height], dtype=np.uint8)
    rgb = rgb.reshape(height, width, 3).astype(np.float64)
    return 0.299 * rgb[..., 0] + 0.587 * rgb[..., 1] + 0.114 * rgb[..., 2]


def block_stats(render, camera, keep, block=16):
    """Median over 16x16 blocks of render RMS / camera RMS, and the share of blocks below 1."""
    h, w = keep.shape
    ratios = []
    for y in range(0, h - block + 1, block):
        for x in range(0, w - block + 1, block):
            k = keep[y:y + block, x:x + block]
            if k.sum() < block * block // 2:
                continue
            cam = np.sqrt((camera[y:y + block, x:x + block][k] ** 2).mean())
            if cam <= 0:
                continue
            ratios.append(np.sqrt((render[y:y + block, x:x + block][k] ** 2).mean()) / cam)
    ratios = np.array(ratios)
    return np.median(ratios), (ratios < 1).mean()


def main(argv):
    if len(argv) != 4:
        sys.exit(__doc__)
    a, b, a_noise = (read_luma(p) for p in argv[1:])
    if not (a.shape == b.shape == a_noise.shape):
        sys.exit("render_noise_ratio.py: the three images differ in size")
    keep = np.ones(a.shape, dtype=bool)
    for image in (a, b, a_noise):
        keep &= (image >= 2) & (image <= 250)
    render = (a - b) / np.sqrt(2)
    camera = a_noise - a
    render_rms = np.sqrt((render[keep] ** 2).mean())
    camera_rms = np.sqrt((camera[keep] ** 2).mean())
    median, share = block_stats(render, camera, keep)
    print(f"pixels {keep.sum()} of {keep.size}")
    print(f"render noise RMS {render_rms:.2f}, camera noise RMS {camera_rms:.2f}, ratio {render_rms / camera_rms:.2f}")
    print(f"16 px blocks: median ratio {median:.2f}, share with render < camera {100 * share:.0f} %")


if __name__ == "__main__":
    main(sys.argv)
