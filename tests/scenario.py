"""The paper's scenario and the repository's paths (constants only)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SSRMS_YAML = ROOT / "config" / "robots" / "ssrms7.yaml"
UR5_YAML = ROOT / "config" / "robots" / "ur5.yaml"
Q_INI_DEG = np.array([100, 124, 98, 130, 146, 174, 57.0])
X_INI = np.array([0.3790, 4.8432, 1.8878])
X_DES = np.array([2.6250, 1.8750, 4.8750])
RPY_TASK_DEG = (90.0, 0.0, 90.0)


def rpy_matrix(roll, pitch, yaw):
    """R = Rz(yaw) Ry(pitch) Rx(roll), angles in rad (written out, not capmap's)."""
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


TASK_R = rpy_matrix(*np.deg2rad(RPY_TASK_DEG))
