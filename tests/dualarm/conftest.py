"""The default config's dual-arm problem pieces (robot with fitted capsules, scene, envelope) and a small
problem on them (40 nodes) for the compiled nodes and solver."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from capmap.config.dualarm import cloud_source, fit_config
from capmap.dualarm.build import fit_settings, load_dual_arm_file, scan_settings
from capmap.dualarm.geometry.chain import pack
from capmap.dualarm.ocp.assembly import assemble, warm_start
from capmap.dualarm.ocp.crocoddyl_nodes import Context
from capmap.dualarm.ocp.settings import Weights
from capmap.dualarm.ocp.solver import initial_guess, node_pairs
from capmap.dualarm.scene.cloud import fit_envelope
from capmap.dualarm.scene.robot import build_dual_arm, fit_capsules
from capmap.dualarm.scene.solids import nearest_solid, scan
from capmap.dualarm.scene_file import load_scene
from tests.scenario import ROOT

SECTION = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())["dualarm"]
W = Weights(control=np.linspace(0.5, 2.0, 14), velocity=1.0, panel=0.01, margin_m=0.005)  # the small problem's


@pytest.fixture(scope="session")
def scene():
    return load_scene(ROOT / SECTION["scene"])


@pytest.fixture(scope="session")
def robot(scene):
    """The robot, fingers closed on the scene's panel, with its capsules."""
    return fit_capsules(build_dual_arm(load_dual_arm_file(ROOT / SECTION["robot"]), float(scene.panel.size[0])))[0]


@pytest.fixture(scope="session")
def envelope(scene):
    _, scan_cfg, seed = cloud_source(SECTION)
    settings = scan_settings(scan_cfg)
    fit_cfg, fit_seed = fit_config(SECTION)

    fit = fit_settings(fit_cfg)
    pts, _ = scan(scene, settings, np.random.default_rng(seed))
    env = fit_envelope(pts, fit, np.random.default_rng(fit_seed))
    labels = (nearest_solid(scene, env.tri.mean(axis=1)), nearest_solid(scene, env.seg.mean(axis=1)))
    return env, labels


@pytest.fixture(scope="session")
def make_assembly(robot, scene, envelope):
    def make(nodes=500, dt=0.02, pre=350):
        return assemble(robot, scene, envelope[0], envelope[1], nodes, dt, pre)
    return make


@pytest.fixture(scope="session")
def small(robot, make_assembly):
    asm = make_assembly(40, 0.25, 28)
    qs = warm_start(asm)
    xs, us = initial_guess(qs, asm.task.dt)
    t = asm.task
    packed = pack(asm.model, (t.left, t.right, t.panel), asm.collision.prims)
    assert not isinstance(packed, str), packed
    ctx = Context(asm.model, asm.task, asm.collision, W, robot.q_lower, robot.q_upper, robot.v_max, mu=1e3,
                  packed=packed)
    keep = node_pairs(asm, qs, 0.15)
    return asm, ctx, xs, us, keep
