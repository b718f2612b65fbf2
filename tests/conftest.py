"""Shared fixtures. Independent reference computations live in tests/reference/, the
scenario's constants in tests/scenario.py."""

from __future__ import annotations

import os

import numpy as np
import pytest
import yaml

from capmap.core.reduction import lock
from capmap.robots import load
from tests.scenario import SSRMS_YAML

os.environ.setdefault("CAPMAP_QUERY_SERVER", "0")  # each query in its own process (tests/io/test_query_service.py: warm)


def pytest_configure(config):
    """Compile the numba kernels once before the xdist workers start (each would compile them)."""
    if not hasattr(config, "workerinput"):
        from capmap.kernels import main

        main([])  # the default config's kernels (others compile in the tests that use them)


@pytest.fixture(scope="session")
def ssrms():
    return load(SSRMS_YAML)


@pytest.fixture(scope="session")
def scenario_arm(ssrms):
    return lock(ssrms, 1, np.deg2rad(100.0))


@pytest.fixture(scope="session")
def gravity_robot_yaml(tmp_path_factory):
    """The spec's arm on the ground: gravity on, base centre of mass off the origin."""
    doc = yaml.safe_load(SSRMS_YAML.read_text())
    doc["gravity_mps2"] = [0.0, 0.0, -9.81]
    doc["base_com_m"] = [0.3, -0.2, 0.15]
    path = tmp_path_factory.mktemp("robots") / "ssrms7_g.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path
