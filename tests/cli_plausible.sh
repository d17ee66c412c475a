#!/bin/sh
# One plausibility check for every command (docs/format.md, "Plausibility"):
# a well-formed run file with a physically impossible sound speed is refused
# by every command that reads a run, with exit status 1 and a message that
# names the file and the value.
set -u
CLI=$1
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
if ! /usr/bin/python3 -c 'import h5py' 2>/dev/null; then echo "h5py missing: skipped"; exit 0; fi
"$CLI" simulate --preset paper-pair -o "$T/run.h5" >/dev/null || { echo "FAIL: simulate"; exit 1; }
cp "$T/run.h5" "$T/nav.h5"
/usr/bin/python3 - "$T/run.h5" <<'PY' || fail "h5py edit"
import sys, h5py
with h5py.File(sys.argv[1], "r+") as f:
    f["/system"].attrs["sound_speed"] = 15.0
PY
check() { # what, then the command line
    what=$1; shift
    "$@" >"$T/out" 2>"$T/err"; rc=$?
    if [ $rc != 1 ]; then fail "$what: exit $rc, expected 1"; fi
    grep -q "run.h5" "$T/err" && grep -q "sound_speed 15 m/s" "$T/err" ||
        fail "$what: message should name the file and the value: $(cat "$T/err")"
}
check image    "$CLI" image "$T/run.h5" -o "$T/img.h5"
check pair     "$CLI" pair "$T/run.h5"
check cuts     "$CLI" cuts "$T/run.h5" -o "$T/cuts"
check navigate "$CLI" navigate "$T/run.h5" -o "$T/n.h5"
check refine   "$CLI" refine "$T/run.h5" "$T/nav.h5" -o "$T/r.h5"
check validate "$CLI" validate "$T/run.h5" -o "$T/val"
for f in img.h5 n.h5 r.h5; do [ -e "$T/$f" ] && fail "$f written despite the error"; done
[ $fails = 0 ] && echo "all passed"
exit $fails
