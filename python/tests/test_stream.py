"""Streamed runs (open_run) and navigations spread over parts
(navigate_part), against runs in memory (docs/survey.md)."""

import numpy as np
import pytest

import sasnav


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    run = sasnav.simulate(preset="paper-trajectory", seed=3, snr=30, n_pings=5)
    path = tmp_path_factory.mktemp("stream") / "run.h5"
    sasnav.write_run(run, path)
    return path, run


def test_streamed_run_matches_read(run_file):
    path, run = run_file
    with sasnav.open_run(path) as st:
        assert (st.n_pings, st.n_rx, st.n_samples) == run.raw.shape
        np.testing.assert_array_equal(st.nav, run.nav)
        np.testing.assert_array_equal(st.truth, run.truth)
        for p in (3, 0, 4):
            np.testing.assert_array_equal(st.ping(p), run.raw[p])
        with pytest.raises(ValueError):
            st.ping(5)
    with pytest.raises(ValueError):
        st.ping(0)  # closed


def test_streamed_navigation_and_image_match(run_file):
    path, run = run_file
    with sasnav.open_run(path) as st:
        a = sasnav.navigate(run, method="dpca", threads=1)
        b = sasnav.navigate(st, method="dpca", threads=1)
        np.testing.assert_array_equal(a.nav, b.nav)
        grid = (-0.6, 0.6, 49, 9.6, 10.4, 33)
        np.testing.assert_array_equal(sasnav.image(run, grid).data, sasnav.image(st, grid).data)
        with pytest.raises(ValueError):
            sasnav.image(st, grid, ping=1)


def test_parts_recombine(run_file):
    path, run = run_file
    with sasnav.open_run(path) as st:
        opts = dict(method="subspace", k=2, i=1, threads=1)
        whole = sasnav.navigate(st, **opts)
        parts = [sasnav.navigate_part(st, r, 2, **opts) for r in range(2)]
        assert [len(p) for p in parts] == [2, 2]
        assert parts[0].pairs == [(0, 1), (2, 3)]
        joined = sasnav.navigate(st, done=sasnav.PairRecords.join(parts), **opts)
        np.testing.assert_array_equal(whole.nav, joined.nav)
        with pytest.raises(sasnav.Error):
            sasnav.navigate_part(st, 2, 2, **opts)
