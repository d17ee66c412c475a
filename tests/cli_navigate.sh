#!/bin/sh
# `sasnav navigate` as a user runs it: simulate a tiny run (3 pings), navigate
# it with --json (subspace, coarse iterations to keep it short, and DPCA),
# check the summary's fields and the output file; a missing input file must
# fail with a message, a non-zero status and no output file.
# Usage: sh tests/cli_navigate.sh path/to/sasnav
set -u
CLI=${1:?usage: cli_navigate.sh path/to/sasnav}
T=$(mktemp -d "${TMPDIR:-/tmp}/sasnav-cli-navigate-XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT INT TERM
FAILED=0
fail() {
    echo "cli_navigate: FAIL: $*" >&2
    FAILED=1
}

cat > "$T/tiny.yaml" <<'EOF'
preset: paper-trajectory
trajectory: {n_pings: 3, x_start: -0.2, surge_rms: 0.003, sway_rms: 0.003, yaw_rms: 0.003}
noise: {snr_db: inf}
EOF
"$CLI" simulate --config "$T/tiny.yaml" -o "$T/run.h5" 2> "$T/sim.err" ||
    { cat "$T/sim.err" >&2; fail "simulate"; exit 1; }

# Subspace (the default method), k = 2, i = 1.
if "$CLI" navigate "$T/run.h5" --k 2 --i 1 --json -o "$T/nav.h5" > "$T/nav.json" 2> "$T/nav.err"; then
    [ -s "$T/nav.h5" ] || fail "no navigation file written"
    # stderr is not a terminal here: no progress bar (no carriage return).
    if tr '\r' '#' < "$T/nav.err" | grep -q '#'; then fail "progress bar drawn on a non-terminal"; fi
    for key in final_surge_error final_sway_error final_yaw_error rms_sway_error pairs \
               track_angle seconds seconds_per_pair; do
        grep -q "\"$key\"" "$T/nav.json" || fail "JSON lacks \"$key\""
    done
    if [ -x /usr/bin/python3 ]; then
        /usr/bin/python3 - "$T/nav.json" <<'EOF' || fail "JSON content (subspace)"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["method"] == "subspace", d["method"]
assert len(d["pairs"]) == 2, d["pairs"]
for p in d["pairs"]:
    for k in ("p", "q", "surge", "sway", "yaw", "truth", "error", "status"):
        assert k in p, k
    for k in ("surge", "sway", "yaw"):
        assert abs(p["error"][k] - (p[k] - p["truth"][k])) < 1e-9, p
for k in ("final_surge_error", "final_sway_error", "final_yaw_error", "rms_sway_error",
          "track_angle", "seconds", "seconds_per_pair"):
    assert isinstance(d[k], float), (k, d[k])
# Coarse iterations on a noise-free run: far inside lambda / 10 = 0.5 mm.
assert abs(d["final_sway_error"]) < 5e-4, d["final_sway_error"]
assert d["seconds"] > 0 and d["seconds_per_pair"] > 0
EOF
    fi
else
    cat "$T/nav.err" >&2
    fail "navigate (subspace) exited non-zero"
fi

# DPCA, text output.
"$CLI" navigate "$T/run.h5" --method dpca -o "$T/nav-dpca.h5" > "$T/dpca.txt" 2> "$T/dpca.err" ||
    { cat "$T/dpca.err" >&2; fail "navigate --method dpca exited non-zero"; }
grep -q "final cumulative error" "$T/dpca.txt" || fail "DPCA text output lacks the final error"
[ -s "$T/nav-dpca.h5" ] || fail "no DPCA navigation file"

# The navigation file images the run.
"$CLI" image "$T/run.h5" --nav "$T/nav-dpca.h5" --grid -0.5,0.5,21,9.5,10.5,21 -o "$T/img.h5" \
    2> "$T/img.err" || { cat "$T/img.err" >&2; fail "image --nav with the navigate output"; }

# Placing the trajectory: --first-pose puts the first centroid at the fix
# (the array yaw equals the fix's yaw, its position is within the EPCA
# offset, 5 cm, of it); --anchor-truth puts it on the true first pose (the
# array yaws of the estimate and the truth written beside it coincide).
first_array() { # FILE GROUP -> "x y yaw" of ping 0
    h5dump -d "/$2/array" -s "0,0" -c "1,3" -y -w 0 "$1" 2>/dev/null |
        sed -n '/DATA {/{n;p;q}' | tr -d ','
}
if command -v h5dump > /dev/null 2>&1; then
    "$CLI" navigate "$T/run.h5" --method dpca --first-pose 1.5,2.5,0.1 -o "$T/nav-fix.h5" > /dev/null 2>&1 ||
        fail "navigate --first-pose"
    set -- $(first_array "$T/nav-fix.h5" nav)
    awk -v x="${1:-nan}" -v y="${2:-nan}" -v t="${3:-nan}" 'BEGIN {
        exit !((x - 1.5) ^ 2 + (y - 2.5) ^ 2 < 0.05 ^ 2 && (t - 0.1) ^ 2 < 1e-10) }' ||
        fail "--first-pose: first array pose ($*) not at the fix 1.5,2.5,0.1"
    "$CLI" navigate "$T/run.h5" --method dpca --anchor-truth -o "$T/nav-anc.h5" > /dev/null 2>&1 ||
        fail "navigate --anchor-truth"
    set -- $(first_array "$T/nav-anc.h5" nav) $(first_array "$T/nav-anc.h5" truth)
    awk -v a="${1:-nan}" -v b="${2:-nan}" -v c="${3:-nan}" -v d="${4:-nan}" -v e="${5:-nan}" -v f="${6:-nan}" \
        'BEGIN { exit !((a - d) ^ 2 + (b - e) ^ 2 < 1e-6 && (c - f) ^ 2 < 1e-10) }' ||
        fail "--anchor-truth: first array pose ($1 $2 $3) is not the true one ($4 $5 $6)"
