"""The dual-arm family's collision-model tables (column schemas, units in the names) and their
readers: the fitted environment (swept triangles and capsules, each labelled with the nearest
scene solid) and the robot's capsules with their coverage of the collision geometry."""

from __future__ import annotations

import numpy as np
import pandas as pd

from capmap.dualarm.cloud import Envelope
from capmap.dualarm.robot import DualArm, LinkCapsule

__all__ = ["envelope_table", "envelope_from", "capsule_table", "capsules_from"]


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


def capsule_table(robot: DualArm, balls: dict[str, tuple[np.ndarray, np.ndarray]]) -> pd.DataFrame:
    """One row per capsule: its segment a-b, radius and length [m], and how far the geometry it
    covers (``balls``: centres (B, 3) m and radii (B,) m per capsule) sticks out of it,
    ``max_excess_m`` (<= 0: covered)."""
    rows = []
    for c in robot.capsules:
        centres, radii = balls[c.name]
        d = c.b - c.a
        t = np.clip((centres - c.a) @ d / max(d @ d, 1e-300), 0, 1)
        excess = float((np.linalg.norm(centres - c.a - np.outer(t, d), axis=1) + radii - c.r).max())
        rows.append({"name": c.name, "part": c.part, "order": c.order, "joint": c.joint,
                     **{f"a{x}_m": c.a[i] for i, x in enumerate("xyz")}, **{f"b{x}_m": c.b[i] for i, x in enumerate("xyz")},
                     "radius_m": c.r, "length_m": float(np.linalg.norm(d)), "covered_balls": len(centres),
                     "max_excess_m": excess})
    return pd.DataFrame(rows)


def capsules_from(df: pd.DataFrame) -> tuple[LinkCapsule, ...]:
    """The capsules back from their table."""
    return tuple(LinkCapsule(r["name"], r["part"], int(r["order"]), r["joint"],
                             np.array([r["ax_m"], r["ay_m"], r["az_m"]]), np.array([r["bx_m"], r["by_m"], r["bz_m"]]),
                             float(r["radius_m"])) for _, r in df.iterrows())
