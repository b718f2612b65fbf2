"""The capacity family's figures tell their result from the data, each headline and panel title in one line:
each verified path's verdict, drawn over the capacity map with a core coloured by its own capacity and, state by
state, beside the map's voxels under it (the voxel's value read at the sample's voxel, along the grid axis of its
travel); each load panel its own limit and verdict, one legend for the panels, the load that binds marked, an
off-scale load marked on the edge it leaves by; the summary map's start, goal and paths where they are (not
projected onto another layer), its 0 kg voxels' share apart from the curve; the 3D page opening solid, cut
under the main task, on the first map's colour scale, with only the paths planned on the shown map, 0 kg voxels
hidden and one meaning per colour; the baseline's and the atlas' verdicts. Synthetic tables; the figures'
texts and artists read from the figure objects."""

from __future__ import annotations

import json
import re
from types import SimpleNamespace

import matplotlib.colors as mcolors
import numpy as np
import pandas as pd
import pytest

import capmap.plots.atlas as pa
import capmap.plots.baseline as pb
import capmap.plots.capacity as pc
import capmap.plots.capacity_loads as pl
import capmap.plots.capacity_paths as pp
from capmap.capacity.directions import GRID_AXES
from capmap.capacity.tables import AXIS_COLUMNS
from capmap.plots.capacity_3d import PATH_COLOURS, PlannedPath, capacity_3d_html
from capmap.plots.capacity_3d_mesh import cube_faces
from capmap.stages.verify_figures import under_path
from tests.plots.figures import figure_texts, keep_figures

EDGE = 1.0
SHAPE = (8, 8, 8)
LIMITS = {"tau_j2_nm": 700.0, "tau_j3_nm": 700.0, "base_fx_n": 200.0, "base_mx_nm": 500.0}


@pytest.fixture
def figures(monkeypatch):
    """The figures the plot functions would save, kept open for reading."""
    yield from keep_figures(monkeypatch, pc, pp, pl, pa, pb)


def _map(rng=None) -> pd.DataFrame:
    """Every voxel of an 8 x 8 x 8 grid of 1 m voxels (C order): capacity 3000 + 100 i kg, 0 kg on the layer
    k = 6; each grid axis a kg above it (axis a); the corner i = 7, j = 7 not reached."""
    idx = np.stack(np.unravel_index(np.arange(np.prod(SHAPE)), SHAPE), axis=1)
    cap = np.where(idx[:, 2] == 6, 0.0, 3000.0 + 100.0 * idx[:, 0])
    vox = pd.DataFrame({"i": idx[:, 0], "j": idx[:, 1], "k": idx[:, 2], **{c: (idx[:, n] + 0.5) * EDGE
                                                                            for n, c in enumerate(("x_m", "y_m", "z_m"))},
                        "n_reachable": np.where((idx[:, 0] == 7) & (idx[:, 1] == 7), 0, 5), "capacity_kg": cap})
    for a, col in enumerate(AXIS_COLUMNS):
        vox[col] = np.where(cap > 0, cap + 100.0 * (a + 1), 0.0)
    vox.attrs = {"capmap": {"grid": {"lower_m": [0.0, 0.0, 0.0], "shape": list(SHAPE), "edge_m": EDGE}}}
    return vox


def _ts(direct_kg: float = 3820.0, planned_kg: float = 4149.0) -> pd.DataFrame:
    """A direct line along +y (one segment) and a planned path along +y then x+y (two segments), each state's
    capacity its path's weakest in the middle, the loads carrying 4000 kg: the direct line's M_x at 105 % of
    its limit, the planned path's at 97 %."""
    rows = []
    legs = {"direct": [((1.5, 0.5, 1.5), (1.5, 6.5, 1.5))],
            "planned": [((1.5, 0.5, 1.5), (1.5, 3.5, 1.5)), ((1.5, 3.5, 1.5), (4.5, 6.5, 1.5))]}
    for name, weakest, mx in (("direct", direct_kg, 525.0), ("planned", planned_kg, 485.0)):
        t0 = 0.0
        for seg, (a, b) in enumerate(legs[name]):
            s = np.linspace(0.0, 1.0, 31)
            pos = np.asarray(a) + s[:, None] * (np.asarray(b) - np.asarray(a))
            cap = np.where(np.abs(s - 0.5) < 0.05, weakest + 500.0 * seg, 6000.0)
            rows.append(pd.DataFrame({"path": name, "t_s": t0 + 10 * s, "segment": seg, "x_m": pos[:, 0],
                                      "y_m": pos[:, 1], "z_m": pos[:, 2], "state_capacity_kg": cap, "tracked": True,
                                      "in_joint_range": True, "tau_j2_nm": 300 * np.sin(6 * s),
                                      "tau_j3_nm": -200 * np.sin(6 * s), "base_fx_n": 50 * np.cos(6 * s),
                                      "base_mx_nm": mx * np.sign(np.sin(6 * s + 0.1))}))
            t0 += 10.0
    ts = pd.concat(rows, ignore_index=True)
    ts["path"] = pd.Categorical(ts.path, ["direct", "planned"])
    return ts


