"""Platform robot files (YAML with ``arms``, degrees) -> :class:`capmap.reconfig.multiarm.PlatformDescription`.

Same schema as single-arm robot files (``schemas/robot.schema.json``), with ``arms`` (each a
mount, joints of type ``revolute`` or ``cylindrical``, a tool) and ``captures`` (two links and
the transform between them). Every problem is one :class:`~capmap.errors.ConfigError` line
naming the file and the key.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from capmap.config.validation import load_yaml, validate
from capmap.errors import ConfigError
from capmap.reconfig.multiarm import Capture, PlatformArm, PlatformDescription, PlatformJoint
from capmap.robots import transform

__all__ = ["parse_platform", "load_platform"]


def _joint(arm: str, j: dict, where: str, source: str) -> PlatformJoint:
    name = f"{arm}.{j['name']}"
    lo, hi = j["range_deg"]
    if not lo < hi:
        raise ConfigError(f"{source}: {where}.range_deg = {j['range_deg']} ({name}): lower must be < upper")
    range_m = None
    if j["type"] == "cylindrical":
        if "axis" not in j:
            raise ConfigError(f"{source}: {where} ({name}): a passive cylindrical joint needs an axis")
        if "range_m" not in j:
            raise ConfigError(f"{source}: {where} ({name}): a passive cylindrical joint needs range_m (extension)")
        if not j["range_m"][0] < j["range_m"][1]:
            raise ConfigError(f"{source}: {where}.range_m = {j['range_m']} ({name}): the extension range is inverted "
                              "(lower must be < upper)")
        range_m = np.asarray(j["range_m"], dtype=float)
    elif "range_m" in j:
        raise ConfigError(f"{source}: {where}.range_m ({name}): only cylindrical joints extend")
    axis = np.asarray(j.get("axis", [0.0, 0.0, 1.0]), dtype=float)
    if not np.linalg.norm(axis) > 1e-9:
        raise ConfigError(f"{source}: {where}.axis = {j.get('axis')} ({name}) must not be zero")
    return PlatformJoint(name=name, kind=j["type"], placement=transform(j["xyz_m"], j["rpy_deg"]),
                         axis=axis / np.linalg.norm(axis), range_rad=np.deg2rad(np.asarray(j["range_deg"], float)),
                         range_m=range_m)


def parse_platform(doc: object, source: str) -> PlatformDescription:
    """Validate a platform document (parsed YAML) and convert it to SI / radians."""
    if not isinstance(doc, dict):
        raise ConfigError(f"{source}: a robot file must be a mapping of keys, got {type(doc).__name__}")
    doc = validate(doc, "robot", source)  # integral floats as ints where the schema says integer
    if "arms" not in doc or "dh" in doc or "urdf" in doc or "links" in doc:
        raise ConfigError(f"{source}: a platform robot is given by 'arms' (and 'captures'), without 'dh', 'urdf' "
                          "or 'links'")
    if "drives" in doc:
        raise ConfigError(f"{source}: drives: a platform's reconfiguration is kinematic (no drive model); drives are "
                          "for a single arm given by 'dh' or 'urdf'")
    arms, seen = [], set()
    for a, arm in enumerate(doc["arms"]):
        if arm["name"] in seen:
            raise ConfigError(f"{source}: arms[{a}].name = {arm['name']!r}: two arms have the same name")
        seen.add(arm["name"])
        names = [j["name"] for j in arm["joints"]]
        dup = sorted({n for n in names if names.count(n) > 1} | ({"ee", "mount"} & set(names)))
        if dup:
            raise ConfigError(f"{source}: arms[{a}].joints: joint name {dup[0]!r} is repeated or reserved in arm "
                              f"{arm['name']}")
        mount, tool = arm.get("mount", {}), arm.get("tool", {})
        arms.append(PlatformArm(
            name=arm["name"], mount=transform(mount.get("xyz_m", [0, 0, 0]), mount.get("rpy_deg", [0, 0, 0])),
            joints=tuple(_joint(arm["name"], j, f"arms[{a}].joints[{k}]", source) for k, j in enumerate(arm["joints"])),
            tool=transform(tool.get("xyz_m", [0, 0, 0]), tool.get("rpy_deg", [0, 0, 0]))))
    links = {link for arm in arms for link in arm.links}
    captures, seen = [], set()
    for c, cap in enumerate(doc.get("captures", [])):
        if cap["name"] in seen:
            raise ConfigError(f"{source}: captures[{c}].name = {cap['name']!r}: two captures have the same name")
        seen.add(cap["name"])
        for key in ("link_a", "link_b"):
            if cap[key] not in links:
                raise ConfigError(f"{source}: captures[{c}].{key} = {cap[key]!r} is not a link of {doc['name']} "
                                  f"(links are <arm>.<joint>, <arm>.ee, <arm>.mount)")
        if cap["link_a"].split(".")[0] == cap["link_b"].split(".")[0]:
            raise ConfigError(f"{source}: captures[{c}] holds two links of the same arm")
        captures.append(Capture(cap["name"], cap["link_a"], cap["link_b"],
                                transform(cap.get("xyz_m", [0, 0, 0]), cap.get("rpy_deg", [0, 0, 0]))))
    return PlatformDescription(name=doc["name"], source=source, arms=tuple(arms), captures=tuple(captures))


def load_platform(path: str | Path) -> PlatformDescription:
    """Read and validate a platform robot file."""
    return parse_platform(load_yaml(path), str(path))
