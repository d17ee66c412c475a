#!/bin/sh
# Installs the dependencies, builds sasnav and runs the main job on the
# built-in default scenario: simulate paper-trajectory and image it.
# Results in out/. Usage: sh scripts/run-demo.sh   (as root on Debian)
set -eu
cd "$(dirname "$0")/.."
sh scripts/install-deps.sh
JOBS=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$JOBS"
mkdir -p out
./build/sasnav simulate --preset paper-trajectory -o out/run.h5
./build/sasnav image out/run.h5 -o out/image-nominal.h5 --png out/image-nominal.png
./build/sasnav image out/run.h5 --truth -o out/image-true.h5 --png out/image-true.png
./build/sasnav pair out/run.h5 --p 7 --q 8
echo "results in $(pwd)/out"
