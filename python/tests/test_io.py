"""Runs, navigation files and images: the binding against h5py and the CLI,
and write / read round trips (exact)."""

import math

import pytest

import h5py
import numpy as np

import sasnav


def _poses_h5(group):
    """[n] PING_POSE_DTYPE from /…/tx and /…/array [n][3]."""
    tx, arr = group["tx"][...], group["array"][...]
    return np.concatenate([tx, arr], axis=1).view(sasnav.PING_POSE_DTYPE).reshape(-1)


def test_read_cli_run_equals_h5py(tmp_path, run_cli):
    path = tmp_path / "pair.h5"
    run_cli("simulate", "--preset", "paper-pair", "-o", path)
    run = sasnav.read_run(path)
    with h5py.File(path, "r") as f:
        raw = f["raw"][...]
        assert raw.dtype == np.complex64
        assert run.raw.dtype == np.complex64
        assert run.raw.shape == raw.shape == (2, 16, run.n_samples)
        assert np.array_equal(run.raw, raw)
        assert np.array_equal(run.nav, _poses_h5(f["nav"]))
        assert np.array_equal(run.truth, _poses_h5(f["truth"]))
        assert np.array_equal(run.array.rx_u, f["array/rx_u"][...])
        for key in ("sound_speed", "f0", "bandwidth", "sample_rate"):
            assert getattr(run.system, key) == f["system"].attrs[key]
    # the same scenario simulated in-process gives the same samples
    assert np.array_equal(sasnav.simulate(preset="paper-pair").raw, run.raw)


def test_simulate_options_match_cli(tmp_path, run_cli):
    path = tmp_path / "p.h5"
    run_cli("simulate", "--preset", "point", "--seed", 5, "--snr", 12, "--error", "0.01,0.002,0.003",
            "--aiding", "-o", path)
    a = sasnav.read_run(path)
    b = sasnav.simulate(preset="point", seed=5, snr=12, error=(0.01, 0.002, 0.003), aiding=True)
    assert np.array_equal(a.raw, b.raw)
    assert np.array_equal(a.truth, b.truth)
    assert np.array_equal(a.aiding.velocity, b.aiding.velocity)


def _assert_runs_equal(a, b):
    assert np.array_equal(a.raw, b.raw)
    assert a.raw.dtype == b.raw.dtype == np.complex64
    assert np.array_equal(a.nav, b.nav)
    assert (a.truth is None) == (b.truth is None)
    if a.truth is not None:
        assert np.array_equal(a.truth, b.truth)
    assert a.system == b.system
    assert np.array_equal(a.array.rx_u, b.array.rx_u)
    for key in ("rx_length", "tx_length", "rx_height", "tx_height"):
        assert getattr(a.array, key) == getattr(b.array, key)
    for key in ("t0", "ping_spacing", "speed", "tx_lag", "range_of_interest"):
        assert getattr(a, key) == getattr(b, key), key
    assert (a.aiding is None) == (b.aiding is None)
    if a.aiding is not None:
        for key in ("time", "yaw_rate", "yaw_rate_sigma", "velocity", "velocity_sigma"):
            x, y = getattr(a.aiding, key), getattr(b.aiding, key)
            assert (x is None) == (y is None)
            if x is not None:
                assert np.array_equal(x, y), key
    assert (a.channel_offset is None) == (b.channel_offset is None)
    if a.channel_offset is not None:
        assert np.array_equal(a.channel_offset, b.channel_offset)


def test_run_round_trip(tmp_path, paper_pair):
    path = tmp_path / "r.h5"
    sasnav.write_run(paper_pair, path)
    _assert_runs_equal(sasnav.read_run(path), paper_pair)


def test_run_round_trip_with_aiding(tmp_path):
    run = sasnav.simulate(preset="point", aiding=True, n_pings=5)
    assert run.aiding is not None and run.aiding.velocity.shape == (5, 2)
    sasnav.write_run(run, tmp_path / "a.h5")
    _assert_runs_equal(sasnav.read_run(tmp_path / "a.h5"), run)


