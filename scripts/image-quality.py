#!/usr/bin/python3
"""Scores tcrwalk's measured frames against full detail: for every SELECTOR-FRAME.png in a
folder beside its reference-FRAME.png, SSIM (colour, scikit-image's structural_similarity) and
PSNR in dB (identical frames count as 99 dB), one JSON object per line on stdout.
Run by tcrwalk --quality-every; by hand: scripts/image-quality.py out/walk/run/quality"""
import json
import os
import re
import sys

from skimage.io import imread
from skimage.metrics import peak_signal_noise_ratio, structural_similarity

IDENTICAL_DB = 99.0


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: image-quality.py FOLDER")
    folder = sys.argv[1]
    pattern = re.compile(r"^(.+)-(\d+)\.png$")
    references = {}
    frames = []
    for name in sorted(os.listdir(folder)):
        m = pattern.match(name)
        if not m:
            continue
        if m.group(1) == "reference":
            references[int(m.group(2))] = os.path.join(folder, name)
        else:
            frames.append((m.group(1), int(m.group(2)), os.path.join(folder, name)))
    for selector, frame, path in frames:
        if frame not in references:
            sys.exit(f"image-quality: {path} has no reference-{frame:05d}.png")
        ref = imread(references[frame])[..., :3]
        img = imread(path)[..., :3]
        if ref.shape != img.shape:
            sys.exit(f"image-quality: {path} is {img.shape}, its reference {ref.shape}")
        if (ref == img).all():  # (PSNR's mean squared error would be 0)
            ssim, psnr = 1.0, IDENTICAL_DB
        else:
            ssim = float(structural_similarity(ref, img, channel_axis=2, data_range=255))
            psnr = float(peak_signal_noise_ratio(ref, img, data_range=255))
        print(json.dumps({"selector": selector, "frame": frame, "ssim": ssim, "psnr": psnr}))


if __name__ == "__main__":
    main()
