#!/bin/sh
# `mpirun -np N sasnav simulate|navigate|image` gives the same files as one
# process, bit for bit (docs/survey.md): a simulation (2 ranks), navigation
# by DPCA (all pairs) and by the
# subspace estimator (coarse iterations, to keep it short), images with 2
# and 3 ranks (uneven bands of rows). Commands that do not split their work
# refuse several ranks with a usage error (2); --checkpoint too. Skipped
# (77) without mpirun or without MPI in the build.
# Usage: sh tests/cli_mpi.sh path/to/sasnav
set -u
CLI=${1:?usage: cli_mpi.sh path/to/sasnav}
command -v mpirun > /dev/null 2>&1 || { echo "cli_mpi: no mpirun: skipped"; exit 77; }
T=$(mktemp -d "${TMPDIR:-/tmp}/sasnav-cli-mpi-XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT INT TERM
FAILED=0
fail() {
    echo "cli_mpi: FAIL: $*" >&2
    FAILED=1
}
# CI machines run as root; these processes are oversubscribed on purpose
# (2-3 ranks on 2 cores), one thread each.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1
MPIRUN="mpirun --oversubscribe"
# Sanitized builds: Open MPI's own allocations (its dlopen'ed components)
# are reported as leaks at exit; leak checking is off for the ranks, the
# address and undefined-behaviour checks stay on. sasnav's own code paths
# are leak-checked by the single-process tests.
if [ "${SASNAV_SANITIZED:-0}" = 1 ]; then
    MPIRUN="env ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0 $MPIRUN"
fi
# Open MPI's shared-memory transport wants a writable session directory.
export TMPDIR="$T"

# Is MPI built in? A command that runs as one process refuses two ranks
# with a usage error (2) in an MPI build; a build without MPI says so (1).
$MPIRUN -np 2 "$CLI" pair --help > "$T/probe.out" 2> "$T/probe.err"
probe=$?
if [ $probe -eq 1 ] && grep -q "has no MPI" "$T/probe.err"; then
    echo "cli_mpi: this build has no MPI: skipped"
    exit 77
fi
[ $probe -eq 2 ] || { cat "$T/probe.err" >&2; fail "pair under 2 ranks: status $probe, expected 2"; }
grep -q "runs as one process" "$T/probe.err" || fail "pair under 2 ranks: no clear message"
[ "$(grep -c "runs as one process" "$T/probe.err")" -eq 1 ] || fail "the usage error printed more than once"

cat > "$T/run.yaml" <<'YAML'
preset: paper-trajectory
trajectory: {n_pings: 5, x_start: -0.4, surge_rms: 0.003, sway_rms: 0.003, yaw_rms: 0.003}
noise: {snr_db: 30}
YAML
"$CLI" simulate --config "$T/run.yaml" -o "$T/run.h5" 2> "$T/sim.err" ||
    { cat "$T/sim.err" >&2; fail "simulate"; exit 1; }
# Simulation: pings over 2 ranks, the same file (noise and all).
$MPIRUN -np 2 "$CLI" simulate --config "$T/run.yaml" -o "$T/run2.h5" 2> "$T/sim.err" ||
    { cat "$T/sim.err" >&2; fail "simulate, 2 ranks"; }
h5diff "$T/run.h5" "$T/run2.h5" > "$T/diff.txt" 2>&1 || { cat "$T/diff.txt" >&2; fail "simulate, 2 ranks: differs"; }

# Same navigation file and same JSON (but timings and the process count).
strip() { grep -v -e '"seconds' -e '"pairs_per_second"' -e '"processes"' -e '"threads_over_pairs"' "$1"; }
same_nav() { # label, extra options...
    label=$1
    shift
    "$CLI" navigate "$T/run.h5" "$@" --json -o "$T/one.h5" > "$T/one.json" 2> "$T/one.err" ||
        { cat "$T/one.err" >&2; fail "$label: one process"; return; }
    $MPIRUN -np 2 "$CLI" navigate "$T/run.h5" "$@" --json -o "$T/two.h5" > "$T/two.json" 2> "$T/two.err" ||
        { cat "$T/two.err" >&2; fail "$label: two ranks"; return; }
    h5diff "$T/one.h5" "$T/two.h5" > "$T/diff.txt" 2>&1 || { cat "$T/diff.txt" >&2; fail "$label: files differ"; }
    strip "$T/one.json" > "$T/one.s"
    strip "$T/two.json" > "$T/two.s"
    cmp -s "$T/one.s" "$T/two.s" || { diff "$T/one.s" "$T/two.s" | head >&2; fail "$label: JSON differs"; }
    grep -q '"processes": 2' "$T/two.json" || fail "$label: JSON does not say 2 processes"
    [ "$(grep -c -- '->' "$T/two.err")" -eq 1 ] || fail "$label: the closing line printed other than once"
}
same_nav dpca --method dpca
# The sanitized build (~20x slower) checks the MPI paths' memory safety with
# DPCA and two ranks; the subspace estimator's bits are the optimised build's.
if [ -z "${SASNAV_SANITIZED:-}" ]; then
    same_nav subspace --k 2 --i 1
    RANKS="2 3"
else
    RANKS="2"
fi

# Image: rows split over 2 and 3 ranks.
"$CLI" image "$T/run.h5" --grid -0.6,0.6,61,9.5,10.5,51 -o "$T/img1.h5" 2> "$T/img.err" ||
    { cat "$T/img.err" >&2; fail "image, one process"; }
for n in $RANKS; do
    $MPIRUN -np $n "$CLI" image "$T/run.h5" --grid -0.6,0.6,61,9.5,10.5,51 -o "$T/img$n.h5" 2> "$T/img.err" ||
        { cat "$T/img.err" >&2; fail "image, $n ranks"; continue; }
    h5diff "$T/img1.h5" "$T/img$n.h5" > "$T/diff.txt" 2>&1 || { cat "$T/diff.txt" >&2; fail "image, $n ranks: differs"; }
done

# FFBP: two tiles (1101 columns of 1024), dealt to the ranks; the same tiles
# as one process, so the same bits.
"$CLI" image "$T/run.h5" --ffbp --grid -0.6,0.6,1101,9.9,10.1,21 -o "$T/ffbp1.h5" 2> "$T/img.err" ||
    { cat "$T/img.err" >&2; fail "image --ffbp, one process"; }
$MPIRUN -np 2 "$CLI" image "$T/run.h5" --ffbp --grid -0.6,0.6,1101,9.9,10.1,21 -o "$T/ffbp2.h5" 2> "$T/img.err" ||
    { cat "$T/img.err" >&2; fail "image --ffbp, 2 ranks"; }
h5diff "$T/ffbp1.h5" "$T/ffbp2.h5" > "$T/diff.txt" 2>&1 || { cat "$T/diff.txt" >&2; fail "image --ffbp, 2 ranks: differs"; }

# Failures: a missing input fails once (rank 0 speaks), status 1, no output.
$MPIRUN -np 2 "$CLI" navigate "$T/absent.h5" -o "$T/none.h5" > /dev/null 2> "$T/err.txt"
st=$?
[ $st -eq 1 ] || fail "missing input under 2 ranks: status $st, expected 1"
[ "$(grep -c "cannot read" "$T/err.txt")" -eq 1 ] || { cat "$T/err.txt" >&2; fail "missing input: message not printed exactly once"; }
[ ! -e "$T/none.h5" ] || fail "missing input: an output was written"
$MPIRUN -np 2 "$CLI" navigate "$T/run.h5" --checkpoint "$T/ck" -o "$T/none.h5" > /dev/null 2> "$T/err.txt"
st=$?
[ $st -eq 2 ] || fail "--checkpoint under 2 ranks: status $st, expected 2"
grep -q "checkpoint is for one process" "$T/err.txt" || fail "--checkpoint under 2 ranks: no clear message"

[ $FAILED -eq 0 ] && echo "cli_mpi: ok"
exit $FAILED
