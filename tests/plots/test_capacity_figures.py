"""The capacity family's figures tell their result from the data: each verified path's verdict and its own
capacity beside the map's voxels under it (the voxel's value read at the sample's voxel, along the grid axis
of its travel), each load panel its own limit and verdict with the legend off the curves, the summary map's
start, goal and paths where they are (not projected onto another layer), the 3D page opening with 0 kg voxels
hidden and one meaning per colour, the baseline's and the atlas' verdicts. Synthetic tables; the figures'
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
from capmap.plots.common import plt
from capmap.stages.verify_figures import under_path

EDGE = 1.0
SHAPE = (8, 8, 8)
LIMITS = {"tau_j2_nm": 700.0, "tau_j3_nm": 700.0, "base_fx_n": 200.0, "base_mx_nm": 500.0}


@pytest.fixture
def figures(monkeypatch):
    """The figures the plot functions would save, kept open for reading."""
    kept = []
    for module in (pc, pp, pl, pa, pb):
        monkeypatch.setattr(module, "save", lambda fig, out_png, rect=None: kept.append(fig))
    yield kept
    for fig in kept:
        plt.close(fig)


def _texts(fig) -> str:
    out = [fig._suptitle.get_text() if fig._suptitle else ""]
    for sub in getattr(fig, "subfigs", []):
        out.append(_texts(sub))
    for ax in fig.axes:
        out += [ax.get_title(), ax.get_xlabel(), ax.get_ylabel()] + [t.get_text() for t in ax.texts]
        if ax.get_legend():
            out += [t.get_text() for t in ax.get_legend().get_texts()]
    out += [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    return "\n".join(out)


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
    return [ax for ax in fig.axes if ax.get_ylabel() == "capacity [kg]"]


def test_the_workspace_figure_gives_each_path_its_verdict_and_where_it_fails(figures):
    vox = _map()
    vox["capacity_best_axis_kg"] = vox[AXIS_COLUMNS].max(axis=1)
    ts = _ts()
    ts.loc[(ts.path == "direct") & (ts.t_s > 8), "state_capacity_kg"] = np.inf  # cruising: unbounded
    pp.workspace_paths(vox, under_path(vox, ts), 4000.0, "w.png", "configuration S-E-W+", planner="A* moves")
    fig = figures[0]
    text = _texts(fig)
    assert "planned path holds: weakest segment 4149 kg (+3.7 % margin)" in text
    assert "direct line FAILS: weakest segment 3820 kg (-4.5 % margin)" in text
    assert "below 4000 kg while it moves (2.80-3.20 m)" in text  # where along the line, from its states
    title = fig._suptitle.get_text()
    assert "direct line fails (3,820 kg < 4000 kg), planned path holds (4,149 kg)" in title and "A* moves" in title
    assert "carries 4000 kg in every direction" in text and "along some grid axes only" in text
    direct, planned = _profiles(fig)
    for ax in (direct, planned):  # the payload drawn on each path's panel, 0 kg above the axis' bottom
        assert any(np.allclose(line.get_ydata(), 4000.0) for line in ax.get_lines())
        assert ax.get_ylim()[0] < 0
    own = ts[ts.path == "direct"].state_capacity_kg.to_numpy()
    thick = next(line for line in direct.get_lines() if line.get_linewidth() == 3)
    np.testing.assert_allclose(thick.get_ydata(), np.where(np.isfinite(own), own, np.nan))  # each state, not a min
    assert "∞" in [t.get_text() for t in direct.get_yticklabels()]  # the unbounded states drawn at ∞


def test_the_workspace_figure_says_where_tracking_was_lost_and_why_a_path_holds_on_weak_voxels(figures):
    vox = _map()
    vox["capacity_best_axis_kg"] = vox[AXIS_COLUMNS].max(axis=1)
    ts = _ts(planned_kg=5000.0)
    direct = (ts.path == "direct").to_numpy()
    lost = direct & (ts.t_s > 6).to_numpy()
    ts.loc[direct & (ts.t_s > 5).to_numpy(), "state_capacity_kg"] = 0.0
    ts.loc[lost, ["state_capacity_kg", "tracked"]] = [np.nan, False]
    path = under_path(vox, ts)
    path.loc[path.path == "planned", "voxel_kg"] = 0.0  # the voxels under it: 0 kg somewhere inside
    pp.workspace_paths(vox, path, 4000.0, "w.png", "configuration S-E-W+")
    text = _texts(figures[0])
    s_lost = path.distance_m[lost].iloc[0]
    assert f"direct line FAILS: tracking lost at {s_lost:.2f} m (t = " in text
    assert "0 kg from 3.20 m" in text and f"tracking lost at {s_lost:.2f} m:" in text
    assert "through voxels of down to 0 kg" in text and "carry ≥ 5,000 kg" in text
    marks = [line for line in _profiles(figures[0])[0].get_lines() if line.get_marker() == "X"]
    assert marks and marks[0].get_ydata()[0] == 0.0  # the 0 kg state marked, above the axis' bottom


def test_when_both_paths_hold_the_title_says_which_is_better_and_what_the_planner_seeks(figures):
    vox = _map()
    vox["capacity_best_axis_kg"] = vox[AXIS_COLUMNS].max(axis=1)
    pp.workspace_paths(vox, under_path(vox, _ts(4500.0, 4200.0)), 1500.0, "w.png", "configuration S-E-W+",
                       planner="the shortest chain of moves")
    title = figures[0]._suptitle.get_text()
    assert "both paths hold, and the direct line is the better motion here" in title
    assert "4,500 vs 4,200 kg, 10 vs 20 s" in title and "the plan is not needed" in title
    assert "the shortest chain of moves" in title and "does not seek the largest margin" in title


def test_each_load_panel_draws_its_limit_and_its_verdict_with_the_legend_beside_it(figures):
    ts = _ts()
    pl.load_series(ts, ["tau_j2_nm", "tau_j3_nm"], LIMITS, "Joint torques carrying 4000 kg", "t.png")
    pl.load_series(ts, ["base_mx_nm"], LIMITS, "Base disturbance moment carrying 4000 kg", "m.png")
    torques, moment = figures
    direct, planned = (ax for ax in moment.axes if ax.get_title())
    assert direct.get_title().startswith("direct line EXCEEDS a limit: M_x at 105 % of its 500 N m limit")
    assert planned.get_title().startswith("planned path within limits: peak M_x at 97 % of its 500 N m limit")
    assert "direct line FAILS (105 %); planned path within limits (97 %)" in moment._suptitle.get_text()
    assert "but exceeds M_x (base_moment.png)" in torques.axes[0].get_title()  # the torques hold, the line does not
    for fig, lim in ((torques, 700.0), (moment, 500.0)):
        for ax in fig.axes:
            levels = {round(float(line.get_ydata()[0]), 6) for line in ax.get_lines() if len(set(line.get_ydata())) == 1}
            assert {lim, -lim} <= levels
            anchor = ax.get_legend().get_bbox_to_anchor().transformed(ax.transAxes.inverted())
            assert anchor.x0 >= 1.0  # beside the axes, off the curves


def test_a_short_stretch_over_a_limit_is_marked_and_the_motion_not_executed_is_named(figures):
    ts = _ts()
    direct = (ts.path == "direct").to_numpy()
    ts.loc[direct, "base_mx_nm"] = 100.0
    ts.loc[direct & np.isclose(ts.t_s, 5.0), "base_mx_nm"] = 900.0  # one sample over: too short to see
    ts.loc[direct & (ts.t_s > 6).to_numpy(), ["base_mx_nm", "tracked"]] = [np.nan, False]
    pl.load_series(ts, ["base_mx_nm"], LIMITS, "Base disturbance moment carrying 4000 kg", "m.png")
    ax = figures[0].axes[0]
    texts = [t.get_text() for t in ax.texts]
    assert "over its limit: t = 5.0-5.0 s" in texts
    assert any("the rest of the" in t and "its planned end" in t and "6.3-10.0 s" in t for t in texts)


def test_the_summary_map_draws_start_goal_and_paths_where_they_are(figures):
    vox = _map()
    start, goal = np.array([1.5, 1.5, 1.5]), np.array([4.5, 5.5, 5.5])
    view = SimpleNamespace(start_m=start, goal_m=goal, payloads_kg=(3200.0, 9000.0))
    path = np.array([start, [2.5, 2.5, 3.5], goal])
    pc.capacity_map(vox, view, "m.png", None, "", [("direct start-goal line", np.stack([start, goal]), {"color": "k"}),
                                                   ("planned path, 3200 kg: each move carries ≥ 4,100 kg", path,
                                                    {"color": PATH_COLOURS[0]}, "the 3200 kg path holds: why")])
    fig = figures[0]
    text = _texts(fig)
    assert "tab:" not in text and "9000 kg: no voxel here" in text
    assert "each move carries ≥ 4,100 kg" in text and "the 3200 kg path holds: why" in text  # the note, on the map
    assert "right panel" in text  # the zoomed box named
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


def _page_traces(page: str) -> list[dict]:
    return json.loads(re.search(r'Plotly.newPlot\(\s*"capmap-3d",\s*(\[.*?\]),\s*\{"template"', page, re.S).group(1))


def test_the_3d_page_opens_readable_with_one_meaning_per_colour():
    vox = _map()
    r = vox[vox.n_reachable > 0]
    path = PlannedPath("planned path, 3200 kg (5.00 m)", np.array([[1.5, 1.5, 1.5], [2.5, 2.5, 2.5]]),
                       moves_kg=np.array([np.nan, 4100.0]), group="main task: starts on S-E-W+")
    task = PlannedPath("task t: planned path, 3200 kg (4.00 m)", np.array([[0.5, 0.5, 0.5], [0.5, 3.5, 0.5]]), ends="t",
                       verdict="verified: holds, weakest segment 4,149 kg (+29.7 %)", group="task t: starts on S+E-W-")
    line = PlannedPath("t: direct line", task.points_m[[0, -1]], ends="t", direct=True, group=task.group,
                       verdict="verified: FAILS, tracking lost at t = 1.0 s")
    page = capacity_3d_html([("configuration S-E-W+", r[["x_m", "y_m", "z_m"]].to_numpy(), r.capacity_kg.to_numpy())],
                            EDGE, np.array([1.5, 1.5, 1.5]), np.array([2.5, 2.5, 2.5]), [path, task, line], (3200.0,), "t")
    traces = {t["name"]: t for t in _page_traces(page)}
    zero = next(t for n, t in traces.items() if n.startswith("0 kg"))
    assert zero["visible"] == "legendonly" and len(zero["x"]) == int((r.capacity_kg == 0).sum())
    below = next(t for n, t in traces.items() if n.startswith("voxels below"))
    assert below["visible"] == "legendonly"
    cubes = next(t for n, t in traces.items() if n.startswith("voxels carrying the payload: cubes"))
    assert cubes["type"] == "mesh3d" and cubes.get("visible", True) is True and cubes["opacity"] <= 0.5  # see-through
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
    assert colour[planned["name"]] not in {mcolors.to_hex("red"), mcolors.to_hex("black")}
    assert colour["t: start"] == colour[verified["name"]] == colour[line.label + "<br>   " + line.verdict]
    layout = json.loads(re.search(r'\{"template".*?\}(?=,\s*\{"displaylogo")', page, re.S).group(0))
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
    conv = pd.DataFrame({"rise_half_step_rel": [0.001, 0.02], "rise_quarter_step_rel": [0.002, 0.03]})
    ctx = pb.BaselineContext("S-E-W+", 1, 100.0, 10.0, EDGE, np.array([1.5, 1.5, 1.5]), (1500.0, 3800.0))
    pb.baseline_figure(b, conv, ctx, "loss.png")
    title = figures[0]._suptitle.get_text()
    assert "1500 kg: 512 → 256 m³ on S-E-W+ (50 % lost)" in title and "3800 kg: 512 → 0 m³ on S-E-W+ (100 % lost)" in title
    assert "2 checked voxels rise by" in title and "3 % at most" in title
    atlas = pd.DataFrame({"joint": [1, 1, 4, 4], "angle_deg": [100.0, 130.0, 100.0, 130.0], "payload_kg": 1500.0,
                          "reachable_volume_m3": [4900.0, 4800.0, 1800.0, 1000.0],
                          "capacity_median_kg": [1900.0, 1800.0, 0.0, 0.0],
                          "volume_carrying_payload_m3": [4300.0, 4100.0, 450.0, 160.0],
                          "plan_exists": [True, True, False, False], "direct_feasible": [True, False, False, False]})
    pa.atlas_heatmap(atlas, "heat.png")
    text = _texts(figures[1])
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
    labels = [label for label, *_ in _map_paths(view, wps, [str(tmp_path / "v.csv")])]
    assert labels[0] == "direct start-goal line, verified: 4000 kg FAILS (-4.5 %)"
    assert labels[1] == "planned path, 1500 kg: each move carries ≥ 4,140 kg along its own direction"  # not verified
    assert labels[2] == "planned path, 4000 kg, verified: holds (+3.7 %), weakest segment 4,149 kg"
