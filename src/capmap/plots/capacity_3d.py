"""Interactive 3D view of the capacity map: one self-contained HTML page (plotly.js inlined, no network at view
time). The voxels that carry the payload are cubes coloured by capacity (solid and cut just under the main
task's paths as the page opens, so that the capacity of the layer under them shows; a button makes them
see-through), their centres give each one's value and the limit that binds it on hover; the voxels below the
payload and the 0 kg voxels (singular slabs) are their own traces; a payload slider, a height slider that cuts
the map at a layer, buttons for the maps of the tasks' configurations and the bound (each on its own colour
scale, the paths planned on it shown, the others a click away), fixed axes; the direct lines, the planned paths
of the task's payloads and of each further task (each with its verified verdict and the configuration it starts
on, in the legend), their starts and goals."""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from capmap.plots.capacity_3d_mesh import cube_faces, page_script
from capmap.plots.palette import PATH_COLOURS

__all__ = ["PlannedPath", "capacity_3d_html", "slider_levels", "PATH_COLOURS"]

SEE_THROUGH = 0.35  # the cubes' opacity of the see-through button (the page opens on solid cubes)
ZOOM = 2.0  # the scene's box, in its units (the orthographic camera's zoom): the main task and the cut under it


@dataclass(frozen=True)
class PlannedPath:
    """A path: ``points_m`` (W, 3) waypoints; ``label`` for the legend (e.g. 'planned path, 1500 kg (4.99 m)');
    ``ends``: the name of a further task (its start and goal marked in the path's colour, named in the legend);
    ``moves_kg`` (W,): the capacity of the move arriving at each waypoint along its own direction (NaN at the
    start; None: not known), in its hover text and, without a ``verdict``, its least in the legend; ``verdict``:
    the verification's, for the legend; ``group``: the title of its task's legend group (the main task's also
    holds the direct line, start and goal); ``direct``: a direct line (thin; the main task's, without ``ends``,
    black: its label and verdict replace the default's); ``on_map``: the indices of the maps it is shown on
    (the map of the configuration it was planned on, the bound; None: every map), hidden on the others (a
    click on its legend entry shows it)."""

    label: str
    points_m: np.ndarray
    ends: str = ""
    moves_kg: np.ndarray | None = None
    verdict: str = ""
    group: str = ""
    direct: bool = False
    on_map: tuple[int, ...] | None = None


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
    switch between them, each on its own colour scale (0 to its largest, as the summary figure's); ``edge_m``
    the voxel edge; ``start_m``, ``goal_m`` (3,) the main task's; the payload slider starts at the first
    payload, the height slider just under the main task's paths (:func:`cut_index`). It opens on solid cubes of
    the voxels carrying the payload up to that cut, so that the layer under the paths shows its capacity (a
    button makes them see-through), those below the payload and the 0 kg ones hidden (a click on their legend
    entry shows them), the paths planned on the shown map (``PlannedPath.on_map``) shown, the others hidden;
    one meaning per colour: the capacity scale for the voxels, red for 0 kg voxels only, black for the main
    task's direct line, start and goal, one colour per planned path (:data:`PATH_COLOURS`, a further task's
    direct line, start and goal in its path's colour)."""
    import plotly.graph_objects as go

    # the binding limits as text, '' where none is given or set (no hover line for it)
    maps = [(m[0], np.asarray(m[1], float).reshape(-1, 3), np.asarray(m[2], float),
             np.array(["" if str(b) in ("nan", "None") else str(b)
                       for b in (m[3] if len(m) == 4 else [""] * len(m[2]))], dtype=object)) for m in maps]
    every = np.concatenate([m[2] for m in maps])
    allxyz = np.concatenate([m[1] for m in maps] + [np.vstack([start_m, goal_m])])
    around = np.concatenate([allxyz] + [np.asarray(p.points_m, float).reshape(-1, 3) for p in paths])
    levels = slider_levels(every, payloads_kg)
    first = float(payloads_kg[0]) if payloads_kg else 0.0
    heights = np.unique(np.round(allxyz[:-2, 2], 4)) if len(allxyz) > 2 else np.array([0.0])
    cut = cut_index(heights, edge_m, np.vstack([start_m] + [p.points_m for p in paths if not p.ends]))
    lo, hi = around.min(axis=0) - edge_m, around.max(axis=0) + edge_m
    names = sorted({str(b) for m in maps for b in m[3]} - {""})
    origin = np.concatenate([m[1] for m in maps]).min(axis=0) if every.size else np.zeros(3)  # the voxel grid's
    cmax = [float(np.nanmax(m[2])) if np.isfinite(m[2]).any() else 1.0 for m in maps]
    fig = go.Figure()
    _add_voxels(fig, go, maps[0], first, cmax[0], (edge_m, origin))
    _add_paths(fig, go, start_m, goal_m, paths)
    task = np.vstack([start_m, goal_m] + [p.points_m for p in paths if not p.ends])
    _layout(fig, maps, levels, heights, (first, cut, (task.min(axis=0) + task.max(axis=0)) / 2), (lo, hi), title)
    data = json.dumps([{"x": m[1][:, 0].round(3).tolist(), "y": m[1][:, 1].round(3).tolist(),
                        "z": m[1][:, 2].round(3).tolist(), "c": m[2].round(1).tolist(), "cmax": round(cmax[n], 1),
                        "b": [names.index(str(b)) if str(b) in names else -1 for b in m[3]],
                        **dict(zip("ijk", _grid_index(m[1], edge_m, origin).T.tolist()))} for n, m in enumerate(maps)])
    shown = [[n, t.meta["maps"]] for n, t in enumerate(fig.data) if isinstance(t.meta, dict) and "maps" in t.meta]
    script = page_script(data, levels, heights, names, {"level": int(np.searchsorted(levels, first)), "height": cut,
                                                        "paths": shown}, edge_m)
    _compact(fig)
    return fig.to_html(include_plotlyjs=True, full_html=True, post_script=script, div_id="capmap-3d",
                       config={"displaylogo": False})


def cut_index(heights: np.ndarray, edge_m: float, points_m: np.ndarray) -> int:
    """The height slider's step as the page opens: the highest voxel layer (its centre in ``heights``) whose top
    face is under every one of ``points_m`` (the main task's start and paths), so that they stand above the cut;
    the top layer (the whole map) when none is."""
    low = float(np.min(np.asarray(points_m, float).reshape(-1, 3)[:, 2]))
    under = np.flatnonzero(np.asarray(heights) + edge_m / 2 <= low + 1e-9)
    return int(under[-1]) if len(under) else len(heights) - 1


def _compact(fig) -> None:
    """The page's numbers as it shows them: positions to the millimetre, capacities to 0.1 kg (the page's
    size is mostly these numbers written out in full)."""
    for tr in fig.data:
        for axis in ("x", "y", "z"):
            v = getattr(tr, axis, None)
            if v is not None and np.asarray(v).dtype.kind == "f":
                setattr(tr, axis, np.round(np.asarray(v, dtype=float), 3).tolist())
        for owner, name in ((getattr(tr, "marker", None), "color"), (tr, "intensity")):
            v = getattr(owner, name, None) if owner is not None else None
            if v is not None and not isinstance(v, str) and np.asarray(v).dtype.kind == "f" and np.ndim(v) == 1:
                setattr(owner, name, np.round(np.asarray(v, dtype=float), 1).tolist())


def _grid_index(xyz: np.ndarray, edge_m: float, origin: np.ndarray) -> np.ndarray:
    """(V, 3) integer indices of voxel centres on the grid of edge ``edge_m`` through ``origin``."""
    return np.round((np.asarray(xyz, float).reshape(-1, 3) - origin) / edge_m).astype(int)


def _layout(fig, maps, levels: np.ndarray, heights: np.ndarray, start: tuple, box, title: str) -> None:
    """Title, fixed axes in metres, a camera on the main task (:func:`_camera`), the sliders (``start``: the payload
    and the height step they open on, and the main task's centre in m), the map and cube buttons and the legend
    (grouped by task, each entry its own toggle) beside the scene."""
    first, cut, focus = start
    lo, hi = box
    span = hi - lo
    focus = (np.asarray(focus, float) - (lo + hi) / 2) / span[0] * ZOOM  # in the scene's units
    steps = [dict(method="skip", label=f"{v:g}", args=[None]) for v in levels]
    cuts = [dict(method="skip", label=f"{z:.2f}", args=[None]) for z in heights]
    mesh = [n for n, t in enumerate(fig.data) if t.type == "mesh3d"]
    style = [dict(method="restyle", label=label, args=[{"opacity": o}, mesh])
             for label, o in (("see-through cubes", SEE_THROUGH), ("solid cubes", 1.0))]
    menus = [dict(type="buttons", direction="right", buttons=style, active=1, x=0.3, y=0.95, xanchor="left",
                  yanchor="top", showactive=True)]
    if len(maps) > 1:
        menus.insert(0, dict(type="buttons", direction="right", active=0, x=0.3, y=1.02, xanchor="left",
                             yanchor="top", showactive=True,
                             buttons=[dict(method="skip", label=m[0], args=[None]) for m in maps]))
    axis = dict(ticksuffix=" m", autorange=False)
    fig.update_layout(
        title=dict(text=title),
        scene=dict(xaxis=dict(title="x", range=[lo[0], hi[0]], **axis),
                   yaxis=dict(title="y", range=[lo[1], hi[1]], **axis),
                   zaxis=dict(title="z", range=[lo[2], hi[2]], **axis),
                   aspectmode="manual", aspectratio=dict(zip("xyz", (ZOOM * span / span[0]).tolist())),
                   domain=dict(x=[0.3, 1.0], y=[0.0, 0.88]), camera=_camera(span, focus)),
        uirevision="capmap",  # the camera stays where the user put it while the sliders redraw
        sliders=[dict(active=int(np.searchsorted(levels, first)), steps=steps, len=0.48, x=0.0, pad=dict(t=30),
                      currentvalue=dict(prefix="payload [kg] >= ")),
                 dict(active=cut, steps=cuts, currentvalue=dict(prefix="show z [m] <= "), pad=dict(t=30),
                      len=0.48, x=0.52)],
        updatemenus=menus,
        legend=dict(x=0.0, y=0.88, xanchor="left", yanchor="top", font=dict(size=11), groupclick="toggleitem",
                    title=dict(text="click to show or hide:"), tracegroupgap=12),
        margin=dict(l=0, r=0, t=90, b=0), height=860)


def _camera(span: np.ndarray, focus: np.ndarray) -> dict:
    """The opening camera: centred on ``focus`` (the main task's paths, in the scene's units: the box's centre
    0, its sides ``ZOOM * span / span[0]``), seen from above the map's -x side, where the default task's paths
    lie across the view (not along it) and their ends apart, the cut under them in view."""
    scale = ZOOM * float(np.max(span / span[0]))  # the scene's largest side in its units
    c = dict(zip("xyz", np.round(focus, 3).tolist()))
    return dict(center=c, eye=dict(x=c["x"] - 1.6 * scale, y=c["y"] + 0.45 * scale, z=c["z"] + 1.1 * scale),
                projection=dict(type="orthographic"))


def _add_voxels(fig, go, shown: tuple, first: float, cmax: float, grid: tuple) -> None:
    """The shown map's voxels (name, centres (V, 3), capacity (V,), binding (V,)) as the script's four traces:
    the centres of those carrying ``first`` kg (tiny dots, for hover), below it (grey, hidden), 0 kg (red,
    hidden) and the cubes of those carrying it (their exposed faces, coloured by capacity from 0 to ``cmax``,
    solid); ``grid``: the voxel edge and the grid's origin. The whole map: the page's script cuts it at the
    height slider's step as the page opens."""
    _, xyz, c, bind = shown
    hov = "(%{x:.2f}, %{y:.2f}, %{z:.2f}) m<br>%{text}<extra></extra>"
    text = np.array([f"{x:.0f} kg" + (f", bound by {y}" if y else "") for x, y in zip(c, bind)], dtype=object)
    keep, zero = c >= first, c == 0
    for sel, name, marker, extra in (
            (keep, "voxels carrying the payload", dict(size=3, color=c[keep].tolist(), cmin=0.0, cmax=cmax,
                                                         colorscale="Viridis", opacity=0.0),  # hover only: the
             dict(legendgroup="voxels", showlegend=False)),  # cubes draw them (dots would make a moiré lattice)
            (~keep, "voxels below the payload (grey)", dict(size=2, color="lightgrey", opacity=0.4),
             dict(visible="legendonly")),
            (zero, "0 kg voxels (red): a singular surface crosses them", dict(size=2.5, color="red", opacity=0.5),
             dict(visible="legendonly"))):
        fig.add_trace(go.Scatter3d(x=xyz[sel, 0].tolist(), y=xyz[sel, 1].tolist(), z=xyz[sel, 2].tolist(),
                                   mode="markers", name=name, marker=marker, text=text[sel].tolist(),
                                   hovertemplate=hov, **extra))
    mesh = cube_faces(_grid_index(xyz[keep], grid[0], grid[1]), xyz[keep], grid[0])
    fig.add_trace(go.Mesh3d(
        x=mesh["x"].tolist(), y=mesh["y"].tolist(), z=mesh["z"].tolist(), i=mesh["i"].tolist(),
        j=mesh["j"].tolist(), k=mesh["k"].tolist(), intensity=c[keep][mesh["owner"]].tolist(),
        name="voxels carrying the payload: cubes by capacity",
        hovertext=text[keep][mesh["owner"]].tolist(), hovertemplate="%{hovertext}<extra></extra>",
        colorscale="Viridis", cmin=0.0, cmax=cmax, opacity=1.0, flatshading=True, legendgroup="voxels",
        showlegend=True, legendrank=1, lighting=dict(ambient=0.8, diffuse=0.35, specular=0.05, roughness=1.0, fresnel=0.0),
        colorbar=dict(title=dict(text="capacity [kg]"), x=1.0)))


def _shown(maps: tuple[int, ...] | None) -> dict:
    """A path trace's visibility as the page opens (on the first map) and the maps it shows on (its ``meta``,
    read by the page's script when a map button is clicked)."""
    return dict(visible=True if maps is None or 0 in maps else "legendonly", meta={"maps": maps})


def _add_paths(fig, go, start_m: np.ndarray, goal_m: np.ndarray, paths: list[PlannedPath]) -> None:
    """The main task's direct line with its start and goal (black) and each path (its own colour, thick; a further
    task's direct line thin, its start and goal marked in its colour), in its task's legend group; each path's
    verdict (else the least capacity of its moves along their own directions) in the legend, each move's in its
    hover text; each shown on the maps of its ``on_map`` (the main task's direct line, start and goal on its
    planned paths' maps)."""
    main = next((p.group for p in paths if not p.ends and p.group), "")
    own = next((p for p in paths if p.direct and not p.ends), None)
    on = next((p.on_map for p in paths if not p.ends), None)
    line = np.vstack([start_m, goal_m])
    fig.add_trace(go.Scatter3d(x=line[:, 0].tolist(), y=line[:, 1].tolist(), z=line[:, 2].tolist(), mode="lines",
                               name=own.label + (f"<br>   {own.verdict}" if own.verdict else "") if own else "direct line",
                               line=dict(color="black", width=6), hoverinfo="skip", legendgroup="main",
                               legendgrouptitle_text=main, **_shown(on)))
    colours = {}
    for p in [p for p in paths if p is not own]:
        colour = colours.setdefault(p.ends or p.label, PATH_COLOURS[len(colours) % len(PATH_COLOURS)])
        fig.add_trace(_path_trace(go, p, colour))
    for pos, name, symbol, where in ((start_m, "start", "circle", "middle left"),
                                     (goal_m, "goal", "diamond", "top center")):  # apart from the paths between them
        fig.add_trace(go.Scatter3d(x=[float(pos[0])], y=[float(pos[1])], z=[float(pos[2])], mode="markers+text",
                                   name=name, text=[name], textfont=dict(size=14, color="black"), legendgroup="main",
                                   textposition=where, marker=dict(size=8, color="black", symbol=symbol), **_shown(on)))
    for p in [p for p in paths if p.ends and not p.direct]:
        pts = np.asarray(p.points_m, float).reshape(-1, 3)
        for pos, end, symbol in ((pts[0], "start", "circle"), (pts[-1], "goal", "diamond")):
            fig.add_trace(go.Scatter3d(x=[float(pos[0])], y=[float(pos[1])], z=[float(pos[2])], mode="markers",
                                       name=f"{p.ends}: {end}", legendgroup=p.ends, hovertemplate=f"{p.ends}: {end}"
                                       "<extra></extra>", marker=dict(size=7, color=colours[p.ends], symbol=symbol,
                                                                      line=dict(color="black", width=1)),
                                       **_shown(p.on_map)))


def _path_trace(go, p: PlannedPath, colour: str):
    """One path's trace: its line (thin for a direct line), its verdict or its moves' least in its legend name."""
    pts = np.asarray(p.points_m, float).reshape(-1, 3)
    moves = np.full(len(pts), np.nan) if p.moves_kg is None else np.asarray(p.moves_kg, float)
    hover = [f"waypoint {i}" + (f": the move here carries {m:,.0f} kg along its own direction"
                                if np.isfinite(m) else "") for i, m in enumerate(moves)]
    text = [""] * len(pts)
    if p.ends:  # a further task's ends named (hover), marked in the scene by their own traces
        text[0], text[-1] = f"{p.ends}: start", f"{p.ends}: goal"
    least = f"each move carries ≥ {np.nanmin(moves):,.0f} kg along its direction" if np.isfinite(moves).any() else ""
    extra = p.verdict or least
    return go.Scatter3d(x=pts[:, 0].tolist(), y=pts[:, 1].tolist(), z=pts[:, 2].tolist(),
                        mode="lines" if p.direct else "lines+markers", name=p.label + (f"<br>   {extra}" if extra else ""),
                        text=text if p.ends else None, hovertext=hover,
                        hovertemplate=("%{text}<br>" if p.ends else "") + "%{hovertext}<extra></extra>",
                        legendgroup=p.ends or "main", legendgrouptitle_text=p.group if p.ends else None,
                        line=dict(width=4 if p.direct else 12, color=colour), marker=dict(size=4, color=colour),
                        **_shown(p.on_map))
