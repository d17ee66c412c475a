#!/bin/sh
# Same-machine A/B of the pair estimator's workers (docs/estimator.md,
# "Batches on as many workers as threads"): OLD and NEW CUDA builds on the
# paper pair (GPU and CPU paths, several thread counts, alternating runs),
# whether their estimates agree (times aside), the device checks of NEW,
# navigate's throughput, and a short Monte Carlo of fresh runs on the GPU.
#   sh bench/gpu/device-workers.sh OLD NEW OUT
# OLD, NEW: folders holding sasnav (and in NEW: test_gpu, bench_trust) of a
# -DSASNAV_CUDA=ON build each; NEW/lib: the shared libraries the machine
# lacks. Logs go to OUT.
set -u
old=$1
new=$2
out=$3
mkdir -p "$out"
libdir=$new/lib
. "$(dirname "$0")/device-env.sh"
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>&1
nproc
run() { # NAME SECONDS COMMAND...
    name=$1; secs=$2; shift 2
    timeout "$secs" "$@" > "$out/$name.txt" 2>&1
    echo "== $name exit $?"
}
secs() { grep -m1 '^  "seconds"' "$1" | tr -dc '0-9.'; }
run test_gpu 90 "$new/test_gpu"
tail -n 4 "$out/test_gpu.txt"
"$new/sasnav" simulate --preset paper-pair -o "$out/pair.h5" > /dev/null
"$new/sasnav" simulate --preset paper-trajectory --seed 3301 --snr 30 -o "$out/traj.h5" > /dev/null
# GPU, 2 threads, alternating
for r in 1 2 3; do
    for v in old new; do
        eval "b=\$$v"
        run "gpu_${v}_t2_$r" 60 "$b/sasnav" pair "$out/pair.h5" --threads 2 --json --gpu
        echo "gpu $v t2 run $r: $(secs "$out/gpu_${v}_t2_$r.txt") s"
    done
done
# GPU, other thread counts (NEW: that many workers; OLD: one)
for r in 1 2; do
    for t in 1 3 5 10; do
        for v in old new; do
            eval "b=\$$v"
            run "gpu_${v}_t${t}_$r" 60 "$b/sasnav" pair "$out/pair.h5" --threads "$t" --json --gpu
            echo "gpu $v t$t run $r: $(secs "$out/gpu_${v}_t${t}_$r.txt") s"
        done
    done
done
# CPU path, 8 and 2 threads, alternating
for r in 1 2; do
    for t in 8 2; do
        for v in old new; do
            eval "b=\$$v"
            run "cpu_${v}_t${t}_$r" 120 "$b/sasnav" pair "$out/pair.h5" --threads "$t" --json
            echo "cpu $v t$t run $r: $(secs "$out/cpu_${v}_t${t}_$r.txt") s"
        done
    done
done
strip() { grep -v -i 'seconds\|time' "$1"; }
for f in "$out"/gpu_*_1.txt "$out"/gpu_*_2.txt "$out"/gpu_*_3.txt; do
    [ -f "$f" ] || continue
    if [ "$(strip "$f" | md5sum)" = "$(strip "$out/gpu_old_t2_1.txt" | md5sum)" ]; then s=same; else s=DIFFERENT; fi
    echo "$(basename "$f"): $s as gpu_old_t2_1 (times aside)"
done
for f in "$out"/cpu_*.txt; do
    if [ "$(strip "$f" | md5sum)" = "$(strip "$out/cpu_old_t2_1.txt" | md5sum)" ]; then s=same; else s=DIFFERENT; fi
    echo "$(basename "$f"): $s as cpu_old_t2_1 (times aside)"
done
for v in old new; do
    eval "b=\$$v"
    timeout 90 "$b/sasnav" navigate "$out/traj.h5" --gpu --threads 8 --json -o "$out/nav_$v.h5" \
        > "$out/navcli_$v.json" 2> "$out/navcli_$v.err"
    echo "== navcli_$v exit $?"; grep 'pairs_per_second' "$out/navcli_$v.json"
    grep -v 'seconds\|pairs_per_second' "$out/navcli_$v.json" > "$out/navcli_$v.strip"
done
cmp -s "$out/navcli_old.strip" "$out/navcli_new.strip" && echo "navigate: old and new agree (times aside)" ||
    echo "navigate: old and new DIFFER"
# fresh runs, micronavigation alone, on the GPU (issue "Trustworthy navigation")
run trust 150 "$new/bench_trust" --seeds 6001 40 --snr 30 --methods paper,subspace --threads 8 --gpu
tail -n 12 "$out/trust.txt"
