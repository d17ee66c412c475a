#!/bin/sh
# CLI manners (docs/cli.md): exit status 2 for usage errors, 1 for runtime
# failures, with the expected message; suggestions for misspelled commands
# and options; --version in the help; --threads accepted by every command
# that computes. Messages are compared by pattern.
set -u
CLI=$1
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
# expect STATUS PATTERN command...: exit status and a stderr line matching
expect() {
    want=$1; pat=$2; shift 2
    "$CLI" "$@" >"$T/out" 2>"$T/err"; rc=$?
    [ $rc = "$want" ] || fail "sasnav $*: exit $rc, expected $want ($(cat "$T/err"))"
    grep -q -e "$pat" "$T/err" || fail "sasnav $*: stderr should match '$pat': $(cat "$T/err")"
}
expect 2 "unknown command 'navgate' (did you mean 'navigate'?)" navgate
expect 2 "unknown command 'frobnicate'$" frobnicate
expect 2 "unknown option '--outptu' (did you mean '--output'?)" navigate x.h5 --outptu y
expect 2 "unknown option '--treads' (did you mean '--threads'?)" image x.h5 --treads 2 -o y.h5
expect 2 "option '--threads' needs a value" pair x.h5 --threads
expect 2 "unknown option '-q'" simulate -q
"$CLI" --help | grep -q -- "--version" || fail "--help lists --version"
"$CLI" --help | grep -q "Exit status: 0 success, 1 a failure" || fail "--help states the exit statuses"
"$CLI" --version | grep -q "^sasnav [0-9][0-9]*\.[0-9][0-9]*\.[0-9][0-9]*$" || fail "--version: $("$CLI" --version)"
# usage errors of each command: 2, naming the command and pointing at its help
expect 2 "sasnav simulate: an output file is required (-o run.h5) (see 'sasnav simulate --help')" simulate
expect 2 "sasnav image: exactly one input run file is required" image
expect 2 "sasnav pair: exactly one input run file is required" pair
expect 2 "sasnav cuts: an output directory is required" cuts x.h5
expect 2 "sasnav ingest: an input is required" ingest -o x.h5
expect 2 "sasnav navigate: an output file is required" navigate x.h5
expect 2 "sasnav refine: a run file and a navigation file are required" refine -o x.h5
expect 2 "sasnav tank: an output directory is required" tank
expect 2 "sasnav validate: an output directory is required" validate x.h5
expect 2 "sasnav demo: --threads needs an integer" demo --threads many
expect 2 "sasnav navigate: --method needs subspace, dpca or aiding" navigate x.h5 --method foo -o y.h5
expect 2 "sasnav image: --nav and --truth exclude each other" image x.h5 --nav n.h5 --truth -o y.h5
# runtime failures: 1, naming the file; --threads accepted by every command
# that computes (the run is missing: a runtime error, not a usage error)
M="$T/missing.h5"
expect 1 "missing.h5: cannot open" image "$M" --threads 1 -o "$T/i.h5"
expect 1 "missing.h5: cannot open" pair "$M" --threads 1
expect 1 "missing.h5: cannot open" cuts "$M" --threads 1 -o "$T/c"
expect 1 "missing.h5: cannot open" navigate "$M" --threads 1 -o "$T/n.h5"
expect 1 "missing.h5: cannot open" refine "$M" "$M" --threads 1 -o "$T/r.h5"
expect 1 "missing.h5: cannot open" validate "$M" --threads 1 -o "$T/v"
expect 1 "nowhere" ingest --airsas "$T/nowhere" --threads 1 -o "$T/x.h5"
expect 1 "nowhere.yaml" simulate --config "$T/nowhere.yaml" --threads 1 -o "$T/s.h5"
"$CLI" tank --threads 1 -o "$T/tank" >/dev/null 2>&1 || fail "tank --threads 1"
for f in i.h5 n.h5 r.h5 x.h5 s.h5; do [ -e "$T/$f" ] && fail "$f written despite the error"; done
[ $fails = 0 ] && echo "all passed"
exit $fails
