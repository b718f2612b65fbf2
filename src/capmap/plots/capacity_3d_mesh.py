"""The 3D page's voxels as cubes: the faces of the shown voxels that no shown neighbour covers (one mesh, coloured
by each voxel's capacity), built here for the page as it opens and by the page's script, the same way, when a
slider or a button changes what is shown."""

from __future__ import annotations

import json

import numpy as np

__all__ = ["FACES", "cube_faces", "page_script"]

# each face of a cube: its outward direction and its 4 corners (units of half an edge), counter-clockwise seen
# from outside (the mesh's lighting reads the winding)
FACES = (((1, 0, 0), ((1, -1, -1), (1, 1, -1), (1, 1, 1), (1, -1, 1))),
         ((-1, 0, 0), ((-1, -1, -1), (-1, -1, 1), (-1, 1, 1), (-1, 1, -1))),
         ((0, 1, 0), ((-1, 1, -1), (-1, 1, 1), (1, 1, 1), (1, 1, -1))),
         ((0, -1, 0), ((-1, -1, -1), (1, -1, -1), (1, -1, 1), (-1, -1, 1))),
         ((0, 0, 1), ((-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1))),
         ((0, 0, -1), ((-1, -1, -1), (-1, 1, -1), (1, 1, -1), (1, -1, -1))))
_KEY = 4096  # voxel indices (+1) below it: a neighbour's key is unique


def _keys(ijk: np.ndarray) -> np.ndarray:
    ijk = np.asarray(ijk, np.int64) + 1
    return (ijk[:, 0] * _KEY + ijk[:, 1]) * _KEY + ijk[:, 2]


def cube_faces(ijk: np.ndarray, centres: np.ndarray, edge_m: float) -> dict:
    """The exposed faces of the cubes of edge ``edge_m`` centred at ``centres`` (V, 3) m, grid indices ``ijk``
    (V, 3): those whose neighbour across the face is not among them. Returns the mesh: vertices ``x``, ``y``,
    ``z`` (4 per face), triangles ``i``, ``j``, ``k`` (2 per face) and ``owner``, the voxel of each vertex."""
    ijk, centres = np.asarray(ijk, np.int64).reshape(-1, 3), np.asarray(centres, float).reshape(-1, 3)
    have = np.sort(_keys(ijk))
    verts, owner = [], []
    for d, corners in FACES:
        nk = _keys(ijk + np.asarray(d))
        pos = np.clip(np.searchsorted(have, nk), 0, max(len(have) - 1, 0))
        open_ = ~(have[pos] == nk) if len(have) else np.zeros(0, bool)
        idx = np.flatnonzero(open_)
        quad = centres[idx][:, None, :] + np.asarray(corners, float)[None] * edge_m / 2  # (n, 4, 3)
        verts.append(quad.reshape(-1, 3))
        owner.append(np.repeat(idx, 4))
    xyz = np.vstack(verts) if verts else np.empty((0, 3))
    base = np.arange(0, len(xyz), 4)
    return {"x": xyz[:, 0], "y": xyz[:, 1], "z": xyz[:, 2], "i": np.repeat(base, 2),
            "j": np.c_[base + 1, base + 2].ravel(), "k": np.c_[base + 2, base + 3].ravel(),
            "owner": np.concatenate(owner) if owner else np.empty(0, int)}


