#!/bin/sh
# Where the GPU path's time goes, on the device machine (docs/estimator.md,
# "GPU"): the kernels' durations (Nsight Compute, one metric, the first
# kernels of bench_gpu: one T, one T^H and a CGLS of k = 8, the kernels of
# every evaluation) and evaluations per second against the number of
# estimators evaluating at once (bench_gpu --concurrent).
#   sh bench/gpu/device-profile.sh BIN OUT
# BIN: a folder holding bench_gpu of a -DSASNAV_CUDA=ON build (and, in
# BIN/lib, the shared libraries the machine lacks); logs go to OUT.
set -u
bin=$1
out=$2
mkdir -p "$out"
libdir=$bin/lib
. "$(dirname "$0")/device-env.sh"
nvidia-smi -L
timeout 200 "$bin/bench_gpu" --concurrent 1,2,4,8,16 --evals 20 > "$out/concurrent.txt" 2>&1
echo "== concurrent exit $?"; cat "$out/concurrent.txt"
if command -v ncu > /dev/null 2>&1; then
    timeout 240 ncu --clock-control none --metrics gpu__time_duration.sum --print-summary per-kernel \
        -c 120 "$bin/bench_gpu" --no-estimates --evals 1 > "$out/ncu.txt" 2>&1
    echo "== ncu exit $?"
    grep -v '^==PROF==' "$out/ncu.txt" | tail -n 60
fi
