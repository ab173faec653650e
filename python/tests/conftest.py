"""Shared fixtures: the device CSTREAMS_DEVICE selects, the benchmark data, and the
command-line program for the C++ side of each comparison."""
import os
import pathlib

import pytest

import cstreams

DATA = pathlib.Path(os.environ.get("CSTREAMS_BENCHMARK_DIR", pathlib.Path(__file__).parents[2] / "scenes" / "benchmarks"))


@pytest.fixture(scope="session")
def context():
    return cstreams.Context()


@pytest.fixture(scope="session")
def data():
    return DATA


@pytest.fixture(scope="session")
def funnel():
    """The cloth-funnel step: (V0, V1, F) and the frames' paths."""
    frames = DATA / "scalable-ccd-sample" / "cloth-funnel" / "frames"
    V0, F = cstreams.read_mesh(str(frames / "227.ply"))
    V1, _ = cstreams.read_mesh(str(frames / "228.ply"))
    return V0, V1, F, [str(frames / "227.ply"), str(frames / "228.ply")]


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("CSTREAMS_CLI")
    if not path:
        pytest.skip("CSTREAMS_CLI names the cstreams program (ctest sets it)")
    return path
