"""Simulation, pair estimates, navigation and imaging through the binding."""

import dataclasses
import json
import math

import numpy as np
import pytest

import sasnav


def test_scenario_presets_and_config(source_dir, tmp_path):
    sc = sasnav.scenario("point")
    assert sc.n_pings == 17
    assert sc.targets.shape == (1, 3)
    cfg = sasnav.scenario(config=source_dir / "examples" / "point-target.yaml")
    assert cfg.name == "point-target"
    assert np.array_equal(cfg.targets, [[0.013, 10.007, 1.0]])
    # a scenario written as YAML reads back the same
    cfg.write(tmp_path / "sc.yaml")
    again = sasnav.scenario("paper-trajectory", config=tmp_path / "sc.yaml")
    assert again.name == cfg.name and again.image_grid == cfg.image_grid
    run = sasnav.simulate(scenario=cfg)
    assert np.array_equal(run.raw, sasnav.simulate(config=source_dir / "examples" / "point-target.yaml").raw)


def test_estimate_pair_paper(paper_pair):
    """The paper pair (Caporale & Petillot Sec. IV-B): ping 1 has a motion
    error of surge -34.5 mm, sway +21.7 mm, yaw 4.10e-2 rad relative to ping
    0; the paper recovers -34.9 mm, 21.7 mm, 4.12e-2 rad.

    Tolerances: the estimator's candidates lie one phase-centre spacing
    apart (15 mm of surge, ~5e-4 rad of yaw, docs/estimator.md), so 2 mm
    of surge proves the right candidate was chosen; sway is measured to a
    fraction of the lambda/2 = 2.5 mm fringe spacing (0.5 mm allowed,
    ~0.02 mm seen); yaw is the weakly observed component (paper: 2e-4 rad
    off; 5e-4 rad allowed, ~2.3e-4 seen)."""
    est = sasnav.estimate_pair(paper_pair, 0, 1)
    assert est.truth == pytest.approx((-0.0345, 0.0217, 0.041), abs=1e-9)
    err = np.subtract(est.error, est.truth)
    assert abs(err[0]) < 2e-3 and abs(err[1]) < 5e-4 and abs(err[2]) < 5e-4, err
    assert est.verdict == "ok" and est.status == "ok"
    assert est.eta < 0.6
    # the pings' relative yaw (0.041 rad) shifts the beam by more than an
    # eighth of the grid: the automatic final stage is eta's
    assert est.final_criterion == "eta"
    # a speckle-like seabed (contrast ~2, below joint_contrast_max): the
    # automatic search grid is the coarse one
    assert est.search_grid == "coarse"
    # nor is the coincidence rule's business there (a compact-scene rule):
    # both images are speckle-like, under the verdict's gate (4)
    assert est.coincidence is False
    assert 0.5 < est.contrast < 4 and 0.5 < est.contrast_q < 4, (est.contrast, est.contrast_q)
    # so its search is equalised (the default equalise, 0.05 m: the paper
    # pair's seabed has a feature 9 dB or more over its smoothed mean); off
    # with 0
    assert est.equalised is True and est.result.equalised == 1
    # its gate's peak, reported, at or above the gate's 8; 0 without the
    # weights
    assert 8 <= est.equalise_peak < 30, est.equalise_peak
    off = sasnav.estimate_pair(paper_pair, 0, 1, equalise=0, k=2, i=1)
    assert off.equalised is False and off.equalise_peak == 0
    assert est.candidates[est.chosen].chosen
    assert len(est.candidates) >= 2
    # displacement = nominal + error
    assert np.allclose(np.add(est.nominal, est.error), est.displacement, atol=1e-12)
    assert est.nominal == pytest.approx((0.2, 0.0, 0.0), abs=1e-12)


@pytest.fixture(scope="module")
def short_trajectory():
    """Three pings of paper-trajectory (smooth random motion errors)."""
    return sasnav.simulate(preset="paper-trajectory", n_pings=3)


