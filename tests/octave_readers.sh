#!/bin/sh
# The MATLAB/Octave readers (matlab/) in GNU Octave against h5py: the CLI
# writes a run (with truth and aiding), a navigation file and an image; h5py
# writes an image as other tools do (complex128 members in the order i, r,
# variable-length strings, no grid attributes). Octave reads each with
# sasnav_read_run / sasnav_read_nav / sasnav_read_image and prints every
# field it returns; /usr/bin/python3 with h5py computes what each field must
# be from the file by the mapping documented in matlab/README.md and compares:
# the same set of fields, the same sizes, the same strings and the same
# numbers.
# Tolerance: none. Every number crosses as a double printed with %.17g,
# which round-trips exactly; float32 samples widen to double exactly on both
# sides, and the image axes are computed with the same operations
# (x0 + ix * dx) in both. So any difference is a reader bug (a wrong index
# order, a swapped r / i, a lost attribute), not rounding.
# Exit status 77 (skipped) without octave, h5py or h5dump (the Octave
# readers' backend, Debian package hdf5-tools).
# Usage: sh tests/octave_readers.sh path/to/sasnav [path/to/octave]
set -u
CLI=${1:?usage: octave_readers.sh path/to/sasnav [path/to/octave]}
OCTAVE=${2:-octave-cli}
HERE=$(cd "$(dirname "$0")" && pwd)
MATLAB_DIR="$HERE/../matlab"
command -v "$OCTAVE" > /dev/null 2>&1 || { echo "octave_readers: no $OCTAVE: skipped"; exit 77; }
command -v h5dump > /dev/null 2>&1 || { echo "octave_readers: no h5dump (hdf5-tools): skipped"; exit 77; }
/usr/bin/python3 -c 'import h5py' 2> /dev/null || { echo "octave_readers: no h5py: skipped"; exit 77; }
T=$(mktemp -d "${TMPDIR:-/tmp}/sasnav-octave-XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT INT TERM

cat > "$T/tiny.yaml" <<'EOF'
preset: paper-trajectory
trajectory: {n_pings: 3, x_start: -0.2, surge_rms: 0.003, sway_rms: 0.003, yaw_rms: 0.003}
EOF
"$CLI" simulate --config "$T/tiny.yaml" --aiding -o "$T/run.h5" > "$T/cli.log" 2>&1 &&
    "$CLI" navigate "$T/run.h5" --method aiding -o "$T/nav.h5" >> "$T/cli.log" 2>&1 &&
    "$CLI" image "$T/run.h5" --grid -0.3,0.3,40,9.8,10.2,30 -o "$T/image.h5" >> "$T/cli.log" 2>&1 ||
    { cat "$T/cli.log" >&2; echo "octave_readers: FAIL: the CLI could not write the files" >&2; exit 1; }

# An image written by another tool (docs/format.md: readers accept float64
# members in either order, variable-length strings, /x and /y alone).
/usr/bin/python3 - "$T/image.h5" "$T/foreign.h5" <<'EOF' || { echo "octave_readers: FAIL: h5py write" >&2; exit 1; }
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r") as f:
    img, x, y = f["image"][...], f["x"][...], f["y"][...]
ir = np.empty(img.shape, dtype=[("i", "<f8"), ("r", "<f8")])
ir["r"], ir["i"] = img.real, img.imag
with h5py.File(sys.argv[2], "w") as f:
    f.attrs["format"] = "sasnav-image"          # variable-length string
    f.attrs["format_version"] = np.int64(1)
    f["image"] = ir
    f["x"] = x
    f["y"] = y
EOF

# Octave: every field of what the readers return, one line each:
#   S key text | Z key size... | N key values... (C order) | I key (imaginary parts)
cat > "$T/dump.m" <<'EOF'
1;
function put(fid, key, v)
  if ischar(v)
    fprintf(fid, 'S %s %s\n', key, v);
  elseif isstruct(v)
    f = fieldnames(v);
    for k = 1:numel(f)
      put(fid, [key '.' f{k}], v.(f{k}));
    end
  else
    fprintf(fid, 'Z %s%s\n', key, sprintf(' %d', size(v)));
    c = permute(v, ndims(v):-1:1);
    fprintf(fid, 'N %s%s\n', key, sprintf(' %.17g', double(real(c(:)))));
    if iscomplex(v)
      fprintf(fid, 'I %s%s\n', key, sprintf(' %.17g', double(imag(c(:)))));
    end
    fprintf(fid, 'C %s %s\n', key, class(v));
  end
end
args = argv();
addpath(args{1});
t = args{2};
fid = fopen([t '/octave.txt'], 'w');
put(fid, 'run', sasnav_read_run([t '/run.h5']));
put(fid, 'nav', sasnav_read_nav([t '/nav.h5']));
put(fid, 'runnav', sasnav_read_nav([t '/run.h5']));
[img, x, y, info] = sasnav_read_image([t '/image.h5']);
put(fid, 'image', struct('img', img, 'x', x, 'y', y, 'info', info));
[img, x, y, info] = sasnav_read_image([t '/foreign.h5']);
put(fid, 'foreign', struct('img', img, 'x', x, 'y', y, 'info', info));
try
  sasnav_read_image([t '/run.h5']);
  fprintf(fid, 'S wrong_format accepted\n');
catch err
  fprintf(fid, 'S wrong_format %s\n', err.message);
end
fclose(fid);
EOF
"$OCTAVE" --no-gui --quiet --no-init-file "$T/dump.m" "$MATLAB_DIR" "$T" > "$T/octave.log" 2>&1
rc=$?
# Octave 7.3 prints "error: ignoring const execution_exception& while
# preparing to exit" at every exit without a display; its status is right.
if [ $rc -ne 0 ] || [ ! -s "$T/octave.txt" ]; then
    cat "$T/octave.log" >&2
    echo "octave_readers: FAIL: octave exited with $rc" >&2
    exit 1
fi

/usr/bin/python3 - "$T" <<'EOF'
import sys, h5py, numpy as np
T = sys.argv[1]
got = {}
for line in open(T + "/octave.txt"):
    kind, key, *rest = line.rstrip("\n").split(" ", 2)
    text = rest[0] if rest else ""
    got[(kind, key)] = text

exp = {}
def string(key, v):
    exp[("S", key)] = v.decode() if isinstance(v, bytes) else str(v)
def array(key, v, cls=None):
    """What put() prints for a value the readers return as v: MATLAB arrays
    have at least 2 dimensions, 1-D datasets are columns, scalars 1 x 1."""
    v = np.asarray(v)
    shape = v.shape if v.ndim >= 2 else (v.size, 1)
    exp[("Z", key)] = " ".join(str(d) for d in shape)
    flat = v.reshape(-1)
    exp[("N", key)] = " ".join(repr(float(a)) for a in flat.real)
    if np.iscomplexobj(v):
        exp[("I", key)] = " ".join(repr(float(a)) for a in flat.imag)
        exp[("C", key)] = "single"
    else:
        exp[("C", key)] = cls or "double"
def attr(key, v):
    if isinstance(v, (bytes, str)):
        string(key, v)
    else:
        array(key, float(v))

def mapping(prefix, f, groups=None):
    """docs: root attributes -> prefix.name; group attributes ->
    prefix.group.name; datasets -> prefix.group.dataset; dataset attributes
    -> prefix.attributes.<path with _>.name"""
    for k, v in f.attrs.items():
        attr(prefix + "." + k, v)
    def visit(name, obj):
        if groups and name.split("/")[0] not in groups:
            return
        if isinstance(obj, h5py.Group):
            for k, v in obj.attrs.items():
                attr(prefix + "." + name.replace("/", ".") + "." + k, v)
        else:
            d = obj[...]
            if d.dtype.names:
                d = (d["r"] + 1j * d["i"]).astype(np.complex64)
            array(prefix + "." + name.replace("/", "."), d)
            for k, v in obj.attrs.items():
                attr(prefix + ".attributes." + name.replace("/", "_") + "." + k, v)
    f.visititems(visit)

with h5py.File(T + "/run.h5", "r") as f:
    mapping("run", f)
    p, l, m = f["raw"].shape
    array("run.n_pings", p); array("run.n_rx", l); array("run.n_samples", m)
for name, path in (("nav", "/nav.h5"), ("runnav", "/run.h5")):
    with h5py.File(T + path, "r") as f:
        mapping(name, f, groups=("nav", "truth", "nav_sigma"))
        for k in ("nav.tx", "nav.array"):   # nav.tx, not nav.nav.tx
            for c in "ZNC":
                exp[(c, name + "." + k[4:])] = exp.pop((c, name + "." + k))
        if "nav_sigma" in f:                # nav.sigma (dead reckoning has it)
            for c in "ZNC":
                exp[(c, name + ".sigma")] = exp.pop((c, name + ".nav_sigma"))
        array(name + ".n_pings", f["nav/tx"].shape[0])
for name, path in (("image", "/image.h5"), ("foreign", "/foreign.h5")):
    with h5py.File(T + path, "r") as f:
        mapping(name + ".info", f)
        for k in ("image", "x", "y"):
            for c in "ZNIC":
                exp.pop((c, name + ".info." + k), None)
        img = f["image"][...]
        if img.dtype.names:
            img = (img["r"] + 1j * img["i"]).astype(np.complex64)
        array(name + ".img", img)
        ny, nx = img.shape
        a = f["image"].attrs
        if "x0" in a:
            g = [float(a[k]) for k in ("x0", "dx", "y0", "dy")]
            x = np.array([g[0] + ix * g[1] for ix in range(nx)])
            y = np.array([g[2] + iy * g[3] for iy in range(ny)])
        else:
            x, y = f["x"][...], f["y"][...]
            g = [x[0], (x[-1] - x[0]) / (nx - 1), y[0], (y[-1] - y[0]) / (ny - 1)]
        array(name + ".x", x); array(name + ".y", y)
        for k, v in zip(("x0", "dx", "y0", "dy"), g):
            array(name + ".info." + k, float(v))
string("wrong_format", 'sasnav: %s/run.h5: format is "sasnav-run", expected "sasnav-image"' % T)
assert ("Z", "nav.sigma") in exp, "the navigation file has no /nav_sigma to compare"

def close(a, b):
    x = np.array(a.split(), dtype=float); y = np.array(b.split(), dtype=float)
    return x.shape == y.shape and np.array_equal(x, y, equal_nan=True)

bad = []
for k in sorted(set(exp) | set(got)):
    if k not in got:
        bad.append("Octave lacks %s %s" % k)
    elif k not in exp:
        bad.append("Octave has %s %s, which the file does not explain" % k)
    elif k[0] in "NI" and not close(exp[k], got[k]):
        bad.append("%s %s differs: expected %.200s..., got %.200s..." % (k + (exp[k], got[k])))
    elif k[0] not in "NI" and exp[k] != got[k]:
        bad.append("%s %s: expected %r, got %r" % (k + (exp[k], got[k])))
for b in bad:
    print("octave_readers: FAIL:", b, file=sys.stderr)
print("octave_readers: %d fields compared, %d differ" % (len(exp), len(bad)))
sys.exit(1 if bad else 0)
EOF
