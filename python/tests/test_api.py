"""The package itself: version, loading, errors."""

import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import sasnav


def test_version_matches_library():
    assert sasnav.__version__ == sasnav.library_version(), \
        "python/src/sasnav/_version.py differs from the C library's version"


def _loaded_library():
    sasnav.library_version()
    for line in pathlib.Path("/proc/self/maps").read_text().splitlines():
        if line.endswith(("/libsasnav.so.0", "/libsasnav.so")) or "/libsasnav.so." in line:
            return line.split()[-1]
    pytest.skip("cannot find the loaded library in /proc/self/maps")


def test_sasnav_library_variable():
    path = _loaded_library()
    code = "import sasnav; print(sasnav.library_version())"
    env = dict(os.environ, SASNAV_LIBRARY=path)
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == sasnav.library_version()
    env["SASNAV_LIBRARY"] = "/nonexistent/libsasnav.so.0"
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert r.returncode != 0 and "SASNAV_LIBRARY" in r.stderr


def test_missing_file_names_it(tmp_path):
    path = tmp_path / "no-such-run.h5"
    for reader in (sasnav.read_run, sasnav.read_nav, sasnav.read_image):
        with pytest.raises(sasnav.Error) as e:
            reader(path)
        assert str(path) in str(e.value)
        assert e.value.code == -3 and e.value.name


def test_wrong_kind_of_file(tmp_path, paper_pair):
    sasnav.write_run(paper_pair, tmp_path / "run.h5")
    with pytest.raises(sasnav.Error) as e:
        sasnav.read_image(tmp_path / "run.h5")
    assert e.value.code == -4 and "run.h5" in str(e.value)


def test_unwritable_path(tmp_path, paper_pair):
    with pytest.raises(sasnav.Error) as e:
        sasnav.write_run(paper_pair, tmp_path / "no-dir" / "run.h5")
    assert "no-dir" in str(e.value)


def test_bad_arguments(paper_pair, tmp_path):
    with pytest.raises(sasnav.Error) as e:
        sasnav.simulate(preset="no-such-preset")
    assert e.value.code == -1
    with pytest.raises(ValueError):
        sasnav.estimate_pair(paper_pair, 0, 5)
    with pytest.raises(ValueError):
        sasnav.estimate_pair(paper_pair, 1, 1)
    with pytest.raises(ValueError, match="unknown pair option"):
        sasnav.estimate_pair(paper_pair, 0, 1, no_such_option=1)
    with pytest.raises((sasnav.Error, ValueError)):
        sasnav.estimate_pair(paper_pair, 0, 1, k=0)
    with pytest.raises(ValueError, match="final_criterion is one of"):
        sasnav.estimate_pair(paper_pair, 0, 1, final_criterion="best")
    with pytest.raises(ValueError, match="search_grid is one of"):
        sasnav.estimate_pair(paper_pair, 0, 1, search_grid="finest")
    with pytest.raises(ValueError):
        sasnav.navigate(paper_pair, method="nope")
    with pytest.raises(ValueError):
        sasnav.navigate(paper_pair.subset([0]))
    with pytest.raises(sasnav.Error, match="eta outlier factor"):
        sasnav.navigate(paper_pair, eta_outlier=1.0)
    with pytest.raises(sasnav.Error, match="link_eta"):
        sasnav.navigate(paper_pair, link_eta=-0.1)
    with pytest.raises(sasnav.Error):
        sasnav.Grid.make(1.0, 0.0, 10, 9.0, 10.0, 10)
    with pytest.raises(ValueError):
        sasnav.image(paper_pair, (0, 1, 2.5, 9, 10, 3))
    with pytest.raises(ValueError):
        sasnav.write_image(sasnav.Image(np.zeros((3, 3)), sasnav.Grid.make(0, 1, 4, 0, 1, 3)),
                           tmp_path / "x.h5")
    bad = tmp_path / "bad.yaml"
    bad.write_text("preset: point\nnoise:\n  snr_dbb: 3\n")
    with pytest.raises(sasnav.Error) as e:
        sasnav.simulate(config=bad)
    assert "snr_dbb" in str(e.value)
    # a run the library refuses (non-finite navigation)
    nav = paper_pair.nav.copy()
    nav[0]["tx"]["x"] = np.nan
    broken = sasnav.Run(paper_pair.raw, paper_pair.system, paper_pair.array, paper_pair.t0, nav)
    with pytest.raises(sasnav.Error):
        sasnav.write_run(broken, tmp_path / "broken.h5")
    assert not (tmp_path / "broken.h5").exists()
