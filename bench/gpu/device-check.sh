#!/bin/sh
# The GPU path's checks and timings on a CUDA machine (bench/gpu/bench_gpu.c).
#   sh bench/gpu/device-check.sh DIR OUT
# DIR holds bench_gpu (built with -DSASNAV_CUDA=ON) and, where the machine
# lacks them, the shared libraries it needs (libgomp, libfftw3f, libnlopt);
# OUT receives the logs. First a memory check of the operator and the
# evaluations (compute-sanitizer, when installed), then the timings.
set -u
dir=$1
out=$2
nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm --format=csv 2>&1
cufft=$(ls /usr/local/cuda/lib64/libcufft.so.12 2>/dev/null ||
        find /usr /opt -name 'libcufft.so.12' 2>/dev/null | head -n 1)
LD_LIBRARY_PATH=$dir:$(dirname "$cufft")${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
export LD_LIBRARY_PATH
ldd "$dir/bench_gpu" | grep -E "not found|cufft" || true
if command -v compute-sanitizer >/dev/null 2>&1; then
    OMP_NUM_THREADS=2 timeout 150 compute-sanitizer --tool memcheck --leak-check full \
        "$dir/bench_gpu" --no-estimates --evals 1 --threads 2 > "$out/memcheck.txt" 2>&1
    echo "memcheck exit $?"
    tail -n 25 "$out/memcheck.txt"
fi
OMP_NUM_THREADS=2 timeout 300 "$dir/bench_gpu" --draws 3 --threads 2 --evals 20 2>&1 | tee "$out/bench_gpu.txt"
echo "bench exit $?"
