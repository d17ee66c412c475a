#!/bin/sh
# Faults (docs/library.md, "Faults"): no output is ever left half-written.
#  - a file-size limit (as a full disk: the write fails with EFBIG): exit 1
#    with one message, the previous output unchanged, no temporary file;
#  - an allocation that fails (address-space limit): exit 1, "out of
#    memory", nothing written;
#  - SIGINT / SIGTERM during a long command: the process ends by the
#    signal (exit status 128 + N in a shell), the previous output unchanged,
#    no temporary file.
set -u
CLI=$1
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
no_tmp() { if ls "$T" | grep -q '\.tmp'; then fail "$1: temporary file left: $(ls "$T")"; fi; }

"$CLI" simulate --preset paper-pair -o "$T/run.h5" >/dev/null 2>&1 || fail "simulate"
cp "$T/run.h5" "$T/prev.h5"

# 1. file-size limit of 50 blocks: the 16-ping run does not fit
(ulimit -f 50; "$CLI" simulate --preset paper-trajectory -o "$T/run.h5") >/dev/null 2>"$T/err"
rc=$?
[ $rc = 1 ] || fail "file-size limit: exit $rc, expected 1"
grep -q "File too large" "$T/err" || fail "file-size limit: message: $(cat "$T/err")"
[ "$(wc -l <"$T/err")" -le 1 ] || fail "file-size limit: one line expected: $(cat "$T/err")"
cmp -s "$T/run.h5" "$T/prev.h5" || fail "file-size limit: previous output changed"
no_tmp "file-size limit"

# 2. out of memory: a scene of 5e7 scatterers (1.2 GB) under 1 GB of address
# space (not under ASan, which reserves terabytes of shadow address space).
# (A long run no longer is one: simulate writes it ping by ping.)
printf 'preset: paper-trajectory\nscene: {density: 8.0e6, x_min: -1.5, x_max: 1.6}\n' >"$T/big.yaml"
if [ -z "${SASNAV_SANITIZED:-}" ]; then
    (ulimit -v 1000000; "$CLI" simulate --config "$T/big.yaml" -o "$T/big.h5") >/dev/null 2>"$T/err"
    rc=$?
    [ $rc = 1 ] || fail "out of memory: exit $rc, expected 1"
    grep -q "out of memory for 49600000 scatterers" "$T/err" || fail "out of memory: message: $(cat "$T/err")"
    [ -e "$T/big.h5" ] && fail "out of memory: output written"
    no_tmp "out of memory"
fi

# 3. signals during a long command (a subspace navigation takes seconds).
# A shell starts background jobs with SIGINT ignored (and sasnav keeps a
# signal ignored when it finds it so, as nohup expects): python starts the
# command with the default dispositions and sends the signal.
"$CLI" simulate --preset paper-trajectory -o "$T/traj.h5" >/dev/null 2>&1 || fail "simulate"
cp "$T/prev.h5" "$T/nav.h5"
for sig in INT TERM; do
    rc=$(/usr/bin/python3 - "$CLI" "$T" "$sig" <<'PY'
import signal, subprocess, sys, time
cli, t, sig = sys.argv[1:4]
p = subprocess.Popen([cli, "navigate", t + "/traj.h5", "--threads", "1", "-o", t + "/nav.h5"],
                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                     preexec_fn=lambda: [signal.signal(s, signal.SIG_DFL)
                                         for s in (signal.SIGINT, signal.SIGTERM)])
time.sleep(2)
p.send_signal(getattr(signal, "SIG" + sig))
print(p.wait())
PY
)
    case $sig in INT) want=-2 ;; TERM) want=-15 ;; esac
    [ "$rc" = $want ] || fail "SIG$sig: ended with $rc, expected killed by the signal ($want)"
    cmp -s "$T/nav.h5" "$T/prev.h5" || fail "SIG$sig: previous output changed"
    no_tmp "SIG$sig"
done
[ $fails = 0 ] && echo "all passed"
exit $fails
