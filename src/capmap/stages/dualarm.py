"""Stages of the dual-arm family, the collision model: dualarm_scan (the scene's point cloud) ->
dualarm_envelope (swept volumes fitted to it) and dualarm_capsules (the robot's capsules)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from capmap.config.dualarm import load_dual_arm_file
from capmap.config.scene_file import load_scene
from capmap.dualarm.cloud import Envelope, fit_envelope, uncovered
from capmap.dualarm.robot import DualArm, LinkCapsule, build_dual_arm, fit_capsules
from capmap.dualarm.scene import nearest_solid, scan
from capmap.errors import CapmapError, ConfigError, DataError
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.stages.common import stage_config

__all__ = ["stage_dualarm_scan", "stage_dualarm_envelope", "stage_dualarm_capsules", "envelope_from", "robot_from",
           "XYZ"]

XYZ = ["x_m", "y_m", "z_m"]


def _read_cloud(path: str) -> np.ndarray:
    """A user's cloud file: CSV or Parquet with columns x_m, y_m, z_m (base frame)."""
    try:
        df = pd.read_parquet(path) if str(path).endswith(".parquet") else pd.read_csv(path)
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        raise ConfigError(f"dualarm.cloud.file = {path!r}: cannot be read ({str(exc).splitlines()[0]})") from None
    missing = [c for c in XYZ if c not in df.columns]
    if missing:
        raise ConfigError(f"dualarm.cloud.file = {path!r}: no column {missing[0]} (need x_m, y_m, z_m)")
    try:
        pts = df[XYZ].to_numpy(dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"dualarm.cloud.file = {path!r}: columns x_m, y_m, z_m must hold numbers only") from None
    if len(pts) == 0:
        raise ConfigError(f"dualarm.cloud.file = {path!r}: no points")
    if not np.isfinite(pts).all():
        raise ConfigError(f"dualarm.cloud.file = {path!r}: {int((~np.isfinite(pts)).any(axis=1).sum())} points are "
                          "not finite")
    return pts


def stage_dualarm_scan(out: str, slice_json: str) -> None:
    """The scene's point cloud: a synthetic scan (seeded), or the user's file."""
    sc = stage_config(slice_json)
    log = stage_logger(__name__, "dualarm scan")
    da = sc.run.dualarm
    cloud_file, settings, seed = da.cloud_file, da.scan, da.scan_seed
    if cloud_file is not None:
        pts = _read_cloud(cloud_file)
        view = np.full(len(pts), -1)
        source = f"file {cloud_file}"
    else:
        pts, view = scan(load_scene(da.scene), settings, np.random.default_rng(seed))
        source = f"synthetic scan from {len(settings.viewpoints)} viewpoints, noise {settings.noise_m:g} m"
    df = pd.DataFrame({"x_m": pts[:, 0], "y_m": pts[:, 1], "z_m": pts[:, 2], "viewpoint": view})
    datasets.write(df, out, datasets.provenance("dualarm_scan", sc.doc, seed=seed, source=source))
    log.info(f"{len(df)} points ({source}) -> {out}")


def stage_dualarm_envelope(cloud: str, out: str, slice_json: str) -> None:
    """Swept triangles and capsules covering the cloud; every point checked inside one."""
    sc = stage_config(slice_json)
    log = stage_logger(__name__, "dualarm envelope")
    pts = datasets.read(cloud)[XYZ].to_numpy()
    fit, seed = sc.run.dualarm.fit, sc.run.dualarm.fit_seed
    env = fit_envelope(pts, fit, np.random.default_rng(seed))
    left = uncovered(pts, env)
    if len(left):
        raise DataError(f"{cloud}: {len(left)} of {len(pts)} points lie inside no fitted volume (e.g. "
                        f"{np.round(pts[left[0]], 3).tolist()})")
    scene = load_scene(sc.run.dualarm.scene)
    tri_label = nearest_solid(scene, env.tri.mean(axis=1))
    seg_label = nearest_solid(scene, env.seg.mean(axis=1))
    rows = []
    for k, v in enumerate(env.tri):
        rows.append({"kind": "triangle", "label": tri_label[k] or f"face {env.tri_patch[k]}", "group": int(env.tri_patch[k]),
                     **_vertices(v), "radius_m": env.tri_radius[k], "n_points": int(env.patch_points[env.tri_patch[k]])})
    for k, s in enumerate(env.seg):
        rows.append({"kind": "segment", "label": seg_label[k] or f"capsule {k}", "group": k,
                     **_vertices(np.vstack([s, np.full((1, 3), np.nan)])), "radius_m": env.seg_radius[k],
                     "n_points": int(env.seg_points[k])})
    df = pd.DataFrame(rows)
    datasets.write(df, out, datasets.provenance("dualarm_envelope", sc.doc, seed=seed, cloud_points=len(pts),
                                                 uncovered_points=0))
    log.info(f"{len(env.patch_points)} faces ({len(env.tri)} triangles, radius {_span(env.tri_radius)}), "
             f"{len(env.seg)} capsules (radius {_span(env.seg_radius)}); all {len(pts)} points covered -> {out}")


