#!/bin/sh
# The subspace pair estimator on a survey-class system (the `survey`
# preset: 300 kHz, 60 kHz band, 32 receivers of 5 cm, range of interest
# 70 m, 0.32 m ping spacing, true bistatic poses, smooth motion errors;
# docs/config.md) at SNR dB (default 30), seeds S0 .. S0 + N - 1: each seed
# is simulated with three pings and pair (1, 2) is estimated with `sasnav
# pair --json`
# and the extra options in PAIR_OPTS (e.g. "--cross-extent 2"). Prints one
# line per seed and a summary: |error| median / 95th percentile / max in
# surge, sway and yaw, the verdicts, slips (off by more than a quarter
# phase-centre spacing in surge, 6.25 mm, or in yaw by more than 0.8 of
# a slip's d / R = 3.6e-4 rad, as bench_trust's 2e-3 rad is at 10 m;
# d = 2.5 cm and R = 70 m are the preset's), unflagged slips (a slip with
# verdict "ok"), and the median wall time and operator applications
# (docs/estimator.md, "A survey-class system").
#
# usage: [PAIR_OPTS="..."] [SNR=30] [THREADS=2] sh bench/survey_pairs.sh path/to/sasnav [S0 N] [WORKDIR]
# (an existing WORKDIR keeps its simulated runs; the estimates are redone)
set -eu
CLI=${1:?usage: survey_pairs.sh path/to/sasnav [S0 N] [WORKDIR]}
S0=${2:-8001}
N=${3:-10}
DIR=${4:-$(mktemp -d)}
PAIR_OPTS=${PAIR_OPTS:-}
THREADS=${THREADS:-2}
SNR=${SNR:-30}
mkdir -p "$DIR"
printf 'preset: survey\ntrajectory:\n  n_pings: 3\n' > "$DIR/survey3.yaml"
TAG=$(printf '%s' "$PAIR_OPTS" | tr -c 'A-Za-z0-9.' '_')
s=$S0
while [ "$s" -lt $((S0 + N)) ]; do
    [ -f "$DIR/run${SNR}_$s.h5" ] || "$CLI" simulate --config "$DIR/survey3.yaml" --seed "$s" \
        --snr "$SNR" -o "$DIR/run${SNR}_$s.h5" 2>/dev/null
    # shellcheck disable=SC2086 # PAIR_OPTS is a list of options
    "$CLI" pair "$DIR/run${SNR}_$s.h5" --p 1 --q 2 --threads "$THREADS" --json $PAIR_OPTS \
        > "$DIR/pair${SNR}${TAG}_$s.json"
    s=$((s + 1))
done
python3 - "$DIR" "$SNR$TAG" "$S0" "$N" <<'EOF'
import json, sys
d, tag, s0, n = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
SLIP_SURGE, SLIP_YAW = 0.00625, 0.8 * 0.025 / 70.0
rows = []
for s in range(s0, s0 + n):
    r = json.load(open(f"{d}/pair{tag}_{s}.json"))
    e = r["estimation_error"]
    slip = abs(e["surge"]) > SLIP_SURGE or abs(e["yaw"]) > SLIP_YAW
    rows.append((s, e, r["verdict"], slip, r["seconds"], r["operator_applications"], r["eta"], r["margin"]))
    print(f"seed {s}: surge {e['surge']*1e3:+.3f} mm  sway {e['sway']*1e6:+.1f} um  yaw {e['yaw']:+.2e} rad"
          f"  eta {r['eta']:.3f}  margin {r['margin']:.2f}  {r['verdict']}{'  SLIP' if slip else ''}"
          f"  {r['seconds']:.1f} s  {r['operator_applications']} applications")
def pct(v, p):
    v = sorted(v)
    k = (len(v) - 1) * p
    i = int(k)
    return v[i] if i + 1 >= len(v) else v[i] + (v[i + 1] - v[i]) * (k - i)
for name, key, scale, unit in (("surge", "surge", 1e3, "mm"), ("sway", "sway", 1e6, "um"), ("yaw", "yaw", 1, "rad")):
    a = [abs(r[1][key]) * scale for r in rows]
    print(f"|{name} error| {unit}: median {pct(a, .5):.4g}  p95 {pct(a, .95):.4g}  max {max(a):.4g}")
verdicts = {}
for r in rows:
    verdicts[r[2]] = verdicts.get(r[2], 0) + 1
slips = sum(r[3] for r in rows)
unflagged = sum(r[3] and r[2] == "ok" for r in rows)
print(f"verdicts {verdicts}  slips {slips} of {len(rows)}  unflagged slips {unflagged}")
print(f"median wall {pct([r[4] for r in rows], .5):.1f} s  applications {pct([r[5] for r in rows], .5):.0f}")
EOF