else
    echo "cli_navigate: h5dump absent, --first-pose / --anchor-truth checks skipped"
fi

# Missing input: non-zero, one message, no output file.
if "$CLI" navigate "$T/missing.h5" -o "$T/out.h5" > /dev/null 2> "$T/missing.err"; then
    fail "a missing input file was accepted"
fi
grep -q "sasnav navigate: cannot read" "$T/missing.err" || fail "missing input: no clear message"
[ ! -e "$T/out.h5" ] || fail "missing input: an output file was written"
ls "$T" | grep -q 'out.h5' && fail "missing input: a temporary output file was left"

# Virtual arrays: a 16-ping circular SISO run (the simulated AirSAS with
# its smooth 3 mm motion errors, noise-free), groups of 4 (3 pairs): the
# plumbing (JSON fields, truth, every displacement's sway within 1 mm of
# the truth: measured 0.1-0.5 mm; the accuracy itself is tested in
# tests/test_virtual.c), then the refusals.
cat > "$T/circ.yaml" <<'EOF'
preset: circular
trajectory: {n_pings: 16}
noise: {snr_db: inf}
EOF
if "$CLI" simulate --config "$T/circ.yaml" -o "$T/circ.h5" 2> "$T/circ.err"; then
    if "$CLI" navigate "$T/circ.h5" --virtual-array 4 --iterations 1 --align-heading --json \
        -o "$T/vnav.h5" > "$T/vnav.json" 2> "$T/vnav.err"; then
        [ -s "$T/vnav.h5" ] || fail "virtual array: no navigation file"
        grep -q "align-heading" "$T/vnav.err" && fail "virtual array: a crab warning on the nominal circle"
        if [ -x /usr/bin/python3 ]; then
            /usr/bin/python3 - "$T/vnav.json" <<'EOF' || fail "virtual array: JSON content"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["virtual_array"] == 4 and d["stride"] == 4 and d["interleave"] == 1, d
assert len(d["pairs"]) == 3, d["pairs"]
assert d["length_scale"] == 1.0, d["length_scale"]
# The input is the nominal circle: its layouts already lie along the
# headings (a 4-ping chord is parallel to its mean heading), so the turns
# are 0 to rounding and no crab warning is printed.
assert d["align_heading"] is True, d["align_heading"]
assert len(d["layout_turn"]) == 4 and all(abs(t) < 1e-9 for t in d["layout_turn"]), d["layout_turn"]
assert abs(d["layout_turn_mean"]) < 1e-9 and d["turn_exposure"] < 1e-9, d
for p in d["pairs"]:
    assert p["status"] in ("ok", "ambiguous", "failed", "no_overlap"), p
    assert abs(p["displacement"]["sway"] - p["truth"]["sway"]) < 0.001, p
EOF
        fi
    else
        cat "$T/vnav.err" >&2
        fail "navigate --virtual-array"
    fi
