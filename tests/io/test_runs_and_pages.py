"""Run folders (stale outputs), the report's table pages and the interactive 3D map page."""

from __future__ import annotations

import json
import re

import numpy as np
import pandas as pd

from capmap.io.html_tables import quantity_label, table_html
from capmap.io.runs import stale_outputs
from capmap.plots.capacity_3d import PlannedPath, capacity_3d_html, slider_levels


def _traces(page: str) -> list[dict]:
    """The traces of the 3D page's figure, as plotly wrote them."""
    return json.loads(re.search(r'Plotly.newPlot\(\s*"capmap-3d",\s*(\[.*?\]),\s*\{"template"', page, re.S).group(1))


def test_stale_outputs_are_what_the_config_no_longer_makes(tmp_path):
    run = tmp_path / "results" / "default"
    for d in ("verify/payload_1500kg", "verify/payload_4000kg", "tasks/a", "tasks/b"):
        (run / d).mkdir(parents=True)
    (run / "capacity").mkdir()
    for f in ("shard_0_of_2.parquet", "shard_1_of_2.parquet", "shard_0_of_4.parquet"):
        (run / "capacity" / f).touch()
    stale = stale_outputs(run, {"verify/payload_*kg": ["verify/payload_1500kg"], "tasks/*": ["tasks/a"],
                                "capacity/shard_*_of_*.parquet": ["capacity/shard_0_of_2.parquet",
                                                                  "capacity/shard_1_of_2.parquet"],
                                "dualarm": []})
    assert stale == sorted(str(run / p) for p in ("verify/payload_4000kg", "tasks/b", "capacity/shard_0_of_4.parquet"))
    assert stale_outputs(tmp_path / "results" / "other", {"tasks/*": []}) == []


def test_quantity_labels_carry_the_unit_of_the_column_suffix():
    assert quantity_label("capacity_kg") == "capacity [kg]"
    assert quantity_label("tau_j3_nm") == "tau j3 [N m]"
    assert quantity_label("qd_j2_deg_s") == "qd j2 [deg/s]"
    assert quantity_label("base_fx_n") == "base fx [N]"
    assert quantity_label("path") == "path" and quantity_label("binding") == "binding"


def test_a_table_page_has_its_caption_and_escapes_cells():
    df = pd.DataFrame({"payload_kg": [1500.0, 1500.0], "path": ["direct", "planned"],
                       "capacity_kg": [1234.5678, 2000.0], "note": ["<b>x</b>", ""]})
    page = table_html(df, "Verification", "What it shows.", transpose=True)
    assert "<h2>Verification</h2>" in page and "What it shows." in page
    assert "<th>1500 kg, direct</th>" in page and "<th>capacity [kg]</th>" in page
    assert "&lt;b&gt;x&lt;/b&gt;" in page and "<b>x</b>" not in page
    assert "1234.6" in page and "http" not in page


def test_slider_levels_start_at_zero_reach_the_top_and_hold_the_payloads():
    cap = np.array([0.0, 120.0, 3999.0])
    lv = slider_levels(cap, (1500.0, 4000.0))
    assert lv[0] == 0 and lv[-1] >= 3999.0 and {1500.0, 4000.0} <= set(lv) and np.all(np.diff(lv) > 0)
    assert len(lv) <= 24


