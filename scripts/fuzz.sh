#!/bin/sh
# Coverage-guided fuzzing of sasnav's readers with libFuzzer (docs/fuzzing.md).
#
# Usage: sh scripts/fuzz.sh SECONDS [HARNESS...]
#   Configures a clang build with SASNAV_FUZZ=ON in build-fuzz (CC=clang, or
#   $FUZZ_CC), builds the harnesses and runs each (all fuzz/fuzz_*.c by
#   default; names with or without the fuzz_ prefix) for SECONDS on a copy of
#   its seed corpus fuzz/corpus/<harness> (the copy, in build-fuzz/corpus,
#   grows between runs; the seeds are never touched), with -rss_limit_mb=2048
#   and -timeout=10. libFuzzer runs in fork mode (-fork=$FUZZ_JOBS, default
#   1) and goes on after a crash, leak, timeout or out-of-memory: every
#   such input is saved to fuzz/crashes/<harness>-<kind>-<sha1>.
#   Prints one summary line per harness: runs, execs/s, coverage (edges),
#   features, corpus size, crashes. Exit status 1 when a harness saved a
#   new crash, leak or timeout input (out-of-memory inputs are reported but,
#   with HDF5's known faults, do not fail), else 0.
# Environment: FUZZ_CC (clang), FUZZ_JOBS (1), FUZZ_BUILD (build-fuzz),
#   FUZZ_FLAGS (extra libFuzzer flags).
set -eu
cd "$(dirname "$0")/.."
if [ $# -lt 1 ]; then
    echo "usage: sh scripts/fuzz.sh SECONDS [HARNESS...]" >&2
    exit 2
fi
SECONDS_EACH=$1
shift
CC_FUZZ=${FUZZ_CC:-clang}
JOBS=${FUZZ_JOBS:-1}
B=${FUZZ_BUILD:-build-fuzz}
NPROC=$(nproc 2>/dev/null || echo 2)

if [ $# -eq 0 ]; then
    set -- $(ls fuzz/fuzz_*.c | sed 's|fuzz/||; s|\.c$||')
fi
HARNESSES=""
for h in "$@"; do
    case $h in fuzz_*) ;; *) h=fuzz_$h ;; esac
    [ -f "fuzz/$h.c" ] || { echo "fuzz.sh: no harness fuzz/$h.c" >&2; exit 2; }
    HARNESSES="$HARNESSES $h"
done

mkdir -p "$B"
CC=$CC_FUZZ cmake -S . -B "$B" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSASNAV_FUZZ=ON \
    -DBUILD_TESTING=OFF >"$B/configure.log" 2>&1 || { cat "$B/configure.log"; exit 1; }
# shellcheck disable=SC2086
cmake --build "$B" -j"$NPROC" --target $HARNESSES

mkdir -p fuzz/crashes
SUMMARY=""
STATUS=0
for h in $HARNESSES; do
    corpus="$B/corpus/$h"
    mkdir -p "$corpus"
    [ -d "fuzz/corpus/$h" ] && cp -n fuzz/corpus/"$h"/* "$corpus"/ 2>/dev/null || true
    log="$B/$h.log"
    before=$(ls fuzz/crashes | grep -c "^$h-" || true)
    echo "== $h: $SECONDS_EACH s (log $log)"
    # shellcheck disable=SC2086
    ASAN_OPTIONS=${ASAN_OPTIONS:-} UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    "$B/$h" -fork="$JOBS" -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 \
        -max_total_time="$SECONDS_EACH" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 \
        -artifact_prefix="fuzz/crashes/$h-" ${FUZZ_FLAGS:-} "$corpus" >"$log" 2>&1 || true
    after=$(ls fuzz/crashes | grep -c "^$h-" || true)
    new=$((after - before))
    bad=$(ls -t fuzz/crashes | grep "^$h-" | head -n "$new" | grep -vc -- "-oom-" || true)
    [ "$new" -gt 0 ] || bad=0
    last=$(grep -E '^#[0-9]+:? .*cov: ' "$log" | tail -n 1)
    runs=$(echo "$last" | sed -n 's/^#\([0-9]*\).*/\1/p')
    cov=$(echo "$last" | sed -n 's/.*cov: \([0-9]*\).*/\1/p')
    ft=$(echo "$last" | sed -n 's/.*ft: \([0-9]*\).*/\1/p')
    corp=$(ls "$corpus" | wc -l)
    eps=$(echo "$last" | sed -n 's/.*exec\/s:* \([0-9]*\).*/\1/p')
    line=$(printf '%-18s %4ss runs %-9s exec/s %-6s cov %-5s ft %-6s corpus %-5s new crash/leak/timeout %s, oom %s' \
        "$h" "$SECONDS_EACH" "${runs:-?}" "${eps:-?}" "${cov:-?}" "${ft:-?}" "$corp" "$bad" "$((new - bad))")
    echo "$line"
    SUMMARY="$SUMMARY$line
"
    [ "$bad" -eq 0 ] || STATUS=1
done
echo
echo "summary ($SECONDS_EACH s each; inputs saved in fuzz/crashes/):"
printf '%s' "$SUMMARY"
exit $STATUS