else
    cat "$T/circ.err" >&2
    fail "simulate circular"
fi
# --along-track input: reported, and it implies --align-heading (the
# geometry of the correction is tested in tests/test_virtual.c).
if [ -s "$T/circ.h5" ]; then
    if "$CLI" navigate "$T/circ.h5" --virtual-array 4 --iterations 1 --along-track input --json \
        -o "$T/anav.h5" > "$T/anav.json" 2> "$T/anav.err"; then
        [ -s "$T/anav.h5" ] || fail "--along-track input: no navigation file"
        grep -q "keeps the input's along-track drift" "$T/anav.err" ||
            fail "--along-track input: no warning of what it keeps"
        if [ -x /usr/bin/python3 ]; then
            /usr/bin/python3 - "$T/anav.json" "$T/vnav.json" <<'EOF' || fail "--along-track input: JSON content"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["along_track"] == "input" and d["align_heading"] is True, d
assert json.load(open(sys.argv[2]))["along_track"] == "echoes"
EOF
        fi
    else
        cat "$T/anav.err" >&2
        fail "navigate --along-track input"
    fi
fi
"$CLI" navigate "$T/run.h5" --along-track input -o "$T/x.h5" > /dev/null 2>&1
[ $? -eq 2 ] || fail "--along-track without --virtual-array: not a usage error"
"$CLI" navigate "$T/circ.h5" --virtual-array 4 --along-track dvl -o "$T/x.h5" > /dev/null 2> "$T/at.err"
[ $? -eq 2 ] && grep -q "echoes or input" "$T/at.err" || fail "--along-track dvl: not a clear usage error"
"$CLI" navigate "$T/circ.h5" --virtual-array 4 --along-track input --estimate-yaw -o "$T/x.h5" > /dev/null 2>&1
[ $? -eq 2 ] || fail "--along-track input with --estimate-yaw: not a usage error"
"$CLI" navigate "$T/run.h5" --stride 2 -o "$T/x.h5" > /dev/null 2>&1
[ $? -eq 2 ] || fail "--stride without --virtual-array: not a usage error"
"$CLI" navigate "$T/run.h5" --virtual-array 4 --method dpca -o "$T/x.h5" > /dev/null 2>&1
[ $? -eq 2 ] || fail "--virtual-array with --method: not a usage error"
"$CLI" navigate "$T/run.h5" --virtual-array 4 --eta-outlier 2 -o "$T/x.h5" > /dev/null 2>&1
[ $? -eq 2 ] || fail "--virtual-array with --eta-outlier (a rule over consecutive pairs): not a usage error"
"$CLI" navigate "$T/run.h5" --virtual-array 200 -o "$T/x.h5" > /dev/null 2>&1
[ $? -eq 2 ] || fail "--virtual-array 200: not a usage error"
"$CLI" navigate "$T/run.h5" --virtual-array 2 -o "$T/x.h5" > /dev/null 2> "$T/few.err"
[ $? -eq 1 ] && grep -q "fewer than two groups" "$T/few.err" || fail "3 pings in groups of 2: no clear failure"
"$CLI" navigate "$T/circ.h5" --virtual-array 4 --closed -o "$T/x.h5" > /dev/null 2> "$T/open.err"
[ $? -eq 1 ] && grep -q "closed needs a track" "$T/open.err" || fail "--closed on an open track: no clear failure"
"$CLI" navigate "$T/run.h5" --closed -o "$T/x.h5" > /dev/null 2>&1
[ $? -eq 2 ] || fail "--closed without --virtual-array: not a usage error"
"$CLI" navigate "$T/run.h5" --keep-length -o "$T/x.h5" > /dev/null 2>&1
[ $? -eq 2 ] || fail "--keep-length without --virtual-array: not a usage error"
"$CLI" navigate "$T/run.h5" --align-heading -o "$T/x.h5" > /dev/null 2>&1
[ $? -eq 2 ] || fail "--align-heading without --virtual-array: not a usage error"

# Usage errors.
"$CLI" navigate "$T/run.h5" --method kalman -o "$T/x.h5" > /dev/null 2>&1 && fail "unknown method accepted"
"$CLI" navigate "$T/run.h5" > /dev/null 2>&1 && fail "missing -o accepted"
[ ! -e "$T/x.h5" ] || fail "an output file was written after a usage error"

[ "$FAILED" -eq 0 ] && echo "cli_navigate: ok"
exit "$FAILED"
