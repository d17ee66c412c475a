#!/bin/sh
# Same-machine comparison on a CUDA machine: the GPU path, this version's CPU
# path and main before the issue "Ten times faster pair estimates" (2126057),
# on the paper pair and on paper-trajectory seed 3301 (30 dB), 2 threads;
# first the GPU checks of tests/test_gpu.c, last a memory check of the GPU
# path (compute-sanitizer, where installed).
#   sh bench/gpu/device-compare.sh DIR OUT
# DIR: bench_gpu and bench_navigate_gpu (this version, -DSASNAV_CUDA=ON);
# test_gpu_dev (tests/test_gpu.c linked against the core library alone,
# testutil's two counters and summary written out); oldpair and oldnav,
# 2126057's bench/bench_pair.c and bench/gpu/navigate_driver.c built against
# that version's build tree OLD:
#   gcc -O2 -std=c11 -D_POSIX_C_SOURCE=200809L -IOLD/include -IOLD/build/include \
#       -IOLD/src OLD/bench/bench_pair.c OLD/build/libsasnav.a -lfftw3f -lnlopt \
#       -fopenmp -lm -o DIR/oldpair
#   (navigate_driver.c: the line in its header, -o DIR/oldnav);
# and the shared libraries the machine lacks (libgomp, libfftw3f, libnlopt).
# Logs go to OUT.
set -u
dir=$1
out=$2
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>&1
libdir=$dir
. "$(dirname "$0")/device-env.sh"
run() { # NAME SECONDS COMMAND...
    name=$1; secs=$2; shift 2
    timeout "$secs" "$@" > "$out/$name.txt" 2>&1
    echo "== $name exit $?"; cat "$out/$name.txt"
}
run test_gpu 30 "$dir/test_gpu_dev"
run bench_gpu 80 "$dir/bench_gpu" --draws 3 --threads 2 --evals 20
run oldpair 30 "$dir/oldpair" --paper-only --threads 2
run nav_gpu 40 "$dir/bench_navigate_gpu" --seeds 3301 1 --threads 2,8 --gpu
run nav_gpu_copy 40 "$dir/bench_navigate_gpu" --seeds 3301 1 --threads 2 --gpu-copy
run oldnav 170 "$dir/oldnav" 3301 2
if command -v compute-sanitizer >/dev/null 2>&1; then
    run memcheck 60 compute-sanitizer --tool memcheck --leak-check full "$dir/bench_gpu" \
        --no-estimates --evals 1 --threads 2
fi