def page_script(data: str, levels: np.ndarray, heights: np.ndarray, names: list[str], start: dict,
                edge_m: float) -> str:
    """The page's script: on a slider step or a map button, the shown map's voxels up to the height cut,
    >= the payload level in trace 0 (their centres, for hover) and as cubes in trace 3 (the exposed faces, as
    :func:`cube_faces`, on the map's colour scale: 0 to its ``cmax``), the others in trace 1, its 0 kg voxels in
    trace 2; on a map button, the paths planned on that map shown, the others hidden. ``start``: the steps of
    the payload and height sliders the page opens on ("level", "height") and the path traces with the maps they
    show on ("paths": [[trace, [map, ...] or null], ...]). Runs once as the page opens."""
    return ("const M = " + data + ", L = " + json.dumps(levels.tolist()) + ", H = " + json.dumps(heights.tolist())
            + ", B = " + json.dumps(names) + ", E = " + json.dumps(float(edge_m)) + ";\n"
            "const F = " + json.dumps([[*d, c] for d, c in FACES]) + ", K = " + str(_KEY) + ";\n"
            "const P = " + json.dumps(start.get("paths", [])) + ";\n"
            "const gd = document.getElementById('{plot_id}');\n"
            "let level = L[" + str(int(start.get("level", 0))) + "], zmax = H["
            + str(int(start.get("height", len(heights) - 1)) % max(len(heights), 1)) + "], shown = 0;\n"
            "const key = (i, j, k) => ((i + 1) * K + j + 1) * K + k + 1;\n"
            "function draw() {\n"
            "  const V = M[shown], a = {x: [], y: [], z: [], c: [], t: []}, b = {x: [], y: [], z: [], t: []},\n"
            "        o = {x: [], y: [], z: [], t: []}, m = {x: [], y: [], z: [], i: [], j: [], k: [], v: [], t: []};\n"
            "  const have = new Set(), mine = [];\n"
            "  for (let n = 0; n < V.c.length; n++) {\n"
            "    if (V.z[n] > zmax + 1e-6) continue;\n"
            "    const t = V.c[n].toFixed(0) + ' kg' + (V.b[n] >= 0 ? ', bound by ' + B[V.b[n]] : '');\n"
            "    const s = V.c[n] >= level ? a : b;\n"
            "    s.x.push(V.x[n]); s.y.push(V.y[n]); s.z.push(V.z[n]); s.t.push(t);\n"
            "    if (s === a) { a.c.push(V.c[n]); have.add(key(V.i[n], V.j[n], V.k[n])); mine.push([n, t]); }\n"
            "    if (V.c[n] === 0) { o.x.push(V.x[n]); o.y.push(V.y[n]); o.z.push(V.z[n]); o.t.push(t); }\n"
            "  }\n"
            "  for (const [n, t] of mine) {\n"
            "    for (const [dx, dy, dz, cs] of F) {\n"
            "      if (have.has(key(V.i[n] + dx, V.j[n] + dy, V.k[n] + dz))) continue;\n"
            "      const b0 = m.x.length;\n"
            "      for (const [cx, cy, cz] of cs) {\n"
            "        m.x.push(V.x[n] + cx * E / 2); m.y.push(V.y[n] + cy * E / 2); m.z.push(V.z[n] + cz * E / 2);\n"
            "        m.v.push(V.c[n]); m.t.push(t);\n"
            "      }\n"
            "      m.i.push(b0, b0); m.j.push(b0 + 1, b0 + 2); m.k.push(b0 + 2, b0 + 3);\n"
            "    }\n"
            "  }\n"
            "  Plotly.restyle(gd, {x: [a.x, b.x, o.x], y: [a.y, b.y, o.y], z: [a.z, b.z, o.z], text: [a.t, b.t, o.t]},\n"
            "                 [0, 1, 2]);\n"
            "  Plotly.restyle(gd, {'marker.color': [a.c]}, [0]);\n"
            "  Plotly.restyle(gd, {x: [m.x], y: [m.y], z: [m.z], i: [m.i], j: [m.j], k: [m.k], intensity: [m.v],\n"
            "                      hovertext: [m.t], cmax: [V.cmax]}, [3]);\n"
            "}\n"
            "function paths() {  // the paths planned on the shown map; the others a click away\n"
            "  if (!P.length) return;\n"
            "  Plotly.restyle(gd, {visible: P.map(([t, ms]) => ms === null || ms.includes(shown) ? true : 'legendonly')},\n"
            "                 P.map(p => p[0]));\n"
            "}\n"
            "gd.on('plotly_sliderchange', function (ev) {  // which slider: by its label\n"
            "  if (ev.slider.currentvalue.prefix.startsWith('payload')) { level = L[ev.step._index]; }\n"
            "  else { zmax = H[ev.step._index]; }\n"
            "  draw();\n"
            "});\n"
            "gd.on('plotly_buttonclicked', function (ev) {  // the map buttons (the others restyle the cubes)\n"
            "  if (ev.button.method === 'skip') { shown = ev.active; draw(); paths(); }\n"
            "});\n"
            "draw();\n")