def test_under_path_reads_the_voxel_each_sample_is_in_along_its_axis_of_travel():
    vox, ts = _map(), _ts()
    ts.loc[5, "tracked"] = False  # an untracked sample does not count in its segment's capacity
    ts.loc[5, "state_capacity_kg"] = 1.0
    out = under_path(vox, ts)
    idx = np.floor(ts[["x_m", "y_m", "z_m"]].to_numpy() / EDGE).astype(int).clip(0, 7)
    row = np.ravel_multi_index(idx.T, SHAPE)
    np.testing.assert_allclose(out.voxel_kg, vox.capacity_kg.to_numpy()[row])
    axis_y = next(a for a, g in enumerate(GRID_AXES) if tuple(g) == (0, 1, 0))
    axis_xy = next(a for a, g in enumerate(GRID_AXES) if tuple(g) == (1, 1, 0))
    along_y = (out.path == "direct") | (out.segment == 0)
    np.testing.assert_allclose(out.voxel_along_kg[along_y], vox[AXIS_COLUMNS[axis_y]].to_numpy()[row[along_y]])
    np.testing.assert_allclose(out.voxel_along_kg[~along_y], vox[AXIS_COLUMNS[axis_xy]].to_numpy()[row[~along_y]])
    for (name, seg), g in out.groupby(["path", "segment"], observed=True):
        src = ts.loc[g.index]
        assert (g.segment_capacity_kg == src.state_capacity_kg[src.tracked].min()).all()
    planned = out[out.path == "planned"]
    assert planned.distance_m.iloc[0] == 0 and planned.distance_m.iloc[-1] == pytest.approx(3 + 3 * np.sqrt(2))


def _profiles(fig) -> list:
    return [ax for ax in fig.axes if ax.get_ylabel() == "capacity [kg]" and not hasattr(ax, "_colorbar")]


def _one_line(fig) -> None:
    """The headline and every panel title: one line each."""
    titles = [fig._suptitle.get_text() if fig._suptitle else ""] + [ax.get_title() for ax in fig.axes]
    assert not [t for t in titles if "\n" in t]


def test_the_workspace_figure_gives_each_path_its_verdict_over_the_capacity_map(figures):
    vox = _map()
    ts = _ts()
    ts.loc[(ts.path == "direct") & (ts.t_s > 8), "state_capacity_kg"] = np.inf  # cruising: unbounded
    path = under_path(vox, ts)
    pp.workspace_paths(vox, path, 4000.0, "w.png", "S-E-W+", colour="magenta")
    fig = figures[0]
    text = figure_texts(fig)
    _one_line(fig)
    assert "planned path holds: weakest segment 4,149 kg (+3.7 %)" in text
    assert "direct line FAILS: weakest segment 3,820 kg (-4.5 %)" in text
    assert fig._suptitle.get_text() == ("Carrying 4000 kg on S-E-W+: the direct line fails (3,820 kg < 4000 kg), the "
                                        "planned path holds (4,149 kg)")
    plane = next(ax for ax in fig.axes if ax.get_images())
    img = plane.get_images()[0]
    assert img.norm.vmax == vox.capacity_kg[vox.n_reachable > 0].max()  # the map's capacity scale, as the summary's
    assert {3000.0 + 100.0 * i for i in (1, 4)} <= set(np.unique(img.get_array().compressed()))  # capacity, not classes
    cores = [c for c in plane.collections if type(c).__name__ == "LineCollection"]
    for core, name in zip(cores, ("direct", "planned")):  # each path's core: its segments' own capacity
        seg = path[path.path == name].segment_capacity_kg.to_numpy()
        np.testing.assert_allclose(core.get_array(), seg[1:])
        assert core.norm is img.norm
    assert any(mcolors.to_hex(line.get_color()) == mcolors.to_hex("magenta") for line in plane.get_lines())
    below = (ts.path == "direct").to_numpy() & (ts.state_capacity_kg < 4000).to_numpy()
    halo = next(line for line in plane.get_lines() if line.get_color() == "tab:red")
    assert np.isfinite(halo.get_ydata()).sum() == below.sum()  # red around the states below the payload
    direct, planned = _profiles(fig)
    for ax in (direct, planned):  # the payload drawn on each path's panel, 0 kg above the axis' bottom
        assert any(np.allclose(line.get_ydata(), 4000.0) for line in ax.get_lines())
        assert ax.get_ylim()[0] < 0
        assert "∞" not in [t.get_text() for t in ax.get_yticklabels()]  # cruising: a gap, no pseudo-tick
    own = ts[ts.path == "direct"].state_capacity_kg.to_numpy()
    thick = next(line for line in direct.get_lines() if line.get_linewidth() == 3)
    np.testing.assert_allclose(thick.get_ydata(), np.where(np.isfinite(own), own, np.nan))  # each state, not a min
    assert "gaps: cruising, no limit" in text


