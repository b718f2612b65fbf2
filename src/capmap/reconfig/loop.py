"""A closed chain through a capture, split at one unlocked passive joint into two open chains.

Two arms holding each other form a loop: platform -> arm a -> link_a =capture= link_b ->
arm b (backwards) -> platform, a product of fixed transforms and joint rotations equal to
the identity. Unlocking one cylindrical joint P on that loop cuts it into two chains from the
platform: side 1 ends at the frame just before P's motion, side 2 (the rest of the loop
walked backwards) at the frame just after it, and the loop says

    T(side 2 end) = T(side 1 end) @ M(theta, d)^k,   M = Tz(d) Rz(theta) in P's aligned frame,

k = +1 when the loop crosses P from its parent to its child body, -1 the other way. The
side with more active joints moves (the short side keeps still, so its end is fixed to the
platform); the long side's end must follow T(fixed end) @ M^(+-k) as (theta, d) follow
their motion law. This works for any capture and any passive joint on the loop.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.core import ik
from capmap.core.kinematics import Chain, inverse_transform, pose_error
from capmap.errors import CapmapError
from capmap.reconfig.multiarm import PlatformDescription, PlatformState, arm_elements, chain_of, joint_motion

__all__ = ["SideChain", "LoopSplit", "loop_elements", "split_loop", "close_capture", "capture_error"]


@dataclass(frozen=True)
class SideChain:
    """An open chain from the platform: its kinematics and the (qualified) names of its joints."""

    chain: Chain
    joints: tuple[str, ...]

    @property
    def dof(self) -> int:
        return len(self.joints)

    def values(self, state: PlatformState) -> np.ndarray:
        """Its joint angles (dof,) rad in a state."""
        return np.array([state.q[name] for name in self.joints])


@dataclass(frozen=True)
class LoopSplit:
    """The loop cut at ``unlocked``: the ``moving`` (long) and ``fixed`` (short) sides; the moving
    end must be at T(fixed end) @ M(theta, d)^power (see the module docstring)."""

    unlocked: str
    capture: str
    moving: SideChain
    fixed: SideChain
    power: int

    def target(self, fixed_end: np.ndarray, theta: np.ndarray, d: np.ndarray) -> np.ndarray:
        """Poses (N, 4, 4) of the moving end for passive values theta rad, d m (N,)."""
        M = np.array([joint_motion(t, x) for t, x in zip(np.atleast_1d(theta), np.atleast_1d(d))])
        if self.power < 0:
            M = inverse_transform(M)
        return fixed_end @ M

    def twist(self, fixed_end: np.ndarray, theta_rate: np.ndarray, d_rate: np.ndarray) -> np.ndarray:
        """Twists (N, 6) [v; omega] (platform axes, at the moving end's origin) for rates of theta
        (rad/s) and d (m/s): the moving end's origin is on P's axis, so v = +-axis d', w = +-axis theta'."""
        axis = fixed_end[:3, 2]
        return self.power * np.concatenate([np.outer(d_rate, axis), np.outer(theta_rate, axis)], axis=1)


def _inverse(elements: list[tuple]) -> list[tuple]:
    """Elements of the inverse product: reversed, fixed transforms inverted, joint signs flipped."""
    out = []
    for e in reversed(elements):
        out.append(("fixed", np.linalg.inv(e[1])) if e[0] == "fixed" else (e[0], e[1], -e[2]))
    return out


def loop_elements(desc: PlatformDescription, capture: str, state: PlatformState,
                  unlocked: str | None = None) -> list[tuple]:
    """The loop platform -> link_a -> link_b -> platform as elements (see :func:`arm_elements`)."""
    cap = desc.capture(capture)
    arm_a, arm_b = desc.arm_of(cap.link_a), desc.arm_of(cap.link_b)
    if arm_a.name == arm_b.name:
        raise CapmapError(f"capture {capture} holds two links of the same arm {arm_a.name}: no loop through the "
                          "platform")
    return (arm_elements(arm_a, cap.link_a, state, unlocked) + [("fixed", np.linalg.inv(cap.transform))]
            + _inverse(arm_elements(arm_b, cap.link_b, state, unlocked)))


def split_loop(desc: PlatformDescription, capture: str, unlocked: str, state: PlatformState) -> LoopSplit:
    """Cut the loop of ``capture`` at the passive joint ``unlocked`` (other passive joints locked at
    their state values); the side with more active joints moves (side 2 on a tie)."""
    joint = desc.joint(unlocked)
    if not joint.passive:
        raise CapmapError(f"{unlocked} is a {joint.kind} joint, not a passive one that can be unlocked")
    loop = loop_elements(desc, capture, state, unlocked)
    at = [i for i, e in enumerate(loop) if e[0] == "unlocked"]
    if not at:
        raise CapmapError(f"{unlocked} is not on the closed chain through capture {capture}")
    p = at[0]
    side1 = SideChain(*chain_of(loop[:p]))
    side2 = SideChain(*chain_of(_inverse(loop[p + 1:])))
    power = loop[p][2]
    if side1.dof > side2.dof:
        return LoopSplit(unlocked, capture, moving=side1, fixed=side2, power=-power)
    return LoopSplit(unlocked, capture, moving=side2, fixed=side1, power=power)


def capture_error(desc: PlatformDescription, capture: str, placements: dict[str, np.ndarray]) -> np.ndarray:
    """Pose error (..., 6) [position m; rotation vector rad] of link_a against T(link_b) @ transform,
    from link poses (..., 4, 4) computed by any model."""
    cap = desc.capture(capture)
    return pose_error(placements[cap.link_a], placements[cap.link_b] @ cap.transform)


def close_capture(desc: PlatformDescription, capture: str, arm: str, state: PlatformState, iters: int = 30,
                  max_change_rad: float = np.deg2rad(2.0)) -> tuple[PlatformState, np.ndarray]:
    """The state with ``arm``'s revolute joints (up to its captured link) solved by damped Newton so
    that the capture holds exactly, the other arm as given (inverse kinematics from the given
    angles); and the change (k,) rad. Raises CapmapError (role ``configuration``) if it does not
    converge to 1e-12 or needs a joint to change by more than max_change_rad (the given angles
    were then not a rounded capture configuration but another pose)."""
    cap = desc.capture(capture)
    if arm not in (cap.link_a.split(".")[0], cap.link_b.split(".")[0]):
        raise CapmapError(f"arm {arm} is not held by capture {capture}")
    own, other = (cap.link_a, cap.link_b) if cap.link_a.startswith(arm + ".") else (cap.link_b, cap.link_a)
    chain_own, names = chain_of(arm_elements(desc.arm(arm), own, state))
    chain_other, other_names = chain_of(arm_elements(desc.arm_of(other), other, state))
    T_other = chain_other.fk(np.array([[state.q[n] for n in other_names]]))[0]
    target = T_other @ cap.transform if own == cap.link_a else T_other @ np.linalg.inv(cap.transform)
    q0 = np.array([[state.q[n] for n in names]])
    q = ik.newton(chain_own, q0, target[None], iters=iters, damping=1e-6)
    err = pose_error(chain_own.fk(q), target[None])[0]
    if not np.all(np.abs(err) < 1e-12):
        raise CapmapError(f"{{configuration}} does not close capture {capture}: solving {arm}'s joints from it "
                          f"leaves {np.linalg.norm(err[:3]):.3g} m, {np.linalg.norm(err[3:]):.3g} rad",
                          configuration="the configuration")
    change = q[0] - q0[0]
    if np.abs(change).max() > max_change_rad:
        j = int(np.argmax(np.abs(change)))
        raise CapmapError(f"{{configuration}} does not close capture {capture}: the nearest closing pose moves "
                          f"{names[j]} by {np.rad2deg(change[j]):.2f} deg (allowed {np.rad2deg(max_change_rad):g})",
                          configuration="the configuration")
    return state.with_values(names, q[0]), change
