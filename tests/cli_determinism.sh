#!/bin/sh
# Determinism as stated in docs/library.md ("Determinism"): the same
# inputs, seed and thread count give the same bits, and so do different
# thread counts (only the timings differ): simulate twice with one seed
# (identical, h5diff without tolerance) and with another seed (different);
# image, pair, navigate and refine with --threads 1 and --threads 2
# (identical files; pair's JSON identical but for its timings). Under the
# sanitizers (memory safety, ~20x slower) simulate and image only.
# Usage: sh tests/cli_determinism.sh path/to/sasnav
set -u
CLI=${1:?usage: cli_determinism.sh path/to/sasnav}
T=$(mktemp -d "${TMPDIR:-/tmp}/sasnav-cli-determinism-XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT INT TERM
FAILED=0
fail() {
    echo "cli_determinism: FAIL: $*" >&2
    FAILED=1
}
same() { # what, file a, file b
    h5diff "$2" "$3" > "$T/diff" 2>&1 || fail "$1: $(head -n 4 "$T/diff")"
}
run() { # what, command...: fails the test when the command fails
    what=$1
    shift
    "$@" > "$T/out" 2> "$T/err" || { fail "$what: $(cat "$T/err")"; return 1; }
}
NP=4
printf 'trajectory: {n_pings: %s}\n' "$NP" > "$T/c.yaml"
for s in a b; do
    run "simulate $s" "$CLI" simulate --preset paper-trajectory --config "$T/c.yaml" --seed 3 --snr 20 -o "$T/$s.h5"
done
same "simulate, same seed" "$T/a.h5" "$T/b.h5"
run "simulate seed 4" "$CLI" simulate --preset paper-trajectory --config "$T/c.yaml" --seed 4 --snr 20 -o "$T/c.h5"
h5diff -q "$T/a.h5" "$T/c.h5" > /dev/null 2>&1 && fail "simulate: seeds 3 and 4 gave the same run"

G="--grid -0.5,0.5,101,9.6,10.4,81"
if [ -n "${SASNAV_SANITIZED:-}" ]; then
    # Under the sanitizers (memory safety, ~20x slower) only the image: the
    # bits of the estimators are the optimised build's to show.
    for t in 1 2; do
        # shellcheck disable=SC2086
        run "image --threads $t" "$CLI" image "$T/a.h5" $G --threads "$t" -o "$T/img$t.h5"
    done
    same "image, 1 vs 2 threads" "$T/img1.h5" "$T/img2.h5"
    [ "$FAILED" -eq 0 ] && echo "cli_determinism: ok (sanitized build: simulate and image only)"
    exit "$FAILED"
fi
for t in 1 2; do
    # shellcheck disable=SC2086
    run "image --threads $t" "$CLI" image "$T/a.h5" $G --threads "$t" -o "$T/img$t.h5"
    run "pair --threads $t" "$CLI" pair "$T/a.h5" --p 0 --q 1 --k 2 --i 1 --json --threads "$t"
    grep -v -E '"seconds[a-z_]*"' "$T/out" > "$T/pair$t.json"
    run "navigate --threads $t" "$CLI" navigate "$T/a.h5" --k 2 --i 1 --threads "$t" -o "$T/nav$t.h5"
    run "refine --threads $t" "$CLI" refine "$T/a.h5" "$T/nav1.h5" --grid -0.4,0.4,81,9.7,10.3,61 --sweeps 2 \
        --threads "$t" -o "$T/ref$t.h5"
done
same "image, 1 vs 2 threads" "$T/img1.h5" "$T/img2.h5"
cmp -s "$T/pair1.json" "$T/pair2.json" || fail "pair, 1 vs 2 threads: $(diff "$T/pair1.json" "$T/pair2.json" | head -n 6)"
grep -q '"verdict"' "$T/pair1.json" || fail "pair --json printed no verdict"
same "navigate, 1 vs 2 threads" "$T/nav1.h5" "$T/nav2.h5"
same "refine, 1 vs 2 threads" "$T/ref1.h5" "$T/ref2.h5"
[ "$FAILED" -eq 0 ] && echo "cli_determinism: ok"
exit "$FAILED"