def test_the_workspace_figure_says_where_tracking_was_lost_and_how_low_the_voxels_under_a_path_go(figures):
    vox = _map()
    ts = _ts(planned_kg=5000.0)
    direct = (ts.path == "direct").to_numpy()
    lost = direct & (ts.t_s > 6).to_numpy()
    ts.loc[direct & (ts.t_s > 5).to_numpy(), "state_capacity_kg"] = 0.0
    ts.loc[lost, ["state_capacity_kg", "tracked"]] = [np.nan, False]
    path = under_path(vox, ts)
    path.loc[path.path == "planned", "voxel_kg"] = 0.0  # the voxels under it: 0 kg somewhere inside
    pp.workspace_paths(vox, path, 4000.0, "w.png", "S-E-W+")
    text = figure_texts(figures[0])
    _one_line(figures[0])
    s_lost = path.distance_m[lost].iloc[0]
    assert f"direct line FAILS: tracking lost at {s_lost:.2f} m (t = " in text and "tracking lost" in text
    assert "planned path holds: weakest segment 5,000 kg (+25.0 %); voxels under it down to 0 kg" in text
    marks = [line for line in _profiles(figures[0])[0].get_lines() if line.get_marker() == "X"]
    assert marks and marks[0].get_ydata()[0] == 0.0  # the 0 kg state marked, above the axis' bottom
    profile = _profiles(figures[0])[0]
    assert not [p for p in profile.patches if p.get_facecolor()[:3] == mcolors.to_rgb("0.85")]  # no grey block


def test_when_both_paths_hold_the_title_says_which_is_better(figures):
    vox = _map()
    pp.workspace_paths(vox, under_path(vox, _ts(4500.0, 4200.0)), 1500.0, "w.png", "S-E-W+")
    title = figures[0]._suptitle.get_text()
    assert title == ("Carrying 1500 kg on S-E-W+: both paths hold; the direct line has more margin (4,500 vs 4,200 kg) "
                     "and is faster (10 vs 20 s)")


def test_each_load_panel_draws_its_limit_and_its_verdict_with_one_legend_beside_them(figures):
    ts = _ts()
    ts["binding"] = "base_mx_nm"
    pl.load_series(ts, ["tau_j2_nm", "tau_j3_nm"], LIMITS, "Joint torques carrying 4000 kg", "t.png")
    pl.load_series(ts, ["base_mx_nm"], LIMITS, "Base disturbance moment carrying 4000 kg", "m.png")
    torques, moment = figures
    direct, planned = (ax for ax in moment.axes if ax.get_title())
    assert direct.get_title().startswith("direct line EXCEEDS a limit: M_x at 105 % of its 500 N m limit")
    assert planned.get_title().startswith("planned path within limits: peak M_x at 97 % of its 500 N m limit")
    assert moment._suptitle.get_text() == ("Base disturbance moment carrying 4000 kg: direct line FAILS (105 %); planned "
                                           "path within limits (97 %); capacity bound by base M_x")
    assert "direct line within limits (43 %) but fails on M_x" in torques._suptitle.get_text()
    assert "capacity bound by base M_x" in torques._suptitle.get_text()  # the binding load, though not drawn here
    for fig, lim in ((torques, 700.0), (moment, 500.0)):
        _one_line(fig)
        assert len(fig.legends) == 1 and not [ax for ax in fig.axes if ax.get_legend()]  # one legend for both
        for ax in fig.axes:
            levels = {round(float(line.get_ydata()[0]), 6) for line in ax.get_lines() if len(set(line.get_ydata())) == 1}
            assert {lim, -lim} <= levels
    labels = [t.get_text() for t in moment.legends[0].get_texts()]
    assert "M_x (binds)" in labels and "weakest state (binds)" in labels
    for ax in moment.axes:  # the binding load drawn thick, its weakest state marked on it
        assert max(line.get_linewidth() for line in ax.get_lines()) > 2
        assert [line for line in ax.get_lines() if line.get_marker() == "X"]


