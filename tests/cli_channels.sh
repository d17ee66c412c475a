#!/bin/sh
# Channels with transmitters of their own through the CLI (docs/format.md,
# "/channels"; docs/model.md, "Channel layouts"): `simulate` with the
# two-transmitter head of examples/two_tx_head.yaml writes a version-2 run
# with /channels; `image` focuses its point target; `navigate` (subspace)
# works on it, without a gyro the transmitters' turn from the pairs (JSON
# tx_yaw "pairs", no warning; --tx-yaw none warns); DPCA is
# refused (status 1, a message, no output file); a config whose
# tx_positions do not match the channels is refused (status 1); a run without
# transmitters of its own is still written as version 1; per-channel heights
# (examples/circular_two_mics.yaml) are written as /array/sizes.
# Usage: sh tests/cli_channels.sh path/to/sasnav
set -u
CLI=${1:?usage: cli_channels.sh path/to/sasnav}
HERE=$(cd "$(dirname "$0")/.." && pwd)
T=$(mktemp -d "${TMPDIR:-/tmp}/sasnav-cli-channels-XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT INT TERM
FAILED=0
fail() {
    echo "cli_channels: FAIL: $*" >&2
    FAILED=1
}
PY=/usr/bin/python3
HAVE_H5PY=0
[ -x "$PY" ] && "$PY" -c "import h5py, numpy" 2>/dev/null && HAVE_H5PY=1

# A point target seen by the two-transmitter head (the "point" preset's
# 17 pings, noise-free).
cp "$HERE/examples/two_tx_head.yaml" "$T/head.yaml"
"$CLI" simulate --preset point --config "$T/head.yaml" -o "$T/point.h5" 2> "$T/sim.err" ||
    { cat "$T/sim.err" >&2; fail "simulate"; exit 1; }
"$CLI" simulate --preset point -o "$T/one.h5" 2> /dev/null || fail "simulate (one transmitter)"
if [ "$HAVE_H5PY" = 1 ]; then
    "$PY" - "$T/point.h5" "$T/one.h5" <<'EOF' || fail "file content"
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r") as f:
    assert int(f.attrs["format_version"]) == 2, f.attrs["format_version"]
    tx = f["/channels/tx"][...]
    assert tx.shape == (16, 3), tx.shape
    assert np.all(tx[:8, 0] == -0.2) and np.all(tx[8:, 0] == 0.2) and not tx[:, 1:].any(), tx
    assert not f["/channels/array"][...].any()
    assert f["/raw"].shape[1] == 16
with h5py.File(sys.argv[2], "r") as f:
    assert int(f.attrs["format_version"]) == 1 and "channels" not in f
EOF
fi

# The image (true poses, 2 mm pixels around the target at (0.013, 10.007)).
"$CLI" image "$T/point.h5" --truth --grid -0.027,0.053,41,9.967,10.047,41 -o "$T/img.h5" 2> "$T/img.err" ||
    { cat "$T/img.err" >&2; fail "image"; }
if [ "$HAVE_H5PY" = 1 ] && [ -s "$T/img.h5" ]; then
    "$PY" - "$T/img.h5" <<'EOF' || fail "the image does not peak at the target"
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r") as f:
    a = np.abs(f["/image"][...]); x = f["/x"][...]; y = f["/y"][...]
iy, ix = np.unravel_index(np.argmax(a), a.shape)
# within one 2 mm pixel of the target (test_channels checks the sub-pixel peak)
assert abs(x[ix] - 0.013) <= 0.002 and abs(y[iy] - 10.007) <= 0.002, (x[ix], y[iy])
EOF
fi

# Navigation of a short noise-free two-transmitter run.
cat > "$T/tiny.yaml" <<'EOF'
preset: paper-trajectory
trajectory: {n_pings: 3, x_start: -0.2, surge_rms: 0.003, sway_rms: 0.003, yaw_rms: 0.003}
noise: {snr_db: inf}
EOF
sed -n '/^array:/,$p' "$HERE/examples/two_tx_head.yaml" >> "$T/tiny.yaml"
"$CLI" simulate --config "$T/tiny.yaml" -o "$T/run.h5" 2> /dev/null || fail "simulate tiny"
if "$CLI" navigate "$T/run.h5" --k 2 --i 1 --json -o "$T/nav.h5" > "$T/nav.json" 2> "$T/nav.err"; then
    # no gyro: the transmitters' turn from the pairs' own yaw estimates
    grep -q '"tx_yaw": "pairs"' "$T/nav.json" || fail "JSON lacks tx_yaw pairs"
    grep -q '"gyro_tx_yaw": false' "$T/nav.json" || fail "JSON lacks gyro_tx_yaw false"
    grep -q "warning" "$T/nav.err" && fail "a warning although the pairs gave the transmitters' yaw"
    [ -s "$T/nav.h5" ] || fail "no navigation file"
else
    cat "$T/nav.err" >&2
    fail "navigate"
fi
if "$CLI" navigate "$T/run.h5" --k 2 --i 1 --tx-yaw none --json -o "$T/nav0.h5" > "$T/nav0.json" \
    2> "$T/nav0.err"; then
    grep -q "taken as zero" "$T/nav0.err" || fail "no warning that the transmitters' yaw is taken as zero"
    grep -q '"tx_yaw": "none"' "$T/nav0.json" || fail "JSON lacks tx_yaw none"
else
    cat "$T/nav0.err" >&2
    fail "navigate --tx-yaw none"
fi
"$CLI" pair "$T/run.h5" --k 2 --i 1 --json > "$T/pair.json" 2> /dev/null || fail "pair"
grep -q '"tx_yaw": "estimate"' "$T/pair.json" || fail "pair JSON lacks tx_yaw estimate (no gyro)"
"$CLI" navigate "$T/run.h5" --tx-yaw sideways -o "$T/bad.h5" 2> /dev/null
[ $? -eq 2 ] || fail "--tx-yaw sideways: status other than 2"
[ -e "$T/bad.h5" ] && fail "--tx-yaw sideways wrote a file"
if "$CLI" navigate "$T/run.h5" --method dpca -o "$T/dpca.h5" 2> "$T/dpca.err"; then
    fail "DPCA accepted a run whose channels have transmitters of their own"
else
    [ $? -eq 1 ] || fail "DPCA refusal: status other than 1"
    grep -q "transmitters of their own" "$T/dpca.err" || fail "DPCA refusal: message"
    [ -e "$T/dpca.h5" ] && fail "DPCA refusal left an output file"
fi

# tx_positions of the wrong length: refused as an invalid configuration
# (status 1, as every bad config value), naming the problem.
cat > "$T/bad.yaml" <<'EOF'
array:
  n_rx: 4
  tx_positions: [-0.2, 0.2]
EOF
"$CLI" simulate --config "$T/bad.yaml" -o "$T/bad.h5" 2> "$T/bad.err"
st=$?
[ $st -eq 1 ] || fail "mismatched tx_positions: status $st, expected 1"
grep -q "transmitter positions for 4 channels" "$T/bad.err" || { cat "$T/bad.err" >&2; fail "mismatched tx_positions: message"; }
[ -e "$T/bad.h5" ] && fail "mismatched tx_positions left an output file"

# Channels of their own heights (examples/circular_two_mics.yaml, 4 pings):
# a version-2 run with /array/sizes holding each microphone's height; a
# height list of the wrong length is refused (status 1, the key named, no
# file).
cp "$HERE/examples/circular_two_mics.yaml" "$T/mics.yaml"
printf 'trajectory: {n_pings: 4}\n' >> "$T/mics.yaml"
"$CLI" simulate --preset circular --config "$T/mics.yaml" -o "$T/mics.h5" 2> /dev/null ||
    fail "simulate with per-channel heights"
if [ "$HAVE_H5PY" = 1 ] && [ -e "$T/mics.h5" ]; then
    "$PY" - "$T/mics.h5" <<'EOF' || fail "per-channel heights: file content"
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r") as f:
    assert int(f.attrs["format_version"]) == 2, f.attrs["format_version"]
    z = f["/array/sizes"][...]
    assert z.shape == (2, 4), z.shape
    assert np.array_equal(z[:, 2], [0.2195, 0.1885]) and np.all(z[:, 3] == 0.2575), z
    assert "/channels" not in f
EOF
fi
cat > "$T/badh.yaml" <<'EOF'
array:
  n_rx: 4
  rx_heights: [0.1, 0.2]
EOF
"$CLI" simulate --config "$T/badh.yaml" -o "$T/badh.h5" 2> "$T/badh.err"
st=$?
[ $st -eq 1 ] || fail "mismatched rx_heights: status $st, expected 1"
grep -q "rx_heights has 2 values for 4 channels" "$T/badh.err" || { cat "$T/badh.err" >&2; fail "mismatched rx_heights: message"; }
[ -e "$T/badh.h5" ] && fail "mismatched rx_heights left an output file"

[ "$FAILED" = 0 ] && echo "cli_channels: ok"
exit "$FAILED"
