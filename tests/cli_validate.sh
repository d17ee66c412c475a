#!/bin/sh
# The tank experiment as a user runs it: `sasnav simulate --preset tank`
# writes the recordings (cut to 14 pings), `sasnav ingest --wav` reads them,
# `sasnav validate --json` (K = 7 only, coarse iterations, to stay short)
# prints the issue's fields and writes its files; the jump and the array yaw against the
# simulated truth within the issue's bounds (1 mm, 2e-3 rad).
# Usage: sh tests/cli_validate.sh path/to/sasnav
set -u
CLI=${1:?usage: cli_validate.sh path/to/sasnav}
T=$(mktemp -d "${TMPDIR:-/tmp}/sasnav-cli-validate-XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT INT TERM
FAILED=0
fail() {
    echo "cli_validate: FAIL: $*" >&2
    FAILED=1
}

"$CLI" simulate --preset tank -o "$T/rec" 2> "$T/sim.err" || { cat "$T/sim.err" >&2; fail "simulate --preset tank"; exit 1; }
for f in ping_000.wav ping_031.wav chirp.wav positions.csv truth.csv array.csv; do
    [ -s "$T/rec/$f" ] || fail "recording lacks $f"
done
# A user's shorter recording: the first 14 pings (the jump between 11 and 12
# included), which keeps the test short under the sanitizers.
for f in positions.csv truth.csv; do
    head -n 15 "$T/rec/$f" > "$T/rec/$f.new" && mv "$T/rec/$f.new" "$T/rec/$f"
done
i=14
while [ "$i" -lt 32 ]; do rm -f "$T/rec/ping_0$(printf %02d "$i").wav"; i=$((i + 1)); done
"$CLI" ingest --wav "$T/rec" -o "$T/tank.h5" 2> "$T/ing.err" || { cat "$T/ing.err" >&2; fail "ingest --wav"; exit 1; }
if "$CLI" validate "$T/tank.h5" --fix-yaw --surge-sigma 0.025 --k-min 7 --k 2 --i 1 --json --checkpoint "$T/ck" -o "$T/val" > "$T/val.json" 2> "$T/val.err"; then
    [ -e "$T/ck" ] && fail "validate's checkpoint not removed after success"
    for key in surge_jump_error yaw_error sway_spread surge_spread surge_spread_ping surge_spread_k sway_spread_ping min_image_correlation; do
        grep -q "\"$key\"" "$T/val.json" || fail "JSON lacks \"$key\""
    done
    for f in validate.json trajectories.csv pairs.csv correlation.csv trajectories_surge.png \
             trajectories_sway.png siso_0.png simo_7.png nominal_simo_0.png report.md; do
        [ -s "$T/val/$f" ] || fail "validate wrote no $f"
    done
    ls "$T/val" | grep -q 'tmp' && fail "temporary files left in the output directory"
    grep -q "Surge prior (--surge-sigma): 0.025 m" "$T/val/report.md" || fail "report.md does not state the surge prior"
    grep -q '"flagged_pairs"' "$T/val.json" || fail "JSON lacks \"flagged_pairs\""
    head -n 1 "$T/val/pairs.csv" | grep -q ',eta,eta_outlier,status,verdict,equalised,equalise_peak$' ||
        fail "pairs.csv lacks the eta, eta_outlier, verdict or equalising columns"
    # eta a number in [0, 10], eta_outlier 0 or 1 (columns 6 and 5 from the end)
    tail -n +2 "$T/val/pairs.csv" |
        awk -F, '!($(NF-5) >= 0 && $(NF-5) <= 10) || $(NF-4) !~ /^[01]$/ { bad = 1 } END { exit bad }' ||
        fail "pairs.csv: an eta or eta_outlier value out of its range"
    # every pair's verdict is one of the estimator's names
    tail -n +2 "$T/val/pairs.csv" | awk -F, '$(NF-2) !~ /^(ok|ambiguous|failed|no_overlap)$/ { bad = 1 } END { exit bad }' ||
        fail "pairs.csv holds a verdict that is not a verdict name"
    # the tank is a compact scene (a few bright reflectors, contrast above
    # 4): its searches are never equalised, but the weights are made (the
    # default --equalise), so every pair reports its peak, a number > 0
    tail -n +2 "$T/val/pairs.csv" |
        awk -F, '$(NF-1) != "0" || $NF !~ /^[0-9]+\.[0-9][0-9][0-9]$/ || !($NF + 0 > 0) { bad = 1 } END { exit bad }' ||
        fail "pairs.csv: a tank pair equalised, or a peak that is not a number > 0"
    # values: jump within 1 mm, array yaw within 2e-3 rad (awk reads the JSON lines)
    awk -F': ' '/"surge_jump_error"/ { gsub(/,/, "", $2); j = $2 }
                /"yaw_error"/ { gsub(/,/, "", $2); y = $2 }
                END { exit !(j != "" && y != "" && j * j < 1e-6 && y * y < 4e-6) }' "$T/val.json" ||
        fail "jump or yaw outside the bounds: $(grep -E '"(surge_jump|yaw)_error"' "$T/val.json" | tr -d '\n')"
else
    cat "$T/val.err" >&2
    fail "validate exited non-zero"
fi
[ "$FAILED" -eq 0 ] && echo "cli_validate: ok"
exit "$FAILED"
