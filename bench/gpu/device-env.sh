# Sourced by the device scripts (device-ab.sh, device-compare.sh,
# device-profile.sh): finds cuFFT and exports LD_LIBRARY_PATH with $libdir
# (the shared libraries the device machine lacks, set by the caller) and
# cuFFT's folder, and
# OMP_NUM_THREADS=2 (two OpenMP threads per estimator).
cufft=$(ls /usr/local/cuda/lib64/libcufft.so.12 2>/dev/null ||
        find /usr /opt -name 'libcufft.so.12' 2>/dev/null | head -n 1)
LD_LIBRARY_PATH=$libdir:$(dirname "$cufft")${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
export LD_LIBRARY_PATH OMP_NUM_THREADS=2