def test_channel_offsets_round_trip(tmp_path, run_cli, source_dir):
    """A two-transmitter run (format version 2, /channels): the CLI's file
    read by the binding equals h5py's view; offsets set in Python are written
    as version 2 and read back exactly; a run without them stays version 1."""
    path = tmp_path / "two.h5"
    run_cli("simulate", "--preset", "point", "--config", source_dir / "examples" / "two_tx_head.yaml",
            "-o", path)
    run = sasnav.read_run(path)
    with h5py.File(path, "r") as f:
        assert int(f.attrs["format_version"]) == 2
        assert np.array_equal(run.channel_offset, _poses_h5(f["channels"]))
    assert run.channel_offset["tx"]["x"].tolist() == [-0.2] * 8 + [0.2] * 8
    rng = np.random.default_rng(2)
    off = rng.uniform(-0.1, 0.1, (16, 6))
    run.channel_offset = sasnav.ping_poses(off)
    sasnav.write_run(run, tmp_path / "py2.h5")
    back = sasnav.read_run(tmp_path / "py2.h5")
    _assert_runs_equal(back, run)
    sub = back.subset([0, 1], channels=[3, 9])
    assert np.array_equal(sub.channel_offset, back.channel_offset[[3, 9]])
    run.channel_offset = None
    sasnav.write_run(run, tmp_path / "py1.h5")
    with h5py.File(tmp_path / "py1.h5", "r") as f:
        assert int(f.attrs["format_version"]) == 1 and "channels" not in f
    run.channel_offset = np.full((16, 6), np.nan)
    with pytest.raises(sasnav.Error, match="offset of channel 0 is not finite"):
        sasnav.write_run(run, tmp_path / "bad.h5")


def test_run_built_in_python(tmp_path):
    rng = np.random.default_rng(1)
    n, nrx, ns = 3, 4, 50
    raw = (rng.standard_normal((n, nrx, ns)) + 1j * rng.standard_normal((n, nrx, ns))).astype(np.complex64)
    nav = np.zeros((n, 2, 3))
    nav[:, 0, 0] = 0.2 * np.arange(n) - 0.05
    nav[:, 1, 0] = 0.2 * np.arange(n) + 0.05
    run = sasnav.Run(raw, sasnav.System.default(), sasnav.SensorArray.uniform(nrx, 0.05, 0.05, 0.05),
                     0.0116, sasnav.ping_poses(nav), ping_spacing=0.2, speed=2.0, tx_lag=0.1,
                     range_of_interest=10.0)
    path = tmp_path / "py.h5"
    sasnav.write_run(run, path)
    with h5py.File(path, "r") as f:
        assert np.array_equal(f["raw"][...], raw)
        assert np.array_equal(f["nav/array"][...], nav[:, 1, :])
        assert "truth" not in f
    back = sasnav.read_run(path)
    _assert_runs_equal(back, run)
    assert back.truth is None
    sub = back.subset([0, 2], channels=[1, 2])
    assert sub.raw.shape == (2, 2, ns)
    assert np.array_equal(sub.raw, raw[[0, 2]][:, 1:3])


def test_nav_round_trip(tmp_path, paper_pair):
    path = tmp_path / "nav.h5"
    sasnav.write_nav(paper_pair.nav, path, truth=paper_pair.truth)
    nav = sasnav.read_nav(path)
    assert np.array_equal(nav.nav, paper_pair.nav)
    assert np.array_equal(nav.truth, paper_pair.truth)
    with h5py.File(path, "r") as f:
        assert np.array_equal(f["nav/tx"][...], paper_pair.nav["tx"].view((np.float64, 3)))
    sasnav.write_nav(sasnav.NavData(paper_pair.truth), tmp_path / "t.h5")
    only = sasnav.read_nav(tmp_path / "t.h5")
    assert only.truth is None and np.array_equal(only.nav, paper_pair.truth)
    # a run file holds /nav too
    sasnav.write_run(paper_pair, tmp_path / "run.h5")
    assert np.array_equal(sasnav.read_nav(tmp_path / "run.h5").nav, paper_pair.nav)


