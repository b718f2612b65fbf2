"""Figure of the lock-angle advice: every task's margin against the angle a joint is braked at."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from capmap.plots.common import legend_beside, plt, save

__all__ = ["advice_figure"]


def _label(task: str, payload: float) -> str:
    return f"{task}, {payload:g} kg" if task != "task" else f"the task, {payload:g} kg"


def advice_figure(rows: pd.DataFrame, healthy: pd.DataFrame, advice: pd.Series, conv: pd.DataFrame,
                  out_png: str | Path) -> None:
    """Two panels against the lock angle of one joint: every task's verified margin (its better path:
    direct line or planned; filled where it carries the payload) with the recommended angle and the one the
    joint stands at; and the map's margin along each task's direct line, the healthy arm's as reference."""
    fig, ax = plt.subplots(2, 1, figsize=(12, 9), sharex=True, layout="constrained")
    groups = list(rows.groupby(["task", "payload_kg"], sort=False))
    for n, ((task, m), g) in enumerate(groups):
        g = g.sort_values("angle_deg")
        colour = f"C{n % 10}"
        label = _label(task, m)
        ax[0].plot(g.angle_deg, g.margin_pct, "-", color=colour, lw=1.5, label=label)
        ok = g.feasible.to_numpy()
        ax[0].plot(g.angle_deg[ok], g.margin_pct[ok], "o", color=colour, ms=5)
        ax[0].plot(g.angle_deg[~ok], g.margin_pct[~ok], "o", mfc="white", mec=colour, ms=5)
        ax[1].plot(g.angle_deg, g.line_margin_pct, "-", color=colour, lw=1.5, label=f"{label}: joint locked")
        h = healthy[(healthy.task == task) & (healthy.payload_kg == m)].line_margin_pct
        if len(h):
            ax[1].axhline(float(h.iloc[0]), color=colour, ls=":", lw=1.8,
                          label=f"{label}: healthy arm\n(each voxel at its best swept angle)")
    rec, here = float(advice.recommended_angle_deg), float(advice.stands_at_deg)
    for a in ax:
        a.axhline(0.0, color="black", lw=1)
        a.axhline(-100.0, color="0.5", lw=1, ls="--")
        a.axvline(rec, color="tab:green", lw=2.5, alpha=0.6)
        a.axvline(here, color="0.4", lw=1.2, ls="--")
        a.grid(alpha=0.3)
    t = ax[0].get_xaxis_transform()
    ax[0].text(rec, 1.01, f"recommended {rec:g} deg", transform=t, color="tab:green", ha="center", va="bottom",
               fontsize=9)
    ax[0].text(here, 1.01 if abs(here - rec) > 25 else 1.07, f"stands at {here:g} deg", transform=t, color="0.3",
               ha="center", va="bottom", fontsize=9)
    ax[0].plot([], [], "o", color="0.3", label="carries its payload (verified)")
    ax[0].plot([], [], "o", mfc="white", mec="0.3", label="does not")
    ax[0].plot([], [], "-", color="black", lw=1, label="0 %: the payload exactly")
    ax[0].plot([], [], "--", color="0.5", lw=1, label="-100 %: carries nothing\n(or the start is out of reach)")
    ax[0].set(ylabel="verified margin [% of the payload]\n(best of direct line, planned paths)")
    ax[1].set(xlabel=f"angle joint {int(advice.joint)} is braked at [deg]",
              ylabel="map margin on the direct line [% of the payload]\n(least voxel capacity on it: any branch,"
                     " any direction;\na lower bound of what a path verifies)")
    legend_beside(ax[0])
    legend_beside(ax[1])
    steps = ", ".join(f"{r.step_deg:g} deg: {r.recommended_angle_deg:g} deg ({r.worst_margin_pct:+.0f} %)"
                      for r in conv.itertuples())
    fig.suptitle(f"Where to brake joint {int(advice.joint)}: at {rec:g} deg the worst task ({advice.worst_task}) keeps "
                 f"{advice.worst_margin_pct:+.0f} % (a step either side: {advice.neighbours_worst_margin_pct:+.0f} %), "
                 f"{int(advice.tasks_carried)} of {int(advice.n_tasks)} tasks carried "
                 f"(where it stands: {advice.stands_at_worst_margin_pct:+.0f} %)\n"
                 f"the recommendation on sweeps of {steps}", fontsize=11)
    save(fig, out_png)
