"""The stored rows of a follower time series (capmap.following.tables.stored_rows), against a
brute-force reading of what a plot of them must keep."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from capmap.following.tables import stored_rows


def _series(rng, lengths, joints=(2, 3, 4)):
    parts = []
    for k, n in enumerate(lengths):
        df = pd.DataFrame({"case": "x", "segment": k, "t_s": np.arange(n) * 1e-3 + 10 * k,
                           "limited": rng.random(n) < 0.02, "infeasible": np.zeros(n, bool)})
        df.loc[n // 3:n // 2, "infeasible"] = True
        for j in joints:
            df[f"tau_j{j}_nm"] = rng.normal(scale=50.0 * j, size=n).astype(np.float32)
            df[f"tau_cmd_j{j}_nm"] = rng.normal(size=n)  # not a tau_j* column: not in the peak
        parts.append(df)
    return pd.concat(parts, ignore_index=True)


@pytest.mark.parametrize("every", [1, 7, 10, 1000])
def test_stored_rows_keep_the_grid_the_ends_the_flag_changes_and_every_windows_peak(every):
    rng = np.random.default_rng(every)
    ts = _series(rng, [523, 1, 88, 2000])
    limit = np.array([100.0, 400.0, 150.0])
    out = stored_rows(ts, every, limit)
    if every == 1:
        assert out.equals(ts)
        return
    kept = set(map(tuple, out[["segment", "t_s"]].itertuples(index=False)))
    ratio = (ts[["tau_j2_nm", "tau_j3_nm", "tau_j4_nm"]].abs() / limit).max(axis=1)
    for seg, g in ts.groupby("segment"):
        rows = g.reset_index(drop=True)
        for w0 in range(0, len(rows), every):  # each window: its first row and its peak row kept
            assert (seg, rows.t_s[w0]) in kept
            peak = ratio[g.index[w0:w0 + every]].idxmax()
            assert (seg, ts.t_s[peak]) in kept
        assert (seg, rows.t_s.iloc[-1]) in kept
        for flag in ("limited", "infeasible"):  # both sides of every change
            change = np.flatnonzero(rows[flag].to_numpy()[1:] != rows[flag].to_numpy()[:-1])
            assert all((seg, rows.t_s[i]) in kept and (seg, rows.t_s[i + 1]) in kept for i in change)
    assert out.t_s.is_monotonic_increasing and len(out) < len(ts)
    assert np.isclose((out[["tau_j2_nm", "tau_j3_nm", "tau_j4_nm"]].abs() / limit).max(axis=1).max(), ratio.max())
    assert len(out) <= 2 * len(ts) / every + 4 * ts.limited.sum() + 40  # it does thin
