#!/bin/sh
# Trust and aiding from the command line, as a user runs them:
# `simulate --aiding` writes /aiding; `navigate --json` reports per pair a
# status, candidates, the resolution and the aiding; `navigate --method
# aiding` dead-reckons; `--no-aiding` ignores the aiding; a run without
# aiding, or without a DVL, refuses --method aiding (exit 1, one message,
# no output); bad
# --motion-sigma, --link-sigma, --link-eta or --method is refused;
# --link-sigma and --link-eta reach the fusion; a compact scene's flagged pairs
# give one warning line each on stderr; the eta-outlier rule's median and
# marks on an 8-ping run. (Exit statuses of usage errors: the
# issue on the CLI's conventions.)
# Usage: sh tests/cli_trust.sh path/to/sasnav
set -u
CLI=${1:?usage: cli_trust.sh path/to/sasnav}
T=$(mktemp -d "${TMPDIR:-/tmp}/sasnav-cli-trust-XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT INT TERM
FAILED=0
fail() {
    echo "cli_trust: FAIL: $*" >&2
    FAILED=1
}

cat > "$T/tiny.yaml" <<'EOF'
preset: paper-trajectory
trajectory: {n_pings: 3, x_start: -0.2, surge_rms: 0.003, sway_rms: 0.003, yaw_rms: 0.003}
noise: {snr_db: inf}
EOF
"$CLI" simulate --config "$T/tiny.yaml" --aiding -o "$T/run.h5" 2> "$T/sim.err" ||
    { cat "$T/sim.err" >&2; fail "simulate --aiding"; exit 1; }
grep -q "+ aiding" "$T/sim.err" || fail "simulate does not say it wrote aiding"
if command -v h5ls > /dev/null 2>&1; then
    h5ls -r "$T/run.h5" | grep -q "/aiding/yaw_rate " || fail "no /aiding/yaw_rate in the run file"
fi

# Fused navigation, JSON.
"$CLI" navigate "$T/run.h5" --k 2 --i 1 --range-extent 0.6 --json -o "$T/nav.h5" > "$T/nav.json" 2> "$T/nav.err" ||
    { cat "$T/nav.err" >&2; fail "navigate with aiding"; }
# Without aiding, same run.
"$CLI" navigate "$T/run.h5" --k 2 --i 1 --range-extent 0.6 --no-aiding --json -o "$T/nav0.h5" > "$T/nav0.json" \
    2> "$T/nav0.err" || { cat "$T/nav0.err" >&2; fail "navigate --no-aiding"; }
# Per-ping offsets from the pairs' surge (second pass) and from the DVL, and
# the jointly estimated aiding bias: they run and keep the noise-free
# fused yaw of a navigation-grade gyro.
"$CLI" navigate "$T/run.h5" --k 2 --i 1 --range-extent 0.6 --no-aiding --speed-lags pairs \
    -o "$T/navl.h5" > "$T/navl.txt" 2> "$T/navl.err" || { cat "$T/navl.err" >&2; fail "--speed-lags pairs"; }
grep -q "final cumulative error" "$T/navl.txt" || fail "--speed-lags pairs: no summary"
"$CLI" navigate "$T/run.h5" --k 2 --i 1 --range-extent 0.6 --speed-lags dvl --aiding-bias 4e-4,4e-4,0 \
    --json -o "$T/navb.h5" > "$T/navb.json" 2> "$T/navb.err" || { cat "$T/navb.err" >&2; fail "--speed-lags dvl --aiding-bias"; }
if [ -x /usr/bin/python3 ]; then
    /usr/bin/python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
assert d['aiding_used'] and all(abs(p['error']['yaw']) < 1e-5 for p in d['pairs']), d['pairs']
" "$T/navb.json" || fail "--speed-lags dvl --aiding-bias: JSON content"
fi

# Dead reckoning.
"$CLI" navigate "$T/run.h5" --method aiding --json -o "$T/nava.h5" > "$T/nava.json" \
    2> "$T/nava.err" || { cat "$T/nava.err" >&2; fail "navigate --method aiding"; }
# Each pair's own estimate (no smoother: no formal standard deviations).
"$CLI" navigate "$T/run.h5" --k 2 --i 1 --range-extent 0.6 --no-resolve --json -o "$T/navr.h5" \
    > "$T/navr.json" 2> "$T/navr.err" || { cat "$T/navr.err" >&2; fail "navigate --no-resolve"; }
if [ -x /usr/bin/python3 ]; then
    /usr/bin/python3 - "$T/nav.json" "$T/nav0.json" "$T/nava.json" "$T/navr.json" <<'EOF' || fail "JSON content"
import json, math, sys
fused, alone, aid, raw = (json.load(open(f)) for f in sys.argv[1:5])
# The formal standard deviations: one per ping, zero at the first, the
# final one repeated; a navigation-grade gyro fused makes the final sway's
# smaller than the pairs' alone (whose yaw, 5e-5 rad a pair, turns the
# steps); none without the smoother.
for d in (fused, alone, aid):
    s = d["formal_sigma"]
    assert len(s) == d["n_pings"] and s[0] == {"surge": 0, "sway": 0, "yaw": 0}, s[0]
    assert d["formal_final_sigma"] == s[-1], (d["formal_final_sigma"], s[-1])
    assert all(math.isfinite(v) and v > 0 for v in s[-1].values()), s[-1]
assert fused["formal_final_sigma"]["sway"] < alone["formal_final_sigma"]["sway"], \
    (fused["formal_final_sigma"], alone["formal_final_sigma"])
assert raw["formal_sigma"] is None and raw["formal_final_sigma"] is None
# ... and in the navigation file, /nav_sigma [ping][3] (where h5py is)
try:
    import h5py
except ImportError:
    h5py = None
if h5py is not None:
    nav_dir = sys.argv[1].rsplit("/", 1)[0]
    with h5py.File(nav_dir + "/nav.h5", "r") as f:
        rows = f["nav_sigma"][()]
    want = [[s["surge"], s["sway"], s["yaw"]] for s in fused["formal_sigma"]]
    assert rows.shape == (len(want), 3), rows.shape
    assert all(abs(a - b) <= 1e-9 * max(abs(b), 1e-30) for r, w in zip(rows, want) for a, b in zip(r, w)), \
        (rows, want)
    with h5py.File(nav_dir + "/navr.h5", "r") as f:
        assert "nav_sigma" not in f
assert fused["aiding_used"] is True and alone["aiding_used"] is False, (fused["aiding_used"], alone["aiding_used"])
assert aid["method"] == "aiding" and aid["aiding_used"] is True
for d in (fused, alone):
    assert len(d["pairs"]) == 2
    for p in d["pairs"]:
        for k in ("status", "first_status", "resolution", "candidates", "estimate", "eta", "error"):
            assert k in p, k
        # two pairs: too few for the run's median eta (6), so no outlier
        assert p["eta_outlier"] is False, p["eta_outlier"]
        assert p["status"] in ("ok", "ambiguous", "failed", "no_overlap"), p["status"]
        assert p["resolution"] in ("kept", "candidate", "re-estimated", "bridged"), p["resolution"]
        assert len(p["candidates"]) >= 1 and sum(c["chosen"] for c in p["candidates"]) == 1
    assert d["eta_median"] is None and d["eta_outliers"] == 0, (d["eta_median"], d["eta_outliers"])
for p in fused["pairs"]:
    assert "aiding" in p and "aiding_sigma" in p, p.keys()
    # A navigation-grade gyro: the fused yaw within 1e-5 rad of the truth.
    assert abs(p["error"]["yaw"]) < 1e-5, p["error"]
for p in alone["pairs"]:
    assert "aiding" not in p
# Noise-free, coarse iterations: the fused final sway within lambda / 25.
assert abs(fused["final_sway_error"]) < 2e-4, fused["final_sway_error"]
assert fused["flagged_pairs"] == 0 and alone["flagged_pairs"] == 0
EOF
fi

# A run without aiding: --method aiding refused, no output.
"$CLI" simulate --config "$T/tiny.yaml" -o "$T/plain.h5" 2> /dev/null || fail "simulate"
if "$CLI" navigate "$T/plain.h5" --method aiding -o "$T/none.h5" > /dev/null 2> "$T/e1"; then
    fail "--method aiding accepted without aiding"
else
    [ $? -eq 1 ] || fail "--method aiding without aiding: exit status not 1"
fi
grep -q "aiding" "$T/e1" || fail "message does not mention the aiding: $(cat "$T/e1")"
[ "$(wc -l < "$T/e1")" -eq 1 ] || fail "more than one message line: $(cat "$T/e1")"
[ -e "$T/none.h5" ] && fail "output written for a refused navigation"
# A gyro without a DVL: dead reckoning refused (its steps would be guesses),
# the message naming the missing velocity; no output.
printf 'aiding: {dvl: false}\n' | cat "$T/tiny.yaml" - > "$T/gyro.yaml"
"$CLI" simulate --config "$T/gyro.yaml" --aiding -o "$T/gyro.h5" 2> /dev/null || fail "simulate, gyro only"
if "$CLI" navigate "$T/gyro.h5" --method aiding -o "$T/gyro-nav.h5" > /dev/null 2> "$T/e1g"; then
    fail "--method aiding accepted without a DVL"
else
    [ $? -eq 1 ] || fail "--method aiding without a DVL: exit status not 1"
fi
grep -q "no velocity" "$T/e1g" || fail "message does not name the missing DVL: $(cat "$T/e1g")"
[ -e "$T/gyro-nav.h5" ] && fail "output written for dead reckoning without a DVL"

# --link-sigma reaches the fusion: pairs weighted 10 m / 10 rad leave the
# aiding alone, so the fused motion errors are dead reckoning's (the same
# smoother without estimates; to 1e-7: the pairs' weight is about 1e-9 of
# the aiding's); the same command without --link-sigma gives a different,
# data-driven fusion (the DVL's noise alone is 0.3 mm per interval).
"$CLI" navigate "$T/run.h5" --k 2 --i 1 --range-extent 0.6 --link-sigma 10,10,10 --aiding-bias 0,0,0 \
    --json -o "$T/navw.h5" > "$T/navw.json" 2> "$T/navw.err" || { cat "$T/navw.err" >&2; fail "--link-sigma"; }
"$CLI" navigate "$T/run.h5" --method aiding --aiding-bias 0,0,0 --json -o "$T/navd.h5" > "$T/navd.json" \
    2> "$T/navd.err" || { cat "$T/navd.err" >&2; fail "--method aiding --aiding-bias 0,0,0"; }
"$CLI" navigate "$T/run.h5" --k 2 --i 1 --range-extent 0.6 --aiding-bias 0,0,0 \
    --json -o "$T/navz.h5" > "$T/navz.json" 2> "$T/navz.err" || { cat "$T/navz.err" >&2; fail "--aiding-bias 0,0,0"; }
if [ -x /usr/bin/python3 ]; then
    /usr/bin/python3 -c "
import json, sys
w, d, f = (json.load(open(a))['pairs'] for a in sys.argv[1:4])
dev = lambda u, v: max(abs(a[c] - b[c]) for a, b in zip(u, v) for c in ('surge', 'sway', 'yaw'))
assert dev(w, d) < 1e-7, ('--link-sigma 10,10,10 is not dead reckoning', dev(w, d))
assert dev(f, d) > 1e-5, ('the default fusion equals dead reckoning', dev(f, d))
" "$T/navw.json" "$T/navd.json" "$T/navz.json" || fail "--link-sigma: fused values"
fi
# --link-eta reaches the fusion: at 1e-6 every pair's standard deviations
# grow by (eta / 1e-6)^2 (over 1e8 at this run's etas), so the fusion is
# dead reckoning's again; at 0 (off) and at 1e6 (above any eta) no pair is
# scaled, so the two agree to the bit.
for le in 1e-6 0 1e6; do
    "$CLI" navigate "$T/run.h5" --k 2 --i 1 --range-extent 0.6 --aiding-bias 0,0,0 --link-eta "$le" \
        --json -o "$T/nave$le.h5" > "$T/nave$le.json" 2> "$T/nave.err" || { cat "$T/nave.err" >&2; fail "--link-eta $le"; }
done
if [ -x /usr/bin/python3 ]; then
    /usr/bin/python3 -c "
import json, sys
t, z, h, d = (json.load(open(a))['pairs'] for a in sys.argv[1:5])
dev = lambda u, v: max(abs(a[c] - b[c]) for a, b in zip(u, v) for c in ('surge', 'sway', 'yaw'))
assert dev(t, d) < 1e-7, ('--link-eta 1e-6 is not dead reckoning', dev(t, d))
assert dev(z, d) > 1e-5, ('--link-eta 0 equals dead reckoning', dev(z, d))
assert dev(z, h) == 0, ('--link-eta 0 and 1e6 differ', dev(z, h))
" "$T/nave1e-6.json" "$T/nave0.json" "$T/nave1e6.json" "$T/navd.json" || fail "--link-eta: fused values"
fi
# Bad weights: refused (exit 2) with a message naming the option.
for case in "link-eta -1" "link-eta nan" "link-eta 2e6" "link-eta x" "link-eta 0.1,0.2" \
    "link-sigma 0.001,0,0.00005" "link-sigma 0.001,nan,0.00005" "link-sigma -1,1,1" \
    "link-sigma 0.001,0.00002" "link-sigma 1e308,1,1"; do
    opt=${case%% *}
    bad=${case#* }
    if "$CLI" navigate "$T/run.h5" "--$opt" "$bad" -o "$T/x.h5" > /dev/null 2> "$T/el"; then
        fail "--$opt $bad accepted"
    else
        [ $? -eq 2 ] || fail "--$opt $bad: exit status not 2"
    fi
    grep -q "$opt" "$T/el" || fail "--$opt $bad: message does not name it"
done
# ... and where no pair estimate is fused (dead reckoning, virtual arrays).
for other in "--method aiding" "--virtual-array 2"; do
    # shellcheck disable=SC2086 # two words on purpose
    for weight in "--link-sigma 1,1,1" "--link-eta 0.3"; do
        # shellcheck disable=SC2086 # two words on purpose
        if "$CLI" navigate "$T/run.h5" $other $weight -o "$T/x.h5" > /dev/null 2> "$T/el"; then
            fail "$weight with $other accepted"
        else
            [ $? -eq 2 ] || fail "$weight with $other: exit status not 2"
        fi
        grep -qE "link-|takes only" "$T/el" || fail "$weight with $other: unclear message: $(cat "$T/el")"
    done
done

# Options of the pair fusion are refused with --virtual-array, not ignored.
for other in "--tx-yaw none" "--final eta"; do
    # shellcheck disable=SC2086 # two words on purpose
    if "$CLI" navigate "$T/run.h5" --virtual-array 2 $other -o "$T/x.h5" > /dev/null 2> "$T/ev"; then
        fail "--virtual-array with $other accepted"
    else
        [ $? -eq 2 ] || fail "--virtual-array with $other: exit status not 2"
    fi
done

# Bad options: refused with a message naming them, nothing written.
if "$CLI" navigate "$T/run.h5" --motion-sigma 0.01,0,0.01 -o "$T/x.h5" > /dev/null 2> "$T/e2"; then
    fail "--motion-sigma with a zero accepted"
fi
grep -q "motion-sigma" "$T/e2" || fail "message does not name --motion-sigma"
if "$CLI" navigate "$T/run.h5" --method nope -o "$T/x.h5" > /dev/null 2> "$T/e3"; then
    fail "--method nope accepted"
fi
grep -q "aiding" "$T/e3" || fail "--method message does not list aiding"
[ -e "$T/x.h5" ] && fail "output written after a bad option"

# A compact scene: one point target; its pairs are ambiguous, each gets one
# warning line naming the pair and its status.
cat > "$T/point.yaml" <<'EOF'
preset: point
trajectory: {n_pings: 3, x_start: -0.2}
EOF
"$CLI" simulate --config "$T/point.yaml" -o "$T/point.h5" 2> /dev/null || fail "simulate point"
"$CLI" navigate "$T/point.h5" --k 2 --i 1 --range-extent 0.6 -o "$T/pnav.h5" > "$T/pnav.txt" 2> "$T/pnav.err" ||
    { cat "$T/pnav.err" >&2; fail "navigate point"; }
grep -q "warning: pair 0-1 is ambiguous" "$T/pnav.err" ||
    fail "no warning for the ambiguous pair 0-1: $(cat "$T/pnav.err")"
grep -q "pairs flagged" "$T/pnav.txt" || fail "the text summary lacks the flagged count"
# Each pair reports the contrasts of p's image and of q's (the larger
# chose the verdict's rules): the point target is compact in both (above
# the default gate, 4), so a pair at a coincidence there is never "ok".
"$CLI" navigate "$T/point.h5" --k 2 --i 1 --range-extent 0.6 --json -o "$T/pnavj.h5" > "$T/pnav.json" \
    2> /dev/null || fail "navigate point --json"
python3 - "$T/pnav.json" <<'EOF' || fail "point target: contrast in navigate --json"
import json, sys
for p in json.load(open(sys.argv[1]))["pairs"]:
    assert p["contrast"] > 4 and p["contrast_q"] > 4, (p["contrast"], p["contrast_q"])
    assert not (p["coincidence"] and p["status"] == "ok"), p
EOF

# The eta-outlier rule through the command line, with a median that is not
# null: an 8-ping run (7 speckle-like pairs, at least the rule's 6) is
# navigated with the default factor; the median that navigate reports must
# be the one computed here from the pairs' etas (the pairs that take part:
# usable, "ok" or "ambiguous" before the resolution, both contrasts at most the
# verdict's gate 4). Then a factor between the largest and the second
# largest ratio to that median: exactly the pair with the largest eta is
# marked, "ambiguous", warned about and counted; the others stay as they
# were.
cat > "$T/eight.yaml" <<'EOF'
preset: paper-trajectory
trajectory: {n_pings: 8, x_start: -0.7, surge_rms: 0.003, sway_rms: 0.003, yaw_rms: 0.003}
noise: {snr_db: inf}
EOF
"$CLI" simulate --config "$T/eight.yaml" -o "$T/eight.h5" 2> /dev/null || fail "simulate (8 pings)"
"$CLI" navigate "$T/eight.h5" --k 2 --i 1 --range-extent 0.6 --json -o "$T/n8.h5" > "$T/n8.json" \
    2> "$T/n8.err" || { cat "$T/n8.err" >&2; fail "navigate (8 pings)"; }
F=$(python3 - "$T/n8.json" <<'EOF'
import json, statistics, sys
d = json.load(open(sys.argv[1]))
part = [p for p in d["pairs"] if p["first_status"] in ("ok", "ambiguous") and
        max(p["contrast"], p["contrast_q"]) <= 4]
assert len(part) >= 6, len(part)
med = statistics.median(p["eta"] for p in part)
assert d["eta_median"] is not None and abs(d["eta_median"] - med) <= 1e-9 * med, (d["eta_median"], med)
r = sorted(p["eta"] / med for p in part)
assert r[-1] > r[-2], r
print("%.6f" % (0.5 * (r[-1] + r[-2])))
EOF
) || fail "eta median through the CLI"
if [ -n "${F:-}" ]; then
    "$CLI" navigate "$T/eight.h5" --k 2 --i 1 --range-extent 0.6 --eta-outlier "$F" --json \
        -o "$T/n8b.h5" > "$T/n8b.json" 2> "$T/n8b.err" || { cat "$T/n8b.err" >&2; fail "navigate --eta-outlier $F"; }
    [ "$(grep -c "with an eta far above the run's" "$T/n8b.err")" -eq 1 ] ||
        fail "--eta-outlier $F: not one warning: $(cat "$T/n8b.err")"
    python3 - "$T/n8.json" "$T/n8b.json" <<'EOF' || fail "--eta-outlier $F: marks"
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:])
top = max(range(len(a["pairs"])), key=lambda j: a["pairs"][j]["eta"])
assert b["eta_outliers"] == 1 and b["eta_median"] == a["eta_median"], (b["eta_outliers"], b["eta_median"])
for j, (pa, pb) in enumerate(zip(a["pairs"], b["pairs"])):
    assert pb["eta_outlier"] is (j == top), (j, pb["eta_outlier"])
    if j == top:
        assert pa["status"] == "ok" and pb["status"] == "ambiguous" and pb["first_status"] == "ambiguous", pb
    else:
        assert pb["status"] == pa["status"] and pb["estimate"] == pa["estimate"], (j, pa["status"], pb["status"])
EOF
fi

# --eta-max sets the bound of the "failed" verdict: the same pairs, with a
# bound below any eta they can reach, are all failed (warned, counted); a
# bound that is not a positive number is a usage error (2) that writes
# nothing.
"$CLI" navigate "$T/run.h5" --k 2 --i 1 --range-extent 0.6 --no-aiding --eta-max 0.001 --json \
    -o "$T/nave.h5" > "$T/nave.json" 2> "$T/nave.err" || { cat "$T/nave.err" >&2; fail "navigate --eta-max"; }
grep -q "warning: pair 0-1 is failed" "$T/nave.err" || fail "--eta-max 0.001: no failed warning: $(cat "$T/nave.err")"
python3 - "$T/nave.json" "$T/nav0.json" <<'EOF' || fail "--eta-max verdicts"
import json, sys
low, default = (json.load(open(f)) for f in sys.argv[1:])
assert all(p["first_status"] == "failed" for p in low["pairs"]), [p["first_status"] for p in low["pairs"]]
assert low["flagged_pairs"] == len(low["pairs"]) == 2, low["flagged_pairs"]
assert all(p["first_status"] == "ok" for p in default["pairs"]), [p["first_status"] for p in default["pairs"]]
EOF
for bad in 0 -1 nan x; do
    "$CLI" pair "$T/run.h5" --eta-max "$bad" > /dev/null 2> "$T/e4"
    rc=$?
    [ "$rc" -eq 2 ] || fail "pair --eta-max $bad: exit $rc (usage errors exit 2)"
    grep -q "eta-max" "$T/e4" || fail "pair --eta-max $bad: message does not name the option"
    "$CLI" navigate "$T/run.h5" --eta-max "$bad" -o "$T/y.h5" > /dev/null 2>&1
    rc=$?
    [ "$rc" -eq 2 ] || fail "navigate --eta-max $bad: exit $rc"
    [ -e "$T/y.h5" ] && fail "navigate --eta-max $bad wrote an output"
done

exit $FAILED
