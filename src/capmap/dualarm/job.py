"""What a dual-arm job plans with (plain data, no solver imported): its inputs (robot, envelope, scene), its
horizon and its planning settings, and the inputs put together on a horizon with unknown boxes in the
environment. The config's sections become these in :mod:`capmap.dualarm.build`; the plan:
:mod:`capmap.dualarm.plan`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.dualarm.ocp.assembly import Assembly, assemble
from capmap.dualarm.ocp.settings import ALSettings, Weights
from capmap.dualarm.scene.cloud import Envelope
from capmap.dualarm.scene.robot import DualArm
from capmap.dualarm.scene.solids import Scene
from capmap.dualarm.scene.unknown import UnknownSettings, with_boxes

__all__ = ["JobInputs", "HorizonSteps", "PlanSettings", "assembly_on"]


@dataclass(frozen=True, eq=False)
class JobInputs:
    """What a dual-arm job plans with: the robot (its capsules fitted), the fitted envelope of the scene and its
    labels (per triangle (T,), per capsule (S,): the solid each belongs to), the scene."""

    robot: DualArm
    env: Envelope
    labels: tuple[np.ndarray, np.ndarray]
    scene: Scene


@dataclass(frozen=True)
class HorizonSteps:
    """A horizon: nodes N (N + 1 states), step dt_s s, the node of the pre-insertion pose."""

    nodes: int
    dt_s: float
    pre_insertion_node: int


@dataclass(frozen=True, eq=False)
class PlanSettings:
    """How a motion is planned and checked: its horizon, the cost weights, the augmented-Lagrangian loop, the
    finer grid's factor (the motion checked at ``fine_factor`` times the nodes) and the unknown space's settings
    (work volume and voxel m; near_m: the boxes within it of the motion go to the optimiser)."""

    horizon: HorizonSteps
    weights: Weights
    solver: ALSettings
    fine_factor: int
    unknown: UnknownSettings


def assembly_on(inputs: JobInputs, h: HorizonSteps, boxes: np.ndarray | None = None,
                voxel_m: float | None = None) -> Assembly:
    """The assembly of ``inputs`` on horizon ``h``; ``boxes`` (B, 2, 3) m of unknown space, of ``voxel_m`` m
    voxels, join the environment."""
    env, labels = inputs.env, inputs.labels
    if boxes is not None and len(boxes):
        env, labels = with_boxes(env, labels, boxes, voxel_m)
    return assemble(inputs.robot, inputs.scene, env, labels, h.nodes, h.dt_s, h.pre_insertion_node)
