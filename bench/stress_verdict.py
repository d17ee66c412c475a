#!/usr/bin/env python3
"""Stress of the pair verdict on scenarios it was not tuned on.

Every seed draws its own scenario around paper-trajectory (8 pings): the
range of interest (6-20 m; the swath, the seabed's range extent and the
disc moved with it; the seabed keeps the preset's +-2.6 m along track, so
beyond about 14 m its ends are inside the beams' main lobe; the Tx-array
offset scaled as the preset's 10 cm at 10 m, a choice, simulated and
assumed alike), the SNR (5-30 dB),
the ping spacing (0.12-0.28 m, against a 0.4 m phase-centre array), the
motion errors (surge and sway 3-30 mm rms, yaw 2-20 mrad rms, correlation
0.5-3 m) and the seabed (ripple period, angle and depth, scatterer density,
a disc of 0-0.4 m radius at 0-10 times the speckle's amplitude). It runs
`sasnav simulate` then `sasnav navigate --json --no-aiding` and counts, over
the pairs, the slips (fused motion error off the truth by more than a
quarter phase-centre spacing in surge or 2e-3 rad in yaw, as bench_trust)
and the unflagged ones (status "ok" and not bridged): the failure this
product must not have. One line per run, then the totals and the drawn
scenario of every run with an unflagged slip. Exit status 1 if any pair
slipped unflagged or any run could not be simulated or navigated (those
are counted, and their files kept in the work folder).

usage: python3 bench/stress_verdict.py path/to/sasnav S0 N [--threads T]
       [--pings P] [--workdir DIR] [--keep] [--pairs FILE.csv]
The scenario of seed S is a function of S alone (numpy's default_rng(S));
the simulation takes --seed S as well.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

PHASE_CENTRE_SPACING = 0.025  # rx_spacing / 2 of the paper's array
YAW_SLIP = 2e-3


def draw_scenario(seed, n_pings):
    g = np.random.default_rng(seed)
    r = g.uniform(6.0, 20.0)
    spacing = g.uniform(0.12, 0.28)
    sc = {
        "snr": round(float(g.uniform(5.0, 30.0)), 2),
        "range": round(float(r), 3),
        "spacing": round(float(spacing), 4),
        "surge_rms": round(float(g.uniform(0.003, 0.03)), 4),
        "sway_rms": round(float(g.uniform(0.003, 0.03)), 4),
        "yaw_rms": round(float(g.uniform(0.002, 0.02)), 4),
        "smooth_length": round(float(g.uniform(0.5, 3.0)), 3),
        "ripple_period": round(float(g.uniform(0.05, 0.3)), 3),
        "ripple_angle": round(float(g.uniform(-1.5, 1.5)), 3),
        "ripple_depth": round(float(g.uniform(0.0, 0.9)), 3),
        "density": round(float(g.uniform(3e3, 2e4)), 0),
        "disc_radius": round(float(g.uniform(0.0, 0.4)), 3),
        "disc_amplitude": round(float(g.uniform(0.0, 10.0)), 2),
    }
    yaml = f"""preset: paper-trajectory
swath: {{range_min: {r - 1.2:.3f}, range_max: {r + 1.6:.3f}, range_of_interest: {r:.3f}}}
trajectory:
  n_pings: {n_pings}
  ping_spacing: {spacing:.4f}
  x_start: {-(n_pings - 1) * spacing / 2:.4f}
  surge_rms: {sc['surge_rms']}
  sway_rms: {sc['sway_rms']}
  yaw_rms: {sc['yaw_rms']}
  smooth_length: {sc['smooth_length']}
  tx_lag: {0.01 * r:.4f}
scene:
  y_min: {r - 1.0:.3f}
  y_max: {r + 1.0:.3f}
  disc_y: {r:.3f}
  ripple_period: {sc['ripple_period']}
  ripple_angle: {sc['ripple_angle']}
  ripple_depth: {sc['ripple_depth']}
  density: {sc['density']:.0f}
  disc_radius: {sc['disc_radius']}
  disc_amplitude: {sc['disc_amplitude']}
