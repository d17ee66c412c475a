"""Shared fixtures of the sasnav Python tests.

Environment: SASNAV_CLI names the `sasnav` tool (tests comparing with it
are skipped without it); the library is found as sasnav finds it
(LD_LIBRARY_PATH or SASNAV_LIBRARY). SASNAV_SOURCE names the source tree
(default: two levels above this folder)."""

import os
import pathlib
import subprocess

import pytest

# Idle OpenMP threads sleep instead of spinning: on a loaded machine (ctest
# -j, two cores) spinning threads make the estimator several times slower.
# Read by libgomp when the library is loaded (at the first sasnav call).
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import sasnav  # noqa: E402

SOURCE = pathlib.Path(os.environ.get("SASNAV_SOURCE") or pathlib.Path(__file__).resolve().parents[2])


@pytest.fixture(scope="session")
def source_dir():
    return SOURCE


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("SASNAV_CLI")
    if not path or not os.access(path, os.X_OK):
        pytest.skip("SASNAV_CLI does not name the sasnav tool")
    return path


@pytest.fixture(scope="session")
def run_cli(cli):
    def run(*args):
        r = subprocess.run([cli, *map(str, args)], capture_output=True, text=True)
        assert r.returncode == 0, f"sasnav {' '.join(map(str, args))}: {r.stderr}"
        return r
    return run


@pytest.fixture(scope="session")
def paper_pair():
    """The paper-pair preset (2 pings, known motion error), simulated once."""
    return sasnav.simulate(preset="paper-pair")


@pytest.fixture(scope="session")
def point_run(source_dir):
    """examples/point-target.yaml: one point target, 17 pings, noise-free."""
    return sasnav.simulate(config=source_dir / "examples" / "point-target.yaml")
