"""Interactive 3D view of the capacity map: one self-contained HTML page (plotly.js inlined, no
network at view time) with the reachable voxels coloured by capacity (hover: the value and the limit
that binds it), the 0 kg voxels (singular slabs) as their own trace, a payload slider that hides the
voxels below it, a height slider that cuts the map at a layer so its inside shows, fixed axes, the
direct line, the planned paths of the task's payloads and of each further task, the start and the goal."""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

__all__ = ["PlannedPath", "capacity_3d_html", "slider_levels", "PATH_COLOURS"]

PATH_COLOURS = ("darkorange", "magenta", "saddlebrown", "deepskyblue", "olive", "orchid")  # not in viridis, not red


@dataclass(frozen=True)
class PlannedPath:
    """A planned path: ``points_m`` (W, 3) waypoints; ``label`` for the legend (e.g. '1500 kg: A*');
    ``ends``: a name written at its first and last waypoint (a further task's own start and goal);
    ``moves_kg`` (W,): the capacity of the move arriving at each waypoint along its own direction (NaN
    at the start; None: not known), in its hover text and the legend (its least)."""

    label: str
    points_m: np.ndarray
    ends: str = ""
    moves_kg: np.ndarray | None = None


def slider_levels(capacity_kg: np.ndarray, payloads_kg: tuple[float, ...], n: int = 20) -> np.ndarray:
    """Payload levels of the slider (kg): 0, ``n`` round steps up to the largest capacity, and the
    task payloads, sorted and unique."""
    top = float(np.nanmax(capacity_kg)) if np.isfinite(capacity_kg).any() else 1.0
    raw = top / n
    mag = 10 ** np.floor(np.log10(max(raw, 1e-9)))
    step = min((m * mag for m in (1, 2, 2.5, 5, 10) if m * mag >= raw), default=10 * mag)
    return np.unique(np.r_[np.arange(0.0, top + step, step), payloads_kg])


def capacity_3d_html(maps: list[tuple], edge_m: float, start_m: np.ndarray,
                     goal_m: np.ndarray, paths: list[PlannedPath], payloads_kg: tuple[float, ...],
                     title: str) -> str:
    """The page. ``maps``: (name, centres_m (V, 3), capacity_kg (V,)[, binding (V,) str]) of the
    reachable voxels of each map (capacity of the voxel: the least over its points and motion
    directions, on the map's IK branches; binding: the limit that sets it), the first shown, buttons
    switch between them; ``edge_m`` the voxel edge; ``start_m``, ``goal_m`` (3,); the payload slider
    starts at the first payload, the height slider at the top (the whole map). It opens on a readable
    view: the voxels carrying the payload faint (the paths show through them), those below it and the
    0 kg ones hidden (a click on their legend entry shows them); one meaning per colour: the capacity
    scale for the voxels, red for 0 kg voxels only, black for the direct line and its start and goal,
    one colour per planned path (:data:`PATH_COLOURS`), drawn thick."""
    import plotly.graph_objects as go

    # the binding limits as text, '' where none is given or set (no hover line for it)
    maps = [(m[0], m[1], m[2], np.array(["" if str(b) in ("nan", "None") else str(b)
                                         for b in (m[3] if len(m) == 4 else [""] * len(m[2]))], dtype=object))
            for m in maps]
    every = np.concatenate([np.asarray(m[2], float) for m in maps])
    allxyz = np.concatenate([np.asarray(m[1], float).reshape(-1, 3) for m in maps] + [np.vstack([start_m, goal_m])])
    around = np.concatenate([allxyz] + [np.asarray(p.points_m, float).reshape(-1, 3) for p in paths])
    levels = slider_levels(every, payloads_kg)
    first = float(payloads_kg[0]) if payloads_kg else 0.0
    heights = np.unique(np.round(allxyz[:-2, 2], 4)) if len(allxyz) > 2 else np.array([0.0])
    lo, hi = around.min(axis=0) - edge_m, around.max(axis=0) + edge_m
    names = sorted({str(b) for m in maps for b in m[3]} - {""})
    fig = go.Figure()
    _add_voxels(fig, go, maps[0], first, float(np.nanmax(every)) if every.size else 1.0)
    _add_paths(fig, go, start_m, goal_m, paths)
    steps = [dict(method="skip", label=f"{v:g}", args=[None]) for v in levels]
    cuts = [dict(method="skip", label=f"{z:.2f}", args=[None]) for z in heights]
    active = int(np.searchsorted(levels, first))
    buttons = [dict(method="skip", label=m[0], args=[None]) for m in maps]
    span = hi - lo
    fig.update_layout(
        title=dict(text=f"{title}<br><sub>shown: {maps[0][0]} (buttons: the other maps); voxel edge {edge_m:g} m; the "
                        "payload slider hides the voxels below a payload,<br>the height slider cuts the map above a layer; "
                        "hover: capacity and the limit that binds it; x, y, z in m (base frame): scroll out for the "
                        "whole map</sub>"),
        scene=dict(xaxis=dict(title="x [m]", range=[lo[0], hi[0]], autorange=False),
                   yaxis=dict(title="y [m]", range=[lo[1], hi[1]], autorange=False),
                   zaxis=dict(title="z [m]", range=[lo[2], hi[2]], autorange=False),
                   aspectmode="manual", aspectratio=dict(x=1.0, y=span[1] / span[0], z=span[2] / span[0]),
                   domain=dict(x=[0.3, 1.0], y=[0.0, 1.0]), camera=_camera(start_m, goal_m, paths, lo, span)),
        uirevision="capmap",  # the camera stays where the user put it while the sliders redraw
        sliders=[dict(active=active, steps=steps, currentvalue=dict(prefix="payload [kg] >= "), pad=dict(t=30),
                      len=0.48, x=0.0),
                 dict(active=len(cuts) - 1, steps=cuts, currentvalue=dict(prefix="show z [m] <= "), pad=dict(t=30),
                      len=0.48, x=0.52)],
        updatemenus=[dict(type="buttons", direction="right", buttons=buttons, active=0, x=0.0, y=1.0,
                          xanchor="left", yanchor="top", showactive=True)] if len(maps) > 1 else [],
        legend=dict(x=0.0, y=0.88, xanchor="left", font=dict(size=11), title=dict(text="click to show or hide:")),
        margin=dict(l=0, r=0, t=110, b=0), height=800)
    data = json.dumps([{"x": np.asarray(m[1])[:, 0].round(4).tolist(), "y": np.asarray(m[1])[:, 1].round(4).tolist(),
                        "z": np.asarray(m[1])[:, 2].round(4).tolist(), "c": np.asarray(m[2], float).round(2).tolist(),
                        "b": [names.index(str(b)) if str(b) in names else -1 for b in m[3]]}
                       for m in maps])
    script = _script(data, levels, heights, names, active)
    return fig.to_html(include_plotlyjs=True, full_html=True, post_script=script, div_id="capmap-3d",
                       config={"displaylogo": False})