def test_loads_far_under_their_limits_share_one_grey_entry(figures):
    ts = _ts()
    ts["tau_j5_nm"], ts["tau_j6_nm"] = 5.0, -3.0
    limits = {**LIMITS, "tau_j5_nm": 700.0, "tau_j6_nm": 700.0}
    pl.load_series(ts, ["tau_j2_nm", "tau_j3_nm", "tau_j5_nm", "tau_j6_nm"], limits, "Joint torques", "t.png")
    labels = [t.get_text() for t in figures[0].legends[0].get_texts()]
    assert "τ joints 5, 6: under 1 % of the limit" in labels and "τ joint 5" not in labels
    assert {"τ joint 2", "τ joint 3"} <= set(labels)


def test_a_short_stretch_over_a_limit_is_marked_and_the_motion_not_executed_is_named(figures):
    ts = _ts()
    direct = (ts.path == "direct").to_numpy()
    ts.loc[direct, "base_mx_nm"] = 100.0
    ts.loc[direct & np.isclose(ts.t_s, 5.0), "base_mx_nm"] = 900.0  # one sample over: too short to see
    ts.loc[direct & (ts.t_s > 6).to_numpy(), ["base_mx_nm", "tracked"]] = [np.nan, False]
    pl.load_series(ts, ["base_mx_nm"], LIMITS, "Base disturbance moment carrying 4000 kg", "m.png")
    ax = figures[0].axes[0]
    texts = {t.get_text(): t for t in ax.texts}
    assert "over its limit: t = 5.0-5.0 s" in texts
    y = texts["over its limit: t = 5.0-5.0 s"].xy[1]
    assert 500.0 < y < ax.get_ylim()[1]  # between the limit line and the edge, off the line
    assert any("tracking lost at 6.3 s: the rest (6.3-10.0 s) not executed" in t for t in texts)
    red = [p for p in ax.patches if mcolors.to_hex(p.get_facecolor()[:3]) == mcolors.to_hex("tab:red")]
    assert red and min(p.get_width() for p in red) >= 0.015 * 10 - 1e-9  # a visible width, though one sample


def test_a_load_off_scale_is_marked_on_the_edge_it_leaves_by(figures):
    ts = _ts()
    direct = (ts.path == "direct").to_numpy()
    ts.loc[direct & np.isclose(ts.t_s, 5.0), "tau_j2_nm"] = -6000.0  # far below: off scale at the bottom
    ts.loc[direct & np.isclose(ts.t_s, 6.0), "tau_j3_nm"] = 3500.0  # far above: off scale at the top
    pl.load_series(ts, ["tau_j2_nm", "tau_j3_nm"], LIMITS, "Joint torques carrying 4000 kg", "t.png")
    ax = figures[0].axes[0]
    lo, hi = ax.get_ylim()
    marks = {line.get_marker(): line.get_ydata()[0] for line in ax.get_lines() if line.get_marker() in ("^", "v")}
    assert marks["v"] < 0.9 * lo and marks["^"] > 0.9 * hi  # each on its own edge
    texts = [t.get_text() for t in ax.texts]
    assert "τ joint 2: off scale, down to -857 % of the limit" in texts
    assert "τ joint 3: off scale, up to +500 % of the limit" in texts


