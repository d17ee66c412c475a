#!/bin/sh
# Same-machine A/B of two CUDA builds of the GPU path (docs/estimator.md,
# "Kept contexts, and the GPU path checked again after its review"): the
# device checks of NEW, then alternating runs of both on the same data
# (bench_navigate_gpu on paper-trajectory seed 3301, sasnav pair on the
# paper pair, bench_gpu --concurrent where both folders hold it), whether
# their outputs agree (times aside), and a memory check of NEW's device
# checks.
#   sh bench/gpu/device-ab.sh OLD NEW OUT
# OLD, NEW: folders holding sasnav, bench_navigate_gpu, test_gpu (and
# optionally bench_gpu) of a -DSASNAV_CUDA=ON build each (and, in NEW/lib,
# the shared libraries the machine lacks); logs go to OUT.
set -u
old=$1
new=$2
out=$3
mkdir -p "$out"
libdir=$new/lib
. "$(dirname "$0")/device-env.sh"
run() { # NAME SECONDS COMMAND...
    name=$1; secs=$2; shift 2
    timeout "$secs" "$@" > "$out/$name.txt" 2>&1
    echo "== $name exit $?"; tail -n 6 "$out/$name.txt"
}
run test_gpu 60 "$new/test_gpu"
"$new/sasnav" simulate --preset paper-trajectory --seed 3301 --snr 30 -o "$out/traj.h5" > /dev/null
"$new/sasnav" simulate --preset paper-pair -o "$out/pair.h5" > /dev/null
for r in 1 2; do
    for v in old new; do
        eval "b=\$$v"
        run "nav_${v}_$r" 60 "$b/bench_navigate_gpu" --seeds 3301 1 --threads 2,8 --gpu
    done
done
for r in 1 2 3; do
    for v in old new; do
        eval "b=\$$v"
        run "pair_${v}_$r" 30 "$b/sasnav" pair "$out/pair.h5" --threads 2 --json --gpu
    done
done
# (only where both binaries have the option: grep finds its name in them)
if grep -q -- '--concurrent' "$old/bench_gpu" 2>/dev/null &&
   grep -q -- '--concurrent' "$new/bench_gpu" 2>/dev/null; then
    for r in 1 2; do
        for v in old new; do
            eval "b=\$$v"
            run "conc_${v}_$r" 90 "$b/bench_gpu" --concurrent 1,8,16 --evals 20
        done
    done
fi
for v in old new; do
    eval "b=\$$v"
    timeout 60 "$b/sasnav" navigate "$out/traj.h5" --gpu --threads 8 --json -o "$out/nav_$v.h5" \
        > "$out/navcli_$v.json" 2> "$out/navcli_$v.err"
    echo "== navcli_$v exit $?"; grep 'pairs_per_second' "$out/navcli_$v.json"
    # stdout alone: with stderr in the same file the lines' order may differ
    grep -v 'seconds\|pairs_per_second' "$out/navcli_$v.json" > "$out/navcli_$v.strip"
    grep -v 'seconds' "$out/pair_${v}_1.txt" > "$out/pair_$v.strip"
done
for k in navcli pair; do
    if cmp -s "$out/${k}_old.strip" "$out/${k}_new.strip"; then echo "$k: old and new agree (times aside)"
    else echo "$k: old and new DIFFER"; fi
done
if command -v compute-sanitizer > /dev/null 2>&1; then
    run memcheck 150 compute-sanitizer --tool memcheck --leak-check full "$new/test_gpu"
fi
