#!/usr/bin/env python3
"""Where a chained virtual-array navigation's error comes from, per axis.

Reads the per-group file of `bench_virtual --dump FILE` (one line per group
g: g, input centroid x y yaw, true centroid x y yaw, then for the step g ->
g + 1 the nominal x y yaw, the estimate x y yaw and whether it was used) and
chains the steps again with each axis taken from the estimate, the input or
the truth:

  input                  the input navigation's own steps
  estimate               the estimated steps (scaled to the input's length,
                         as --keep-length does)
  truth surge, est sway  what the estimated sway alone would give
  est surge, truth sway  what the estimated surge alone would give
  input along, est across  the input's positions moved only across its
                         track, by the estimated sway steps: each group's
                         correction c along its normal chained from
                         (X[g+1] - X[g]) . n[g] = estimated sway step,
                         c = 0 at the first group, the misclosure spread;
                         the estimated steps scaled as in "estimate"
                         (a fusion that takes the along-track from the
                         input, an INS with a DVL, and the across-track
                         from the echoes; mixing the steps' axes in each
                         group's frame instead leaks one into the other)
  input along, true across  the same with the truth's sway steps, a
                         reference: on an across-track drift what is left
                         is about the input's error at the first group;
                         where the input errs along-track too, that error
                         stays and moves the normals the steps are read
                         along
  input surge, est sway (steps)  the steps' axes mixed instead: the
                         input's surge steps and the estimated sway ones,
                         chained in each group's frame (the input's sway
                         error leaks into its surge steps as the frames
                         turn)
  surge: kept drift      the truth plus the part of the surge errors that
                         follows the input's step errors (b x input error)
  surge: noise           the truth plus the rest of the surge errors

Closed runs (--closed) spread the misclosure evenly, as the library does.
Errors are rms over the groups in the true centroid's frame (along,
across), after the rigid move that puts the first input centroid on the
first true one, as bench_virtual aligns; with --rigid after the
least-squares rigid fit of all groups onto the truth instead (a
navigation is known up to a rigid move: this does not charge a path for
its first group's error).

--fit L,LAM additionally fits a smooth correction of the input navigation
to all steps (world translations at knots every L groups, linear between
them, a second-difference penalty LAM, each axis weighted by its residual
rms): a least-squares alternative to chaining (docs/airsas.md, section 3).

--synthetic SURGE,SWAY replaces the estimates by the truth's steps plus
white noise of those rms (mm; seed 1) before everything else: what the
chaining and the fit give with unbiased steps of that quality.

usage: virtual_decompose.py DUMP [--closed] [--rigid] [--fit L,LAM ...] [--synthetic SURGE,SWAY]
"""
import sys

import numpy as np


def rot(t):
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, -s], [s, c]])


RIGID = False