def test_image_round_trip(tmp_path):
    grid = sasnav.Grid.make(-0.5, 0.5, 21, 9.0, 11.0, 11)
    assert np.allclose(grid.x, np.linspace(-0.5, 0.5, 21))
    assert np.allclose(grid.y, np.linspace(9.0, 11.0, 11))
    rng = np.random.default_rng(2)
    data = (rng.standard_normal(grid.shape) + 1j * rng.standard_normal(grid.shape)).astype(np.complex64)
    path = tmp_path / "img.h5"
    sasnav.write_image(sasnav.Image(data, grid), path)
    img = sasnav.read_image(path)
    assert img.data.dtype == np.complex64 and img.data.shape == (11, 21)
    assert np.array_equal(img.data, data)
    assert img.grid == grid
    assert np.array_equal(img.x, grid.x) and np.array_equal(img.y, grid.y)
    with h5py.File(path, "r") as f:
        assert np.array_equal(f["image"][...], data)
        assert np.allclose(f["x"][...], img.x, rtol=0, atol=1e-12)
        assert np.allclose(f["y"][...], img.y, rtol=0, atol=1e-12)


def test_image_written_by_h5py_as_complex128(tmp_path):
    """Readers accept complex128 (docs/format.md): converted to complex64."""
    path = tmp_path / "h.h5"
    x, y = np.linspace(0, 1, 5), np.linspace(9, 10, 3)
    data = np.arange(15).reshape(3, 5) * (1 + 0.5j)
    with h5py.File(path, "w") as f:
        f.attrs["format"] = np.bytes_("sasnav-image")
        f.attrs["format_version"] = 1
        f["image"], f["x"], f["y"] = data, x, y
    img = sasnav.read_image(path)
    assert img.data.dtype == np.complex64
    assert np.array_equal(img.data, data.astype(np.complex64))
    assert np.allclose(img.x, x) and np.allclose(img.y, y)


def test_read_cli_image(tmp_path, run_cli, point_run):
    sasnav.write_run(point_run, tmp_path / "pt.h5")
    run_cli("image", tmp_path / "pt.h5", "--grid", "-0.1,0.1,41,9.9,10.1,41", "-o", tmp_path / "i.h5")
    img = sasnav.read_image(tmp_path / "i.h5")
    with h5py.File(tmp_path / "i.h5", "r") as f:
        assert np.array_equal(img.data, f["image"][...])
    # the binding's backprojection gives the same image
    mine = sasnav.image(point_run, (-0.1, 0.1, 41, 9.9, 10.1, 41))
    assert mine.grid == img.grid
    assert np.allclose(mine.data, img.data, rtol=0, atol=1e-5 * np.abs(img.data).max())
    assert math.isclose(np.abs(mine.data).max(), np.abs(img.data).max(), rel_tol=1e-5)
    # FFBP: as the CLI's --ffbp (the same tiles: bit for bit), and within
    # -35 dB of the direct image (its interpolation error, docs/survey.md)
    run_cli("image", tmp_path / "pt.h5", "--ffbp", "--grid", "-0.1,0.1,41,9.9,10.1,41", "-o", tmp_path / "f.h5")
    fast = sasnav.image(point_run, (-0.1, 0.1, 41, 9.9, 10.1, 41), ffbp=True)
    assert np.array_equal(fast.data, sasnav.read_image(tmp_path / "f.h5").data)
    err = np.linalg.norm(fast.data - mine.data) / np.linalg.norm(mine.data)
    assert 20 * np.log10(err) < -35
    with pytest.raises(sasnav.Error):
        sasnav.image(point_run, (-0.1, 0.1, 41, 9.9, 10.1, 41), ffbp=True, ffbp_oversampling=1.0)