def test_the_summary_map_draws_start_goal_and_paths_where_they_are(figures):
    vox = _map()
    start, goal = np.array([1.5, 1.5, 1.5]), np.array([4.5, 5.5, 5.5])
    view = SimpleNamespace(start_m=start, goal_m=goal, payloads_kg=(3200.0, 9000.0))
    path = np.array([start, [2.5, 2.5, 3.5], goal])
    pc.capacity_map(vox, view, "m.png", None, "", [("direct line", np.stack([start, goal]), {"color": "k"}, None),
                                                   ("A* plan for 3200 kg: holds (4,100 kg)", path,
                                                    {"color": PATH_COLOURS[0]}, np.array([4100.0, 4300.0]))],
                    "3200 kg holds only on its A* plan")
    fig = figures[0]
    text = figure_texts(fig)
    _one_line(fig)
    assert "tab:" not in text and "9000 kg: none here" in text
    assert fig._suptitle.get_text().endswith("; 3200 kg holds only on its A* plan")
    assert "A* plan for 3200 kg: holds (4,100 kg)" in text
    assert "right panel" in text  # the zoomed box named
    reached = vox.capacity_kg[vox.n_reachable > 0]
    share = 100 * (reached >= 3200).mean()
    assert "of the reachable voxels carry 3200 kg" in fig._suptitle.get_text() and f"{share:.0f} %" in text
    assert f"0 kg voxels: {100 * (reached == 0).mean():.0f} %" in text  # the 0 kg voxels' share, apart
    curve = fig.axes[0].get_lines()[0]
    assert curve.get_ydata()[0] == pytest.approx(100 * (reached > 0).mean())  # starts at M > 0, not at 100 %
    core = next(c for c in fig.axes[2].collections if type(c).__name__ == "LineCollection")
    np.testing.assert_allclose(core.get_array(), [4100.0, 4300.0])  # the path coloured by its own capacity
    d = np.hypot(*(goal - start)[:2])
    for ax in fig.axes[1:3]:  # both map panels: start and goal at their own place on the plane
        marks = [line for line in ax.get_lines() if line.get_marker() in ("o", "*")]
        xy = {line.get_marker(): (line.get_xdata()[0], line.get_ydata()[0]) for line in marks}
        assert xy["o"] == pytest.approx((0.0, start[2])) and xy["*"] == pytest.approx((d, goal[2]))
        for label in [t for t in ax.texts if t.get_text().endswith(" kg")]:  # contour labels: inside the view
            x, y = label.get_position()
            assert ax.get_xlim()[0] < x < ax.get_xlim()[1] and ax.get_ylim()[0] < y < ax.get_ylim()[1]
    hatched = [c for c in fig.axes[1].collections if c.get_hatch()]
    zero_cells = sum(int(np.count_nonzero(~np.ma.getmaskarray(c.get_array()))) for c in hatched)
    img = fig.axes[1].get_images()[0].get_array()
    assert zero_cells == int(np.count_nonzero(img.filled(np.nan) == 0))  # every 0 kg cell hatched, whole
    assert "not reached (white)" in text


def _page_traces(page: str) -> list[dict]:
    return json.loads(re.search(r'Plotly.newPlot\(\s*"capmap-3d",\s*(\[.*?\]),\s*\{"template"', page, re.S).group(1))


