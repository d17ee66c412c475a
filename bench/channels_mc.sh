#!/bin/sh
# Monte Carlo of a two-transmitter head against the one-transmitter head
# (docs/model.md, "Channel layouts"): paper-trajectory (16 pings, 30 dB,
# true bistatic poses, smooth motion errors) with the head of
# examples/two_tx_head.yaml, seeds S0 .. S0 + N - 1, each simulated with
# aiding. Navigations per seed (VARIANTS, default all five):
#   two_gyro   the two-Tx run, default: layouts with the gyro's transmitter
#              yaw, aiding fused
#   two_pairs  the two-Tx run with --no-aiding: transmitter yaw from the
#              pairs' own yaw estimates (--tx-yaw auto without a gyro), no
#              fusion
#   two_plain  the two-Tx run with --no-aiding --tx-yaw none: transmitter
#              yaw 0, no fusion
#   one_aided  the same seed with the paper's one-Tx head, aiding fused
#   one_plain  the same one-Tx run with --no-aiding
# (the pair errors are the raw estimates', before any fusion: two_gyro
# against one_plain compares the heads; the final errors include the
# fusion where aiding is used: compare two_gyro with one_aided.)
# Prints per variant the median and 95th percentile of |pair sway error|
# (raw estimates: estimate - truth) and of |final sway error|, and the runs
# within lambda / 25 = 0.2 mm final sway.
#
# usage: [VARIANTS="two_pairs ..."] sh bench/channels_mc.sh path/to/sasnav [S0 N] [WORKDIR]
# (an existing WORKDIR keeps its runs and the navigations not asked for)
set -eu
VARIANTS=${VARIANTS:-two_gyro two_pairs two_plain one_aided one_plain}
CLI=${1:?usage: channels_mc.sh path/to/sasnav [S0 N] [WORKDIR]}
S0=${2:-2001}
N=${3:-10}
DIR=${4:-$(mktemp -d)}
HERE=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$DIR"
s=$S0
while [ "$s" -lt $((S0 + N)) ]; do
    [ -f "$DIR/two_$s.h5" ] || "$CLI" simulate --preset paper-trajectory \
        --config "$HERE/examples/two_tx_head.yaml" --seed "$s" --snr 30 --aiding -o "$DIR/two_$s.h5" 2>/dev/null
    [ -f "$DIR/one_$s.h5" ] || "$CLI" simulate --preset paper-trajectory --seed "$s" --snr 30 --aiding \
        -o "$DIR/one_$s.h5" 2>/dev/null
    for v in $VARIANTS; do
        case $v in
            two_gyro) set -- "$DIR/two_$s.h5" ;;
            two_pairs) set -- "$DIR/two_$s.h5" --no-aiding ;;
            two_plain) set -- "$DIR/two_$s.h5" --no-aiding --tx-yaw none ;;
            one_aided) set -- "$DIR/one_$s.h5" ;;
            one_plain) set -- "$DIR/one_$s.h5" --no-aiding ;;
            *) echo "channels_mc.sh: unknown variant $v" >&2; exit 2 ;;
        esac
        "$CLI" navigate "$@" --json -o "$DIR/n.h5" 2>/dev/null > "$DIR/${v}_$s.json"
    done
    echo "seed $s done" >&2
    s=$((s + 1))
done
python3 - "$DIR" "$S0" "$N" <<'PY'
import json, math, os, sys
def median(v):
    v = sorted(v); k = len(v)
    return 0.5 * (v[(k - 1) // 2] + v[k // 2])
def p95(v):  # linear interpolation between order statistics
    v = sorted(v); x = 0.95 * (len(v) - 1); i = int(math.floor(x))
    return v[i] if i + 1 >= len(v) else v[i] + (x - i) * (v[i + 1] - v[i])
d, s0, n = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
print(f"seeds {s0}..{s0 + n - 1}, paper-trajectory 30 dB, 16 pings")
print(f"{'variant':<10} {'pair sway mm median/p95':>24} {'final sway mm median/p95':>25} "
      f"{'<= 0.2 mm':>9} {'flagged':>7}")
for v in ("two_gyro", "two_pairs", "two_plain", "one_aided", "one_plain"):
    pair, final, flagged = [], [], 0
    if not os.path.exists(f"{d}/{v}_{s0}.json"):
        continue
    for s in range(s0, s0 + n):
        j = json.load(open(f"{d}/{v}_{s}.json"))
        final.append(abs(j["final_sway_error"]) * 1e3)
        flagged += j["flagged_pairs"]
        for p in j["pairs"]:
            pair.append(abs(p["estimate"]["sway"] - p["truth"]["sway"]) * 1e3)
    print(f"{v:<10} {median(pair):>11.4f} / {p95(pair):<10.4f} "
          f"{median(final):>11.3f} / {p95(final):<11.3f} "
          f"{sum(f <= 0.2 for f in final):>4d}/{n:<4d} {flagged:>7d}")
PY