def _vertices(v: np.ndarray) -> dict:
    return {f"{c}{k}_m": v[k, i] for k in range(3) for i, c in enumerate("xyz")}


def _span(r: np.ndarray) -> str:
    return f"{1e3 * r.min():.0f}-{1e3 * r.max():.0f} mm" if len(r) else "-"


def envelope_from(df: pd.DataFrame) -> tuple[Envelope, tuple[np.ndarray, np.ndarray]]:
    """The envelope (and its labels) back from its dataset."""
    cols = [[f"{c}{k}_m" for c in "xyz"] for k in range(3)]
    tri = df[df.kind == "triangle"]
    seg = df[df.kind == "segment"]
    tri_v = np.stack([tri[c].to_numpy() for c in cols], axis=1)
    seg_v = np.stack([seg[c].to_numpy() for c in cols[:2]], axis=1)
    groups = tri.group.to_numpy()
    env = Envelope(tri_v, tri.radius_m.to_numpy(), groups, seg_v, seg.radius_m.to_numpy(),
                   np.array([tri.n_points[groups == g].iloc[0] for g in np.unique(groups)], int),
                   seg.n_points.to_numpy())
    return env, (tri.label.to_numpy(dtype=object), seg.label.to_numpy(dtype=object))


def stage_dualarm_capsules(out: str, slice_json: str) -> None:
    """A minimum-volume capsule per group of the robot's collision geometry; coverage checked."""
    sc = stage_config(slice_json)
    log = stage_logger(__name__, "dualarm capsules")
    robot = _build(sc.run.dualarm.robot)
    robot, balls = fit_capsules(robot)
    rows = []
    for c in robot.capsules:
        centres, radii = balls[c.name]
        d = c.b - c.a
        t = np.clip((centres - c.a) @ d / max(d @ d, 1e-300), 0, 1)
        excess = float((np.linalg.norm(centres - c.a - np.outer(t, d), axis=1) + radii - c.r).max())
        if excess > 1e-9:
            raise DataError(f"capsule {c.name} leaves its geometry uncovered by {excess:.3g} m")
        rows.append({"name": c.name, "part": c.part, "order": c.order, "joint": c.joint,
                     **{f"a{x}_m": c.a[i] for i, x in enumerate("xyz")}, **{f"b{x}_m": c.b[i] for i, x in enumerate("xyz")},
                     "radius_m": c.r, "length_m": float(np.linalg.norm(d)), "covered_balls": len(centres),
                     "max_excess_m": excess})
    datasets.write(pd.DataFrame(rows), out, datasets.provenance("dualarm_capsules", sc.doc, robot=robot.description.name))
    log.info(f"{len(rows)} capsules over {robot.description.name}'s collision geometry, every ball covered -> {out}")


def _build(robot_file: str) -> DualArm:
    try:
        return build_dual_arm(load_dual_arm_file(robot_file))
    except ConfigError:
        raise
    except CapmapError as exc:
        raise ConfigError(f"dualarm.robot = {robot_file!r}: {exc.in_terms(urdf='its URDF')}") from None


def robot_from(robot_file: str, capsules: pd.DataFrame) -> DualArm:
    """The robot with its capsules read back from their dataset."""
    robot = _build(robot_file)
    caps = tuple(LinkCapsule(r["name"], r["part"], int(r["order"]), r["joint"],
                             np.array([r["ax_m"], r["ay_m"], r["az_m"]]), np.array([r["bx_m"], r["by_m"], r["bz_m"]]),
                             float(r["radius_m"])) for _, r in capsules.iterrows())
    return DualArm(robot.description, robot.model, robot.geometry, robot.gripper_frames, robot.q_lower, robot.q_upper,
                   robot.v_max, caps)
