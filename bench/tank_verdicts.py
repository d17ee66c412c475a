#!/usr/bin/env python3
"""Verdicts of the pair estimator on simulated tank recordings (compact
scenes) against the truth: how many slipped pairs come back "ok"
(docs/validation.md, "Flagged pairs"; docs/estimator.md, "Verdict").

usage: python3 bench/tank_verdicts.py SASNAV --seeds S0 N [--dir DIR] [--threads T]
           [--tank-opts "OPTS"] [--ingest-opts "OPTS"]
       python3 bench/tank_verdicts.py --tables DIR/t*/val/pairs.csv [--tolerance T] [--gate G]

For each seed: `sasnav tank -o REC --seed S`, `sasnav ingest --wav REC -o
tank.h5`, `sasnav validate tank.h5 --fix-yaw --surge-sigma 0.025 -o val`
(about 1-3 minutes a seed on two cores), then the table over all pairs of
all seeds: pairs passed as "ok", slipped pairs (surge off the truth by more
than a quarter phase-centre spacing, 6.25 mm) passed as "ok", and the
surge errors of the "ok" pairs and of the pairs at a phase-centre
coincidence; the same for the verdict without the coincidence rule (the
margin alone: what the verdict was before it), recomputed from the
`margin` column; then the verdicts recomputed for other coincidence
tolerances and compact-scene margins (`--grid`; docs/validation.md, "A
wider tolerance and a compact scene's margin"), and for other contrast
gates of the compact-scene rules (`--gate`: the gate the tables were made
with; docs/validation.md, "Scenes just under the compact gate"), on p's
image's contrast and, for tables with the `contrast_q` column, on the
larger of p's and q's (the verdict since stop 55, "A bright feature
entering the beam"). Python's standard library only.
"""
import argparse
import csv
import os
import shlex
import shutil
import subprocess
import sys

MARGIN_MIN = 1.15  # opts.verdict_margin_min
SPACING = 0.025  # m: the tank's phase-centre spacing
SLIP = SPACING / 4  # m: a slipped pair's surge error, more than a quarter spacing
TOLERANCE = 0.5  # opts.verdict_coincidence's default (the self-check's; --tolerance)
GATE = 4.0  # opts.verdict_contrast's default (--gate): compact for the verdict above it
GRID_GATE = (3.5, 4.0, 4.25, 4.5, 4.75, 5.0)
GRID_TOL = (0.04, 0.06, 0.08, 0.10, 0.15, 0.20, 0.25, 0.5)
GRID_MARGIN = (1.15, 1.20, 1.25, 1.30, 1.40, 1.50)


def run_seed(sasnav, seed, top, threads, tank_opts="", ingest_opts=""):
    d = os.path.join(top, f"t{seed}")
    os.makedirs(d, exist_ok=True)
    rec, h5, val = os.path.join(d, "rec"), os.path.join(d, "tank.h5"), os.path.join(d, "val")
    steps = [[sasnav, "tank", "-o", rec, "--seed", str(seed)] + shlex.split(tank_opts),
             [sasnav, "ingest", "--wav", rec, "-o", h5] + shlex.split(ingest_opts),
             [sasnav, "validate", h5, "--fix-yaw", "--surge-sigma", "0.025", "-o", val,
              "--threads", str(threads)]]
    for cmd in steps:
        with open(os.path.join(d, "log.txt"), "a") as log:
            rc = subprocess.call(cmd, stdout=log, stderr=log)
        if rc:
            sys.exit(f"tank_verdicts: seed {seed}: {' '.join(cmd)} failed ({rc}); see {d}/log.txt")
        if cmd[1] == "ingest":
            shutil.rmtree(rec)  # the WAV recording, no longer needed
    return os.path.join(val, "pairs.csv")


