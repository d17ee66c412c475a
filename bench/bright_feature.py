#!/usr/bin/env python3
"""Paper-trajectory runs with a brighter disc (docs/validation.md, "A bright
feature entering the beam"): seeds S0 .. S0 + N - 1 are simulated with
`scene: {disc_amplitude: A}` (the preset's 4; 16 is 24 dB above the ripple
seabed) at SNR dB and navigated with `sasnav navigate --json` (no aiding).
Prints one line per run and a summary over the pairs:

- slips: the pair's motion error off by more than a quarter phase-centre
  spacing in surge (6.25 mm) or 2e-3 rad in yaw (the Monte Carlo's
  definition, bench_trust); unflagged slips: those with status "ok";
- large errors: more than 3 mm of surge or 5e-4 rad of yaw (ten times the
  speckle pairs' usual yaw error), and those with status "ok";
- the pairs whose compact-scene verdict came from q's image alone (p's
  contrast at most the gate, q's above it: `contrast`, `contrast_q`), and
  the slips among them: what reading q's image adds to the verdict;
- the pairs over navigate's eta-outlier line (`eta_outlier`), and the
  slips and other large errors among them;
- the runs' |final sway error|: median, max, and how many within lambda/25.

usage: python3 bench/bright_feature.py path/to/sasnav --seeds S0 N
           [--amplitude A] [--snr DB] [--dir DIR] [--threads T] [--gate G]
           [--navigate-args="ARGS"]
(--navigate-args="...": more options of `sasnav navigate`, e.g.
--navigate-args="--equalise 0" or "--eta-outlier inf", to compare with the
defaults on the same runs in another DIR: the runs are simulated again, the
same bits)
(an existing DIR keeps its runs and navigations; about 15-30 s a run on two
cores)
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

SPACING = 0.025  # the paper system's phase-centre spacing (m)
SLIP_SURGE, SLIP_YAW = SPACING / 4, 2e-3
LARGE_SURGE, LARGE_YAW = 3e-3, 5e-4


def run_one(cli, d, amp, seed, snr, threads, extra=()):
    cfg = os.path.join(d, "disc.yaml")
    with open(cfg, "w") as f:
        f.write("preset: paper-trajectory\nscene: {disc_amplitude: %s}\n" % amp)
    run = os.path.join(d, "run_%d.h5" % seed)
    js = os.path.join(d, "nav_%d.json" % seed)
    if not os.path.exists(js):
        if not os.path.exists(run):
            subprocess.run([cli, "simulate", "--config", cfg, "--seed", str(seed), "--snr", snr,
                            "-o", run], check=True, capture_output=True)
        nav = os.path.join(d, "nav_%d.h5" % seed)
        r = subprocess.run([cli, "navigate", run, "--json", "-o", nav, "--threads", str(threads)] + list(extra),
                           check=True, capture_output=True, text=True)
        with open(js + ".tmp", "w") as f:
            f.write(r.stdout)
        os.replace(js + ".tmp", js)
        os.remove(nav)
    with open(js) as f:
        return json.load(f)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("cli")
    ap.add_argument("--seeds", nargs=2, type=int, required=True, metavar=("S0", "N"))
    ap.add_argument("--amplitude", default="16")
    ap.add_argument("--snr", default="30")
    ap.add_argument("--dir")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--navigate-args", default="", help="more options of sasnav navigate")
    ap.add_argument("--gate", type=float, default=4.0,
                    help="the verdict's contrast gate the runs were made with (default %(default)s)")
    a = ap.parse_args()
    d = a.dir or tempfile.mkdtemp()
    os.makedirs(d, exist_ok=True)
    t = dict(pairs=0, ok=0, slips=0, unflagged=0, large=0, large_ok=0, by_q=0, by_q_slips=0, by_q_large=0,
             eta_out=0, eta_out_slips=0, eta_out_large=0)
    finals = []
    print("disc amplitude %s, SNR %s dB, seeds %d..%d, runs in %s" % (a.amplitude, a.snr, a.seeds[0],
                                                                       a.seeds[0] + a.seeds[1] - 1, d))
    for s in range(a.seeds[0], a.seeds[0] + a.seeds[1]):
        nav = run_one(a.cli, d, a.amplitude, s, a.snr, a.threads, a.navigate_args.split())
        line = []
        for p in nav["pairs"]:
            e = p.get("error")
            if e is None:
                continue
            slip = abs(e["surge"]) > SLIP_SURGE or abs(e["yaw"]) > SLIP_YAW
            large = abs(e["surge"]) > LARGE_SURGE or abs(e["yaw"]) > LARGE_YAW
            ok = p["status"] == "ok"
            c, cq = p.get("contrast", 0.0), p.get("contrast_q", 0.0)
            by_q = c <= a.gate < cq
            t["pairs"] += 1
            t["ok"] += ok
            t["slips"] += slip
            t["unflagged"] += slip and ok
            t["large"] += large
            t["large_ok"] += large and ok
            t["by_q"] += by_q
            t["by_q_slips"] += by_q and slip
            t["by_q_large"] += by_q and large
            eo = bool(p.get("eta_outlier", False))
            t["eta_out"] += eo
            t["eta_out_slips"] += eo and slip
            t["eta_out_large"] += eo and large and not slip
            if slip or (large and ok):
                line.append("%d-%d %s %+.1f mm %+.1e rad (c %.2f, q %.2f, eta %.2f%s)" % (
                    p["p"], p["q"], p["status"], 1e3 * e["surge"], e["yaw"], c, cq, p["eta"],
                    ", eta outlier" if eo else ""))
        finals.append(abs(nav["final_sway_error"]))
        print("seed %d: final sway %+.3f mm, %d flagged; %s" % (s, 1e3 * nav["final_sway_error"],
                                                                 nav["flagged_pairs"],
                                                                 "; ".join(line) if line else "-"))
    print("pairs %(pairs)d, ok %(ok)d; slips %(slips)d, unflagged %(unflagged)d; large errors %(large)d, "
          "of them ok %(large_ok)d; compact by q's image alone %(by_q)d (slips %(by_q_slips)d, "
          "large %(by_q_large)d); eta outliers %(eta_out)d (slips %(eta_out_slips)d, other large "
          "%(eta_out_large)d)" % t)
    if finals:
        print("|final sway| median %.3f mm, max %.3f mm; within lambda/25 (0.2 mm) %d of %d" % (
            1e3 * statistics.median(finals), 1e3 * max(finals), sum(f <= 2e-4 for f in finals), len(finals)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
