#!/bin/sh
# examples/airsas_compare.py (docs/airsas.md): the correlations against an
# AirSAS-style reference are right on constructed images, and bad inputs
# fail with a message. The image comes from the tool itself (`sasnav
# image` of a simulated point run on the reference's 400 x 400 grid), so
# the reader sees sasnav's own image layout:
# - the image against itself as the reference: 1.000 and 1.000;
# - times a complex constant (exp(1.3 j) x 2.5): still 1.000 / 1.000 (the
#   correlations are normalised and the coherent one takes the modulus);
# - its complex conjugate: the magnitudes still 1.000, the coherent one
#   well below (measured 0.000; bound 0.9);
# - an image on another grid, a missing file: status 1 and a message.
CLI="$1"
SRC="$(cd "$(dirname "$0")/.." && pwd)"
T="$(mktemp -d)"
trap 'rm -rf "$T"' EXIT
PY=/usr/bin/python3
$PY -c "import h5py, numpy" 2>/dev/null || { echo "SKIP: no python3-h5py/numpy"; exit 77; }
fail() { echo "FAIL: $*" >&2; exit 1; }

"$CLI" simulate --preset point --snr inf -o "$T/run.h5" 2> /dev/null || fail "simulate"
Y=$($PY - "$T/run.h5" <<'PYEOF'
import h5py, sys
with h5py.File(sys.argv[1]) as f:
    print(f["system"].attrs["range_of_interest"])
PYEOF
) || fail "range of interest"
GRID=$($PY -c "r = float('$Y'); print(f'-0.3,0.3,400,{r - 0.3},{r + 0.3},400')")
"$CLI" image "$T/run.h5" --grid "$GRID" -o "$T/img.h5" 2> /dev/null || fail "image"
"$CLI" image "$T/run.h5" --grid "-0.3,0.3,200,$(echo "$GRID" | cut -d, -f4,5),200" -o "$T/small.h5" 2> /dev/null \
    || fail "image (small)"
$PY - "$T" <<'PYEOF' || fail "references"
import h5py, numpy as np, sys
t = sys.argv[1]
with h5py.File(t + "/img.h5") as f:
    d = f["image"][()]
a = d if np.iscomplexobj(d) else d["r"] + 1j * d["i"]
x = np.linspace(-0.3, 0.3, 400)
for name, img in (("same", a), ("scaled", 2.5 * np.exp(1.3j) * a), ("conj", np.conj(a))):
    with h5py.File(f"{t}/ref_{name}.h5", "w") as f:
        f["real"] = img.real
        f["imag"] = img.imag
        f["x"] = x
        f["y"] = x
PYEOF
for ref in same scaled; do
    out=$($PY "$SRC/examples/airsas_compare.py" "$T/ref_$ref.h5" "$T/img.h5") || fail "$ref: status $?"
    echo "$out" | grep -q "coherent |NCC| 1.000, magnitude NCC 1.000" || fail "$ref: $out"
done
out=$($PY "$SRC/examples/airsas_compare.py" "$T/ref_conj.h5" "$T/img.h5") || fail "conj: status $?"
echo "$out" | grep -q "magnitude NCC 1.000" || fail "conj magnitudes: $out"
c=$(echo "$out" | sed 's/.*coherent |NCC| \([0-9.]*\),.*/\1/')
echo "conjugate: coherent $c"
$PY -c "import sys; sys.exit(0 if float('$c') < 0.9 else 1)" || fail "conjugate: coherent $c"
$PY "$SRC/examples/airsas_compare.py" "$T/ref_same.h5" "$T/small.h5" > /dev/null 2> "$T/err"
[ $? -eq 1 ] && grep -q "reference" "$T/err" || fail "another grid: no clear failure"
$PY "$SRC/examples/airsas_compare.py" "$T/ref_same.h5" "$T/missing.h5" > /dev/null 2> "$T/err"
[ $? -eq 1 ] && grep -q "cannot read" "$T/err" || fail "missing image: no clear failure"
$PY "$SRC/examples/airsas_compare.py" "$T/ref_same.h5" > /dev/null 2>&1
[ $? -eq 2 ] || fail "no image: not a usage error"
echo "airsas_compare: ok"
