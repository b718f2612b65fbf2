"""Stages of the dual-arm family, the collision model: dualarm_scan (the scene's point cloud) ->
dualarm_envelope (swept volumes fitted to it) -> dualarm_unknown (the space no camera observed), and
dualarm_capsules (the robot's capsules)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from capmap.dualarm.build import build_robot, fit_settings, scan_settings, stop_distance, unknown_settings
from capmap.dualarm.cloud_file import XYZ, read_cloud
from capmap.dualarm.scene.cloud import depth, fit_envelope, radius_span, uncovered
from capmap.dualarm.scene.robot import fit_capsules
from capmap.dualarm.scene.solids import nearest_solid, scan
from capmap.dualarm.scene.unknown import Grid, unknown_space
from capmap.dualarm.scene_file import load_scene
from capmap.dualarm.tables import capsule_table, envelope_from, envelope_table, unknown_table
from capmap.errors import CapmapError, ConfigError, DataError
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.stages.common import stage_config

__all__ = ["stage_dualarm_scan", "stage_dualarm_envelope", "stage_dualarm_unknown", "stage_dualarm_capsules", "XYZ"]


def stage_dualarm_scan(out: str, slice_json: str) -> None:
    """The scene's point cloud: a synthetic scan (seeded), or the user's file."""
    sc = stage_config(slice_json)
    log = stage_logger(__name__, "dualarm scan")
    da = sc.run.dualarm
    cloud_file, settings, seed = da.cloud_file, scan_settings(da.scan), da.scan_seed
    if cloud_file is not None:
        pts, view = read_cloud(cloud_file, len(settings.viewpoints))
        source = f"file {cloud_file}, {len(settings.viewpoints)} viewpoints"
    else:
        pts, view = scan(load_scene(da.scene), settings, np.random.default_rng(seed))
        source = f"synthetic scan from {len(settings.viewpoints)} viewpoints, noise {settings.noise_m:g} m"
    # a synthetic scan in float32, as a scanner's (0.5 um at 5 m, far below its noise; half the run's largest
    # dual-arm file); a user's cloud as given
    xyz = np.asarray(pts, dtype=np.float32 if cloud_file is None else float)
    df = pd.DataFrame({"x_m": xyz[:, 0], "y_m": xyz[:, 1], "z_m": xyz[:, 2], "viewpoint": view})
    datasets.write(df, out, datasets.provenance("dualarm_scan", sc.doc, seed=seed, source=source))
    log.info(f"{len(df)} points ({source}) -> {out}")


def stage_dualarm_envelope(cloud: str, out: str, slice_json: str) -> None:
    """Swept triangles and capsules covering the cloud; every point checked inside one."""
    sc = stage_config(slice_json)
    log = stage_logger(__name__, "dualarm envelope")
    pts = datasets.read(cloud)[XYZ].to_numpy(dtype=float)
    fit, seed = fit_settings(sc.run.dualarm.fit), sc.run.dualarm.fit_seed
    env = fit_envelope(pts, fit, np.random.default_rng(seed))
    left = uncovered(pts, env)
    if len(left):
        raise DataError(f"{cloud}: {len(left)} of {len(pts)} points lie inside no fitted volume (e.g. "
                        f"{np.round(pts[left[0]], 3).tolist()})")
    scene = load_scene(sc.run.dualarm.scene)
    tri_label = nearest_solid(scene, env.tri.mean(axis=1))
    seg_label = nearest_solid(scene, env.seg.mean(axis=1))
    df = envelope_table(env, tri_label, seg_label)
    datasets.write(df, out, datasets.provenance("dualarm_envelope", sc.doc, seed=seed, cloud_points=len(pts),
                                                 uncovered_points=0))
    log.info(f"{len(env.patch_points)} faces ({len(env.tri)} triangles, radius {radius_span(env.tri_radius)}), "
             f"{len(env.seg)} capsules (radius {radius_span(env.seg_radius)}); all {len(pts)} points covered -> {out}")


def stage_dualarm_unknown(cloud: str, environment: str, out: str, slice_json: str) -> None:
    """The unknown space of the work volume (:func:`capmap.dualarm.scene.unknown.unknown_space`): what no
    viewpoint's rays crossed and no fitted volume holds, as boxes (one row each); checked that every
    cloud point lies outside the observed-free voxels."""
    sc = stage_config(slice_json)
    log = stage_logger(__name__, "dualarm unknown")
    da = sc.run.dualarm
    df = datasets.read(cloud)
    pts, view = df[XYZ].to_numpy(dtype=float), df["viewpoint"].to_numpy()
    env, _ = envelope_from(datasets.read(environment))
    u = unknown_settings(da.unknown)
    grid = Grid.over(u.work_lower, u.work_upper, u.voxel_m)
    space = unknown_space(grid, pts, scan_settings(da.scan).viewpoints[view], stop_m=stop_distance(da),
                          covered=lambda c, r: depth(c, env) <= -r)
    table = unknown_table(space)
    datasets.write(table, out, datasets.provenance("dualarm_unknown", sc.doc, voxels=int(np.prod(grid.shape)),
                                                   free_voxels=int(space.free.sum()),
                                                   unknown_voxels=int(space.unknown.sum())))
    log.info(f"{int(space.free.sum()):,} of {int(np.prod(grid.shape)):,} voxels of {u.voxel_m:g} m observed free; "
             f"{int(space.unknown.sum()):,} unknown and not inside a fitted volume, as {len(table)} boxes -> {out}")


def stage_dualarm_capsules(out: str, slice_json: str) -> None:
    """A minimum-volume capsule per group over the robot's visual and/or collision geometry (the robot
    file's ``cover``); coverage checked, the excess of a model left out reported."""
    sc = stage_config(slice_json)
    log = stage_logger(__name__, "dualarm capsules")
    robot = build_robot(sc.run.dualarm.robot, sc.run.dualarm.scene)
    try:
        robot, covered = fit_capsules(robot)
    except CapmapError as exc:
        raise ConfigError(f"dualarm.robot = {sc.run.dualarm.robot!r}: {exc.in_terms(urdf='its URDF')}") from None
    df = capsule_table(robot, covered)
    bad = df[df.max_excess_m > 1e-9]  # the first, in the capsules' order
    if len(bad):
        raise DataError(f"capsule {bad.name.iloc[0]} leaves its geometry uncovered by {bad.max_excess_m.iloc[0]:.3g} m")
    cover = robot.description.cover
    datasets.write(df, out, datasets.provenance("dualarm_capsules", sc.doc, robot=robot.description.name,
                                                 cover=" ".join(cover), locked=robot.description.locked))
    log.info(f"{len(df)} capsules over {robot.description.name}'s {' and '.join(cover)} geometry, every part covered "
             f"(largest excess {1e3 * df.max_excess_m.max():.2g} mm) -> {out}")
    for kind in ("visual", "collision"):
        worst = df[f"{kind}_excess_m"].max()
        if kind not in cover and worst > 0:
            log.warning(f"the capsules leave the {kind} geometry uncovered by up to {1e3 * worst:.1f} mm "
                        f"({df.name[df[f'{kind}_excess_m'].idxmax()]}): cover: {list(cover)} in {sc.run.dualarm.robot}")
