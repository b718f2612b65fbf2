"""Interactive 3D view of the capacity map: one self-contained HTML page (plotly.js inlined, no
network at view time) with the reachable voxels coloured by capacity, a payload slider that hides
the voxels below it, the direct line, the planned paths, the start and the goal."""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

__all__ = ["PlannedPath", "capacity_3d_html", "slider_levels"]


@dataclass(frozen=True)
class PlannedPath:
    """A planned path: ``points_m`` (W, 3) waypoints; ``label`` for the legend (e.g. '1500 kg: A*')."""

    label: str
    points_m: np.ndarray


def slider_levels(capacity_kg: np.ndarray, payloads_kg: tuple[float, ...], n: int = 20) -> np.ndarray:
    """Payload levels of the slider (kg): 0, ``n`` round steps up to the largest capacity, and the
    task payloads, sorted and unique."""
    top = float(np.nanmax(capacity_kg)) if np.isfinite(capacity_kg).any() else 1.0
    raw = top / n
    mag = 10 ** np.floor(np.log10(max(raw, 1e-9)))
    step = min((m * mag for m in (1, 2, 2.5, 5, 10) if m * mag >= raw), default=10 * mag)
    return np.unique(np.r_[np.arange(0.0, top + step, step), payloads_kg])


def capacity_3d_html(maps: list[tuple[str, np.ndarray, np.ndarray]], edge_m: float, start_m: np.ndarray,
                     goal_m: np.ndarray, paths: list[PlannedPath], payloads_kg: tuple[float, ...],
                     title: str) -> str:
    """The page. ``maps``: (name, centres_m (V, 3), capacity_kg (V,)) of the reachable voxels of each
    map (capacity of the voxel: the least over its points and motion directions, on the map's IK
    branches), the first shown, buttons switch between them; ``edge_m`` the voxel edge; ``start_m``,
    ``goal_m`` (3,); the slider starts at the first payload."""
    import plotly.graph_objects as go

    _, xyz, c = maps[0]
    c = np.asarray(c, float)
    xyz = np.asarray(xyz, float)
    every = np.concatenate([np.asarray(m[2], float) for m in maps])
    levels = slider_levels(every, payloads_kg)
    first = float(payloads_kg[0]) if payloads_kg else 0.0
    cmax = float(np.nanmax(every)) if every.size else 1.0
    keep = c >= first
    fig = go.Figure()
    fig.add_trace(go.Scatter3d(
        x=xyz[keep, 0].tolist(), y=xyz[keep, 1].tolist(), z=xyz[keep, 2].tolist(), mode="markers",
        name="voxels carrying the payload",
        marker=dict(size=3, color=c[keep].tolist(), cmin=0.0, cmax=cmax, colorscale="Viridis", opacity=0.5,
                    colorbar=dict(title=dict(text="capacity [kg]"), x=1.02)),
        text=[f"{v:.0f} kg" for v in c[keep]], hovertemplate="(%{x:.2f}, %{y:.2f}, %{z:.2f}) m<br>%{text}<extra></extra>"))
    fig.add_trace(go.Scatter3d(
        x=xyz[~keep, 0].tolist(), y=xyz[~keep, 1].tolist(), z=xyz[~keep, 2].tolist(), mode="markers",
        name="reachable, below the payload",
        marker=dict(size=2, color="lightgrey", opacity=0.25), visible="legendonly",
        text=[f"{v:.0f} kg" for v in c[~keep]], hovertemplate="(%{x:.2f}, %{y:.2f}, %{z:.2f}) m<br>%{text}<extra></extra>"))
    line = np.vstack([start_m, goal_m])
    fig.add_trace(go.Scatter3d(x=line[:, 0].tolist(), y=line[:, 1].tolist(), z=line[:, 2].tolist(), mode="lines",
                               name="direct line",
                               line=dict(color="red", width=5, dash="dash")))
    for k, p in enumerate(paths):
        pts = np.asarray(p.points_m, float)
        fig.add_trace(go.Scatter3d(x=pts[:, 0].tolist(), y=pts[:, 1].tolist(), z=pts[:, 2].tolist(),
                                   mode="lines+markers", name=p.label,
                                   line=dict(width=6, color=["black", "darkorange", "magenta", "cyan"][k % 4]),
                                   marker=dict(size=3)))
    for pos, name, colour in ((start_m, "start", "green"), (goal_m, "goal", "red")):
        fig.add_trace(go.Scatter3d(x=[float(pos[0])], y=[float(pos[1])], z=[float(pos[2])], mode="markers+text",
                                   name=name, text=[name],
                                   marker=dict(size=8, color=colour, symbol="diamond")))
    steps = [dict(method="skip", label=f"{v:g}", args=[None]) for v in levels]
    active = int(np.searchsorted(levels, first))
    buttons = [dict(method="skip", label=name, args=[None]) for name, _, _ in maps]
    fig.update_layout(
        title=dict(text=f"{title}<br><sub>shown: {maps[0][0]} (buttons: the other maps); voxel edge {edge_m:g} m; the "
                        f"slider hides the voxels below a payload (shown: capacity >= payload)</sub>"),
        scene=dict(xaxis_title="x [m]", yaxis_title="y [m]", zaxis_title="z [m]", aspectmode="data"),
        sliders=[dict(active=active, steps=steps, currentvalue=dict(prefix="payload [kg] >= "), pad=dict(t=30))],
        updatemenus=[dict(type="buttons", direction="right", buttons=buttons, active=0, x=0.0, y=1.06,
                          xanchor="left", yanchor="bottom", showactive=True)] if len(maps) > 1 else [],
        legend=dict(x=0.0, y=0.95), margin=dict(l=0, r=0, t=110, b=0), height=800)
    data = json.dumps([{"x": np.asarray(m[1])[:, 0].round(4).tolist(), "y": np.asarray(m[1])[:, 1].round(4).tolist(),
                        "z": np.asarray(m[1])[:, 2].round(4).tolist(), "c": np.asarray(m[2], float).round(2).tolist()}
                       for m in maps])
    # on a slider step or a map button: the shown map's voxels >= the level in trace 0, the others in trace 1
    script = ("const M = " + data + ", L = " + json.dumps(levels.tolist()) + ";\n"
              "const gd = document.getElementById('{plot_id}');\n"
              "let level = L[" + str(active) + "], shown = 0;\n"
              "function draw() {\n"
              "  const V = M[shown], a = {x: [], y: [], z: [], c: [], t: []}, b = {x: [], y: [], z: [], t: []};\n"
              "  for (let i = 0; i < V.c.length; i++) {\n"
              "    const s = V.c[i] >= level ? a : b;\n"
              "    s.x.push(V.x[i]); s.y.push(V.y[i]); s.z.push(V.z[i]); s.t.push(V.c[i].toFixed(0) + ' kg');\n"
              "    if (s === a) { a.c.push(V.c[i]); }\n"
              "  }\n"
              "  Plotly.restyle(gd, {x: [a.x, b.x], y: [a.y, b.y], z: [a.z, b.z], text: [a.t, b.t]}, [0, 1]);\n"
              "  Plotly.restyle(gd, {'marker.color': [a.c]}, [0]);\n"
              "}\n"
              "gd.on('plotly_sliderchange', function (ev) { level = L[ev.step._index]; draw(); });\n"
              "gd.on('plotly_buttonclicked', function (ev) { shown = ev.active; draw(); });\n")
    return fig.to_html(include_plotlyjs=True, full_html=True, post_script=script, div_id="capmap-3d",
                       config={"displaylogo": False})
