#!/usr/bin/env python3
"""Regenerates the seed corpus fuzz/corpus/<harness>/ (docs/fuzzing.md).

Usage: python3 fuzz/make_corpus.py [SASNAV_CLI] [AIRSAS_DIR]
  SASNAV_CLI  the built tool (default build/sasnav): writes small run, nav
              and config files for fuzz_run_h5_raw and fuzz_config;
  AIRSAS_DIR  a real AirSAS recording (default ../shared/data/airsas/bg_20k):
              its first flights, cut short, seed fuzz_airsas_dir.
Standard library only (and h5repack, if installed). Every file is < 100 KB;
no seed ends in .h5 (.gitignore)."""
import math, os, random, shutil, struct, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CORPUS = os.path.join(ROOT, "fuzz", "corpus")
CLI = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build", "sasnav")
AIRSAS = sys.argv[2] if len(sys.argv) > 2 else os.path.join(ROOT, "..", "shared", "data", "airsas", "bg_20k")


def out(harness, name, data):
    d = os.path.join(CORPUS, harness)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    assert len(data) < 100_000, (harness, name, len(data))
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def pack(files):
    """The directory container of fuzz_common.h: (u8 index, u16 LE length, bytes)."""
    b = b""
    for idx, data in files:
        if isinstance(data, str):
            data = data.encode()
        assert len(data) < 65536
        b += struct.pack("<BH", idx, len(data)) + data
    return b


def wav(channels, rate, fmt="float"):
    """channels: list of equal-length lists of floats in [-1, 1]."""
    n = len(channels[0])
    nch = len(channels)
    if fmt == "float":
        tag, bits = 3, 32
        frames = b"".join(struct.pack("<" + "f" * nch, *(c[i] for c in channels)) for i in range(n))
    else:
        tag, bits = 1, 16
        frames = b"".join(struct.pack("<" + "h" * nch, *(int(32767 * c[i]) for c in channels)) for i in range(n))
    block = nch * bits // 8
    fmt_chunk = struct.pack("<HHIIHH", tag, nch, rate, rate * block, block, bits)
    body = b"WAVE" + b"fmt " + struct.pack("<I", len(fmt_chunk)) + fmt_chunk
    if tag == 3:
        body += b"fact" + struct.pack("<II", 4, n)
    body += b"data" + struct.pack("<I", len(frames)) + frames
    return b"RIFF" + struct.pack("<I", len(body)) + body


# --- fuzz_tank_dir: small tank recordings (1 MHz, 90-120 kHz chirp of 0.2 ms)
def tank_seeds():
    rng = random.Random(1)
    fs, f1, f2, T = 1_000_000, 90e3, 120e3, 2e-4
    nc = int(T * fs)
    chirp = [0.5 * math.cos(2 * math.pi * (f1 * t + 0.5 * (f2 - f1) / T * t * t))
             for t in (k / fs for k in range(nc))]
    for variant, (n_rx, n_pings, n, fmt) in enumerate([(2, 2, 700, "float"), (1, 3, 500, "float"),
                                                      (3, 2, 600, "pcm16")]):
        files = [(2, wav([chirp], fs, fmt))]
        pos = "ping,x,y,yaw\n" + "".join(f"{p},{-0.025 + 0.025 * p:.6f},0.000000,0.0e+00\n" for p in range(n_pings))
        files.append((0, pos))
        files.append((1, pos.replace("0.000000,", "0.001000,")))
        files.append((3, "rx_spacing,element_length,directivity\n0.05,0.05,1\n"))
        for p in range(n_pings):
            chans = []
            for l in range(n_rx):
                x = [rng.gauss(0, 1e-3) for _ in range(n)]
                d = 200 + 7 * l + 3 * p
                for k in range(nc):
                    if d + k < n:
                        x[d + k] += 0.3 * chirp[k]
                chans.append(x)
            files.append((4 + p, wav(chans, fs, fmt)))
        out("fuzz_tank_dir", f"tank{variant}", pack(files))


# --- fuzz_airsas_dir: the real recording's metadata and its first flights, cut short
def airsas_seeds():
    if not os.path.isdir(AIRSAS):
        print("no AirSAS recording at", AIRSAS, "- fuzz_airsas_dir gets a synthetic seed only")
        coord = "Flight #,Angle,Height,Temp,Waveform\n1.000,0.000,150.000,21.718,0.000\n2.000,1.000,150.000,21.718,0.000\n"
        sysp = ("Speaker x,0\nSpeaker y,-0.8485\nSpeaker z,0.285\nMic1 x,0\nMic1 y,-0.8615\nMic1 z,0.247\n"
                "Center x,0\nCenter y,0\nCenter z,0.1775\nFs,100.0E+3\nGroup Delay,62.3\n")
        wave = "LFM_3.00E+4Hz_1.00E+4Hz_1.00E-3s_5.00E-1V_tukeywin_1.00E-1\n"
        flights = ["".join(f"{0.01 * math.sin(0.3 * k + p):.9f},{0.01 * math.cos(0.2 * k):.9f}\n" for k in range(300))
                   for p in range(2)]
    else:
        rd = lambda n: open(os.path.join(AIRSAS, n)).read()
        coord_lines = rd("Coordinates.csv").splitlines(True)
        sysp, wave = rd("SysParams.csv"), rd("WaveformParams.csv")
        flights = [rd(f"Flight-{p + 1:06d}.csv") for p in range(3)]
    for variant, (n_pings, rows) in enumerate([(2, 300), (3, 200), (1, 400)]):
        if os.path.isdir(AIRSAS):
            coord = "".join(coord_lines[:1 + n_pings])
        fl = ["".join(f.splitlines(True)[:rows]) for f in flights[:n_pings]]
        files = [(0, coord), (1, sysp), (2, wave)] + [(3 + p, fl[p]) for p in range(len(fl))]
        out("fuzz_airsas_dir", f"airsas{variant}", pack(files))


