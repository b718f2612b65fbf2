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

__all__ = ["RecordingWindow", "Overlay", "Inset", "new_scene", "write_html", "segment_pose", "cylinder", "capsule",
           "material", "aim", "hide_helpers", "facing", "g"]

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
class Inset:
    """A small live plot over the view: each of ``series`` (name, colour 0xRRGGBB, value per frame) against the
    frames' time (``seconds``: the last frame's), with a cursor at the current frame; ``label``: what the values are."""

    label: str
    series: tuple[tuple[str, int, tuple[float, ...]], ...]
    seconds: float

    def markup(self) -> tuple[str, str]:
        """The inset's SVG (the cursor ``capmap-cursor``, the current values ``capmap-dot<k>``) and its frames'
        y coordinates (for the script)."""
        w, h, x0, y0 = 300, 84, 34, 6  # the plot's box in the SVG, px
        vals = np.concatenate([np.asarray(v, float) for _, _, v in self.series])
        lo, hi = float(vals.min()), float(vals.max())
        ys = [[round(y0 + h * (hi - v) / ((hi - lo) or 1.0), 1) for v in vals_] for _, _, vals_ in self.series]
        n = max(len(v) for _, _, v in self.series)
        xs = [round(x0 + w * k / max(n - 1, 1), 1) for k in range(n)]
        rgb = [f"#{c:06x}" for _, c, _ in self.series]
        lines = "".join(f'<polyline fill="none" stroke="{c}" stroke-width="2" points="'
                        + " ".join(f"{x},{y}" for x, y in zip(xs, y)) + f'"/><circle id="capmap-dot{k}" r="4" fill="{c}"/>'
                        for k, (c, y) in enumerate(zip(rgb, ys)))
        ticks = "".join(f'<text x="{x0 - 4}" y="{y + 4}" text-anchor="end">{v:.3g}</text>' for v, y in ((hi, y0), (lo, y0 + h)))
        ticks += "".join(f'<text x="{x}" y="{y0 + h + 14}" text-anchor="middle">{t}</text>'
                         for x, t in ((x0, "0 s"), (x0 + w, f"{self.seconds:.0f} s")))
        key = " ".join(f'<span style="color:{c}">&#9644; {html.escape(name)}</span>' for c, (name, _, _) in zip(rgb, self.series))
        svg = (f'<svg width="{x0 + w + 22}" height="{y0 + h + 18}" font-size="11"><rect x="{x0}" y="{y0}" width="{w}" '
               f'height="{h}" fill="none" stroke="#999"/>{ticks}{lines}<line id="capmap-cursor" y1="{y0}" y2="{y0 + h}" '
               'stroke="#111" stroke-dasharray="3,2"/></svg>')
        return f'<div id="capmap-inset"><div>{html.escape(self.label)}: {key}</div>{svg}</div>', json.dumps([xs, ys])


@dataclass(frozen=True)
class Overlay:
    """Words over an animation's 3D view (top left, clicks pass through to the view but for the legend, which a click
    folds): the ``title``, ``lines`` under it (verdicts), the simulated time as the animation plays (the clip's time
    in s: the frames must be sampled at their simulated times) with ``frame_text[k]`` under it at frame k (``fps``
    frames per second), an ``inset`` plot with a cursor at the current frame, and a ``legend`` of (colour 0xRRGGBB,
    opacity, what it is; its swatch drawn at the opacity's square root: a faint colour's hue stays legible). The view
    opens at the simulated time ``start`` s (then loops from 0)."""

    title: str
    lines: tuple[str, ...] = ()
    legend: tuple[tuple[int, float, str], ...] = ()
    frame_text: tuple[str, ...] = ()
    fps: float = 1.0
    inset: Inset | None = None
    start: float = 0.0

    def markup(self) -> str:
        """The overlay's HTML, its style and the script that updates the time readout."""
        esc = html.escape
        rows = "".join(f'<div class="capmap-key"><span style="background:rgba({c >> 16},{(c >> 8) & 255},{c & 255},'
                       f'{max(o, 0.09) ** 0.5:.2f})"></span>{esc(text)}</div>' for c, o, text in self.legend)
        legend = f'<details id="capmap-legend" open><summary>legend</summary>{rows}</details>' if rows else ""
        lines = "".join(f'<div class="capmap-line">{esc(line)}</div>' for line in self.lines)
        inset, series = self.inset.markup() if self.inset else ("", "[[], []]")
        texts = json.dumps(list(self.frame_text)).replace("</", "<\\/")
        return _OVERLAY.format(title=esc(self.title), lines=lines, legend=legend, texts=texts, fps=float(self.fps),
                               inset=inset, series=series, start=float(self.start))


