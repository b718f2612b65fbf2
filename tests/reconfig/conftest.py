"""The reference three-arm robot and its capture configuration (shared/spec/reconfigurable-robot.md)."""

from __future__ import annotations

import numpy as np
import pytest

from capmap.reconfig.law import QuinticLaw
from capmap.reconfig.loop import close_capture
from capmap.reconfig.multiarm import PlatformState
from capmap.reconfig.platform_file import load_platform
from capmap.reconfig.problem import build_problem
from tests.scenario import ROOT

RECONFIG_YAML = ROOT / "config" / "robots" / "reconfig3.yaml"
CAPTURE_DEG = {"arm1": [83.7461, -41.3056, -16.5977, 103.0840, 44.7619, 3.1810],
               "arm2": [144.82, -106.30, -48.86, 110.72, 44.00, -4.24],
               "arm3": [0, -80, 160, -80, 0, 0]}
SPEC_LAW = QuinticLaw(0.0, np.deg2rad(40.0), 0.0, 0.6, 40.0)  # the spec's reference law


def state_of(desc, q_deg: dict[str, list[float]]) -> PlatformState:
    return PlatformState({n: float(np.deg2rad(v)) for arm in desc.arms for n, v in zip(arm.revolute, q_deg[arm.name])})


@pytest.fixture(scope="session")
def platform():
    return load_platform(RECONFIG_YAML)


@pytest.fixture(scope="session")
def captured(platform):
    """The capture configuration, arm 1 closed exactly by IK."""
    state, _ = close_capture(platform, "arm1_arm2", "arm1", state_of(platform, CAPTURE_DEG))
    return state


@pytest.fixture(scope="session")
def spec_problem(platform):
    return build_problem(platform, "arm1_arm2", "arm1.P1", state_of(platform, CAPTURE_DEG), SPEC_LAW)
