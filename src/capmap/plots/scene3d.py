"""Offline 3D scenes with MeshCat: a visualizer whose window records the scene in-process (no
server, no sockets), and ``vis.static_html()`` packs it, with MeshCat's viewer script, into
one self-contained HTML file that opens without a network.

The recorder keeps the scene tree exactly as MeshCat's own server does (``set_object``,
``set_transform``, ``set_property``, ``set_animation``, ``delete``) and renders it with the
server's static-HTML template.
"""

from __future__ import annotations

import html
import json
import os
from dataclasses import dataclass
from pathlib import Path

import meshcat
import meshcat.geometry as g
import numpy as np
import umsgpack
from meshcat.servers.tree import SceneTree, find_node, walk
from meshcat.servers.zmqserver import VIEWER_ROOT, create_command

__all__ = ["RecordingWindow", "Overlay", "new_scene", "write_html", "segment_pose", "cylinder", "capsule", "material", "aim",
           "hide_helpers", "facing", "g"]

_TEMPLATE = """<!DOCTYPE html>
<html>
    <head> <meta charset=utf-8> <title>{title}</title> </head>
    <body>
        <div id="meshcat-pane">
        </div>
        <script>
            {mainminjs}
        </script>
        <script>
            var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
            {commands}
        </script>
         <style>
            body {{margin: 0; }}
            #meshcat-pane {{
                width: 100vw;
                height: 100vh;
                overflow: hidden;
            }}
        </style>
        <script id="embedded-json"></script>
{overlay}
    </body>
</html>
"""


@dataclass(frozen=True)
class Overlay:
    """Words over an animation's 3D view (top left, clicks pass through to the view): the ``title``, ``lines``
    under it (settings, verdicts), a ``legend`` of (colour 0xRRGGBB, opacity, what it is), and the simulated
    time as the animation plays (the clip's time in s: the frames must be sampled at their simulated times),
    with ``frame_text[k]`` next to it at frame k (``fps`` frames per second)."""

    title: str
    lines: tuple[str, ...] = ()
    legend: tuple[tuple[int, float, str], ...] = ()
    frame_text: tuple[str, ...] = ()
    fps: float = 1.0

    def markup(self) -> str:
        """The overlay's HTML, its style and the script that updates the time readout."""
        esc = html.escape
        rows = "".join(f'<div class="capmap-key"><span style="background:rgba({c >> 16},{(c >> 8) & 255},{c & 255},'
                       f'{max(o, 0.25):.2f})"></span>{esc(text)}</div>' for c, o, text in self.legend)
        lines = "".join(f'<div class="capmap-line">{esc(line)}</div>' for line in self.lines)
        texts = json.dumps(list(self.frame_text)).replace("</", "<\\/")
        return _OVERLAY.format(title=esc(self.title), lines=lines, legend=rows, texts=texts, fps=float(self.fps))


_OVERLAY = """<div id="capmap-overlay"><div id="capmap-title">{title}</div>{lines}{legend}
<div id="capmap-time"></div><div id="capmap-frame"></div></div>
<style>
#capmap-overlay {{position: absolute; top: 8px; left: 8px; width: min(40em, 46vw); padding: 8px 12px; pointer-events: none;
  background: rgba(255, 255, 255, 0.85); border-radius: 6px; font: 13px/1.35 sans-serif; color: #111;}}
#capmap-title {{font-size: 17px; font-weight: bold; margin-bottom: 2px;}}
.capmap-line {{color: #333;}}
.capmap-key {{margin-top: 2px;}}
.capmap-key span {{display: inline-block; width: 14px; height: 14px; margin-right: 6px; vertical-align: -2px;
  border: 1px solid #555;}}
#capmap-time {{font: bold 16px monospace; margin-top: 6px;}}
#capmap-frame {{font-family: monospace;}}
</style>
<script>
(function () {{
    var texts = {texts}, fps = {fps};
    var time = document.getElementById("capmap-time"), frame = document.getElementById("capmap-frame");
    function tick() {{
        var a = viewer.animator;
        var t = a && a.duration > 0 ? a.time : 0;
        if (a && a.duration > 0) {{
            time.textContent = "simulated time t = " + t.toFixed(2) + " s of " + a.duration.toFixed(2) + " s";
        }}
        if (texts.length) {{
            frame.textContent = texts[Math.min(texts.length - 1, Math.max(0, Math.round(t * fps)))];
        }}
        requestAnimationFrame(tick);
    }}
    tick();
}})();
</script>"""


class RecordingWindow:
    """A MeshCat window that records the scene tree in-process (what ``meshcat-server`` keeps); ``overlay``:
    words drawn over the view (none: the bare view)."""

    def __init__(self, title: str = "MeshCat", overlay: Overlay | None = None):
        self.tree = SceneTree()
        self.title = title
        self.overlay = overlay

    def send(self, command) -> None:
        data = command.lower()
        path = [p for p in data["path"].split("/") if p]
        packed = umsgpack.packb(data)
        kind = data["type"]
        if kind == "set_transform":
            find_node(self.tree, path).transform = packed
        elif kind == "set_object":
            find_node(self.tree, path).object = packed
            find_node(self.tree, path).properties = []
        elif kind == "set_property":
            find_node(self.tree, path).properties.append(packed)
        elif kind == "set_animation":
            find_node(self.tree, path).animation = packed
        elif kind == "delete":
            if path:
                parent = find_node(self.tree, path[:-1])
                parent.pop(path[-1], None)
            else:
                self.tree = SceneTree()

    def get_scene(self) -> str:
        """The static HTML of the recorded scene (MeshCat's viewer script embedded)."""
        commands = []
        for node in walk(self.tree):
            for item in (node.object, *node.properties, node.transform, node.animation):
                if item is not None:
                    commands.append(create_command(item))
        script = Path(os.path.join(VIEWER_ROOT, "main.min.js")).read_text()
        return _TEMPLATE.format(title=html.escape(self.title), mainminjs=script, commands="".join(commands),
                                overlay=self.overlay.markup() if self.overlay else "")