def quantile(v, q):
    v = sorted(v)
    if not v:
        return float("nan")
    x = q * (len(v) - 1)
    i = int(x)
    return v[i] if i + 1 >= len(v) else v[i] + (x - i) * (v[i + 1] - v[i])


def summary(label, rows):
    err = [1e3 * abs(float(r["error_surge"])) for r in rows]
    return (f"{len(rows)} pairs, |surge error| median {quantile(err, 0.5):.2f} / "
            f"p95 {quantile(err, 0.95):.2f} / max {max(err) if err else float('nan'):.2f} mm")


def table(paths, tolerance=TOLERANCE, gate=GATE):
    rows = []
    for p in paths:
        with open(p) as f:
            rows += list(csv.DictReader(f))
    if not rows:
        sys.exit("tank_verdicts: no pairs")
    slipped = [r for r in rows if abs(float(r["error_surge"])) > SLIP]
    ok_now = [r for r in rows if r["verdict"] == "ok"]
    # the verdict by the margin alone: an estimate ambiguous only for its
    # coincidence was "ok" before the rule
    ok_before = [r for r in rows if r["verdict"] == "ok" or
                 (r["verdict"] == "ambiguous" and float(r["margin"]) >= MARGIN_MIN)]
    coinc = [r for r in rows if r["coincidence"] == "1"]
    print(f"{len(paths)} recordings, {len(rows)} pairs, {len(slipped)} slipped "
          f"(surge off the truth by more than {1e3 * SLIP:.2f} mm)")
    print("| verdicts | \"ok\" pairs | slipped pairs passed as \"ok\" | \"ok\" pairs |")
    print("|---|---|---|---|")
    for label, ok in (("margin alone (before the coincidence rule)", ok_before),
                      ("the build's verdicts", ok_now)):
        ok_ids = {id(r) for r in ok}  # rows by identity: two pairs may print alike
        bad = sum(1 for r in slipped if id(r) in ok_ids)
        print(f"| {label} | {len(ok)} of {len(rows)} | {bad} of {len(slipped)} | {summary(label, ok)} |")
    print(f"pairs at a phase-centre coincidence: {summary('coincidence', coinc)}; "
          f"{sum(1 for r in slipped if r['coincidence'] == '1')} of the slipped pairs among them")
    for r in slipped:
        if r["verdict"] == "ok":
            print(f"  passed as ok: K = {r['k']} ({r['p']}, {r['q']}), surge error "
                  f"{1e3 * float(r['error_surge']):+.2f} mm, estimate {1e3 * float(r['surge']):+.3f} mm")
    grid(rows, slipped, tolerance, gate)
    gates(rows, slipped)


def grid(rows, slipped, tolerance, gate):
    """The verdicts recomputed for other coincidence tolerances (rows) and
    compact-scene margins (columns): "ok" pairs / slipped among them. The
    tank's pairs are a whole number of plotter steps of one spacing apart,
    so a pair is at a coincidence where its surge (the estimate's departure
    from the nominal step) lies within the tolerance of a multiple of the
    spacing; checked against the `coincidence` column at the tolerance the
    tables were made with."""
    def dist(r):
        u = float(r["surge"]) / SPACING
        return abs(u - round(u))

    def compact(r):  # tables of builds before the contrast column: every tank pair was compact
        return "contrast" not in r or verdict_contrast(r) > gate
    miss = sum(1 for r in rows if (compact(r) and dist(r) < tolerance) != (r["coincidence"] == "1"))
    print(f"verdicts recomputed (\"ok\" / slipped among them; {miss} of {len(rows)} pairs disagree "
          f"with the coincidence column at tolerance {tolerance}):")
    print("| tolerance \\ margin | " + " | ".join(f"{m:.2f}" for m in GRID_MARGIN) + " |")
    print("|---" * (len(GRID_MARGIN) + 1) + "|")
    slip_ids = {id(r) for r in slipped}
    for tol in GRID_TOL:
        cells = []
        for m in GRID_MARGIN:
            ok = [r for r in rows if r["status"] == "ok" and float(r["margin"]) >= m and dist(r) >= tol]
            cells.append(f"{len(ok)} / {sum(1 for r in ok if id(r) in slip_ids)}")
        print(f"| {tol:.2f} | " + " | ".join(cells) + " |")


