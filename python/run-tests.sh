#!/bin/sh
# Tests the Python package against a build of the C library:
#   sh python/run-tests.sh BUILD_DIR SASNAV_CLI [pytest arguments...]
# Creates (once) a virtual environment BUILD_DIR/python-venv with Debian's
# python3 and its site packages (numpy, h5py, pytest), installs the package
# into it offline (pip --no-index --no-build-isolation, from a copy of
# python/ in BUILD_DIR/python-package, so that the source tree stays
# untouched), and runs python/tests with the build's shared libraries on
# LD_LIBRARY_PATH. PYTHON overrides the interpreter (default
# /usr/bin/python3). Run by ctest as the test python_package.
set -eu
if [ $# -lt 2 ]; then
    echo "usage: $0 BUILD_DIR SASNAV_CLI [pytest arguments...]" >&2
    exit 2
fi
build=$(cd "$1" && pwd)
cli=$2
shift 2
here=$(cd "$(dirname "$0")" && pwd)
source=$(dirname "$here")
python=${PYTHON:-/usr/bin/python3}
venv=$build/python-venv
pkg=$build/python-package

if [ ! -e "$build/libsasnav.so.0" ]; then
    echo "$0: $build/libsasnav.so.0 not found (build the shared libraries first)" >&2
    exit 1
fi
if [ ! -x "$venv/bin/python" ]; then
    "$python" -m venv --system-site-packages "$venv"
fi
rm -rf "$pkg"
mkdir -p "$pkg"
cp -R "$here/pyproject.toml" "$here/README.md" "$here/src" "$pkg/"
"$venv/bin/python" -m pip install --quiet --no-index --no-build-isolation --no-cache-dir \
    --disable-pip-version-check --force-reinstall --no-deps "$pkg"

# the build's libraries, not an installed copy or an explicit path
unset SASNAV_LIBRARY
LD_LIBRARY_PATH=$build${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
SASNAV_CLI=$cli
SASNAV_SOURCE=$source
OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}
PYTHONDONTWRITEBYTECODE=1
export LD_LIBRARY_PATH SASNAV_CLI SASNAV_SOURCE OMP_WAIT_POLICY PYTHONDONTWRITEBYTECODE
cd "$build"
exec "$venv/bin/python" -m pytest -p no:cacheprovider -q "$here/tests" "$@"
