"""Forward kinematics of a platform robot file written out by hand from the YAML (no capmap code):
each joint frame = previous frame @ Trans(xyz) Rot(rpy), then the joint's motion about its local
z (revolute: Rz(q); cylindrical: Tz(d) Rz(theta)); the tool after the last joint."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from tests.scenario import rpy_matrix


def _T(xyz, rpy_deg):
    M = np.eye(4)
    M[:3, :3] = rpy_matrix(*np.deg2rad(rpy_deg))
    M[:3, 3] = xyz
    return M


def _rz(q):
    M = np.eye(4)
    c, s = np.cos(q), np.sin(q)
    M[:2, :2] = [[c, -s], [s, c]]
    return M


def _tz(d):
    M = np.eye(4)
    M[2, 3] = d
    return M


def link_poses(path: str | Path, q_deg: dict[str, list[float]], passive: dict[str, tuple[float, float]] | None = None
               ) -> dict[str, np.ndarray]:
    """Poses of every link '<arm>.<joint>' and '<arm>.ee'; q_deg: revolute angles per arm (deg);
    passive: '<arm>.<joint>' -> (theta deg, d m), default (0, 0). Joint axes must be local z."""
    doc = yaml.safe_load(Path(path).read_text())
    passive = passive or {}
    out = {}
    for arm in doc["arms"]:
        m = arm.get("mount", {})
        M = _T(m.get("xyz_m", [0, 0, 0]), m.get("rpy_deg", [0, 0, 0]))
        values = iter(q_deg[arm["name"]])
        for j in arm["joints"]:
            assert j.get("axis", [0, 0, 1]) == [0, 0, 1]
            M = M @ _T(j["xyz_m"], j["rpy_deg"])
            if j["type"] == "revolute":
                M = M @ _rz(np.deg2rad(next(values)))
            else:
                theta, d = passive.get(f"{arm['name']}.{j['name']}", (0.0, 0.0))
                M = M @ _tz(d) @ _rz(np.deg2rad(theta))
            out[f"{arm['name']}.{j['name']}"] = M.copy()
        t = arm.get("tool", {})
        out[f"{arm['name']}.ee"] = M @ _T(t.get("xyz_m", [0, 0, 0]), t.get("rpy_deg", [0, 0, 0]))
    return out