def test_navigate_short_run(short_trajectory, tmp_path):
    calls = []
    # range_extent (a pair option, passed through): half the default grid
    # depth, half the cost, the same accuracy here
    nav = sasnav.navigate(short_trajectory, range_extent=0.8, progress=lambda *a: calls.append(a))
    assert nav.method == "subspace" and nav.n_pings == 3
    assert nav.nav.dtype == sasnav.PING_POSE_DTYPE and nav.nav.shape == (3,)
    assert len(nav.pairs) == 2 and nav.n_failed == 0
    assert calls[0][0] == 0 and calls[-1][0] == calls[-1][1] == 2
    # same tolerances as the pair test (per pair, fused motion error - truth)
    for pr in nav.pairs:
        assert pr.verdict == "ok"
        assert abs(pr.error.surge) < 2e-3 and abs(pr.error.sway) < 5e-4 and abs(pr.error.yaw) < 5e-4
        assert np.allclose(np.subtract(pr.fused, pr.truth), pr.error, atol=1e-12)
    assert nav.has_truth and nav.cumulative.shape == (3,)
    assert abs(nav.cumulative[-1]["y"]) < 1e-3
    # two pairs: too few (6) for the run's median eta, no outlier
    assert math.isnan(nav.eta_median) and nav.n_eta_outliers == 0
    assert not any(pr.eta_outlier for pr in nav.pairs)
    # formal standard deviations: two "ok" pairs weighed with the default
    # link_sigma (1 mm, 20 microns, 5e-5 rad), the motion model far looser,
    # so the steps' errors independent with those deviations: the final
    # yaw sqrt(2) x 5e-5 rad; across the aligned track each step's surge
    # and sway errors by its heading psi_j (the track turns: psi ~ 0.01
    # rad), and the first step's yaw error turning the second step (lever:
    # its along-track length); 2 % for the motion model and the prior
    fs, c = nav.formal_sigma, nav.centroids
    assert fs.shape == (3,) and fs[0]["x"] == fs[0]["y"] == fs[0]["theta"] == 0
    assert fs[-1]["theta"] == pytest.approx(math.sqrt(2) * 5e-5, rel=0.02)
    var_y = sum((1e-3 * math.sin(c[j]["theta"])) ** 2 + (2e-5 * math.cos(c[j]["theta"])) ** 2
                for j in range(2))
    var_y += (5e-5 * (c[2]["x"] - c[1]["x"])) ** 2
    assert fs[-1]["y"] == pytest.approx(math.sqrt(var_y), rel=0.02)
    assert fs[-1]["x"] == pytest.approx(math.sqrt(2) * 1e-3, rel=0.02)
    sasnav.write_nav(nav, tmp_path / "nav.h5")
    back = sasnav.read_nav(tmp_path / "nav.h5")
    assert np.array_equal(back.nav, nav.nav) and np.array_equal(back.truth, short_trajectory.truth)
    # the formal standard deviations travel with the navigation (/nav_sigma)
    assert np.array_equal(back.formal_sigma, nav.formal_sigma)
    sasnav.write_nav(nav.nav, tmp_path / "plain.h5")
    assert sasnav.read_nav(tmp_path / "plain.h5").formal_sigma is None
    bad = nav.formal_sigma.copy()
    bad[1]["y"] = -1.0
    with pytest.raises(sasnav.Error):
        sasnav.write_nav(sasnav.NavData(nav.nav, None, bad), tmp_path / "bad.h5")
    assert not (tmp_path / "bad.h5").exists()
    placed = nav.placed((1.0, 2.0, 0.1))
    c0 = sasnav.centroids(placed)[0]
    assert (c0["x"], c0["y"], c0["theta"]) == pytest.approx((1.0, 2.0, 0.1), abs=1e-9)


def test_navigate_dpca_and_options(short_trajectory):
    nav = sasnav.navigate(short_trajectory, method="dpca", resolve=0, threads=1,
                          dpca={"upsampling": 4})
    assert nav.method == "dpca" and len(nav.pairs) == 2
    assert all(abs(pr.error.sway) < 1e-3 for pr in nav.pairs)
    assert nav.formal_sigma is None  # no smoother (resolve=0)
    # DPCA through the smoother: its surge is nominal, no formal deviations
    assert sasnav.navigate(short_trajectory, method="dpca", threads=1).formal_sigma is None