def test_the_3d_page_opens_readable_with_one_meaning_per_colour():
    vox = _map()
    r = vox[vox.n_reachable > 0]
    path = PlannedPath("planned path, 3200 kg (5.00 m)", np.array([[1.5, 1.5, 1.5], [2.5, 2.5, 2.5]]),
                       moves_kg=np.array([np.nan, 4100.0]), group="main task: starts on S-E-W+", on_map=(0, 2))
    task = PlannedPath("task t: planned path, 3200 kg (4.00 m)", np.array([[0.5, 0.5, 0.5], [0.5, 3.5, 0.5]]), ends="t",
                       verdict="verified: holds, weakest segment 4,149 kg (+29.7 %)", group="task t: starts on S+E-W-",
                       on_map=(1, 2))
    line = PlannedPath("t: direct line", task.points_m[[0, -1]], ends="t", direct=True, group=task.group,
                       verdict="verified: FAILS, tracking lost at t = 1.0 s", on_map=(1, 2))
    xyz, cap = r[["x_m", "y_m", "z_m"]].to_numpy(), r.capacity_kg.to_numpy()
    page = capacity_3d_html([("configuration S-E-W+", xyz, cap), ("configuration S+E-W-", xyz, 2 * cap),
                             ("any configuration", xyz, cap / 2)], EDGE, np.array([1.5, 1.5, 1.5]),
                            np.array([2.5, 2.5, 2.5]), [path, task, line], (3200.0,), "t")
    traces = {t["name"]: t for t in _page_traces(page)}
    layout = json.loads(re.search(r'\{"template".*?\}(?=,\s*\{"displaylogo")', page, re.S).group(0))
    assert layout["title"]["text"] == "t"  # the headline as given, one line
    cubes = next(t for n, t in traces.items() if n.startswith("voxels carrying the payload: cubes"))
    assert cubes["opacity"] == 1 and cubes["cmax"] == cap.max()  # solid, on the first map's own scale
    heights = json.loads(page.split(", H = ")[1].split(", B = ")[0])
    assert heights[0] == 0.5 and "zmax = H[0]" in page  # cut under the main task's paths (start 1.5 m: the layer 0.5 m)
    assert layout["sliders"][1]["active"] == 0 and layout["updatemenus"][-1]["active"] == 1
    assert layout["scene"]["zaxis"]["title"]["text"] == "z" and layout["scene"]["zaxis"]["ticksuffix"] == " m"
    assert traces["planned path, 3200 kg (5.00 m)<br>   each move carries ≥ 4,100 kg along its direction"]["visible"]
    for name in ("task t: planned path", "t: direct line", "t: start"):  # planned on another map: a click away
        trace = next(t for n, t in traces.items() if n.startswith(name))
        assert trace["visible"] == "legendonly" and trace["meta"]["maps"] == [1, 2]
    data = json.loads(page.split("const M = ")[1].split(", L = ")[0])
    assert [m["cmax"] for m in data] == pytest.approx([cap.max(), 2 * cap.max(), cap.max() / 2])  # each map's scale
    assert "const P = [[" in page and "paths();" in page  # the map buttons show that map's paths
    zero = next(t for n, t in traces.items() if n.startswith("0 kg"))
    assert zero["visible"] == "legendonly" and len(zero["x"]) == int((r.capacity_kg == 0).sum())
    below = next(t for n, t in traces.items() if n.startswith("voxels below"))
    assert below["visible"] == "legendonly"
    assert cubes["type"] == "mesh3d" and cubes.get("visible", True) is True
    assert min(cubes["intensity"]) >= 3200 and len(cubes["x"]) == 4 * len(cubes["i"]) // 2  # 4 corners, 2 triangles
    centres = traces["voxels carrying the payload"]  # hover only: the cubes draw them
    assert len(centres["x"]) == int((r.capacity_kg >= 3200).sum()) and centres["marker"]["opacity"] == 0
    planned = next(t for n, t in traces.items() if n.startswith("planned path, 3200 kg (5.00 m)"))
    assert "each move carries ≥ 4,100 kg" in planned["name"] and planned["line"]["width"] >= 8
    verified = next(t for n, t in traces.items() if n.startswith("task t: planned path"))
    assert "weakest segment 4,149 kg" in verified["name"] and "carries ≥" not in verified["name"]  # the verified number
    assert verified["mode"] == "lines+markers" and verified["legendgrouptitle"]["text"] == "task t: starts on S+E-W-"
    assert "tracking lost" in traces["t: direct line<br>   verified: FAILS, tracking lost at t = 1.0 s"]["name"]
    assert {"t: start", "t: goal"} <= set(traces)  # a further task's ends: markers named in the legend, no scene text
    colour = {n: mcolors.to_hex(t.get("line", t.get("marker", {})).get("color", "none")) for n, t in traces.items()
              if not n.startswith("voxels carrying")}
    assert colour[zero["name"]] == mcolors.to_hex("red")
    assert {colour["direct line"], colour["start"], colour["goal"]} == {mcolors.to_hex("black")}
    assert traces["direct line"]["line"].get("dash", "solid") == "solid"  # as its legend entry draws it
    assert traces["direct line"]["meta"]["maps"] == [0, 2]  # the main task's: on its paths' maps
    assert colour[planned["name"]] not in {mcolors.to_hex("red"), mcolors.to_hex("black")}
    assert colour["t: start"] == colour[verified["name"]] == colour[line.label + "<br>   " + line.verdict]
    assert layout["scene"]["camera"]["projection"]["type"] == "orthographic"


