#!/bin/sh
# Installs the dependencies, builds sasnav and runs the main job on the
# built-in default scenario: `sasnav demo` simulates paper-trajectory,
# navigates it with the subspace estimator and with DPCA, images it with the
# nominal, true and estimated navigations and writes out/report.md.
# Usage: sh scripts/run-demo.sh   (as root on Debian; a few minutes)
set -eu
cd "$(dirname "$0")/.."
sh scripts/install-deps.sh
JOBS=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$JOBS"
./build/sasnav demo -o out
echo "results in $(pwd)/out (start with out/report.md)"