def _camera(start_m: np.ndarray, goal_m: np.ndarray, paths: list[PlannedPath], lo: np.ndarray, span: np.ndarray):
    """The opening camera: looking at the middle of the task (start, goal, the paths) from above one side,
    close enough that the paths read (scroll to zoom out to the whole map)."""
    pts = np.vstack([start_m, goal_m] + [np.asarray(p.points_m, float).reshape(-1, 3) for p in paths])
    scale = span / span[0]  # the scene's normalised units: the x extent is 1
    mid = 2 * ((pts.min(axis=0) + pts.max(axis=0)) / 2 - (lo + span / 2)) / span * scale  # the box: -scale..scale
    eye = mid + np.array([0.6, 0.6, 0.42])
    return dict(center=dict(zip("xyz", mid.round(4).tolist())), eye=dict(zip("xyz", eye.round(4).tolist())))


def _add_voxels(fig, go, shown: tuple, first: float, cmax: float) -> None:
    """The shown map's voxels (name, centres (V, 3), capacity (V,), binding (V,)) as the script's three
    traces: carrying ``first`` kg (faint, by capacity), below it (grey, hidden), 0 kg (red, hidden)."""
    _, xyz, c, bind = shown
    c, xyz = np.asarray(c, float), np.asarray(xyz, float)
    hov = "(%{x:.2f}, %{y:.2f}, %{z:.2f}) m<br>%{text}<extra></extra>"

    def text(sel):
        return [f"{x:.0f} kg" + (f", bound by {y}" if y else "") for x, y in zip(c[sel], bind[sel])]

    keep, zero = c >= first, c == 0
    fig.add_trace(go.Scatter3d(
        x=xyz[keep, 0].tolist(), y=xyz[keep, 1].tolist(), z=xyz[keep, 2].tolist(), mode="markers",
        name="voxels carrying the payload",
        marker=dict(size=3, color=c[keep].tolist(), cmin=0.0, cmax=cmax, colorscale="Viridis", opacity=0.3,
                    colorbar=dict(title=dict(text="voxel capacity [kg]<br><sub>least over its points<br>and every "
                                                  "direction</sub>"), x=1.02)),
        text=text(keep), hovertemplate=hov))
    fig.add_trace(go.Scatter3d(
        x=xyz[~keep, 0].tolist(), y=xyz[~keep, 1].tolist(), z=xyz[~keep, 2].tolist(), mode="markers",
        name="voxels below the payload (grey)", marker=dict(size=2, color="lightgrey", opacity=0.25),
        visible="legendonly", text=text(~keep), hovertemplate=hov))
    fig.add_trace(go.Scatter3d(
        x=xyz[zero, 0].tolist(), y=xyz[zero, 1].tolist(), z=xyz[zero, 2].tolist(), mode="markers",
        name="0 kg voxels (red): a singular surface crosses them", marker=dict(size=2.5, color="red", opacity=0.35),
        visible="legendonly", text=text(zero), hovertemplate=hov))