_OVERLAY = """<div id="capmap-overlay"><div id="capmap-title">{title}</div>{lines}
<div id="capmap-time"></div><div id="capmap-frame"></div>{inset}{legend}</div>
<style>
#capmap-overlay {{position: absolute; top: 8px; left: 8px; max-width: min(36em, 46vw); padding: 6px 10px;
  pointer-events: none; background: rgba(255, 255, 255, 0.88); border: 1px solid #bbb; border-radius: 6px;
  font: 12px/1.3 sans-serif; color: #111;}}
#capmap-title {{font-size: 14px; font-weight: bold;}}
.capmap-line {{color: #333;}}
#capmap-time {{font: bold 13px monospace; margin-top: 4px;}}
#capmap-frame {{font: 11.5px/1.3 monospace; white-space: pre-line;}}
#capmap-inset {{margin-top: 4px;}}
#capmap-legend {{pointer-events: auto; margin-top: 4px; cursor: pointer;}}
#capmap-legend summary {{color: #555;}}
.capmap-key {{margin-top: 1px;}}
.capmap-key span {{display: inline-block; width: 12px; height: 12px; margin-right: 5px; vertical-align: -2px;
  border: 1px solid #555;}}
</style>
<script>
(function () {{
    var texts = {texts}, fps = {fps}, series = {series}, start = {start}, opened = false;
    var time = document.getElementById("capmap-time"), frame = document.getElementById("capmap-frame");
    var cursor = document.getElementById("capmap-cursor");
    function tick() {{
        var a = viewer.animator;
        if (a && a.duration > 0 && !opened) {{
            opened = true;
            if (start > 0) {{ a.seek(start); a.display_progress(start); }}
        }}
        var t = a && a.duration > 0 ? a.time : 0;
        if (a && a.duration > 0) {{
            time.textContent = "simulated time t = " + t.toFixed(2) + " s of " + a.duration.toFixed(2) + " s";
        }}
        var k = Math.max(0, Math.round(t * fps));
        if (texts.length) {{
            frame.textContent = texts[Math.min(texts.length - 1, k)];
        }}
        if (cursor && series[0].length) {{
            var x = series[0][Math.min(series[0].length - 1, k)];
            cursor.setAttribute("x1", x); cursor.setAttribute("x2", x);
            series[1].forEach(function (ys, i) {{
                var dot = document.getElementById("capmap-dot" + i);
                dot.setAttribute("cx", x); dot.setAttribute("cy", ys[Math.min(ys.length - 1, k)]);
            }});
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


LIGHT = (0xF7F7F5, 0xC9CDD3)  # a pale grey background's (top, bottom): translucent colours keep their hue on it


def new_scene(title: str | Overlay, light: bool = False, **words) -> meshcat.Visualizer:
    """A MeshCat visualizer recording into a :class:`RecordingWindow`, the title (and ``words``: the other
    fields of an :class:`Overlay`, its ``inset`` an :class:`Inset` or the tuple of its fields) drawn over the view; or
    the whole :class:`Overlay`. ``light``: a pale grey background (else MeshCat's sky blue)."""
    if isinstance(words.get("inset"), tuple):
        words["inset"] = Inset(*words["inset"])
    overlay = title if isinstance(title, Overlay) else Overlay(title, **words)
    vis = meshcat.Visualizer(window=RecordingWindow(overlay.title, overlay))
    for end, colour in zip(("top_color", "bottom_color"), LIGHT if light else ()):
        vis["/Background"].set_property(end, [((colour >> s) & 255) / 255 for s in (16, 8, 0)])
    return vis


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
