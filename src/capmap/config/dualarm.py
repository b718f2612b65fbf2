"""Config section of the dual-arm family (``dualarm``): frozen data; its numerics are built in
:mod:`capmap.dualarm.build`, which also reads the dual-arm robot files.

A dual-arm robot file names a URDF (a path relative to the file, or a file shipped by a pip
package), the two arms' joints and gripper frames, the joints to lock and their values, and
the capsule groups (URDF geometry objects each capsule covers), ``cover`` (the URDF models the
capsules cover: visual and/or collision, default both) and the self-collision rules ``self_gap``,
``body_skip`` and ``hold`` (see :mod:`capmap.dualarm.ocp.assembly`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from capmap.config.typed import FILE
from capmap.errors import ConfigError

__all__ = ["DualArmConfig", "Horizon", "CheckSettings", "ScanConfig", "FitConfig", "WeightsConfig", "SolverConfig",
           "UnknownConfig", "cloud_source", "fit_config", "horizon", "check_settings", "unknown_config", "weights_config"]


@dataclass(frozen=True)
class ScanConfig:
    """``dualarm.cloud``: the cameras' viewpoints (V of them, m, base frame), the synthetic scan's point
    spacing and range noise (m; 0 for a user's cloud file, whose viewpoints these are)."""

    viewpoints_m: tuple[tuple[float, float, float], ...]
    spacing_m: float
    noise_m: float


@dataclass(frozen=True)
class FitConfig:
    """``dualarm.fit``: the envelope fit's settings given in the config; None: the fit's own default
    (:class:`capmap.dualarm.scene.cloud.FitSettings`, where each default lives)."""

    plane_tol_m: float | None = None
    normal_tol_deg: float | None = None
    neighbours: int | None = None
    cell_m: float | None = None
    min_fill: float | None = None
    min_width_m: float | None = None
    absorb: float | None = None
    min_patch_points: int | None = None
    margin_m: float | None = None
    max_capsule_radius_m: float | None = None
    ransac_iterations: int | None = None
    thin_m: float | None = None


@dataclass(frozen=True)
class WeightsConfig:
    """``dualarm.weights`` (control: one per arm joint, 14) and ``dualarm.margin_m`` (m)."""

    control: tuple[float, ...]
    velocity: float
    panel: float
    margin_m: float


@dataclass(frozen=True)
class SolverConfig:
    """``dualarm.solver``: the augmented-Lagrangian loop's settings given in the config; None: the
    solver's own default (:class:`capmap.dualarm.ocp.settings.ALSettings`)."""

    mu0: float | None = None
    mu_factor: float | None = None
    decrease: float | None = None
    mu_max: float | None = None
    max_outer: int | None = None
    max_inner: int | None = None
    inner_stop: float | None = None
    tolerance: float | None = None
    filter_m: float | None = None


@dataclass(frozen=True)
class UnknownConfig:
    """``dualarm.unknown``: the work volume's lower and upper corners (m) and, given, the carving voxel
    edge and the near distance (m; None: :class:`capmap.dualarm.scene.unknown.UnknownSettings`' defaults)."""

    work_lower: tuple[float, float, float]
    work_upper: tuple[float, float, float]
    voxel_m: float | None = None
    near_m: float | None = None


@dataclass(frozen=True)
class Horizon:
    """nodes N (N + 1 states), step dt_s, the node of the pre-insertion pose."""

    nodes: int
    dt_s: float
    pre_insertion_node: int


@dataclass(frozen=True)
class CheckSettings:
    """The CSQP cross-check: its horizon, SQP iteration limit and KKT tolerance (CSQP's own
    criterion, whose dual part is only as accurate as its inner ADMM QP solves), and the tighter
    tolerance of the AL-FDDP solve it is compared with."""

    horizon: Horizon
    max_iterations: int = 100
    tolerance: float = 1e-6
    al_tolerance: float = 1e-9


@dataclass(frozen=True)
class DualArmConfig:
    """``dualarm``: robot and scene files, the cloud (a file, or a synthetic scan), fitting
    overrides, the horizon, cost weights, the safety margin, solver settings, the CSQP check's
    horizon, the re-check's refinement and the animation's frame rate."""

    robot: str = field(metadata=FILE)
    scene: str = field(metadata=FILE)
    cloud_file: str | None = field(metadata=FILE)
    scan: ScanConfig | None  # a user's cloud: its viewpoints here too (spacing and noise unused)
    scan_seed: int
    fit: FitConfig
    fit_seed: int
    horizon: Horizon
    weights: WeightsConfig
    solver: SolverConfig
    check: CheckSettings
    unknown: UnknownConfig
    fine_factor: int = 5  # the defaults of dualarm.fine_factor and dualarm.animation_fps
    animation_fps: float = 25.0

    @classmethod
    def from_doc(cls, d: dict) -> "DualArmConfig":
        """The whole section (every key a job might read; see the piece builders below)."""
        cloud_file, scan, scan_seed = cloud_source(d)
        fit, fit_seed = fit_config(d)
        return cls(robot=d["robot"], scene=d["scene"], cloud_file=cloud_file, scan=scan, scan_seed=scan_seed, fit=fit,
                   fit_seed=fit_seed, horizon=horizon(d), weights=weights_config(d), solver=SolverConfig(**d["solver"]),
                   check=check_settings(d), unknown=unknown_config(d),
                   **{k: d[k] for k in ("fine_factor", "animation_fps") if k in d})


# --------------------------------------------------------------------------- the section's pieces (from the YAML)


def _points(v) -> tuple[tuple[float, float, float], ...]:
    return tuple(tuple(float(x) for x in p) for p in v)


def cloud_source(d: dict) -> tuple[str | None, ScanConfig | None, int]:
    """``dualarm.cloud``: (the user's file, its viewpoints (spacing and noise 0), 0) or (None, the scan's
    settings, its seed)."""
    cloud = d["cloud"]
    if "file" in cloud:
        extra = sorted(set(cloud) - {"file", "viewpoints_m"})
        if extra:
            raise ConfigError(f"dualarm.cloud: give either file (and the viewpoints_m it was taken from) or a synthetic "
                              f"scan (viewpoints_m, spacing_m, noise_m, seed), not both (found {extra[0]} with file)")
        if "viewpoints_m" not in cloud:
            raise ConfigError("dualarm.cloud.viewpoints_m is required with dualarm.cloud.file: the cameras' positions "
                              "tell observed free space from space no camera saw (which is taken as occupied)")
        return cloud["file"], ScanConfig(_points(cloud["viewpoints_m"]), 0.0, 0.0), 0
    missing = [k for k in ("viewpoints_m", "spacing_m", "noise_m", "seed") if k not in cloud]
    if missing:
        raise ConfigError(f"dualarm.cloud.{missing[0]} is required for a synthetic scan (or give dualarm.cloud.file)")
    scan = ScanConfig(_points(cloud["viewpoints_m"]), float(cloud["spacing_m"]), float(cloud["noise_m"]))
    return None, scan, int(cloud["seed"])


def unknown_config(d: dict) -> UnknownConfig:
    """``dualarm.unknown``."""
    u = d["unknown"]
    box = [tuple(float(v) for v in u["work_volume_m"][ax]) for ax in ("x_m", "y_m", "z_m")]
    if not all(lo < hi for lo, hi in box):
        raise ConfigError(f"dualarm.unknown.work_volume_m = {u['work_volume_m']}: each lower bound must be < its upper")
    return UnknownConfig(tuple(b[0] for b in box), tuple(b[1] for b in box),
                         **{k: float(u[k]) for k in ("voxel_m", "near_m") if k in u})


def fit_config(d: dict) -> tuple[FitConfig, int]:
    """``dualarm.fit`` (the keys given), and its RANSAC seed."""
    fit = dict(d.get("fit", {}))
    seed = int(fit.pop("seed", 0))
    return FitConfig(**fit), seed


def _horizon(key: str, h: dict) -> Horizon:
    out = Horizon(int(h["nodes"]), float(h["dt_s"]), int(h["pre_insertion_node"]))
    if not 0 < out.pre_insertion_node < out.nodes:
        raise ConfigError(f"dualarm.{key}.pre_insertion_node = {out.pre_insertion_node} must lie between 0 and "
                          f"dualarm.{key}.nodes = {out.nodes}")
    return out


def horizon(d: dict) -> Horizon:
    """``dualarm.horizon``."""
    return _horizon("horizon", d["horizon"])


def check_settings(d: dict) -> CheckSettings:
    """``dualarm.check``."""
    c = d["check"]
    return CheckSettings(_horizon("check", c), **{k: c[k] for k in ("max_iterations", "tolerance", "al_tolerance")
                                                   if k in c})  # else CheckSettings' defaults


def weights_config(d: dict) -> WeightsConfig:
    """``dualarm.weights`` (one control weight for every joint, or 14) and ``dualarm.margin_m``."""
    w = d["weights"]
    c = [float(v) for v in w["control"]] if isinstance(w["control"], (list, tuple)) else [float(w["control"])]
    control = tuple(c * 14 if len(c) == 1 else c)
    if len(control) != 14:
        raise ConfigError(f"dualarm.weights.control has {len(control)} values: give one, or one per arm joint (14)")
    return WeightsConfig(control, float(w["velocity"]), float(w["panel"]), float(d["margin_m"]))
