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
cufft=$(ls /usr/local/cuda/lib64/libcufft.so.12 2>/dev/null ||
        find /usr /opt -name 'libcufft.so.12' 2>/dev/null | head -n 1)
LD_LIBRARY_PATH=$bin/lib:$(dirname "$cufft")${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
export LD_LIBRARY_PATH OMP_NUM_THREADS=2
nvidia-smi -L
timeout 200 "$bin/bench_gpu" --concurrent 1,2,4,8,16 --evals 20 > "$out/concurrent.txt" 2>&1
echo "== concurrent exit $?"; cat "$out/concurrent.txt"
if command -v ncu > /dev/null 2>&1; then
    timeout 240 ncu --clock-control none --metrics gpu__time_duration.sum --print-summary per-kernel \
        -c 120 "$bin/bench_gpu" --no-estimates --evals 1 > "$out/ncu.txt" 2>&1
    echo "== ncu exit $?"
    grep -v '^==PROF==' "$out/ncu.txt" | tail -n 60
fi