def test_the_cubes_are_the_faces_no_neighbour_covers():
    ijk = np.array([[0, 0, 0], [1, 0, 0], [5, 5, 5]])
    mesh = cube_faces(ijk, ijk * 0.75, 0.75)
    assert len(mesh["x"]) == 4 * (10 + 6) and len(mesh["i"]) == 2 * (10 + 6)  # two touching cubes: 10 faces
    assert sorted(np.bincount(mesh["owner"]).tolist()) == [20, 20, 24]
    xyz = np.c_[mesh["x"], mesh["y"], mesh["z"]]
    np.testing.assert_allclose(np.abs(xyz - (ijk * 0.75)[mesh["owner"]]), 0.375)  # corners of each cube
    quads = xyz.reshape(-1, 4, 3)
    assert not np.any(np.all(np.isclose(quads[:, :, 0], 0.375), axis=1))  # the face between the two: not drawn


def test_the_baseline_and_atlas_figures_state_what_the_failure_cost(figures):
    vox = _map()
    b = vox[["i", "j", "k", "x_m", "y_m", "z_m"]].copy()
    b["healthy_capacity_kg"] = 4000.0
    b["capacity_kg"] = b["arm_configuration_capacity_kg"] = np.where(b.i < 4, 3500.0, 1000.0)
    b["arm_configuration_loss_kg"] = b.healthy_capacity_kg - b.arm_configuration_capacity_kg
    conv = pd.DataFrame({"shortfall_rel": [-0.01, 0.002, 0.03]})
    ctx = pb.BaselineContext("S-E-W+", 1, 100.0, 10.0, 1.0, EDGE, np.array([1.5, 1.5, 1.5]), (1500.0, 3800.0))
    pb.baseline_figure(b, conv, ctx, "loss.png")
    title = figures[0]._suptitle.get_text()
    assert "1500 kg: 512 → 256 m³ on S-E-W+ (50 % lost)" in title and "3800 kg: 512 → 0 m³ on S-E-W+ (100 % lost)" in title
    assert "against a 1 deg sweep, 3 checked voxels lie 3 % below at most (1 by more than 1 %)" in title
    atlas = pd.DataFrame({"joint": [1, 1, 4, 4], "angle_deg": [100.0, 130.0, 100.0, 130.0], "payload_kg": 1500.0,
                          "reachable_volume_m3": [4900.0, 4800.0, 1800.0, 1000.0],
                          "capacity_median_kg": [1900.0, 1800.0, 0.0, 0.0],
                          "volume_carrying_payload_m3": [4300.0, 4100.0, 450.0, 160.0],
                          "plan_exists": [True, True, False, False], "direct_feasible": [True, False, False, False]})
    pa.atlas_heatmap(atlas, "heat.png")
    text = figure_texts(figures[1])
    assert "most with joint 1 at 100 deg (4,300 m³), least with joint 4 at 130 deg (160 m³)" in text
    assert "plan + direct" in text and "no path" in text


def test_the_summary_labels_each_path_with_its_verified_verdict_else_its_planned_moves(tmp_path):
    from capmap.io import datasets
    from capmap.stages.capacity_figures import MapView, _map_paths

    view = MapView(np.zeros(3), np.ones(3), (1500.0, 4000.0))
    wps = []
    for m in view.payloads_kg:
        wp = pd.DataFrame({"x_m": [0.0, 0.5, 1.0], "y_m": [0.0, 0.5, 1.0], "z_m": [0.0, 0.5, 1.0],
                           "move_capacity_kg": [np.nan, 4140.0, 4200.0]})
        datasets.write(wp, tmp_path / f"wp{m:g}.parquet", {"payload_kg": m, "status": "ok", "cost_m": 1.7})
        wps.append(str(tmp_path / f"wp{m:g}.parquet"))
    pd.DataFrame({"payload_kg": [4000.0, 4000.0], "path": ["direct", "planned"], "capacity_kg": [3820.0, 4149.0],
                  "feasible": [False, True]}).to_csv(tmp_path / "v.csv", index=False)
    paths, verdict = _map_paths(view, wps, [str(tmp_path / "v.csv")])
    labels = [label for label, *_ in paths]
    assert labels[0] == "direct line: 3,820 kg, 4000 kg FAILS"
    assert labels[1] == "A* plan for 1500 kg: moves ≥ 4,140 kg (not verified)"
    assert labels[2] == "A* plan for 4000 kg: holds (4,149 kg)"
    np.testing.assert_allclose(paths[2][3], [4140.0, 4200.0])  # each piece's own capacity, for its colour
    np.testing.assert_allclose(paths[0][3], [3820.0])
    assert verdict == "4000 kg holds only on its A* plan"
