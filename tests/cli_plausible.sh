#!/bin/sh
# One plausibility check for every command (docs/format.md, "Plausibility"):
# for each rule, a well-formed run file that breaks it (crafted with h5py
# from a simulated one: an impossible sound speed, carrier, sample rate,
# speed, ping spacing, range, window, receiver height, element length or
# position, transmitter pose, a NaN sample) is refused by every command
# that reads a run (image, pair, cuts, navigate, refine, validate) with
# exit status 1 and the same message, which names the file and the value;
# no output is written.
set -u
CLI=$1
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
if ! /usr/bin/python3 -c 'import h5py' 2>/dev/null; then echo "h5py missing: skipped"; exit 0; fi
"$CLI" simulate --preset paper-pair -o "$T/good.h5" >/dev/null 2>&1 || { echo "FAIL: simulate"; exit 1; }
cp "$T/good.h5" "$T/nav.h5"
# rule | h5py edit (f: the open file) | text the message must hold
cat > "$T/rules" <<'RULES'
sound speed 15 m/s|f["/system"].attrs["sound_speed"] = 15.0|sound_speed 15 m/s
sound speed 15000 m/s|f["/system"].attrs["sound_speed"] = 15000.0|sound_speed
carrier 50 Hz|f["/system"].attrs["f0"] = 50.0|f0
carrier 1 GHz|f["/system"].attrs["f0"] = 1e9|f0
sample rate 1 THz|f["/system"].attrs["sample_rate"] = 1e12|sample_rate
speed 1000 m/s|f["/system"].attrs["speed"] = 1000.0|speed
ping spacing 10 km|f["/system"].attrs["ping_spacing"] = 1e4|ping_spacing
range of interest 10000 km|f["/system"].attrs["range_of_interest"] = 1e7|range_of_interest
window 200 s late|f["/system"].attrs["t0"] = 200.0|window
receiver height -100 km|f["/array"].attrs["rx_height"] = -1e5|heights
element length 500 m|f["/array"].attrs["rx_length"] = 500.0|element lengths
receiver 10 km away|d = f["/array/rx_u"]; v = d[...]; v[1] = 1e4; d[...] = v|rx_u[1]
transmitter 1e6 m away|d = f["/nav/tx"]; v = d[...]; v[1, 0] = 1e6; d[...] = v|transmitter
NaN sample|d = f["/raw"]; d[0, 0, 5] = complex(float("nan"), 0.0)|sample 5 of channel 0 of ping 0 is not finite
RULES
k=0
while IFS='|' read -r what edit want; do
    k=$((k + 1))
    run="$T/run$k.h5"
    cp "$T/good.h5" "$run"
    /usr/bin/python3 - "$run" "$edit" <<'PY' || { fail "$what: h5py edit"; continue; }
import sys, h5py
with h5py.File(sys.argv[1], "r+") as f:
    exec(sys.argv[2])
PY
    first=""
    for cmd in image pair cuts navigate refine validate; do
        case $cmd in
        image) set -- image "$run" -o "$T/img.h5" ;;
        pair) set -- pair "$run" ;;
        cuts) set -- cuts "$run" -o "$T/cuts" ;;
        navigate) set -- navigate "$run" -o "$T/n.h5" ;;
        refine) set -- refine "$run" "$T/nav.h5" -o "$T/r.h5" ;;
        validate) set -- validate "$run" -o "$T/val" ;;
        esac
        "$CLI" "$@" >"$T/out" 2>"$T/err"; rc=$?
        [ $rc = 1 ] || fail "$what: $cmd exit $rc, expected 1 ($(cat "$T/err"))"
        # the library's message: what follows "cannot read FILE: "
        msg=$(sed -n "s|^sasnav $cmd: cannot read [^:]*: ||p" "$T/err")
        [ -n "$msg" ] || { fail "$what: $cmd: no 'cannot read' line: $(cat "$T/err")"; continue; }
        case $msg in *"$want"*) ;; *) fail "$what: $cmd: message lacks '$want': $msg" ;; esac
        grep -q "run$k.h5" "$T/err" || fail "$what: $cmd: message does not name the file"
        if [ -z "$first" ]; then first=$msg; elif [ "$msg" != "$first" ]; then
            fail "$what: $cmd says '$msg', image said '$first'"
        fi
    done
    for f in img.h5 n.h5 r.h5; do [ -e "$T/$f" ] && fail "$what: $f written despite the error"; done
done < "$T/rules"
[ "$k" -eq 14 ] || fail "read $k rules, expected 14"
[ $fails = 0 ] && echo "all passed ($k rules x 6 commands)"
exit $fails