def test_image_point_target(point_run, source_dir):
    """examples/point-target.yaml: one point at (0.013, 10.007) m, 17 pings,
    noise-free, imaged on 2.5 mm pixels: the peak must be at the pixel
    nearest to the target (within half a pixel plus 0.5 mm of focusing
    bias, i.e. 1.75 mm, far below the 2.5 cm resolution)."""
    sc = sasnav.scenario(config=source_dir / "examples" / "point-target.yaml")
    tx, ty, _ = sc.targets[0]
    for nav in (None, "truth"):
        img = sasnav.image(point_run, sc.image_grid, nav=nav)
        assert img.data.shape == (121, 121) and img.data.dtype == np.complex64
        px, py = img.peak()
        assert abs(px - tx) < 1.75e-3 and abs(py - ty) < 1.75e-3, (px, py)
    # a single ping's backprojection and CGLS inverse have their own peaks
    one = sasnav.image(point_run, sc.image_grid, ping=8)
    inv = sasnav.image(point_run, sc.image_grid, ping=8, cgls=3)
    assert np.abs(one.data).max() > 0 and np.abs(inv.data).max() > 0
    assert not np.allclose(one.data, inv.data)
    # the default grid (as `sasnav image`) covers the target
    g = sasnav.default_grid(point_run)
    assert g.x[0] < tx < g.x[-1] and g.y[0] < ty < g.y[-1]


def test_two_transmitter_head(tmp_path, run_cli):
    """A run whose channels have transmitters of their own (the head of
    examples/two_tx_head.yaml, docs/model.md "Channel layouts"): the
    binding's pair estimate uses the channels' layouts, as `sasnav pair`
    does (the same estimate to the digits the JSON prints), and its one-ping
    image places the transmitters where the run says (the image with the
    offsets dropped differs by more than 10 %)."""
    rx = ", ".join(f"{0.05 * (l - 3.5):g}" for l in range(8))
    cfg = tmp_path / "two.yaml"
    cfg.write_text("preset: paper-trajectory\n"
                   "trajectory: {n_pings: 2, x_start: -0.1, surge_rms: 0.003, sway_rms: 0.003, "
                   "yaw_rms: 0.003, true_bistatic: false}\nnoise: {snr_db: inf}\n"
                   f"array:\n  rx_positions: [{rx}, {rx}]\n"
                   f"  tx_positions: [{', '.join(['-0.2'] * 8 + ['0.2'] * 8)}]\n")
    path = tmp_path / "two.h5"
    run_cli("simulate", "--config", cfg, "-o", path)
    run = sasnav.read_run(path)
    assert run.channel_offset is not None and run.n_rx == 16
    est = sasnav.estimate_pair(run, 0, 1, k=2, i=1, range_extent=0.6)
    cli = json.loads(run_cli("pair", path, "--json", "--k", 2, "--i", 1, "--range-extent", 0.6).stdout)
    for a, key in zip(est.error, ("surge", "sway", "yaw")):
        assert a == pytest.approx(cli[key], rel=1e-9, abs=1e-12), key
    err = np.subtract(est.error, est.truth)
    assert abs(err[1]) < 0.2e-3 and abs(err[0]) < 1.5e-3, err  # lambda / 25 sway, as test_channels
    with pytest.raises(ValueError, match="lags"):
        sasnav.estimate_pair(run, 0, 1, lags=(0.1, 0.1))
    grid = sasnav.Grid.make(-0.3, 0.3, 31, 9.7, 10.3, 31)
    a = sasnav.image(run, grid=grid, ping=0).data
    plain = sasnav.Run(run.raw, run.system, run.array, run.t0, run.nav, run.truth, run.ping_spacing,
                       run.speed, run.tx_lag, run.range_of_interest)
    b = sasnav.image(plain, grid=grid, ping=0).data
    assert np.linalg.norm(a - b) > 0.1 * np.linalg.norm(a)
    # navigation without a gyro: the transmitters' turn from the pairs'
    # own yaw (the default), as `sasnav navigate` does; tx_yaw=0: none
    small = dict(k=2, i=1, range_extent=0.6, threads=1)
    nav = sasnav.navigate(run, **small)
    assert nav.tx_yaw == "pairs"
    out = tmp_path / "nav.h5"
    cli = json.loads(run_cli("navigate", path, "--json", "--k", 2, "--i", 1, "--range-extent", 0.6,
                             "--threads", 1, "-o", out).stdout)
    assert cli["tx_yaw"] == "pairs"
    assert nav.pairs[0].estimate.error.sway == pytest.approx(cli["pairs"][0]["sway"], rel=1e-9, abs=1e-12)
    assert sasnav.navigate(run, tx_yaw="none", **small).tx_yaw == "none"
    # both pings at one place: no distance to take a turn per metre over;
    # navigated without one, not refused
    same = dataclasses.replace(run, nav=np.repeat(run.nav[:1], 2))
    assert sasnav.navigate(same, align=False, **small).tx_yaw == "none"


