#!/bin/sh
# Installs the Debian packages sasnav needs to build, test and plot.
# Run as root (or with sudo) on Debian 12 or later.
set -eu
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update
$SUDO apt-get install -y --no-install-recommends \
    build-essential cmake pkg-config \
    libfftw3-dev libhdf5-dev hdf5-tools \
    libnlopt-dev libplplot-dev plplot-driver-cairo \
    libpng-dev libfyaml-dev libjansson-dev libsndfile1-dev \
    python3 python3-numpy python3-h5py python3-pytest python3-venv python3-setuptools python3-pip \
    openmpi-bin libopenmpi-dev \
    clang libclang-rt-14-dev libomp-dev llvm octave
