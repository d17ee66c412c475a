#!/bin/sh
# The CLI as a user runs it: bad inputs give one clear message on stderr, a
# non-zero exit status and no output file; good inputs work end to end.
# usage: sh tests/cli_errors.sh path/to/sasnav
set -u
SASNAV=$1
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fails=0

# expect_fail NAME OUTPUT_PATH COMMAND...: non-zero exit, a message, no output.
expect_fail() {
    name=$1; out=$2; shift 2
    if "$@" >"$T/stdout" 2>"$T/stderr"; then
        echo "FAIL $name: exit status 0"; fails=$((fails + 1)); return
    fi
    if [ ! -s "$T/stderr" ]; then
        echo "FAIL $name: no error message"; fails=$((fails + 1)); return
    fi
    if [ -n "$out" ] && ls "$out"* >/dev/null 2>&1; then
        echo "FAIL $name: output file left behind"; fails=$((fails + 1)); return
    fi
    echo "ok   $name: $(head -n 1 "$T/stderr")"
}

expect_ok() {
    name=$1; shift
    if ! "$@" >"$T/stdout" 2>"$T/stderr"; then
        echo "FAIL $name: $(cat "$T/stderr")"; fails=$((fails + 1)); return
    fi
    echo "ok   $name"
}

expect_ok "help" "$SASNAV" --help
expect_ok "simulate --help" "$SASNAV" simulate --help
expect_ok "image --help" "$SASNAV" image --help
expect_ok "pair --help" "$SASNAV" pair --help
expect_fail "unknown command" "" "$SASNAV" frobnicate

# A small noise-free run: the point preset with 3 pings.
cat >"$T/point3.yaml" <<'YAML'
preset: point
trajectory: {n_pings: 3, x_start: -0.2}
YAML
expect_ok "simulate point" "$SASNAV" simulate --config "$T/point3.yaml" -o "$T/run.h5"
expect_ok "image point" "$SASNAV" image "$T/run.h5" --grid -0.1,0.1,41,9.9,10.1,41 -o "$T/img.h5" --png "$T/img.png"
[ -s "$T/img.png" ] || { echo "FAIL png not written"; fails=$((fails + 1)); }

# A scene loaded from an image file (the image just written), re-simulated
# with its scatterers jittered off the grid, then imaged: the peak of the
# new image is where the point target was (within two pixels).
printf 'preset: point\ntrajectory: {n_pings: 3, x_start: -0.2}\nscene: {kind: file, file: "%s"}\n' "$T/img.h5" >"$T/scene.yaml"
expect_ok "simulate scene from file" "$SASNAV" simulate --config "$T/scene.yaml" -o "$T/run2.h5"
expect_ok "image scene from file" "$SASNAV" image "$T/run2.h5" --grid -0.1,0.1,41,9.9,10.1,41 -o "$T/img2.h5"
if command -v /usr/bin/python3 >/dev/null && /usr/bin/python3 -c 'import h5py, numpy' 2>/dev/null; then
    /usr/bin/python3 - "$T/img.h5" "$T/img2.h5" <<'PY' || fails=$((fails + 1))
import sys, h5py, numpy as np
def peak(path):
    with h5py.File(path, "r") as f:
        img = np.abs(f["image"][()])
        iy, ix = np.unravel_index(np.argmax(img), img.shape)
        return f["x"][ix], f["y"][iy]
a, b = peak(sys.argv[1]), peak(sys.argv[2])
ok = abs(a[0] - b[0]) <= 0.011 and abs(a[1] - b[1]) <= 0.011
print(("ok  " if ok else "FAIL") + " scene from file: peak %s vs %s" % (b, a))
sys.exit(0 if ok else 1)
PY
fi