"""
    return sc, yaml


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("cli")
    ap.add_argument("s0", type=int)
    ap.add_argument("n", type=int)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--pings", type=int, default=8)
    ap.add_argument("--workdir")
    ap.add_argument("--keep", action="store_true", help="keep the runs and navigations")
    ap.add_argument("--pairs", help="write one CSV line per pair (its scenario, verdict and errors)")
    a = ap.parse_args()
    work = a.workdir or tempfile.mkdtemp(prefix="stress_verdict.")
    os.makedirs(work, exist_ok=True)
    tot = {"pairs": 0, "slips": 0, "unflagged": 0, "flagged": 0, "flagged_right": 0, "runs": 0, "errors": 0}
    bad = []
    pf = open(a.pairs, "w") if a.pairs else None
    if pf:
        keys = list(draw_scenario(0, a.pings)[0].keys())
        pf.write("seed,p,q," + ",".join(keys) + ",status,first_status,resolution,slip,err_surge,err_sway,"
                 "err_yaw,eta,margin,coincidence,contrast,contrast_q,eta_outlier\n")
    print(f"{'seed':>6} {'snr':>5} {'range':>6} {'spacing':>7} {'pairs':>5} {'slips':>5} "
          f"{'unflagged':>9} {'flagged':>7} {'final_sway_mm':>13}")
    for s in range(a.s0, a.s0 + a.n):
        sc, yaml = draw_scenario(s, a.pings)
        cfg = os.path.join(work, f"s{s}.yaml")
        run = os.path.join(work, f"s{s}.h5")
        nav = os.path.join(work, f"s{s}_nav.h5")
        with open(cfg, "w") as f:
            f.write(yaml)
        sim = subprocess.run([a.cli, "simulate", "--config", cfg, "--seed", str(s), "--snr", str(sc["snr"]),
                              "--threads", str(a.threads), "-o", run], capture_output=True, text=True)
        if sim.returncode != 0:
            print(f"{s:>6} simulate failed: {sim.stderr.strip()}")
            tot["errors"] += 1
            continue
        nv = subprocess.run([a.cli, "navigate", run, "--no-aiding", "--json", "--threads", str(a.threads),
                             "-o", nav], capture_output=True, text=True)
        if nv.returncode != 0:
            print(f"{s:>6} navigate failed (rc {nv.returncode}): {nv.stderr.strip()}")
            tot["errors"] += 1
            continue
        js = json.loads(nv.stdout)
        if any(p["error"][c] is None for p in js["pairs"] for c in ("surge", "sway", "yaw")):
            print(f"{s:>6} navigate gave a pair without a finite error (kept in {work})")
            tot["errors"] += 1
            continue
        slips = unflagged = flagged = flagged_right = 0
        for p in js["pairs"]:
            e = p["error"]
            slip = abs(e["surge"]) > PHASE_CENTRE_SPACING / 4 or abs(e["yaw"]) > YAW_SLIP
            ok = p["status"] == "ok" and p["resolution"] != "bridged"
            slips += slip
            unflagged += slip and ok
            flagged += not ok
            flagged_right += (not ok) and not slip
            if pf:
                pf.write(f"{s},{p['p']},{p['q']}," + ",".join(str(v) for v in sc.values()) +
                         f",{p['status']},{p['first_status']},{p['resolution']},{int(slip)},{e['surge']:.6g},"
                         f"{e['sway']:.6g},{e['yaw']:.6g},{p['eta']},{p.get('margin')},"
                         f"{int(p['coincidence'])},{p.get('contrast')},{p.get('contrast_q')},"
                         f"{int(p['eta_outlier'])}\n")
            if slip and ok:
                bad.append((s, p["p"], p["q"], e, p["eta"], p.get("margin"), sc))
        if pf:
            pf.flush()
        final = js["cumulative_error"][-1]["sway"]
        n = len(js["pairs"])
        tot["pairs"] += n
        tot["slips"] += slips
        tot["unflagged"] += unflagged
        tot["flagged"] += flagged
        tot["flagged_right"] += flagged_right
        tot["runs"] += 1
        print(f"{s:>6} {sc['snr']:>5.1f} {sc['range']:>6.2f} {sc['spacing']:>7.3f} {n:>5} {slips:>5} "
              f"{unflagged:>9} {flagged:>7} {1e3 * final:>+13.3f}", flush=True)
        if not a.keep:
            for path in (run, nav, cfg):
                os.remove(path)
    print(f"\nruns {tot['runs']} (failed to run: {tot['errors']}), pairs {tot['pairs']}: slips {tot['slips']}, "
          f"unflagged slips {tot['unflagged']}, flagged pairs {tot['flagged']} ({tot['flagged_right']} of them "
          f"right)")
    for s, p, q, e, eta, margin, sc in bad:
        print(f"UNFLAGGED SLIP seed {s} pair {p}-{q}: error surge {1e3 * e['surge']:+.2f} mm, yaw "
              f"{e['yaw']:+.2e} rad; eta {eta}, margin {margin}; scenario {json.dumps(sc)}")
    if pf:
        pf.close()
    if not a.workdir and not a.keep and not tot["errors"]:
        shutil.rmtree(work, ignore_errors=True)
    return 1 if tot["unflagged"] or tot["errors"] else 0


if __name__ == "__main__":
    sys.exit(main())
