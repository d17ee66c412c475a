#!/usr/bin/env python3
"""Compare sasnav images of the AirSAS recording with the authors' reference.

usage: python3 examples/airsas_compare.py REFERENCE.h5 IMAGE.h5 [IMAGE.h5 ...]

REFERENCE.h5 is ../shared/data/airsas/reference_das_small_features_20k.h5
(datasets real, imag: image[iy][ix] at (x[ix], y[iy]), 400 x 400 over
+-0.3 m); each IMAGE.h5 is the output of
`sasnav image airsas.h5 [--nav NAV.h5] --grid -0.3,0.3,400,-0.3,0.3,400 -o IMAGE.h5`
(the same grid). Prints, over the 0.3 m circle (the pixels the authors
image), the coherent normalised correlation |<a, b>| / (|a| |b|) of the
complex images (phase-sensitive: what a navigation error spoils first) and
the correlation of their magnitudes <|a|, |b|> / (|a| |b|) (what a viewer
compares). docs/airsas.md lists the values for the turntable's navigation,
a drifted one and the estimated ones. Needs Debian's python3-numpy and
python3-h5py.
"""
import sys

import h5py
import numpy as np


def read_image(path):
    with h5py.File(path, "r") as f:
        d = f["image"][()]
    return d if np.iscomplexobj(d) else d["r"] + 1j * d["i"]


def main(argv):
    if len(argv) < 3:
        sys.stderr.write(__doc__)
        return 2
    with h5py.File(argv[1], "r") as f:
        ref = f["real"][()] + 1j * f["imag"][()]
        x, y = f["x"][()], f["y"][()]
    xx, yy = np.meshgrid(x, y)
    mask = xx**2 + yy**2 <= 0.3**2
    status = 0
    for path in argv[2:]:
        try:
            img = read_image(path)
        except (OSError, KeyError) as e:
            sys.stderr.write(f"airsas_compare: cannot read {path}: {e}\n")
            status = 1
            continue
        if img.shape != ref.shape:
            sys.stderr.write(f"airsas_compare: {path} is {img.shape}, the reference {ref.shape}: "
                             "image on --grid -0.3,0.3,400,-0.3,0.3,400\n")
            status = 1
            continue
        r, b = ref[mask], img[mask]
        nr, nb = np.linalg.norm(r), np.linalg.norm(b)
        if not (nr > 0 and nb > 0):
            sys.stderr.write(f"airsas_compare: {path}: an image is zero on the circle\n")
            status = 1
            continue
        coherent = abs(np.vdot(r, b)) / (nr * nb)
        magnitude = np.dot(abs(r), abs(b)) / (nr * nb)
        print(f"{path}: coherent |NCC| {coherent:.3f}, magnitude NCC {magnitude:.3f}")
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv))