def test_the_3d_page_is_offline_and_holds_every_voxel_and_path():
    """Two maps (the arm's configuration first, the bound second): each map's voxels in the page's data,
    the first shown at the first payload, a button per map, the paths, start and goal."""
    rng = np.random.default_rng(0)
    xyz = rng.uniform(-5, 5, (300, 3))
    cap = rng.uniform(0, 5000, 300)
    bound = np.minimum(cap, rng.uniform(0, 5000, 300))[:250]
    path = PlannedPath("planned path, 1500 kg (3.00 m)", np.array([[0, 0, 0], [1, 0, 0], [1, 2, 0.0]]))
    page = capacity_3d_html([("configuration S+E+W+", xyz, cap), ("any configuration", xyz[:250], bound)], 0.75,
                            np.zeros(3), np.array([1, 2, 0.0]), [path], (1500.0,), "test map")
    assert not re.search(r"<script[^>]+src=", page)  # plotly.js inlined, nothing fetched at view time
    assert "Plotly.restyle" in page and "plotly_sliderchange" in page and "plotly_buttonclicked" in page
    data = json.loads(re.search(r"const M = (\[.*?\]), L = ", page).group(1))
    levels = json.loads(re.search(r", L = (\[.*?\]), H = ", page).group(1))
    for m, (x, c) in zip(data, ((xyz, cap), (xyz[:250], bound))):
        np.testing.assert_allclose(np.c_[m["x"], m["y"], m["z"]], x, atol=5e-4)  # the page's mm
        np.testing.assert_allclose(m["c"], c, atol=0.05)  # and 0.1 kg
    assert 1500.0 in levels
    fig = _traces(page)
    shown = next(t for t in fig if t.get("name") == "voxels carrying the payload")
    assert len(shown["x"]) == int((cap >= 1500).sum()) and min(shown["marker"]["color"]) >= 1500
    assert any(t.get("name") == path.label for t in fig) and {"start", "goal", "direct line"} <= {t.get("name") for t in fig}
    assert re.search(r'"label":\s*"configuration S\+E\+W\+"', page) and re.search(r'"label":\s*"any configuration"', page)


def test_the_3d_page_shows_0_kg_voxels_cuts_by_height_fixes_its_axes_and_names_the_binding_limit():
    """The 0 kg voxels as their own trace (exactly those), a height slider over every voxel layer, axes
    fixed to the data (not rescaled at each redraw), and hover text with the binding limit."""
    rng = np.random.default_rng(1)
    xyz = np.round(rng.uniform(-3, 3, (200, 3)) / 0.75) * 0.75
    cap = np.where(rng.random(200) < 0.2, 0.0, rng.uniform(1, 4000, 200))
    bind = np.array(["tau_j2_nm", "base_mx_nm"], dtype=object)[rng.integers(0, 2, 200)]
    page = capacity_3d_html([("configuration S+E+W+", xyz, cap, bind)], 0.75, np.zeros(3), np.ones(3), [], (1500.0,), "t")
    fig = _traces(page)
    zero = next(t for t in fig if t.get("name", "").startswith("0 kg"))
    np.testing.assert_allclose(np.c_[zero["x"], zero["y"], zero["z"]], xyz[cap == 0])
    assert all(", bound by " in t for t in zero["text"])
    heights = json.loads(re.search(r", H = (\[.*?\]), B = ", page).group(1))
    assert sorted(heights) == sorted(set(np.round(xyz[:, 2], 4)))
    text = page.replace("\\u003c", "<")  # plotly's JSON escapes '<'
    assert '"autorange":false' in text.replace(" ", "") and "show z [m] <= " in text and '"uirevision"' in text


def test_the_3d_page_draws_every_tasks_path_with_its_ends_named_and_keeps_it_in_view():
    """A further task's path as its own trace (its waypoints, its name at its start and goal) and the
    fixed axes wide enough for it, even where it leaves the voxels' extent."""
    xyz = np.array([[0.0, 0, 0], [0.75, 0, 0], [0, 0.75, 0.75]])
    task = PlannedPath("task over_the_top: planned path, 3200 kg (7.37 m)",
                       np.array([[0, 0, 0], [0, 0, 4.0], [0.75, 0, 4.0], [0.75, 0, 0]]), ends="over_the_top")
    page = capacity_3d_html([("configuration S+E+W+", xyz, np.array([1.0, 2.0, 3.0]))], 0.75, np.zeros(3),
                            np.array([0.75, 0, 0]), [task], (1500.0,), "t")
    fig = _traces(page)
    trace = next(t for t in fig if t.get("name", "").startswith("task over_the_top"))
    np.testing.assert_allclose(np.c_[trace["x"], trace["y"], trace["z"]], task.points_m)
    assert trace["text"][0] == "over_the_top: start" and trace["text"][-1] == "over_the_top: goal"
    zrange = json.loads(re.search(r'"zaxis":\{"title":\{[^}]*\},"range":(\[[^\]]*\])', page.replace(" ", "")).group(1))
    assert zrange[1] >= 4.0
