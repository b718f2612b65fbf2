"""The dual-arm family's collision-model tables (column schemas, units in the names) and their
readers: the fitted environment (swept triangles and capsules, each labelled with the nearest
scene solid) and the robot's capsules with their coverage of the visual and collision geometry."""

from __future__ import annotations

import numpy as np
import pandas as pd

from capmap.dualarm.scene.cloud import Envelope
from capmap.dualarm.scene.robot import Covered, DualArm, LinkCapsule
from capmap.dualarm.scene.unknown import UnknownSpace

__all__ = ["envelope_table", "envelope_from", "capsule_table", "capsules_from", "unknown_table", "unknown_boxes"]


def _vertices(v: np.ndarray) -> dict:
    return {f"{c}{k}_m": v[k, i] for k in range(3) for i, c in enumerate("xyz")}


def envelope_table(env: Envelope, tri_label: np.ndarray, seg_label: np.ndarray) -> pd.DataFrame:
    """One row per swept triangle (three vertices, radius, its face and the face's points) and per
    capsule (two vertices, the third NaN); labels: the nearest scene solid of each (None: unnamed)."""
    rows = []
    for k, v in enumerate(env.tri):
        rows.append({"kind": "triangle", "label": tri_label[k] or f"face {env.tri_patch[k]}", "group": int(env.tri_patch[k]),
                     **_vertices(v), "radius_m": env.tri_radius[k], "n_points": int(env.patch_points[env.tri_patch[k]])})
    for k, s in enumerate(env.seg):
        rows.append({"kind": "segment", "label": seg_label[k] or f"capsule {k}", "group": k,
                     **_vertices(np.vstack([s, np.full((1, 3), np.nan)])), "radius_m": env.seg_radius[k],
                     "n_points": int(env.seg_points[k])})
    return pd.DataFrame(rows)


def envelope_from(df: pd.DataFrame) -> tuple[Envelope, tuple[np.ndarray, np.ndarray]]:
    """The envelope (and its labels) back from its table."""
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


def capsule_table(robot: DualArm, covered: dict[str, Covered]) -> pd.DataFrame:
    """One row per capsule: its segment a-b, radius and length [m], what it covers, and how far that
    geometry sticks out of it: ``max_excess_m`` over the covered set (the robot file's ``cover``; <= 0:
    covered), and per model ``visual_excess_m`` and ``collision_excess_m`` (NaN: none on this capsule)."""
    rows = []
    cover = robot.description.cover
    for c in robot.capsules:
        cov = covered[c.name]
        d = c.b - c.a
        t = np.clip((cov.centres - c.a) @ d / max(d @ d, 1e-300), 0, 1)
        excess = np.linalg.norm(cov.centres - c.a - np.outer(t, d), axis=1) + cov.radii - c.r
        fit = np.isin(cov.source, cover)
        per = {kind: float(excess[cov.source == kind].max()) if (cov.source == kind).any() else np.nan
               for kind in ("visual", "collision")}
        rows.append({"name": c.name, "part": c.part, "order": c.order, "joint": c.joint,
                     **{f"a{x}_m": c.a[i] for i, x in enumerate("xyz")}, **{f"b{x}_m": c.b[i] for i, x in enumerate("xyz")},
                     "radius_m": c.r, "length_m": float(np.linalg.norm(d)), "covered_balls": int(fit.sum()),
                     "max_excess_m": float(excess[fit].max()),
                     "visual_excess_m": per["visual"], "collision_excess_m": per["collision"],
                     "covers": " ".join(cov.objects)})
    return pd.DataFrame(rows)


def capsules_from(df: pd.DataFrame) -> tuple[LinkCapsule, ...]:
    """The capsules back from their table."""
    return tuple(LinkCapsule(r["name"], r["part"], int(r["order"]), r["joint"],
                             np.array([r["ax_m"], r["ay_m"], r["az_m"]]), np.array([r["bx_m"], r["by_m"], r["bz_m"]]),
                             float(r["radius_m"])) for _, r in df.iterrows())


def unknown_table(space: UnknownSpace) -> pd.DataFrame:
    """One row per box of unknown space: its lower and upper corners [m] and its voxels."""
    b = space.boxes
    cols = {f"{s}{x}_m": b[:, k, i] for k, s in enumerate(("lo_", "hi_")) for i, x in enumerate("xyz")}
    return pd.DataFrame({**cols, "voxels": np.round(np.prod(b[:, 1] - b[:, 0], axis=1) / space.grid.voxel**3).astype(int)})


def unknown_boxes(df: pd.DataFrame) -> np.ndarray:
    """The boxes (B, 2, 3) m back from their table."""
    lo = df[["lo_x_m", "lo_y_m", "lo_z_m"]].to_numpy()
    hi = df[["hi_x_m", "hi_y_m", "hi_z_m"]].to_numpy()
    return np.stack([lo, hi], axis=1)
