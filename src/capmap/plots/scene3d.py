"""Offline 3D scenes with MeshCat: a visualizer whose window records the scene in-process (no
server, no sockets), and ``vis.static_html()`` packs it, with MeshCat's viewer script, into
one self-contained HTML file that opens without a network.

The recorder keeps the scene tree exactly as MeshCat's own server does (``set_object``,
``set_transform``, ``set_property``, ``set_animation``, ``delete``) and renders it with the
server's static-HTML template.
"""

from __future__ import annotations

import os
from pathlib import Path

import meshcat
import meshcat.geometry as g
import numpy as np
import umsgpack
from meshcat.servers.tree import SceneTree, find_node, walk
from meshcat.servers.zmqserver import VIEWER_ROOT, create_command

__all__ = ["RecordingWindow", "new_scene", "write_html", "segment_pose", "cylinder", "material", "g"]

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
    </body>
</html>
"""


class RecordingWindow:
    """A MeshCat window that records the scene tree in-process (what ``meshcat-server`` keeps)."""

    def __init__(self, title: str = "MeshCat"):
        self.tree = SceneTree()
        self.title = title

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
        return _TEMPLATE.format(title=self.title, mainminjs=script, commands="".join(commands))


def new_scene(title: str) -> meshcat.Visualizer:
    """A MeshCat visualizer recording into a :class:`RecordingWindow`."""
    return meshcat.Visualizer(window=RecordingWindow(title))


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


def material(color: int, opacity: float = 1.0) -> g.MeshLambertMaterial:
    """A flat-shaded material of colour 0xRRGGBB."""
    return g.MeshLambertMaterial(color=color, opacity=opacity, transparent=opacity < 1.0)