def test_channel_sizes(tmp_path, run_cli):
    """Channels of their own heights and lengths (docs/model.md, "Channels
    of their own sizes"): the config's lists reach the run file (format
    version 2, /array/sizes) and the binding reads and writes them bit for
    bit; the binding's image uses them (the same data imaged with one size
    for all channels differs by more than 10 %); bad sizes are refused."""
    cfg = tmp_path / "sizes.yaml"
    cfg.write_text("preset: point\ntrajectory: {n_pings: 3}\n"
                   "array:\n  n_rx: 4\n  rx_spacing: 0.05\n  tx_height: 1.0\n"
                   "  rx_heights: [0.4, 1.6, 0.4, 1.6]\n  rx_lengths: [0.05, 0.04, 0.05, 0.03]\n")
    path = tmp_path / "sizes.h5"
    run_cli("simulate", "--config", cfg, "-o", path)
    run = sasnav.read_run(path)
    want = np.array([[0.05, 0.05, 0.4, 1.0], [0.04, 0.05, 1.6, 1.0],
                     [0.05, 0.05, 0.4, 1.0], [0.03, 0.05, 1.6, 1.0]])
    assert run.array.sizes is not None and np.array_equal(run.array.sizes, want)
    assert run.array.rx_height == pytest.approx(1.0) and run.array.rx_length == 0.05
    assert run.array.min_rx_length() == 0.03
    out = tmp_path / "back.h5"
    sasnav.write_run(run, out)
    back = sasnav.read_run(out)
    assert np.array_equal(back.array.sizes, run.array.sizes) and np.array_equal(back.raw, run.raw)
    grid = sasnav.Grid.make(-0.1, 0.1, 21, 9.9, 10.1, 21)
    a = sasnav.image(run, grid=grid).data
    one = sasnav.SensorArray(run.array.rx_u, run.array.rx_length, run.array.tx_length,
                             run.array.rx_height, run.array.tx_height)
    plain = sasnav.Run(run.raw, run.system, one, run.t0, run.nav, run.truth, run.ping_spacing,
                       run.speed, run.tx_lag, run.range_of_interest)
    b = sasnav.image(plain, grid=grid).data
    assert np.linalg.norm(a - b) > 0.1 * np.linalg.norm(a)
    with pytest.raises(ValueError, match="sizes"):
        sasnav.SensorArray(run.array.rx_u, sizes=np.zeros((3, 4)))._to_c()
    bad = want.copy()
    bad[2, 0] = -0.01
    with pytest.raises(sasnav.Error, match="channel 2"):
        sasnav.SensorArray(run.array.rx_u, sizes=bad)._to_c()