# Bad configs: NaN, zero elements, a negative range, syntax, missing file.
printf 'preset: paper-pair\nsystem: {f0: .nan}\n' >"$T/nan.yaml"
expect_fail "NaN in config" "$T/out1.h5" "$SASNAV" simulate --config "$T/nan.yaml" -o "$T/out1.h5"
printf 'preset: paper-pair\narray: {n_rx: 0}\n' >"$T/zero.yaml"
expect_fail "zero elements" "$T/out2.h5" "$SASNAV" simulate --config "$T/zero.yaml" -o "$T/out2.h5"
printf 'preset: paper-pair\nswath: {range_min: -3}\n' >"$T/neg.yaml"
expect_fail "negative range" "$T/out3.h5" "$SASNAV" simulate --config "$T/neg.yaml" -o "$T/out3.h5"
printf 'preset: paper-pair\nsystem: [f0: 3\n' >"$T/syntax.yaml"
expect_fail "YAML syntax" "$T/out4.h5" "$SASNAV" simulate --config "$T/syntax.yaml" -o "$T/out4.h5"
expect_fail "missing config" "$T/out5.h5" "$SASNAV" simulate --config "$T/none.yaml" -o "$T/out5.h5"
expect_fail "unknown preset" "$T/out6.h5" "$SASNAV" simulate --preset nope -o "$T/out6.h5"
expect_fail "bad --error" "$T/out7.h5" "$SASNAV" simulate --preset paper-pair --error 1,2 -o "$T/out7.h5"
expect_fail "NaN --snr" "$T/out8.h5" "$SASNAV" simulate --preset paper-pair --snr nan -o "$T/out8.h5"

# Bad run files: missing, not HDF5, truncated, missing dataset.
expect_fail "missing run" "$T/i1.h5" "$SASNAV" image "$T/nothere.h5" -o "$T/i1.h5"
# --gpu in a build without CUDA: refused before any work, saying how to get it
# (a CUDA build runs it: tests/test_gpu.c)
if "$SASNAV" pair "$T/run.h5" --gpu >/dev/null 2>"$T/gpu.txt" || ! grep -q "has no CUDA" "$T/gpu.txt"; then
    echo "ok   --gpu: this build has CUDA (checked by test_gpu)"
else
    expect_fail "--gpu without CUDA" "$T/g1.h5" "$SASNAV" navigate "$T/run.h5" --gpu -o "$T/g1.h5"
    grep -q "SASNAV_CUDA=ON" "$T/stderr" || { echo "FAIL --gpu message: $(cat "$T/stderr")"; fails=$((fails + 1)); }
fi
echo "not an hdf5 file" >"$T/text.h5"
expect_fail "not HDF5" "$T/i2.h5" "$SASNAV" image "$T/text.h5" -o "$T/i2.h5"
size=$(wc -c <"$T/run.h5")
head -c $((size / 2)) "$T/run.h5" >"$T/trunc.h5"
expect_fail "truncated run" "$T/i3.h5" "$SASNAV" image "$T/trunc.h5" -o "$T/i3.h5"
expect_fail "image file as run" "$T/i4.h5" "$SASNAV" image "$T/img.h5" -o "$T/i4.h5"
expect_fail "bad grid" "$T/i5.h5" "$SASNAV" image "$T/run.h5" --grid 1,0,10,9,10,10 -o "$T/i5.h5"
# the grid's own reason reaches the user (not a generic syntax message)
grep -q "must be increasing" "$T/stderr" || { echo "FAIL bad grid message: $(cat "$T/stderr")"; fails=$((fails + 1)); }
"$SASNAV" image "$T/run.h5" --grid -1,1,100000,9,11,100000 -o "$T/i5.h5" >/dev/null 2>"$T/stderr"
[ $? -eq 2 ] && grep -q "too large" "$T/stderr" ||
    { echo "FAIL huge grid: status or message: $(cat "$T/stderr")"; fails=$((fails + 1)); }
# a FIFO given as a config or run is refused at once, not waited on
mkfifo "$T/fifo.yaml" && {
    timeout 30 "$SASNAV" simulate --config "$T/fifo.yaml" -o "$T/f.h5" >/dev/null 2>"$T/stderr"
    st=$?
    [ $st -eq 1 ] && grep -q "not a regular file" "$T/stderr" ||
        { echo "FAIL FIFO config: exit $st, $(cat "$T/stderr")"; fails=$((fails + 1)); }
    timeout 30 "$SASNAV" image "$T/fifo.yaml" -o "$T/f.h5" >/dev/null 2>"$T/stderr"
    st=$?
    [ $st -eq 1 ] && grep -q "not a regular file" "$T/stderr" ||
        { echo "FAIL FIFO run: exit $st, $(cat "$T/stderr")"; fails=$((fails + 1)); }
}
expect_fail "output in missing dir" "$T/nodir/i6.h5" "$SASNAV" image "$T/run.h5" -o "$T/nodir/i6.h5"

