#!/usr/bin/env python3
"""Remove an across-track drift from the AirSAS navigation with the echoes,
in Python (docs/airsas.md, section 3, "--along-track input").

usage: python3 examples/airsas_drift.py airsas.h5 REFERENCE.h5 [--drift MM]
           [--shape sway|smooth] [--k K] [--threads T]

airsas.h5 is the recording ingested with `sasnav ingest --airsas` (its
navigation is the turntable's, taken as the truth); REFERENCE.h5 is
../shared/data/airsas/reference_das_small_features_20k.h5. The script adds
a smooth drift to the navigation in each ping's frame (default: the sway
part of `bench_virtual --drift 5`, 5 sin(3 pi u) mm across track, u from 0
at the first ping to 1 at the last; `--shape smooth` adds the surge part,
5 sin(5 pi u) mm along track), navigates with virtual arrays of K pings
(default 8, every other ping, closed loop, the steps' length from the
input, the along-track from the input and the across-track from the
echoes), and prints, for the drifted and the estimated navigation, the
rms position error along and across track after the least-squares rigid
fit onto the turntable's path (a navigation is known up to a rigid move)
and the |NCC| of the image with the authors' reference over the 0.3 m
circle (coherent, and of the magnitudes). About 10 minutes on two cores.
Needs the sasnav Python package (python/README.md), numpy and h5py.
"""
import argparse
import sys

import h5py
import numpy as np

import sasnav


def compose(poses, d):
    """Each pose of a POSE_DTYPE array moved by d = (dx, dy) in its own frame."""
    out = poses.copy()
    c, s = np.cos(poses["theta"]), np.sin(poses["theta"])
    out["x"] = poses["x"] + c * d[:, 0] - s * d[:, 1]
    out["y"] = poses["y"] + s * d[:, 0] + c * d[:, 1]
    return out


def rigid_errors(nav, truth):
    """rms along / across track (mm) of nav's array positions after the
    least-squares rigid fit onto truth's, in each true ping's frame."""
    a = np.c_[nav["array"]["x"], nav["array"]["y"]]
    t = np.c_[truth["array"]["x"], truth["array"]["y"]]
    a0, t0 = a.mean(0), t.mean(0)
    u, _, vt = np.linalg.svd((a - a0).T @ (t - t0))
    r = vt.T @ np.diag([1.0, np.sign(np.linalg.det(vt.T @ u.T))]) @ u.T
    e = (r @ (a - a0).T).T + t0 - t
    th = truth["array"]["theta"]
    along = np.cos(th) * e[:, 0] + np.sin(th) * e[:, 1]
    across = -np.sin(th) * e[:, 0] + np.cos(th) * e[:, 1]
    return 1e3 * np.sqrt(np.mean(along**2)), 1e3 * np.sqrt(np.mean(across**2))


def ncc(img, ref, mask):
    a, b = ref[mask], img.data[mask]
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    return abs(np.vdot(a, b)) / (na * nb), np.dot(abs(a), abs(b)) / (na * nb)


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("run")
    p.add_argument("reference")
    p.add_argument("--drift", type=float, default=5.0, help="drift amplitude, mm")
    p.add_argument("--shape", choices=("sway", "smooth"), default="sway")
    p.add_argument("--k", type=int, default=8)
    p.add_argument("--threads", type=int, default=0)
    a = p.parse_args(argv[1:])

    run = sasnav.read_run(a.run)
    truth = run.nav.copy()
    n = run.n_pings
    u = np.arange(n) / (n - 1)
    d = np.zeros((n, 2))
    d[:, 1] = 1e-3 * a.drift * np.sin(1.5 * 2 * np.pi * u)
    if a.shape == "smooth":
        d[:, 0] = 1e-3 * a.drift * np.sin(2.5 * 2 * np.pi * u)
    drifted = truth.copy()
    drifted["tx"] = compose(truth["tx"], d)
    drifted["array"] = compose(truth["array"], d)
    run.nav, run.truth = drifted, truth

    vn = sasnav.navigate_virtual(run, a.k, interleave=2, closed=True, iterations=1, keep_length=True,
                                 along_track="input", threads=a.threads)
    flagged = sum(not s.used for s in vn.pairs)
    print(f"{len(vn.pairs)} steps of virtual pings of {vn.k} pings ({flagged} flagged), "
          f"{vn.seconds:.0f} s")

    with h5py.File(a.reference, "r") as f:
        ref = f["real"][()] + 1j * f["imag"][()]
        x, y = f["x"][()], f["y"][()]
    xx, yy = np.meshgrid(x, y)
    mask = xx**2 + yy**2 <= 0.3**2
    grid = (float(x[0]), float(x[-1]), len(x), float(y[0]), float(y[-1]), len(y))
    print("navigation            along mm  across mm  |NCC| coherent (magnitudes)")
    for name, nav in (("turntable", truth), ("drifted (input)", drifted), ("estimated", vn.nav)):
        img = sasnav.image(run, grid, nav=nav, threads=a.threads)
        along, across = rigid_errors(nav, truth)
        co, mag = ncc(img, ref, mask)
        print(f"{name:20s}  {along:8.3f}  {across:9.3f}  {co:.3f} ({mag:.3f})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