def test_navigate_virtual(tmp_path, run_cli):
    """Virtual arrays of a single-channel sonar (the simulated AirSAS,
    `circular` preset, 16 pings, noise-free, its smooth 3 mm motion errors
    the truth): the binding gives the estimates of `sasnav navigate
    --virtual-array 4` (the same defaults: grid, box, fixed yaw; equal to
    the JSON's ten digits), each step's sway within 1 mm of the truth (as
    tests/cli_navigate.sh; measured 0.1-0.5 mm); with along_track="input"
    each group moves along its normal only and keeps its yaw; bad options
    are refused."""
    run = sasnav.simulate(preset="circular", n_pings=16, snr=math.inf)
    vn = sasnav.navigate_virtual(run, 4, iterations=1)
    assert vn.k == 4 and vn.stride == 4 and vn.interleave == 1 and not vn.closed
    assert vn.along_track == "echoes" and vn.nav.shape == (16,) and vn.centroid.shape == (4,)
    assert len(vn.pairs) == 3 and vn.misclosure is None and vn.length_scale == 1.0
    for pr in vn.pairs:
        assert abs(pr.estimate.displacement.sway - pr.truth.sway) < 1e-3, pr
        assert pr.used == (pr.estimate.verdict == "ok")
    sasnav.write_run(run, tmp_path / "circ.h5")
    out = run_cli("navigate", tmp_path / "circ.h5", "--virtual-array", 4, "--iterations", 1, "--json",
                  "-o", tmp_path / "v.h5")
    cli_pairs = json.loads(out.stdout)["pairs"]
    for pr, cp in zip(vn.pairs, cli_pairs):
        assert (pr.p, pr.q) == (cp["p"], cp["q"]) and pr.estimate.verdict == cp["status"]
        for axis in ("surge", "sway", "yaw"):
            assert getattr(pr.estimate.displacement, axis) == pytest.approx(cp["displacement"][axis],
                                                                         rel=1e-9, abs=1e-13)
    va = sasnav.navigate_virtual(run, 4, iterations=1, along_track="input")
    assert va.along_track == "input" and va.align_heading
    th = va.centroid_in["theta"]
    along = (np.cos(th) * (va.centroid["x"] - va.centroid_in["x"])
             + np.sin(th) * (va.centroid["y"] - va.centroid_in["y"]))
    across = (-np.sin(th) * (va.centroid["x"] - va.centroid_in["x"])
              + np.cos(th) * (va.centroid["y"] - va.centroid_in["y"]))
    assert np.abs(along).max() < 1e-12 and np.array_equal(va.centroid["theta"], th)
    assert across[0] == 0 and np.abs(across[1:]).max() > 1e-5
    # the chained centroids give every used step's sway (virtual.h)
    c = va.centroid
    for g, pr in enumerate(va.pairs):
        a, b = c[g], c[g + 1]
        sway = -np.sin(a["theta"]) * (b["x"] - a["x"]) + np.cos(a["theta"]) * (b["y"] - a["y"])
        assert sway == pytest.approx(pr.step.sway, abs=1e-12), (g, sway, pr.step)
    with pytest.raises(ValueError, match="echoes"):
        sasnav.navigate_virtual(run, 4, along_track="dvl")
    with pytest.raises(ValueError, match="estimate_yaw"):
        sasnav.navigate_virtual(run, 4, along_track="input", estimate_yaw=True)
    with pytest.raises(sasnav.Error, match="fewer than two groups"):
        sasnav.navigate_virtual(run, 9)
    with pytest.raises(ValueError, match="unknown pair option"):
        sasnav.navigate_virtual(run, 4, bogus=1)
    with pytest.raises(ValueError, match="fix_yaw"):
        sasnav.navigate_virtual(run, 4, along_track="input", fix_yaw=0)
    with pytest.raises(ValueError, match="2 or more"):
        sasnav.navigate_virtual(run, 1)


def test_airsas_drift_helpers(source_dir):
    """examples/airsas_drift.py's error measure (the example itself needs
    the AirSAS recording and 8 minutes): on a 0.85 m circle of 360 poses,
    a rigid move of the whole path costs nothing; a change of radius by
    c (every pose moved c across its track) is no rigid move and comes out
    as c across, 0 along; compose() moves each pose in its own frame."""
    import importlib.util
    spec = importlib.util.spec_from_file_location("airsas_drift", source_dir / "examples" / "airsas_drift.py")
    ex = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ex)
    phi = np.arange(360) * np.pi / 180
    truth = np.zeros(360, sasnav.PING_POSE_DTYPE)
    for part in ("tx", "array"):
        truth[part]["x"], truth[part]["y"] = 0.85 * np.cos(phi), 0.85 * np.sin(phi)
        truth[part]["theta"] = phi + np.pi / 2
    moved = truth.copy()
    c, s = np.cos(0.3), np.sin(0.3)
    for part in ("tx", "array"):
        moved[part]["x"] = c * truth[part]["x"] - s * truth[part]["y"] + 0.2
        moved[part]["y"] = s * truth[part]["x"] + c * truth[part]["y"] - 0.1
        moved[part]["theta"] = truth[part]["theta"] + 0.3
    assert ex.rigid_errors(moved, truth) == pytest.approx((0, 0), abs=1e-9)
    radius = truth.copy()
    d = np.zeros((360, 2))
    d[:, 1] = 0.002  # 2 mm to the left of the track: towards the centre
    radius["array"] = ex.compose(truth["array"], d)
    assert np.allclose(np.hypot(radius["array"]["x"], radius["array"]["y"]), 0.848, atol=1e-12)
    assert ex.rigid_errors(radius, truth) == pytest.approx((0, 2), abs=1e-6)