def _add_paths(fig, go, start_m: np.ndarray, goal_m: np.ndarray, paths: list[PlannedPath]) -> None:
    """The direct line with its start and goal (black), each planned path (its own colour, thick; its ends
    named, the capacity of each move along its own direction in its hover text and its least in the legend)."""
    line = np.vstack([start_m, goal_m])
    fig.add_trace(go.Scatter3d(x=line[:, 0].tolist(), y=line[:, 1].tolist(), z=line[:, 2].tolist(), mode="lines",
                               name="direct line", line=dict(color="black", width=7, dash="dash"), hoverinfo="skip"))
    for k, p in enumerate(paths):
        pts = np.asarray(p.points_m, float)
        colour = PATH_COLOURS[k % len(PATH_COLOURS)]
        moves = np.full(len(pts), np.nan) if p.moves_kg is None else np.asarray(p.moves_kg, float)
        hover = [f"waypoint {i}" + (f": the move here carries {m:,.0f} kg along its own direction"
                                    if np.isfinite(m) else "") for i, m in enumerate(moves)]
        text = [""] * len(pts)
        if p.ends:
            text[0], text[-1] = f"{p.ends}: start", f"{p.ends}: goal"
            if len(pts) == 1:
                text[0] = f"{p.ends}: start and goal"
        least = f"<br>   each move carries ≥ {np.nanmin(moves):,.0f} kg along its direction" if np.isfinite(
            moves).any() else ""
        fig.add_trace(go.Scatter3d(x=pts[:, 0].tolist(), y=pts[:, 1].tolist(), z=pts[:, 2].tolist(),
                                   mode="lines+markers+text" if p.ends else "lines+markers", name=p.label + least,
                                   text=text if p.ends else None, textfont=dict(color=colour), hovertext=hover,
                                   hovertemplate="%{hovertext}<extra></extra>",
                                   line=dict(width=11, color=colour), marker=dict(size=4, color=colour)))
    for pos, name, symbol in ((start_m, "start", "circle"), (goal_m, "goal", "diamond")):
        fig.add_trace(go.Scatter3d(x=[float(pos[0])], y=[float(pos[1])], z=[float(pos[2])], mode="markers+text",
                                   name=name, text=[name], textfont=dict(size=14, color="black"),
                                   marker=dict(size=8, color="black", symbol=symbol)))


def _script(data: str, levels: np.ndarray, heights: np.ndarray, names: list[str], active: int) -> str:
    """The page's script: on a slider step or a map button, the shown map's voxels up to the height cut,
    >= the payload level in trace 0, the others in trace 1, its 0 kg voxels in trace 2."""
    return ("const M = " + data + ", L = " + json.dumps(levels.tolist()) + ", H = " + json.dumps(heights.tolist())
              + ", B = " + json.dumps(names) + ";\n"
              "const gd = document.getElementById('{plot_id}');\n"
              "let level = L[" + str(active) + "], zmax = H[H.length - 1], shown = 0;\n"
              "function draw() {\n"
              "  const V = M[shown], a = {x: [], y: [], z: [], c: [], t: []}, b = {x: [], y: [], z: [], t: []},\n"
              "        o = {x: [], y: [], z: [], t: []};\n"
              "  for (let i = 0; i < V.c.length; i++) {\n"
              "    if (V.z[i] > zmax + 1e-6) continue;\n"
              "    const t = V.c[i].toFixed(0) + ' kg' + (V.b[i] >= 0 ? ', bound by ' + B[V.b[i]] : '');\n"
              "    const s = V.c[i] >= level ? a : b;\n"
              "    s.x.push(V.x[i]); s.y.push(V.y[i]); s.z.push(V.z[i]); s.t.push(t);\n"
              "    if (s === a) { a.c.push(V.c[i]); }\n"
              "    if (V.c[i] === 0) { o.x.push(V.x[i]); o.y.push(V.y[i]); o.z.push(V.z[i]); o.t.push(t); }\n"
              "  }\n"
              "  Plotly.restyle(gd, {x: [a.x, b.x, o.x], y: [a.y, b.y, o.y], z: [a.z, b.z, o.z], text: [a.t, b.t, o.t]},\n"
              "                 [0, 1, 2]);\n"
              "  Plotly.restyle(gd, {'marker.color': [a.c]}, [0]);\n"
              "}\n"
              "gd.on('plotly_sliderchange', function (ev) {  // which slider: by its label\n"
              "  if (ev.slider.currentvalue.prefix.startsWith('payload')) { level = L[ev.step._index]; }\n"
              "  else { zmax = H[ev.step._index]; }\n"
              "  draw();\n"
              "});\n"
              "gd.on('plotly_buttonclicked', function (ev) { shown = ev.active; draw(); });\n")