def verdict_contrast(r, with_q=True):
    """The contrast the verdict's gate reads: p's image's, and since stop 55
    the larger of it and q's (`contrast_q`, in tables of builds that have
    it)."""
    c = float(r["contrast"])
    if with_q and r.get("contrast_q"):
        c = max(c, float(r["contrast_q"]))
    return c


def gates(rows, slipped):
    """The verdicts recomputed for other contrast gates of the compact-scene
    rules (opts.verdict_contrast), with the default tolerance (0.5: every
    pair whose phase centres overlap, as all the tank's pairs do, is at a
    coincidence) and margins: above the gate "ambiguous", at or below it
    "ok" where the margin reaches verdict_margin_min; "failed" and
    "no_overlap" stay. Needs the `contrast` column."""
    if not rows or "contrast" not in rows[0]:
        return
    c = sorted(float(r["contrast"]) for r in rows)
    sc = sorted(float(r["contrast"]) for r in slipped)
    print(f"contrast of p's image: min {c[0]:.2f}, median {quantile(c, 0.5):.2f}, max {c[-1]:.2f}"
          + (f"; of the slipped pairs {sc[0]:.2f} .. {sc[-1]:.2f}" if sc else ""))
    has_q = bool(rows[0].get("contrast_q"))
    print("| compact-verdict gate | \"ok\" pairs | slipped pairs passed as \"ok\" (contrast) |"
          + (" the gate on p's or q's: \"ok\" | slipped \"ok\" |" if has_q else ""))
    print("|---|---|---|" + ("---|---|" if has_q else ""))
    slip_ids = {id(r) for r in slipped}
    for g in GRID_GATE:
        cells = []
        for with_q in ([False, True] if has_q else [False]):
            ok = [r for r in rows if r["verdict"] not in ("failed", "no_overlap") and
                  verdict_contrast(r, with_q) <= g and float(r["margin"]) >= MARGIN_MIN]
            bad = [r for r in ok if id(r) in slip_ids]
            cells.append(f"{len(ok)} | {len(bad)}"
                         + (" (" + ", ".join(f"{verdict_contrast(r, with_q):.2f}" for r in bad) + ")"
                            if bad else ""))
        print(f"| {g:.2f} | " + " | ".join(cells) + " |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sasnav", nargs="?")
    ap.add_argument("--seeds", nargs=2, type=int, metavar=("S0", "N"))
    ap.add_argument("--dir", default="tank_verdicts")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--tables", nargs="+", metavar="PAIRS_CSV")
    ap.add_argument("--tank-opts", default="",
                    help="more options of `sasnav tank` (another scene, e.g. \"--plate-range 2.0\")")
    ap.add_argument("--ingest-opts", default="",
                    help="more options of `sasnav ingest` (e.g. \"--range 2.0\" with that plate)")
    ap.add_argument("--tolerance", type=float, default=TOLERANCE,
                    help="the coincidence tolerance the tables were made with (default %(default)s)")
    ap.add_argument("--gate", type=float, default=GATE,
                    help="the compact-verdict contrast gate the tables were made with (default %(default)s)")
    a = ap.parse_args()
    if a.tables:
        table(a.tables, a.tolerance, a.gate)
        return
    if not a.sasnav or not a.seeds:
        ap.error("SASNAV and --seeds S0 N, or --tables FILES")
    s0, n = a.seeds
    table([run_seed(a.sasnav, s, a.dir, a.threads, a.tank_opts, a.ingest_opts) for s in range(s0, s0 + n)],
          a.tolerance, a.gate)


if __name__ == "__main__":
    main()
