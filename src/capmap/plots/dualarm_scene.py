"""The dual-arm assembly in 3D: a MeshCat static HTML animation of the arms carrying the panel onto its pins, in the
envelope fitted to the scan (each of its solids in its own colour, named in the legend)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import meshcat.animation as ma
import numpy as np

from capmap.plots.scene3d import Overlay, aim, capsule, cylinder, facing, g, hide_helpers, material, new_scene, write_html

__all__ = ["Surroundings", "Held", "animation"]


@dataclass(frozen=True, eq=False)
class Surroundings:
    """The static environment the arms move in: swept triangles ``tri`` (T, 3, 3) m (their cores) and capsules
    ``seg`` (a (3,) m, b (3,) m, radius m) each; ``tri_label`` (T,): the solid each triangle was fitted to
    (empty: unknown; the enclosure's walls are then told from the obstacles by their extent)."""

    tri: np.ndarray
    seg: list[tuple[np.ndarray, np.ndarray, float]]
    tri_label: np.ndarray = field(default_factory=lambda: np.array([], dtype=object))


@dataclass(frozen=True, eq=False)
class Held:
    """The held panel and where it goes: the body (index) it is fixed to and its pose there (4, 4); its size (3,) m along
    its x (thickness), y, z; its holes (h, 2) panel-local (y, z) m of radius ``hole_r`` m; its final pose (4, 4) in the
    world (None: not drawn); the pins it slides onto, the scene's solids (a (3,) m, b (3,) m, radius m)."""

    body: int
    in_body: np.ndarray
    size: np.ndarray
    holes: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    hole_r: float = 0.0
    final: np.ndarray | None = None
    pins: tuple = ()


ROBOT, STATIC, PANEL, PIN, HOLE = 0x4070B0, 0x8090A0, 0xD0A030, 0xC02020, 0x202020  # the robot, the panel, the pins
CABIN, ROD = 0xB09870, 0x505050  # the fitted envelope's enclosure and capsules
SOLIDS = (0x2E9E5A, 0x8050C0, 0xB04070, 0x20A0B0, 0x8B5A2B)  # its obstacles, one colour each (in their names' order)
EYE = np.array([0.75, -0.85, 0.35])  # the camera from the insertion's centre, m: in front, right, above: no arm in the way


def _walls(env: Surroundings) -> np.ndarray:
    """Which triangles belong to the enclosure: their solid spans at least 90 % of the whole environment's
    extent along two axes (a wall, the floor, the ceiling), the rest being the obstacles in the cabin."""
    labels = _labels(env)
    span = np.ptp(env.tri.reshape(-1, 3), axis=0) if len(env.tri) else np.ones(3)
    wall = {lab: (np.ptp(env.tri[labels == lab].reshape(-1, 3), axis=0) >= 0.9 * span).sum() >= 2
            for lab in np.unique(labels)}
    return np.array([wall[lab] for lab in labels], dtype=bool)


def _labels(env: Surroundings) -> np.ndarray:
    """The solid of each triangle (its index when the envelope has no labels)."""
    return env.tri_label if len(env.tri_label) == len(env.tri) else np.arange(len(env.tri)).astype(str)


def _panel(node, held: Held, look, holes: bool) -> None:
    """The panel's board under ``node`` (its frame) and its holes (dark discs through it); without them, its outline."""
    node["board"].set_object(g.Box(list(held.size)), look)
    t, w, h = np.asarray(held.size, float) / 2
    pieces = ([(np.array([-t - 0.001, y, z]), np.array([t + 0.001, y, z]), held.hole_r) for y, z in held.holes] if holes
              else [(np.array([0, *a]), np.array([0, *b]), 0.002) for a, b in zip([(-w, -h), (w, -h), (w, h), (-w, h)],
                                                                                  [(w, -h), (w, h), (-w, h), (-w, -h)])])
    for k, (a, b, r) in enumerate(pieces):
        geom, pose = cylinder(a, b, r)
        node[f"edge{k}"].set_object(geom, material(HOLE if holes else PANEL))
        node[f"edge{k}"].set_transform(pose)


def _envelope(env: Surroundings, centre: np.ndarray) -> list[tuple[str, int, float, np.ndarray]]:
    """The fitted envelope's parts (name, colour, opacity, which triangles): each obstacle in its own colour, the cabin
    faint with its walls facing the camera cut away."""
    labels, walls = _labels(env), _walls(env)
    parts = [(str(lab).replace("_", " "), SOLIDS[k % len(SOLIDS)], 0.25, labels == lab)
             for k, lab in enumerate(np.unique(labels[~walls]))]
    return parts + [("cabin", CABIN, 0.12, walls & ~facing(env.tri, labels, centre, EYE))]


def _draw(vis, env: Surroundings, parts: list) -> None:
    """The envelope's ``parts`` (translucent triangle cores) and its capsules."""
    for name, colour, opacity, keep in parts:
        if keep.any():
            tri = env.tri[keep].reshape(-1, 3)
            mesh = g.TriangularMeshGeometry(tri, np.arange(len(tri)).reshape(-1, 3))
            vis[f"environment/{name.replace(' ', '_')}"].set_object(mesh, material(colour, opacity))
    for k, (a, b, r) in enumerate(env.seg):
        capsule(vis[f"environment/capsule{k}"], a, b, r, material(ROD, 0.45))


def animation(capsules: list[tuple[str, int, np.ndarray, np.ndarray, float]], poses: np.ndarray, held: Held,
              env: Surroundings, fps: float, caption: Overlay, out_html: str | Path) -> None:
    """MeshCat static HTML: capsules (name, body index, a, b in the body frame, r) moved by body poses
    (F, B, 4, 4), sampled at ``fps`` from t = 0; the ``held`` panel with its holes, its final pose (translucent)
    and the pins; the environment's swept triangles (their cores, translucent, each solid in its colour: the enclosure
    faint, its walls facing the camera cut away) and capsules (static), on a pale background. The camera looks at the
    insertion (the panel's path and the pins). Over the view: the ``caption`` (title, lines, one text per frame), the
    simulated time (looped) and a legend of the colours (a click folds it)."""
    panel_at = np.einsum("fij,jk->fik", poses[:, held.body], held.in_body)[:, :3, 3]
    ends = np.vstack([panel_at, *[np.vstack([a, b]) for a, b, _ in held.pins]])
    centre = (ends.min(axis=0) + ends.max(axis=0)) / 2
    parts = _envelope(env, centre)
    keys = ((ROBOT, 1.0, "Baxter's arms (capsules)"), (STATIC, 0.18, "torso, head, pedestal"),
            (PANEL, 1.0, "panel, held by both grippers"), (PANEL, 0.25, "panel's final pose on the pins"),
            (PIN, 1.0, f"{len(held.pins)} pins"), *[(c, o, n) for n, c, o, _ in parts],
            (ROD, 0.45, "fitted rods: strut, pins, edges"))
    vis = new_scene(replace(caption, legend=keys, fps=fps), light=True)
    _draw(vis, env, parts)
    for name, body, a, b, r in capsules:
        capsule(vis[f"robot/body{body}/{name}"], a, b, r, material(ROBOT) if body else material(STATIC, 0.18))
    vis[f"robot/body{held.body}/panel"].set_transform(held.in_body)
    _panel(vis[f"robot/body{held.body}/panel"], held, material(PANEL), holes=True)
    if held.final is not None:
        _panel(vis["environment/final_pose"], held, material(PANEL, 0.25), holes=False)
        vis["environment/final_pose"].set_transform(held.final)
    for k, (a, b, r) in enumerate(held.pins):
        geom, pose = cylinder(a, b, r)
        vis[f"environment/pin{k}"].set_object(geom, material(PIN))
        vis[f"environment/pin{k}"].set_transform(pose)
    anim = ma.Animation(default_framerate=fps)
    for f, frame in enumerate(poses):
        with anim.at_frame(vis, f) as fv:
            for b, T in enumerate(frame):
                fv[f"robot/body{b}"].set_transform(T)
    for b, T in enumerate(poses[0]):
        vis[f"robot/body{b}"].set_transform(T)
    vis.set_animation(anim, play=True, repetitions=2**31 - 1)  # looped until the page is closed
    hide_helpers(vis)  # the cabin's floor is the ground
    aim(vis, ("robot", "environment"), centre, EYE, right=0.12)
    write_html(vis, out_html)
