"""The plan-gain experiment as a family function: its payloads, its random tasks (drawn only
between voxels carrying the payload, far enough apart, the same tasks for the same seed) and its
summary counts, checked against counts made directly from the task table and against the planner
itself on a map where only direction-aware moves pass."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from capmap.capacity import planning
from capmap.capacity.gain import MIN_SEPARATION, GainMap, gain_payloads, gain_summary, gain_tasks
from capmap.capacity.voxels import Grid


def test_payloads_are_the_task_payloads_and_rounded_percentiles():
    cap = np.array([np.nan, 0.0, 1000.0, 2000.0, 3000.0, 4000.0])
    payloads, sweep = gain_payloads(cap, [1500, 4000])
    positive = np.array([1000.0, 2000.0, 3000.0, 4000.0])
    assert sweep == [round(np.percentile(positive, q), -2) for q in (50, 75, 90)] == [2500.0, 3200.0, 3700.0]
    assert payloads == [1500.0, 2500.0, 3200.0, 3700.0, 4000.0]
    assert gain_payloads(np.full(3, np.nan), [100]) == ([100.0], [])


class _NeverTracked:
    """A verifier stand-in for maps without an arm: no branch at the start (no IK solutions)."""

    class _Arm:
        pass

    def __init__(self):
        self.dyn = type("Dyn", (), {"arm": self._Arm()})()
        self.rotation = np.eye(3)


def _corridor_map():
    """A 9 x 3 x 1 grid: row 1 carries 2000 kg every way; rows 0 and 2 nothing. The along-x axis
    capacity of row 1 is high, so both planners agree there; the map is only for task drawing."""
    grid = Grid(lower=np.zeros(3), shape=(9, 3, 1), edge_m=1.0)
    idx = grid.all_indices()
    cap = np.where(idx[:, 1] == 1, 2000.0, np.nan)
    axis = np.where(np.isfinite(cap)[:, None], 2000.0, np.nan) * np.ones((1, 13))
    return GainMap(grid, cap, axis, idx)


def test_tasks_join_voxels_that_carry_the_payload_far_enough_apart(monkeypatch):
    import capmap.capacity.gain as gain
    monkeypatch.setattr(gain.ik, "solve", lambda arm, pos, rot: type("S", (), {"n_solutions": np.zeros(1, int)})())
    gm = _corridor_map()
    rng = np.random.default_rng(3)
    tasks = gain_tasks(gm, _NeverTracked(), [1000.0, 2500.0], 12, rng)
    assert set(tasks.payload_kg) == {1000.0}  # no voxel carries 2500 kg: no tasks for it
    assert len(tasks) == 12
    s = gm.grid.index(tasks[["start_x_m", "start_y_m", "start_z_m"]].to_numpy())
    g = gm.grid.index(tasks[["goal_x_m", "goal_y_m", "goal_z_m"]].to_numpy())
    assert (s[:, 1] == 1).all() and (g[:, 1] == 1).all()
    assert (np.abs(s - g).max(axis=1) >= MIN_SEPARATION).all()
    for _, r in tasks.iterrows():  # both plans exist in the corridor, with the planner's own length
        p = planning.plan(gm.grid, gm.capacity_kg, [r.start_x_m, r.start_y_m, r.start_z_m],
                          [r.goal_x_m, r.goal_y_m, r.goal_z_m], r.payload_kg)
        assert r.isotropic_path and r.axis_path and r.isotropic_length_m == pytest.approx(p.length_m, rel=1e-12)
        assert r.verified_branch == -1 and not r.verified_feasible  # no branch tracked it
    again = gain_tasks(gm, _NeverTracked(), [1000.0, 2500.0], 12, np.random.default_rng(3))
    pd.testing.assert_frame_equal(tasks, again)  # the same seed draws the same tasks


def test_summary_counts_what_the_table_says():
    rng = np.random.default_rng(0)
    n = 40
    t = pd.DataFrame({"payload_kg": rng.choice([100.0, 200.0], n), "isotropic_path": rng.random(n) < 0.4,
                      "axis_path": rng.random(n) < 0.7, "verified_branch": rng.choice([-1, 0, 2], n),
                      "verified_capacity_kg": rng.uniform(0, 500, n), "verified_feasible": rng.random(n) < 0.5,
                      "direct_feasible": rng.random(n) < 0.3})
    s = gain_summary(t).set_index("payload_kg")
    for M in (100.0, 200.0):
        rows = [r for _, r in t.iterrows() if r.payload_kg == M]
        gained = [r for r in rows if r.axis_path and not r.isotropic_path]
        assert s.loc[M, "tasks"] == len(rows)
        assert s.loc[M, "gained_by_axis_moves"] == len(gained)
        assert s.loc[M, "lost_by_axis_moves"] == sum(r.isotropic_path and not r.axis_path for r in rows)
        assert s.loc[M, "gained_tracked"] == sum(r.verified_branch >= 0 for r in gained)
        assert s.loc[M, "gained_verified_carrying"] == sum(bool(r.verified_feasible) for r in gained)
        assert s.loc[M, "direct_line_fails_detour_carries"] == sum(r.verified_feasible and not r.direct_feasible
                                                                   for r in rows)
    assert gain_summary(pd.DataFrame()).empty
