#!/bin/sh
# Interrupted and resumed: `sasnav navigate --checkpoint FILE` killed by
# SIGTERM in the middle of a run leaves no output and FILE with the pairs
# it had finished; the same command again resumes from FILE ("resuming ...
# N pairs") and writes a navigation identical, dataset for dataset
# (h5diff without tolerance), to an uninterrupted run's, and the same
# per-pair JSON but for the timings; FILE is then removed. A torn last
# record (cut by 7 bytes) is dropped and that pair estimated again, with
# the same result. A file in use by another process, FILE of another
# command and a foreign file are refused (exit 1, one clear line); a
# navigate that cannot write its output keeps FILE. `sasnav refine
# --checkpoint` the same way (its state after each sweep). `sasnav validate --checkpoint`
# is exercised in cli_validate.sh.
# Usage: sh tests/cli_checkpoint.sh path/to/sasnav
set -u
CLI=${1:?usage: cli_checkpoint.sh path/to/sasnav}
T=$(mktemp -d "${TMPDIR:-/tmp}/sasnav-cli-checkpoint-XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT INT TERM
mkdir -p "$T/ro" && : > "$T/ro/x" # a file where a directory is needed
FAILED=0
fail() {
    echo "cli_checkpoint: FAIL: $*" >&2
    FAILED=1
}
# Sanitized builds run ~20x slower: 4 pings there, 12 here; coarse
# iterations either way (what is tested is the bookkeeping, not accuracy).
NP=12
[ -n "${SASNAV_SANITIZED:-}" ] && NP=4
printf 'trajectory: {n_pings: %s}\n' "$NP" > "$T/c.yaml"
"$CLI" simulate --preset paper-trajectory --config "$T/c.yaml" --seed 7 --snr 30 -o "$T/run.h5" 2> "$T/sim.err" ||
    { cat "$T/sim.err" >&2; fail "simulate"; exit 1; }
OPTS="--k 2 --i 1 --range-extent 0.6 --threads 2 --json"
# shellcheck disable=SC2086
"$CLI" navigate "$T/run.h5" $OPTS -o "$T/a.h5" > "$T/a.json" 2> "$T/a.err" || { cat "$T/a.err" >&2; fail "navigate"; exit 1; }

# Interrupted once at least two records are in the file: the header is
# 52 bytes, a record 744 (x86-64), so 1500 bytes hold two and not three.
# shellcheck disable=SC2086
"$CLI" navigate "$T/run.h5" $OPTS --checkpoint "$T/ck" -o "$T/b.h5" > "$T/b1.json" 2> "$T/b1.err" &
PID=$!
i=0
while [ "$i" -lt 3000 ]; do
    sz=$(stat -c %s "$T/ck" 2>/dev/null || echo 0)
    [ "$sz" -ge 1500 ] && break
    kill -0 "$PID" 2>/dev/null || break
    sleep 0.1
    i=$((i + 1))
done
# While it runs, a second process on the same checkpoint is refused.
if kill -0 "$PID" 2>/dev/null; then
    "$CLI" navigate "$T/run.h5" --method dpca --checkpoint "$T/ck" -o "$T/c.h5" > /dev/null 2> "$T/c.err"
    st=$?
    [ "$st" -eq 1 ] && grep -q "in use by another process" "$T/c.err" ||
        fail "a checkpoint in use: exit $st, $(cat "$T/c.err")"
fi
kill -TERM "$PID" 2>/dev/null
wait "$PID"
st=$?
if [ "$st" -eq 0 ]; then
    fail "navigate finished before it could be interrupted (make the run longer)"
else
    [ -e "$T/b.h5" ] && fail "an interrupted navigate left an output"
    ls "$T" | grep -q 'tmp-' && fail "an interrupted navigate left a temporary file"
    [ -s "$T/ck" ] || fail "no checkpoint kept after the interruption"
    # A torn last record, as from a kill during its write.
    sz=$(stat -c %s "$T/ck")
    truncate -s $((sz - 7)) "$T/ck"
    # shellcheck disable=SC2086
    if "$CLI" navigate "$T/run.h5" $OPTS --checkpoint "$T/ck" -o "$T/b.h5" > "$T/b.json" 2> "$T/b.err"; then
        grep -q "resuming from .*ck (.* pairs estimated before)" "$T/b.err" || fail "no 'resuming' line: $(cat "$T/b.err")"
        grep -q "pairs taken from checkpoint" "$T/b.err" || fail "no count of resumed pairs"
        [ -e "$T/ck" ] && fail "checkpoint not removed after success"
        h5diff "$T/a.h5" "$T/b.h5" > "$T/diff.txt" 2>&1 || fail "resumed navigation differs: $(head -n 5 "$T/diff.txt")"
        # the JSON without its timings
        for f in a b; do grep -v -E '"(seconds[a-z_]*|pairs_per_second)"' "$T/$f.json" > "$T/$f.cut"; done
        cmp -s "$T/a.cut" "$T/b.cut" || fail "resumed JSON differs: $(diff "$T/a.cut" "$T/b.cut" | head -n 6)"
    else
        cat "$T/b.err" >&2
        fail "resume failed"
    fi
fi

# refine --checkpoint: killed after its first sweep's state is written,
# resumed (with another thread count) to the uninterrupted result. A small
# scene grid keeps sweeps short; what is tested is the bookkeeping.
RG="--grid -0.4,0.4,81,9.7,10.3,61 --sweeps 6"
# shellcheck disable=SC2086
"$CLI" refine "$T/run.h5" "$T/a.h5" $RG --threads 1 -o "$T/ra.h5" > /dev/null 2> "$T/ra.err" || fail "refine: $(cat "$T/ra.err")"
# shellcheck disable=SC2086
"$CLI" refine "$T/run.h5" "$T/a.h5" $RG --threads 1 --checkpoint "$T/rck.h5" -o "$T/rb.h5" > /dev/null 2>&1 &
PID=$!
i=0
while [ "$i" -lt 6000 ] && [ ! -e "$T/rck.h5" ] && kill -0 "$PID" 2>/dev/null; do
    sleep 0.05
    i=$((i + 1))
done
kill -TERM "$PID" 2>/dev/null
wait "$PID"
if [ $? -eq 0 ]; then
    fail "refine finished before it could be interrupted"
else
    [ -e "$T/rb.h5" ] && fail "an interrupted refine left an output"
    # shellcheck disable=SC2086
    if "$CLI" refine "$T/run.h5" "$T/a.h5" $RG --threads 2 --checkpoint "$T/rck.h5" -o "$T/rb.h5" > /dev/null 2> "$T/rb.err"; then
        grep -q "resuming from .*rck.h5 (. sweeps done before)" "$T/rb.err" || fail "refine: no 'resuming' line: $(cat "$T/rb.err")"
        h5diff "$T/ra.h5" "$T/rb.h5" > "$T/diff.txt" 2>&1 || fail "resumed refine differs: $(head -n 5 "$T/diff.txt")"
        [ -e "$T/rck.h5" ] && fail "refine checkpoint not removed after success"
    else
        fail "refine resume failed: $(cat "$T/rb.err")"
    fi
fi
# A refinement state of other options is refused by the library.
# shellcheck disable=SC2086
"$CLI" refine "$T/run.h5" "$T/a.h5" $RG --checkpoint "$T/rck2.h5" -o "$T/ro/x/r.h5" > /dev/null 2>&1
[ -e "$T/rck2.h5" ] || fail "a refine that could not write its output removed its state"
"$CLI" refine "$T/run.h5" "$T/a.h5" --grid -0.4,0.4,81,9.7,10.3,61 --sweeps 6 --sparsity 0.5 --checkpoint "$T/rck2.h5" -o "$T/r.h5" > /dev/null 2> "$T/r.err"
[ $? -eq 1 ] && grep -q "another run, input navigation, grid or options" "$T/r.err" ||
    fail "refine state of other options: $(cat "$T/r.err")"

# Refusals: exit 1 and one line naming the file.
expect_refusal() { # what, pattern, command...
    what=$1 pat=$2
    shift 2
    "$@" > /dev/null 2> "$T/r.err"
    st=$?
    [ "$st" -eq 1 ] || fail "$what: exit $st, want 1"
    grep -q "$pat" "$T/r.err" || fail "$what: stderr lacks '$pat': $(cat "$T/r.err")"
    [ "$(wc -l < "$T/r.err")" -eq 1 ] || fail "$what: more than one line on stderr"
}
printf 'not a checkpoint\n' > "$T/foreign"
expect_refusal "a foreign file" "not a sasnav checkpoint" \
    "$CLI" navigate "$T/run.h5" --method dpca --checkpoint "$T/foreign" -o "$T/c.h5"
grep -q "not a checkpoint" "$T/foreign" || fail "the refused foreign file was changed"
# A navigate that cannot write its output keeps its checkpoint (and says
# how to resume); given to another command, that checkpoint is refused.
"$CLI" navigate "$T/run.h5" --method dpca --checkpoint "$T/ck2" -o "$T/ro/x/nav.h5" > /dev/null 2> "$T/d.err"
[ -s "$T/ck2" ] || fail "a navigate that could not write its output removed its checkpoint"
grep -q "run the same command again to resume" "$T/d.err" || fail "no resume hint after a failed write: $(cat "$T/d.err")"
expect_refusal "another command's checkpoint" "another job" \
    "$CLI" validate "$T/run.h5" --checkpoint "$T/ck2" -o "$T/val"
[ "$FAILED" -eq 0 ] && echo "cli_checkpoint: ok"
exit "$FAILED"