# The pair estimator and the cuts on the paper's pair (coarse iterations to
# keep the sanitized run short): JSON fields present, values finite, the
# estimate within 2 mm / lambda/10 / 2e-3 rad of the truth at k = i = 2.
expect_ok "simulate paper-pair" "$SASNAV" simulate --preset paper-pair -o "$T/pair.h5"
if "$SASNAV" pair "$T/pair.h5" --json --k 2 --i 2 >"$T/pair.json" 2>"$T/pair.err"; then
    if /usr/bin/python3 - "$T/pair.json" <<'PY'
import json, math, sys
d = json.load(open(sys.argv[1]))
for k in ("surge", "sway", "yaw", "truth", "zeta_stage", "evaluations", "status"):
    assert k in d, "missing field " + k
t = d["truth"]
assert d["status"] == "converged", d["status"]
assert abs(d["surge"] - t["surge"]) < 2e-3 and abs(d["sway"] - t["sway"]) < 5e-4 and abs(d["yaw"] - t["yaw"]) < 2e-3, d
# Where the time went: the four stages, their applications summing to no
# more than the whole (the closing evaluation may lie outside them).
st = d["stages"]
apps = sum(st[s]["applications"] for s in ("global", "zeta", "eta", "final"))
assert 0 < apps <= d["operator_applications"], (apps, d["operator_applications"])
assert all(st[s]["seconds"] >= 0 for s in st), st
# The verdict and the candidates: the paper pair is well posed ("ok"), one
# candidate is chosen, and the chosen one is the estimate's neighbourhood.
assert d["verdict"] == "ok", d["verdict"]
c = d["candidates"]
assert len(c) >= 1 and sum(x["chosen"] for x in c) == 1, c
ch = [x for x in c if x["chosen"]][0]
assert abs(ch["surge"] - d["surge"]) < 5e-3 and abs(ch["yaw"] - d["yaw"]) < 2e-3, (ch, d["surge"])
print("ok   pair --json: error (%.3f mm, %.4f mm, %.1e rad)" % (1e3 * (d["surge"] - t["surge"]), 1e3 * (d["sway"] - t["sway"]), d["yaw"] - t["yaw"]))
PY
    then :; else echo "FAIL pair --json content"; fails=$((fails + 1)); fi
else
    echo "FAIL pair --json: $(cat "$T/pair.err")"; fails=$((fails + 1))
fi
expect_ok "cuts" "$SASNAV" cuts "$T/pair.h5" --n 5 --k 2 --i 1 -o "$T/cuts"
for f in cut_surge.csv cut_sway.csv cut_yaw.csv cut_surge.png cut_sway.png cut_yaw.png; do
    [ -s "$T/cuts/$f" ] || { echo "FAIL cuts: $f missing"; fails=$((fails + 1)); }
done

# Pair estimation refusals: same ping twice, ping out of range.
expect_fail "pair same ping" "" "$SASNAV" pair "$T/run.h5" --p 1 --q 1
expect_fail "pair out of range" "" "$SASNAV" pair "$T/run.h5" --p 0 --q 7

