#!/bin/sh
# The library as a component (docs/library.md):
#  1. the C examples built in this tree against the shared libraries run and
#     give a right answer (the pair estimate within the paper's bounds; a
#     DPCA navigation of a simulated run written and read back);
#  2. (not in sanitized builds, whose libraries need the sanitizer runtime)
#     the shared libraries export only sasnav_ symbols; `cmake --install`
#     to a prefix, then an outside CMake project (find_package) and an
#     outside Makefile (pkg-config) build the examples against it and they
#     run; the pkg-config files still work after the prefix is moved
#     (relocatable).
# Usage: package_examples.sh BUILD_DIR SOURCE_DIR CLI SANITIZED(0|1)
set -u
B=$1; S=$2; CLI=$3; SAN=$4
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

# 1. in-tree examples (the pair estimate takes ~2 s here, ~100 s under the
# sanitizers, whose coverage of the estimator comes from test_estimator)
if [ "$SAN" != 1 ]; then
    out=$("$B/example_estimate_pair" 7) || fail "estimate_pair (seed 7): $out"
    echo "$out"
    echo "$out" | grep -q "^sasnav [0-9]*\.[0-9]*\.[0-9]* (headers " || fail "estimate_pair prints the version"
fi
"$CLI" simulate --preset paper-trajectory -o "$T/run.h5" >/dev/null || fail "simulate"
out=$("$B/example_navigate_run" "$T/run.h5" "$T/nav.h5" dpca) || fail "navigate_run: $out"
[ "$(echo "$out" | grep -c '^pair')" = 15 ] || fail "navigate_run prints 15 pairs"
"$CLI" image "$T/run.h5" --nav "$T/nav.h5" -o "$T/img.h5" >/dev/null 2>&1 || fail "the example's navigation is readable by the CLI"
"$B/example_navigate_run" "$T/missing.h5" "$T/x.h5" >/dev/null 2>"$T/err"; rc=$?
[ $rc = 1 ] && grep -q "missing.h5" "$T/err" || fail "missing run: exit 1 naming the file (got $rc)"
"$B/example_navigate_run" >/dev/null 2>&1; [ $? = 2 ] || fail "usage error exits 2"

if [ "$SAN" = 1 ]; then
    echo "sanitized build: install checks skipped"
    [ $fails = 0 ] && echo "all passed"; exit $fails
fi

# 2. exported symbols
for lib in "$B/libsasnav.so" "$B/libsasnav_core.so"; do
    bad=$(nm -D --defined-only "$lib" | awk 'NF == 3 {print $3}' | grep -v '^sasnav_')
    [ -z "$bad" ] || fail "$lib exports non-sasnav_ symbols: $(echo $bad | head -c 300)"
    n=$(nm -D --defined-only "$lib" | awk 'NF == 3' | wc -l)
    [ "$n" -gt 20 ] || fail "$lib exports only $n symbols"
done
readelf -d "$B/libsasnav.so" | grep -q "SONAME.*libsasnav.so.0" || fail "libsasnav soname"
readelf -d "$B/libsasnav_core.so" | grep -q "SONAME.*libsasnav_core.so.0" || fail "libsasnav_core soname"
# the core does not link the I/O libraries
if readelf -d "$B/libsasnav_core.so" | grep -E "NEEDED.*(hdf5|fyaml|sndfile|plplot)"; then
    fail "the core links an I/O library"
fi

# 3. install, then outside projects
P="$T/prefix"
cmake --install "$B" --prefix "$P" >/dev/null || fail "cmake --install"
for f in include/sasnav/sasnav.h include/sasnav/version.h bin/sasnav; do
    [ -e "$P/$f" ] || fail "installed $f"
done
LIBDIR=$(dirname "$(find "$P" -name 'libsasnav.so.0' | head -n 1)")
[ -n "$LIBDIR" ] && [ -e "$LIBDIR/libsasnav.a" ] && [ -e "$LIBDIR/libsasnav_core.a" ] || fail "installed shared and static libraries"
[ -e "$LIBDIR/cmake/sasnav/sasnavConfig.cmake" ] && [ -e "$LIBDIR/cmake/sasnav/sasnavConfigVersion.cmake" ] || fail "installed CMake package"
if cmake -S "$S/examples/external" -B "$T/ext" -DCMAKE_PREFIX_PATH="$P" -DCMAKE_BUILD_TYPE=Release >"$T/ext.log" 2>&1 &&
   cmake --build "$T/ext" >>"$T/ext.log" 2>&1; then
    LD_LIBRARY_PATH="$LIBDIR" "$T/ext/estimate_pair" 7 >"$T/o1" || fail "find_package build: estimate_pair runs"
    LD_LIBRARY_PATH="$LIBDIR" "$T/ext/navigate_run" "$T/run.h5" "$T/nav2.h5" dpca >"$T/o2" || fail "find_package build: navigate_run runs"
else
    cat "$T/ext.log"; fail "outside CMake project (find_package(sasnav))"
fi
# relocatable pkg-config files: move the prefix first
mv "$P" "$T/moved"; P="$T/moved"; LIBDIR=$(dirname "$(find "$P" -name 'libsasnav.so.0' | head -n 1)")
inc=$(PKG_CONFIG_PATH="$LIBDIR/pkgconfig" pkg-config --cflags-only-I sasnav | tr ' ' '\n' | sed -n 's/^-I//p' | head -n 1)
[ -f "$inc/sasnav/sasnav.h" ] && case "$inc" in "$P"/*) true ;; *) false ;; esac ||
    fail "sasnav.pc is relocatable (first include dir: $inc)"
PKG_CONFIG_PATH="$LIBDIR/pkgconfig" pkg-config --libs --static sasnav | grep -q -- "-lhdf5" ||
    fail "sasnav.pc names its private dependencies"
if make -s -C "$S/examples/external" -f Makefile OUT="$T" PKG_CONFIG_PATH="$LIBDIR/pkgconfig" >"$T/mk.log" 2>&1; then
    LD_LIBRARY_PATH="$LIBDIR" "$T/estimate_pair_pc" 7 >/dev/null || fail "pkg-config build: estimate_pair runs"
    LD_LIBRARY_PATH="$LIBDIR" "$T/navigate_run_pc" "$T/run.h5" "$T/nav4.h5" dpca >/dev/null || fail "pkg-config build: navigate_run runs"
else
    cat "$T/mk.log"; fail "outside Makefile (pkg-config --cflags --libs sasnav)"
fi
[ $fails = 0 ] && echo "all passed"
exit $fails
