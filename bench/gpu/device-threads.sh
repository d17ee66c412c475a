#!/bin/sh
# The pair estimator's CPU path on a many-core host (docs/estimator.md,
# "Batches on as many workers as threads"): OLD and NEW builds on the paper
# pair with 2, 8 and 16 threads, alternating runs, whether the estimates
# agree (times aside); then, where NEW/bench_trust is a CUDA build, a short
# Monte Carlo of fresh runs on the GPU.
#   sh bench/gpu/device-threads.sh OLD NEW OUT [SEED0 N SNR]
# OLD, NEW: folders holding sasnav; NEW/lib: the shared libraries the
# machine lacks. Logs go to OUT.
set -u
old=$1
new=$2
out=$3
mkdir -p "$out"
libdir=$new/lib
. "$(dirname "$0")/device-env.sh"
echo "cores: $(getconf _NPROCESSORS_ONLN)"
secs() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); s=d['stages']; print('%.3f s (' % d['seconds'] + ', '.join('%s %.3f' % (k, s[k]['seconds']) for k in s) + ')')" "$1" 2>/dev/null || echo failed; }
"$new/sasnav" simulate --preset paper-pair -o "$out/pair.h5" > /dev/null
for r in 1 2 3; do
    for t in 2 8 16; do
        for v in old new; do
            eval "b=\$$v"
            timeout 120 "$b/sasnav" pair "$out/pair.h5" --threads "$t" --json > "$out/${v}_t${t}_$r.json" 2>&1
            echo "$v --threads $t run $r: $(secs "$out/${v}_t${t}_$r.json")"
        done
    done
done
strip() { grep -v -i 'seconds\|time' "$1" | md5sum; }
ref=$(strip "$out/old_t2_1.json")
n=0; d=0
for f in "$out"/*_t*_*.json; do n=$((n + 1)); [ "$(strip "$f")" = "$ref" ] || { d=$((d + 1)); echo "DIFFERENT: $f"; }; done
echo "estimates: $n runs, $d differ from old --threads 2 (times aside)"
if [ $# -ge 6 ] && [ -x "$new/bench_trust" ]; then
    timeout 200 "$new/bench_trust" --seeds "$4" "$5" --snr "$6" --methods paper,subspace --threads 8 --gpu \
        > "$out/trust.txt" 2>&1
    echo "== trust exit $?"; tail -n 5 "$out/trust.txt"
fi
