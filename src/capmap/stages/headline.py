"""The run's headline: per method family the answer in a line or two, read from the run's summary tables,
printed when a Snakemake run ends (``onsuccess`` in workflow/rules/common.smk). A family whose summary
is not there (not a target of this run) is left out; nothing here computes anything new."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

__all__ = ["headline"]


def _quantities(path: Path) -> pd.Series:
    return pd.read_csv(path).set_index("quantity")["value"]


def _capacity(out: Path) -> list[str]:
    s = _quantities(out / "summary" / "capacity_summary.csv")
    binding = {k.removeprefix("points bound by "): float(v) for k, v in s.items() if k.startswith("points bound by ")}
    top = max(binding, key=binding.get) if binding else "-"
    zero = int(float(s.get("voxels of 0 kg for any configuration", 0)))
    return [f"capacity map: {int(float(s['reachable voxels'])):,} reachable voxels, median "
            f"{float(s['voxel capacity median [kg]']):,.0f} kg, max {float(s['voxel capacity max [kg]']):,.0f} kg; "
            f"{zero:,} voxels carry 0 kg (singular); most points bound by {top}",
            "  (a voxel's value holds for a motion in any direction; a path is verified along its own direction, "
            "so it can carry more than the map's voxels it crosses)"]


def _plans(out: Path) -> list[str]:
    v = pd.read_csv(out / "verify" / "summary.csv", keep_default_na=False)
    lines = []
    for (task, payload), grp in v.groupby(["task", "payload_kg"], sort=False):
        parts = []
        for _, r in grp.iterrows():
            kind = "planned" if "planned" in str(r["path"]) else "direct line"
            if str(r["tracking"]) != "ok":
                parts.append(f"{kind}: tracking lost ({str(r['tracking']).split(':')[0]})")
            elif r["feasible"] in (True, "True"):
                parts.append(f"{kind} holds (peak {float(r['peak_load_pct']):.0f} % of {r['peak_load']})")
            else:
                parts.append(f"{kind} exceeds {r['limits_exceeded_at_payload'] or r['peak_load']} "
                             f"({float(r['peak_load_pct']):.0f} %)")
        where = "" if task == "task" else f" ({task})"
        lines.append(f"{float(payload):g} kg{where}: " + "; ".join(parts))
    return ["verified plans: " + lines[0]] + ["  " + line for line in lines[1:]] if lines else []


def _follow(out: Path) -> list[str]:
    f = pd.read_csv(out / "follow" / "summary.csv")
    feasible = f["feasible"].astype(str) == "True" if "feasible" in f else pd.Series(True, index=f.index)
    return ["following: " + "; ".join(
        f"{r['case']} ({r['robot']}) {r['follower_duration_s']:.3g} s vs TOPP-RA {r['toppra_duration_s']:.3g} s "
        f"(x{r['duration_ratio']:.3f}), peak torque {r['follower_peak_torque_pct']:.1f} %" if ok else
        f"{r['case']} ({r['robot']}) cannot be followed: {r['reason']}" for ok, (_, r) in zip(feasible, f.iterrows()))]


def _reconfig(out: Path) -> list[str]:
    r = pd.read_csv(out / "reconfig" / "summary.csv", keep_default_na=False)
    return ["reconfiguration: " + "; ".join(
        f"{x['method']} {x['status']}, manipulability {float(x['m_initial']):.1f} -> {float(x['m_final']):.1f} "
        f"(min {float(x['m_min']):.1f})" for _, x in r.iterrows())]


def _dualarm(out: Path) -> list[str]:
    s = _quantities(out / "dualarm" / "summary.csv")
    ok = str(s.get("converged")) == "True"
    fine = next(k for k in s.index if k.startswith("min safety distance, ") and "finer grid" in k)  # 'Nx finer grid'
    line = (f"dual-arm assembly: {'converged' if ok else 'NOT converged'}, closed chain "
            f"{float(s['max closed-chain error at nodes [m]']):.1e} m, min safety distance "
            f"{1e3 * float(s[fine]):.2f} mm on the {fine.split(', ')[1].removesuffix(' [m]')}")
    key = "peak torque / effort limit, least-norm internal force [%]"
    if key in s:
        line += f", peak torque {float(s[key]):.0f} % of the effort limits"
    return [line]


_FAMILIES = (("summary/capacity_summary.csv", _capacity), ("verify/summary.csv", _plans),
             ("follow/summary.csv", _follow), ("reconfig/summary.csv", _reconfig), ("dualarm/summary.csv", _dualarm))


def headline(out: str | Path) -> list[str]:
    """Lines saying what the run at ``out`` (results/<run>) found, one family after another, and where the
    report is made; a family whose table cannot be read is named as such rather than stopping the rest."""
    out = Path(out)
    lines = []
    for rel, part in _FAMILIES:
        if not (out / rel).is_file():
            continue
        try:
            lines += part(out)
        except (KeyError, ValueError, OSError, StopIteration, pd.errors.ParserError) as exc:
            lines.append(f"{rel}: cannot be summarised ({type(exc).__name__}: {exc})")
    if lines:
        lines.append(f"tables and figures under {out}/; the report: snakemake --report {out}/report.zip")
    return lines
