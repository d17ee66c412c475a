#!/usr/bin/env python3
"""Image focus metrics against smooth navigation errors (docs/airsas.md,
"Tried and dropped: autofocus on the image's sharpness").

usage: PYTHONPATH=python/src SASNAV_LIBRARY=build/libsasnav.so \
       python3 bench/focus_metrics.py RUN.h5|circular [--radius M] [--pixels N]

Backprojects the run on an N x N grid over +-radius (default 0.3 m, 200)
with its navigation (a run file: its /nav, e.g. the AirSAS turntable; the
word `circular`: the simulated AirSAS, seed 201, 30 dB, with its true
poses) and with that navigation plus, in each ping's frame, the smooth
drift of `bench_virtual --drift` scaled by a factor (surge 2.5 and sway
1.5 cycles over the run, 5 mm), or a constant sway (a radius error on a
circle). Prints, over the disc of the grid, the image entropy of |I|^2
(lower = sharper) and the sharpness sum |I|^4 / (sum |I|^2)^2 x pixels
(higher = sharper). An autofocus can only recover a navigation at which
these metrics have their optimum. Needs Debian's python3-numpy.
"""
import argparse

import numpy as np

import sasnav


def shifted(nav, du, dv):
    """nav [n][6] moved by du along and dv across each pose's heading."""
    out = nav.copy()
    for b in (0, 3):
        th = nav[:, b + 2]
        out[:, b] += du * np.cos(th) - dv * np.sin(th)
        out[:, b + 1] += du * np.sin(th) + dv * np.cos(th)
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run")
    ap.add_argument("--radius", type=float, default=0.3)
    ap.add_argument("--pixels", type=int, default=200)
    a = ap.parse_args()
    if a.run == "circular":
        run = sasnav.simulate("circular", seed=201, snr=30)
        nav = run.truth
    else:
        run = sasnav.read_run(a.run)
        nav = run.nav
    nav0 = np.array(nav.tolist(), dtype=float).reshape(-1, 6)
    n, r, nx = nav0.shape[0], a.radius, a.pixels
    u = np.arange(n) / max(n - 1, 1)
    xs = np.linspace(-r, r, nx)
    xx, yy = np.meshgrid(xs, xs)
    disc = xx**2 + yy**2 <= r * r

    def metrics(nv):
        im = sasnav.image(run, (-r, r, nx, -r, r, nx), nv, threads=2).data
        p2 = np.abs(im[disc]) ** 2
        p = p2 / p2.sum()
        return -(p * np.log(p + 1e-30)).sum(), (p2**2).sum() / p2.sum() ** 2 * p2.size

    print(f"# {a.run}: {n} pings, grid {nx} x {nx} over +-{r} m; entropy / sharpness")
    for name, su, sv in (("surge drift", 1, 0), ("sway drift", 0, 1)):
        for f in (-1, -0.5, 0, 0.5, 1):
            e, s = metrics(shifted(nav0, su * f * 5e-3 * np.sin(5 * np.pi * u),
                                   sv * f * 5e-3 * np.sin(3 * np.pi * u)))
            print(f"{name:12s} x {f:+4.1f}: {e:.4f} {s:8.3f}")
    for c in (-8, -4, -2, 0, 2, 4, 8):
        e, s = metrics(shifted(nav0, 0 * u, c * 1e-3 + 0 * u))
        print(f"sway {c:+3d} mm     : {e:.4f} {s:8.3f}")


if __name__ == "__main__":
    main()