# Validation and tank refusals.
expect_fail "validate missing run" "" "$SASNAV" validate "$T/none.h5" -o "$T/val"
expect_fail "validate no output" "" "$SASNAV" validate "$T/pair.h5"
expect_fail "validate two yaw models" "" "$SASNAV" validate "$T/pair.h5" --fix-yaw --yaw-sigma 1e-3 -o "$T/val"
expect_fail "validate K above the run's" "" "$SASNAV" validate "$T/pair.h5" --k-max 12 -o "$T/val"
expect_fail "tank preset with --snr" "" "$SASNAV" simulate --preset tank --snr 10 -o "$T/tankrec"
expect_fail "pair negative yaw sigma" "" "$SASNAV" pair "$T/pair.h5" --yaw-sigma -1
expect_fail "pair negative surge sigma" "" "$SASNAV" pair "$T/pair.h5" --surge-sigma -1
expect_fail "pair zero range extent" "" "$SASNAV" pair "$T/pair.h5" --range-extent 0
expect_fail "pair coincidence beyond half a spacing" "" "$SASNAV" pair "$T/pair.h5" --coincidence 0.6
expect_fail "navigate negative coincidence" "$T/nav_co.h5" "$SASNAV" navigate "$T/pair.h5" --coincidence -0.1 -o "$T/nav_co.h5"
expect_fail "pair negative compact contrast" "" "$SASNAV" pair "$T/pair.h5" --compact-contrast -1
expect_fail "navigate compact contrast not a number" "$T/nav_cc.h5" "$SASNAV" navigate "$T/pair.h5" --compact-contrast x -o "$T/nav_cc.h5"
expect_fail "navigate eta outlier factor 1" "$T/nav_eo.h5" "$SASNAV" navigate "$T/pair.h5" --eta-outlier 1 -o "$T/nav_eo.h5"
expect_fail "navigate eta outlier not a number" "$T/nav_eo.h5" "$SASNAV" navigate "$T/pair.h5" --eta-outlier x -o "$T/nav_eo.h5"
expect_fail "navigate range extent not a number" "$T/nav_re.h5" "$SASNAV" navigate "$T/pair.h5" --range-extent x -o "$T/nav_re.h5"
expect_fail "validate surge sigma not a number" "" "$SASNAV" validate "$T/pair.h5" --surge-sigma x -o "$T/val"
expect_fail "tank negative clutter" "" "$SASNAV" tank --clutter -1 -o "$T/tankrec"
expect_fail "tank plate beyond the record" "" "$SASNAV" tank --plate-range 5 -o "$T/tankrec"
expect_fail "ingest wav negative range" "" "$SASNAV" ingest --wav "$T/tankrec" --range -1 -o "$T/tank.h5"
expect_fail "navigate first pose and anchor" "" "$SASNAV" navigate "$T/pair.h5" --first-pose 0,0,0 --anchor-truth -o "$T/nav.h5"
expect_fail "refine no output" "" "$SASNAV" refine "$T/run.h5" "$T/run.h5"
expect_fail "refine missing navigation" "$T/ref.h5" "$SASNAV" refine "$T/run.h5" "$T/missing.h5" -o "$T/ref.h5"
expect_fail "refine ping counts differ" "$T/ref.h5" "$SASNAV" refine "$T/run.h5" "$T/pair.h5" -o "$T/ref.h5"
expect_fail "refine two pings" "$T/ref.h5" "$SASNAV" refine "$T/pair.h5" "$T/pair.h5" -o "$T/ref.h5"
expect_fail "refine zero sweeps" "$T/ref.h5" "$SASNAV" refine "$T/run.h5" "$T/run.h5" --sweeps 0 -o "$T/ref.h5"
expect_fail "refine negative sparsity" "$T/ref.h5" "$SASNAV" refine "$T/run.h5" "$T/run.h5" --sparsity -1 -o "$T/ref.h5"
expect_fail "refine sparsity not a number" "$T/ref.h5" "$SASNAV" refine "$T/run.h5" "$T/run.h5" --sparsity abc -o "$T/ref.h5"
expect_fail "validate negative sparsity" "" "$SASNAV" validate "$T/pair.h5" --refine --sparsity -1 -o "$T/val"
expect_fail "refine grid out of reach" "$T/ref.h5" "$SASNAV" refine "$T/run.h5" "$T/run.h5" --grid -0.1,0.1,5,40,40.1,5 -o "$T/ref.h5"
expect_ok "refine point run" "$SASNAV" refine "$T/run.h5" "$T/run.h5" --grid -0.1,0.1,41,9.9,10.1,41 --sweeps 1 -o "$T/ref.h5"
[ -s "$T/ref.h5" ] || { echo "FAIL refined navigation not written"; fails=$((fails + 1)); }

ls "$T" | grep -q 'tmp-' && { echo "FAIL temporary files left: $(ls "$T")"; fails=$((fails + 1)); }
echo "cli_errors: $fails failures"
[ "$fails" -eq 0 ]