def new_scene(title: str | Overlay, **words) -> meshcat.Visualizer:
    """A MeshCat visualizer recording into a :class:`RecordingWindow`, the title (and ``words``: the other
    fields of an :class:`Overlay`) drawn over the view; or the whole :class:`Overlay`."""
    overlay = title if isinstance(title, Overlay) else Overlay(title, **words)
    return meshcat.Visualizer(window=RecordingWindow(overlay.title, overlay))


def write_html(vis: meshcat.Visualizer, out_html: str | Path) -> None:
    """Write ``vis.static_html()`` to a file (parents created)."""
    Path(out_html).parent.mkdir(parents=True, exist_ok=True)
    Path(out_html).write_text(vis.static_html())


def segment_pose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pose (4, 4) of MeshCat's cylinder (axis y, centred) that spans the segment a -> b (3,)."""
    d = np.asarray(b, float) - np.asarray(a, float)
    length = np.linalg.norm(d)
    y = d / length if length > 0 else np.array([0.0, 1.0, 0.0])
    helper = np.array([1.0, 0, 0]) if abs(y[0]) < 0.9 else np.array([0, 0, 1.0])
    x = np.cross(y, helper)
    x /= np.linalg.norm(x)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, y, np.cross(x, y)])
    T[:3, 3] = (np.asarray(a, float) + np.asarray(b, float)) / 2
    return T


def cylinder(a: np.ndarray, b: np.ndarray, radius: float) -> tuple[g.Cylinder, np.ndarray]:
    """A cylinder geometry spanning a -> b and its pose."""
    return g.Cylinder(float(np.linalg.norm(np.asarray(b) - np.asarray(a))), float(radius)), segment_pose(a, b)


def capsule(node, a: np.ndarray, b: np.ndarray, radius: float, look) -> None:
    """A capsule (the segment a -> b (3,) m swept by a sphere of ``radius`` m) under ``node``: its cylinder and its
    two end spheres, in material ``look``."""
    geom, pose = cylinder(a, b, radius)
    node["core"].set_object(geom, look)
    node["core"].set_transform(pose)
    for k, end in enumerate((a, b)):
        node[f"cap{k}"].set_object(g.Sphere(float(radius)), look)
        T = np.eye(4)
        T[:3, 3] = end
        node[f"cap{k}"].set_transform(T)


def facing(tri: np.ndarray, labels: np.ndarray, centre: np.ndarray, eye: np.ndarray) -> np.ndarray:
    """(T,) bool: the triangles ``tri`` (T, 3, 3) m whose solid (``labels`` (T,): the solid of each) has its centre on
    the camera's side of ``centre`` (``eye``: the camera from the centre), those a cutaway drawing leaves out."""
    side = {lab: float((tri[labels == lab].reshape(-1, 3).mean(axis=0) - centre) @ eye) > 0 for lab in np.unique(labels)}
    return np.array([side[lab] for lab in labels], dtype=bool)


def material(color: int, opacity: float = 1.0) -> g.MeshLambertMaterial:
    """A flat-shaded material of colour 0xRRGGBB."""
    return g.MeshLambertMaterial(color=color, opacity=opacity, transparent=opacity < 1.0)


def aim(vis: meshcat.Visualizer, roots: tuple[str, ...], centre: np.ndarray, eye: np.ndarray, right: float = 0.0) -> None:
    """Look at ``centre`` (m, world frame) from ``eye`` (m, from the centre; z up), the centre ``right`` x |eye| m right
    of the view's middle (clear of the words over its top left). MeshCat's camera orbits the world's origin: the
    scene's ``roots`` (every top-level node), the grid and the axes are moved by -(the point looked at)."""
    eye = np.asarray(eye, float)
    side = np.cross(-eye, [0.0, 0.0, 1.0])  # the view's right
    side = side / max(np.linalg.norm(side), 1e-12)
    shift = np.eye(4)
    shift[:3, 3] = -(np.asarray(centre, float) - right * np.linalg.norm(eye) * side)
    for root in (*roots, "/Grid", "/Axes"):
        vis[root].set_transform(shift)
    x, y, z = eye
    vis["/Cameras/default/rotated/<object>"].set_property("position", [x, z, -y])  # the camera's frame: y up


def hide_helpers(vis: meshcat.Visualizer) -> None:
    """Hide MeshCat's floor grid and world axes (unexplained in a scene that has its own ground, or none)."""
    for helper in ("/Grid", "/Axes"):
        vis[helper].set_property("visible", False)
