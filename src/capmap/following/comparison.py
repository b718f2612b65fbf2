"""The follower against its references: the S-curve command it was given and TOPP-RA's
time-optimal motion on the same path and limits (durations, peak torques, violations)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.core.limits import AffineLimits
from capmap.following.follower import SATURATED, FollowedSegment
from capmap.following.toppra_reference import ToppraResult

__all__ = ["FollowComparison", "compare", "model_terms"]


@dataclass(frozen=True)
class FollowComparison:
    """A followed path (one or more segments, rest to rest each) against its references.

    Durations in s (sums over segments); ``*_peak_torque_pct``: the largest |tau| / limit over
    joints and time, in %; ``*_max_violation_pct``: how far above 100 % that is (0 if not);
    saturated_joints: joints whose followed peak reaches SATURATED of their limit;
    limited_periods_pct: periods in which the torque limits clipped the acceleration. The torques of
    both are measured with the full drive model (links, payload, armature, Coulomb and viscous
    friction: ``follower_terms``); ``toppra_terms`` says what TOPP-RA itself could model (no viscous
    friction) and ``toppra_modelled_peak_torque_pct`` its peak with those terms. With viscous friction,
    ``*_no_viscous`` compare a follower run without it against TOPP-RA like for like (NaN otherwise)."""

    segments: int
    length_m: float
    torque_limits_nm: str
    command_duration_s: float
    follower_duration_s: float
    toppra_duration_s: float
    duration_ratio: float
    command_vs_toppra_ratio: float
    command_peak_torque_pct: float
    follower_peak_torque_pct: float
    follower_max_violation_pct: float
    toppra_peak_torque_pct: float
    toppra_max_violation_pct: float
    saturated_joints: str
    limited_periods_pct: float
    infeasible_periods: int
    max_lag_m: float
    max_deviation_m: float
    max_deviation_rad: float
    follower_terms: str
    toppra_terms: str
    toppra_modelled_peak_torque_pct: float
    follower_no_viscous_duration_s: float
    duration_ratio_no_viscous: float
    follower_no_viscous_peak_torque_pct: float


def _terms(robot, active, viscous: bool = True) -> str:
    """The torque terms of a model, e.g. 'links+armature+coulomb+viscous'."""
    out = ["links"]
    terms = [("armature", robot.armature_kgm2), ("coulomb", robot.coulomb_nm)]
    for name, values in terms + ([("viscous", robot.viscous_nms)] if viscous else []):
        if np.any(values[active] > 0):
            out.append(name)
    return "+".join(out)


def model_terms(arm) -> str:
    """The torque terms of the locked arm's model, e.g. 'links+armature+coulomb+viscous'."""
    return _terms(arm.robot, arm.active)


def compare(followed: list[FollowedSegment], toppra: list[ToppraResult], limits: AffineLimits, arm,
            no_viscous: list[FollowedSegment] | None = None) -> FollowComparison:
    """Summary of the followed segments against the command and TOPP-RA, per-segment pairs, on ``arm``
    (:class:`capmap.core.reduction.LockedArm`); ``no_viscous``: the same path followed without the
    drives' viscous friction (the model TOPP-RA has)."""
    length = np.array([f.table.length_m for f in followed]).sum()
    command = np.array([f.command.duration_s for f in followed]).sum()
    follower = np.array([f.result.duration_s for f in followed]).sum()
    optimal = np.array([t.duration_s for t in toppra]).sum()
    ratio_f = limits.ratio(np.concatenate([f.tau for f in followed]))
    ratio_c = limits.ratio(np.concatenate([f.tau_cmd for f in followed]))
    ratio_t = limits.ratio(np.concatenate([t.tau for t in toppra]))
    limited = np.concatenate([f.result.limited for f in followed])
    joints = [name.removeprefix("tau_").removesuffix("_nm") for name in limits.names]
    return FollowComparison(
        segments=len(followed), length_m=float(length), torque_limits_nm=" ".join(f"{t:g}" for t in limits.limit),
        command_duration_s=float(command), follower_duration_s=float(follower), toppra_duration_s=float(optimal),
        duration_ratio=float(follower / optimal), command_vs_toppra_ratio=float(command / optimal),
        command_peak_torque_pct=100 * float(ratio_c.max()), follower_peak_torque_pct=100 * float(ratio_f.max()),
        follower_max_violation_pct=100 * max(0.0, float(ratio_f.max()) - 1),
        toppra_peak_torque_pct=100 * float(ratio_t.max()),
        toppra_max_violation_pct=100 * max(0.0, float(ratio_t.max()) - 1),
        saturated_joints=" ".join(j for c, j in enumerate(joints) if ratio_f[:, c].max() > SATURATED),
        limited_periods_pct=100 * float(limited.mean()),
        infeasible_periods=int(np.concatenate([f.result.infeasible for f in followed]).sum()),
        max_lag_m=float(np.concatenate([f.result.s_cmd - f.result.s for f in followed]).max()),
        max_deviation_m=float(np.concatenate([f.deviation_m for f in followed]).max()),
        max_deviation_rad=float(np.concatenate([f.deviation_rad for f in followed]).max()),
        follower_terms=_terms(arm.robot, arm.active), toppra_terms=_terms(arm.robot, arm.active, viscous=False),
        toppra_modelled_peak_torque_pct=100 * float(limits.ratio(np.concatenate([t.tau_modelled for t in toppra])).max()),
        follower_no_viscous_duration_s=float(sum(f.result.duration_s for f in no_viscous)) if no_viscous else np.nan,
        duration_ratio_no_viscous=(float(sum(f.result.duration_s for f in no_viscous) / optimal) if no_viscous
                                   else np.nan),
        follower_no_viscous_peak_torque_pct=(100 * float(limits.ratio(np.concatenate([f.tau for f in no_viscous])).max())
                                             if no_viscous else np.nan))
