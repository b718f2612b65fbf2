"""Scene files (YAML) -> :class:`capmap.dualarm.scene.solids.Scene`; one-line errors naming the file and key."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from capmap.config.validation import load_yaml, validate
from capmap.dualarm.scene.solids import Box, Cylinder, PanelSpec, Scene, pose
from capmap.errors import ConfigError

__all__ = ["parse_scene", "load_scene"]


def _range(source: str, key: str, values) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    if not v[0] < v[1]:
        raise ConfigError(f"{source}: {key} = {list(values)}: lower must be < upper")
    return v


def parse_scene(doc: object, source: str) -> Scene:
    """Validate a scene document (parsed YAML) and convert it to SI / radians."""
    if not isinstance(doc, dict):
        raise ConfigError(f"{source}: a scene file must be a mapping of keys, got {type(doc).__name__}")
    doc = validate(doc, "scene", source)  # integral floats as ints where the schema says integer
    boxes = []
    for k, b in enumerate(doc["boxes"]):
        lim = np.array([_range(source, f"boxes[{k}].{ax}", b[ax]) for ax in ("x_m", "y_m", "z_m")])
        boxes.append(Box(b["name"], lim[:, 0], lim[:, 1]))
    cylinders = []
    for k, c in enumerate(doc["cylinders"]):
        p0, p1 = np.asarray(c["p0_m"], float), np.asarray(c["p1_m"], float)
        if not np.linalg.norm(p1 - p0) > 0:
            raise ConfigError(f"{source}: cylinders[{k}] ({c['name']}): p0_m and p1_m must differ")
        cylinders.append(Cylinder(c["name"], p0, p1, float(c["radius_m"])))
    names = [s.name for s in (*boxes, *cylinders)]
    if len(set(names)) != len(names):
        raise ConfigError(f"{source}: solid names must be unique (repeated: "
                          f"{sorted({n for n in names if names.count(n) > 1})[0]!r})")
    pn = doc["panel"]
    size = np.asarray(pn["size_m"], float)
    if not (size > 0).all():
        raise ConfigError(f"{source}: panel.size_m = {pn['size_m']} must be > 0")
    mass = float(pn["mass_kg"])
    x, y, z = size
    box = mass / 12 * np.array([y * y + z * z, x * x + z * z, x * x + y * y])  # a uniform box
    inertia = np.asarray(pn.get("inertia_kgm2", box), float)
    a, b, c = inertia
    if not (a + b >= c and a + c >= b and b + c >= a):
        raise ConfigError(f"{source}: panel.inertia_kgm2 = {list(inertia)} violates the triangle inequality of "
                          "principal moments (no rigid body has them)")
    panel = PanelSpec(size=size, holes=np.asarray(pn["holes_m"], float).reshape(-1, 2),
                      hole_radius=float(pn["hole_radius_m"]),
                      grasp=np.array([pn["grasp_m"]["left"], pn["grasp_m"]["right"]], dtype=float),
                      mass=mass, inertia=inertia)
    poses = {k: pose(v["xyz_m"], v["rpy_deg"]) for k, v in pn["poses"].items()}
    axis = doc["insertion_axis"]
    direction = np.asarray(axis["direction"], float)
    if not np.linalg.norm(direction) > 0:
        raise ConfigError(f"{source}: insertion_axis.direction must not be zero")
    zone = np.array([_range(source, f"pin_zone_m.{ax}", doc["pin_zone_m"][ax]) for ax in ("x_m", "y_m", "z_m")]).T
    q = doc["start_configuration_rad"]
    for side in ("left", "right"):
        if len(q[side]) != 7:
            raise ConfigError(f"{source}: start_configuration_rad.{side} has {len(q[side])} values; an arm has 7 joints")
    return Scene(name=doc["name"], boxes=tuple(boxes), cylinders=tuple(cylinders), panel=panel, start=poses["start"],
                 pre_insertion=poses["pre_insertion"], final=poses["final"],
                 axis_point=np.asarray(axis["point_m"], float), axis_direction=direction / np.linalg.norm(direction),
                 pin_zone=zone, q_start=np.array(q["left"] + q["right"], dtype=float))


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene file."""
    return parse_scene(load_yaml(path), str(path))
