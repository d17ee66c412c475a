#!/usr/bin/env python3
"""Cramer-Rao bound on a ping pair's (surge, sway, yaw) from the matrices
written by bench_crlb (see its header; docs/estimator.md, "What the data
allow: a Cramer-Rao bound").

usage: python3 bench/crlb.py PREFIX [PREFIX ...] [--snr DB [DB ...]]

For each PREFIX and SNR: sigma_n^2 = (the clean run's mean power) /
10^(SNR/10), the simulator's definition; C = C0 + sigma_n^2 I; the Fisher
information F_ij = Re tr(C^-1 dC_i C^-1 dC_j) (circular complex Gaussian
samples); printed: the bound sqrt((F^-1)_ii) per component, the bound
on yaw with surge and sway known (1 / sqrt(F_yy)), and the first-order
bias of a criterion that keeps the likelihood's data term phi^H C^-1 phi
and leaves out log det C: (2F)^-1 t, t_i = tr(C^-1 dC_i) (the term
tr(C^-1 d2C) of its Hessian left out too: an order of magnitude).
"""
import argparse
import sys

import numpy as np


def load(prefix):
    meta = {}
    with open(prefix + ".txt") as f:
        for line in f:
            k, *v = line.split()
            meta[k] = [float(x) for x in v]
    m = int(meta["m"][0])
    mp = m // 2
    raw = np.fromfile(prefix + ".bin", dtype=np.complex64)
    if raw.size != m * m + 3 * mp * m:
        sys.exit(f"{prefix}.bin: {raw.size} values, expected {m * m + 3 * mp * m}")
    c0 = raw[: m * m].reshape(m, m).astype(np.complex128)
    c0 = 0.5 * (c0 + c0.conj().T)  # Hermitian up to float rounding
    d = []
    for i in range(3):
        off = m * m + i * mp * m
        dq = raw[off: off + mp * m].reshape(mp, m).astype(np.complex128)
        full = np.zeros((m, m), dtype=np.complex128)
        full[mp:, :] = dq
        full[:mp, mp:] = dq[:, :mp].conj().T
        # the q-q block of a derivative is Hermitian too
        full[mp:, mp:] = 0.5 * (dq[:, mp:] + dq[:, mp:].conj().T)
        d.append(full)
    return meta, c0, d


def fisher(c0, d, noise):
    m = c0.shape[0]
    c = c0 + noise * np.eye(m)
    ci = np.linalg.inv(c)
    p = [ci @ di for di in d]
    f = np.empty((3, 3))
    for i in range(3):
        for j in range(i, 3):
            f[i, j] = f[j, i] = np.real(np.sum(p[i] * p[j].T))
    t = np.array([np.real(np.trace(pi)) for pi in p])
    return f, t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("prefix", nargs="+")
    ap.add_argument("--snr", nargs="+", type=float, default=[30.0])
    a = ap.parse_args()
    print("| seed | pair | samples | grid dx, dy mm | surge step mm | SNR dB | surge bound mm "
          "| sway bound microns | yaw bound rad | yaw bound, surge and sway known | model/data power "
          "| data term's bias: surge mm, sway microns, yaw rad |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for prefix in a.prefix:
        meta, c0, d = load(prefix)
        ratio = meta["power_window_model"][0] / meta["power_window_data"][0]
        for snr in a.snr:
            noise = meta["power_run"][0] / 10 ** (snr / 10)
            f, t = fisher(c0, d, noise)
            cov = np.linalg.inv(f)
            # The data term phi^H C^-1 phi alone (the likelihood without
            # log det C): its expected gradient at the truth is -t,
            # t_i = tr(C^-1 dC_i) = d log det C / dsigma_i, and its expected
            # Hessian 2F - tr(C^-1 d2C); with the last term left out (not
            # computed), the first-order bias of its minimiser is (2F)^-1 t.
            bias = np.linalg.solve(2 * f, t)
            sd = np.sqrt(np.diag(cov))
            print(f"| {int(meta['seed'][0])} | {int(meta['pair'][0])} | {int(meta['samples'][0])}:"
                  f"{int(meta['samples'][1])} | {1e3 * meta['dx'][0]:g}, {1e3 * meta['dy'][0]:g} | "
                  f"{1e3 * meta['h'][0]:g} | {snr:g} | {1e3 * sd[0]:.4f} | {1e6 * sd[1]:.3f} | "
                  f"{sd[2]:.3e} | {1 / np.sqrt(f[2, 2]):.3e} | {ratio:.3f} | {1e3 * bias[0]:+.3f}, "
                  f"{1e6 * bias[1]:+.2f}, {bias[2]:+.2e} |", flush=True)


if __name__ == "__main__":
    main()