def errors(P, T, C):
    """rms along / across (mm) of positions P + C against the truth T."""
    if RIGID:
        A = P[:, :2] + C
        A0, T0 = A.mean(0), T[:, :2].mean(0)
        U, _, Vt = np.linalg.svd((A - A0).T @ (T[:, :2] - T0))
        D = np.diag([1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
        Q = (Vt.T @ D @ U.T @ (A - A0).T).T + T0
    else:
        R = rot(T[0, 2] - P[0, 2])
        Q = (R @ (P[:, :2] + C - P[0, :2]).T).T + T[0, :2]
    e = Q - T[:, :2]
    along = np.cos(T[:, 2]) * e[:, 0] + np.sin(T[:, 2]) * e[:, 1]
    across = -np.sin(T[:, 2]) * e[:, 0] + np.cos(T[:, 2]) * e[:, 1]
    return 1e3 * np.sqrt(np.mean(along**2)), 1e3 * np.sqrt(np.mean(across**2))


def chain(P, steps, closed):
    """Corrections (world) of the chained steps (in each group's frame)."""
    G = P.shape[0]
    Q = np.zeros((G, 2))
    Q[0] = P[0, :2]
    for g in range(G - 1):
        Q[g + 1] = Q[g] + rot(P[g, 2]) @ steps[g]
    if closed:
        end = Q[G - 1] + rot(P[G - 1, 2]) @ steps[G - 1]
        Q -= np.outer(np.arange(G) / G, end - Q[0])
    return Q - P[:, :2]


def across_only(P, N, Es, closed):
    """Corrections (world) of the input's positions along each group's
    normal, chained from the estimated sway steps (see the docstring)."""
    G = P.shape[0]
    npair = G if closed else G - 1
    c = np.zeros(npair + 1)
    for g in range(npair):
        h = (g + 1) % G
        c[g + 1] = (Es[g, 1] - N[g, 1] + c[g]) / np.cos(P[h, 2] - P[g, 2])
    c = c[:G]
    if closed:
        c = c - np.arange(G) / G * (c[0] + (Es[G - 1, 1] - N[G - 1, 1] + c[G - 1])
                                    / np.cos(P[0, 2] - P[G - 1, 2]) - c[0])
    return np.c_[-np.sin(P[:, 2]) * c, np.cos(P[:, 2]) * c]


def fit(P, N, E, used, closed, L, lam):
    """Smooth correction at knots every L groups fitted to E - N."""
    G = P.shape[0]
    npair = N.shape[0]
    nk = int(np.ceil(G / L)) if closed else int(np.ceil((G - 1) / L)) + 1

    def basis(g):
        u = g / L
        k = int(np.floor(u))
        if not closed:
            k = min(k, nk - 2)
        w = u - k
        return [(k % nk, 1 - w), ((k + 1) % nk, w)]

    sig = np.array([3e-4, 3e-5])
    for _ in range(3):
        rows, rhs = [], []
        for g in range(npair):
            if not used[g]:
                continue
            h = (g + 1) % G
            Rt = rot(P[g, 2]).T
            dg = E[g] - N[g]
            for ax in range(2):
                row = np.zeros(2 * nk)
                for k, w in basis(h):
                    row[2 * k:2 * k + 2] += w * Rt[ax]
                for k, w in basis(g):
                    row[2 * k:2 * k + 2] -= w * Rt[ax]
                rows.append(row / sig[ax])
                rhs.append(dg[ax] / sig[ax])
        A, b = np.array(rows), np.array(rhs)
        reg = []
        for k in range(nk if closed else nk - 2):
            for ax in range(2):
                row = np.zeros(2 * nk)
                for j, c in zip(range(3), (1.0, -2.0, 1.0)):
                    row[2 * ((k + j) % nk) + ax] += c
                reg.append(lam * row / 1e-3)
        anchor = np.zeros((2, 2 * nk))
        anchor[0, 0] = anchor[1, 1] = 1e3
        A2 = np.vstack([A, np.array(reg), anchor])
        b2 = np.concatenate([b, np.zeros(len(reg) + 2)])
        x = np.linalg.lstsq(A2, b2, rcond=None)[0]
        sig = np.sqrt(np.mean(((A @ x - b).reshape(-1, 2) * sig) ** 2, axis=0))
    C = np.zeros((G, 2))
    for g in range(G):
        for k, w in basis(g):
            C[g] += w * x[2 * k:2 * k + 2]
    return C - C[0], sig


def main(argv):
    if len(argv) < 2:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    global RIGID
    closed = "--closed" in argv
    RIGID = "--rigid" in argv
    fits = [tuple(argv[i + 1].split(",")) for i, a in enumerate(argv) if a == "--fit"]
    d = np.loadtxt(argv[1], ndmin=2)
    G = d.shape[0]
    P, T = d[:, 1:4], d[:, 4:7]
    npair = G if closed else G - 1
    N, E, used = d[:npair, 7:9], d[:npair, 10:12], d[:npair, 13] > 0
    tr = np.array([rot(-T[g, 2]) @ (T[(g + 1) % G, :2] - T[g, :2]) for g in range(npair)])
    if "--synthetic" in argv:
        ns, nw = (1e-3 * float(v) for v in argv[argv.index("--synthetic") + 1].split(","))
        rng = np.random.default_rng(1)
        E = tr + np.c_[ns * rng.standard_normal(npair), nw * rng.standard_normal(npair)]
    scale = np.sum(np.hypot(*N[used].T)) / np.sum(np.hypot(*E[used].T))
    Es = np.where(used[:, None], E * scale, N)
    es, ei = Es[:, 0] - tr[:, 0], N[:, 0] - tr[:, 0]
    eic = ei - ei.mean()
    b = float(np.dot(es - es.mean(), eic) / np.dot(eic, eic)) if np.dot(eic, eic) > 0 else 0.0
    noise = es - b * ei
    rows = [
        ("input", N),
        ("estimate (input's length)", Es),
        ("truth surge, est sway", np.c_[tr[:, 0], Es[:, 1]]),
        ("est surge, truth sway", np.c_[Es[:, 0], tr[:, 1]]),
        ("surge: kept drift only", np.c_[tr[:, 0] + b * ei, tr[:, 1]]),
        ("surge: noise only", np.c_[tr[:, 0] + noise, tr[:, 1]]),
    ]
    print("# %d groups, %s%s; steps' surge error = %.3f x input error + noise of %.3f mm rms"
          % (G, "closed" if closed else "open", ", rigid fit" if RIGID else "", b, 1e3 * noise.std()))
    print("# %-28s  along mm  across mm" % "steps chained")
    for name, st in rows:
        print("  %-28s  %8.3f  %9.3f" % ((name,) + errors(P, T, chain(P, st, closed))))
    print("  %-28s  %8.3f  %9.3f" % (("input along, est across",) + errors(P, T, across_only(P, N, Es, closed))))
    print("  %-28s  %8.3f  %9.3f" % (("input along, true across",) + errors(P, T, across_only(P, N, tr, closed))))
    print("  %-28s  %8.3f  %9.3f" % (("input surge, est sway (steps)",) + errors(P, T, chain(P, np.c_[N[:, 0], Es[:, 1]], closed))))
    for L, lam in fits:
        C, sig = fit(P, N, Es, used, closed, int(L), float(lam))
        print("  %-28s  %8.3f  %9.3f   (residual rms %.3f / %.4f mm)"
              % (("smooth fit L=%s lam=%s" % (L, lam),) + errors(P, T, C) + tuple(1e3 * sig)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