# --- fuzz_cli_args: option values as typed on the command line
def cli_seeds():
    for i, s in enumerate(["1.5", "-3", "0.1,0.2,0.3", "-0.15,0.15,121,9.85,10.15,121", "inf", "1e400",
                           "0x1p-3", "  7", "1,,2", "42", "9223372036854775807"]):
        out("fuzz_cli_args", f"arg{i}", s)


# --- fuzz_{run,nav,image}_h5: decision streams; empty = the valid file
def generator_seeds():
    for h in ("fuzz_run_h5", "fuzz_nav_h5", "fuzz_image_h5"):
        out(h, "valid", b"")
        out(h, "latest-format", b"\x01")
    out("fuzz_run_h5", "truth-aiding", b"\x00" * 50 + b"\x0f")
    out("fuzz_nav_h5", "run-format-truth", b"\x00\x00\x00\x00\x01" + b"\x00" * 10 + b"\x01")
    out("fuzz_image_h5", "no-attrs", b"\x00" * 30 + b"\x01")


# --- fuzz_config and fuzz_run_h5_raw: from the CLI
def cli_outputs():
    for name in ("paper-pair.yaml", "point-target.yaml", "paper-trajectory.yaml"):
        src = os.path.join(ROOT, "examples", name)
        if os.path.exists(src):
            shutil.copy(src, os.path.join(CORPUS, "fuzz_config", name))
    out("fuzz_config", "flow.yaml", "preset: point\ntrajectory: {n_pings: 8, pair_error: none}\n"
        "array: {rx_positions: [-0.1, 0.0, 0.1]}\nnoise: {snr_db: inf}\n")
    if not os.access(CLI, os.X_OK):
        print("no sasnav tool at", CLI, "- fuzz_run_h5_raw gets no seeds")
        return
    tmp = tempfile.mkdtemp()
    try:
        small = os.path.join(tmp, "small.yaml")
        with open(small, "w") as f:
            f.write("preset: point\narray: {n_rx: 2}\nswath: {range_min: 9.9, range_max: 10.1}\n"
                    "trajectory: {n_pings: 3, pair_error: none}\nnoise: {snr_db: inf}\n")
        shutil.copy(small, os.path.join(CORPUS, "fuzz_config", "small.yaml"))
        for extra, name in (([], "run"), (["--aiding"], "run-aiding")):
            h5 = os.path.join(tmp, name + ".h5")
            subprocess.run([CLI, "simulate", "--preset", "point", "--config", small, "--threads", "1"] + extra +
                           ["-o", h5], check=True, capture_output=True)
            out("fuzz_run_h5_raw", name, open(h5, "rb").read())
        # format version 2: two channels with transmitters of their own
        chan = os.path.join(tmp, "channels.yaml")
        with open(chan, "w") as f:
            f.write("preset: point\narray: {rx_positions: [0.0, 0.0], tx_positions: [-0.1, 0.1]}\n"
                    "swath: {range_min: 9.9, range_max: 10.1}\n"
                    "trajectory: {n_pings: 3, pair_error: none}\nnoise: {snr_db: inf}\n")
        h5 = os.path.join(tmp, "run-channels.h5")
        subprocess.run([CLI, "simulate", "--preset", "point", "--config", chan, "--threads", "1", "-o", h5],
                       check=True, capture_output=True)
        out("fuzz_run_h5_raw", "run-channels", open(h5, "rb").read())
        # format version 2: two channels of their own heights and lengths
        sizes = os.path.join(tmp, "sizes.yaml")
        with open(sizes, "w") as f:
            f.write("preset: point\narray: {rx_positions: [0.0, 0.05], rx_heights: [0.5, 1.0], "
                    "tx_lengths: [0.04, 0.05]}\nswath: {range_min: 9.9, range_max: 10.1}\n"
                    "trajectory: {n_pings: 3, pair_error: none}\nnoise: {snr_db: inf}\n")
        shutil.copy(sizes, os.path.join(CORPUS, "fuzz_config", "sizes.yaml"))
        h5 = os.path.join(tmp, "run-sizes.h5")
        subprocess.run([CLI, "simulate", "--preset", "point", "--config", sizes, "--threads", "1", "-o", h5],
                       check=True, capture_output=True)
        out("fuzz_run_h5_raw", "run-sizes", open(h5, "rb").read())
        # the same run in HDF5's oldest format without checksums or filters
        # (as h5py or MATLAB may write): what HDF5's parsers see unprotected
        legacy = os.path.join(tmp, "legacy.h5")
        if shutil.which("h5repack"):
            subprocess.run(["h5repack", "-f", "NONE", os.path.join(tmp, "run.h5"), legacy], check=True)
            out("fuzz_run_h5_raw", "run-legacy", open(legacy, "rb").read())
    finally:
        shutil.rmtree(tmp)


os.makedirs(CORPUS, exist_ok=True)
tank_seeds()
airsas_seeds()
cli_seeds()
generator_seeds()
os.makedirs(os.path.join(CORPUS, "fuzz_config"), exist_ok=True)
cli_outputs()
total = sum(os.path.getsize(os.path.join(dp, f)) for dp, _, fs in os.walk(CORPUS) for f in fs)
print(f"corpus: {total} bytes in {CORPUS}")
