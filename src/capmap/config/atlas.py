"""Config section of the fault atlas: ``atlas`` (joints x lock angles, coarse map settings)."""

from __future__ import annotations

from dataclasses import dataclass

from capmap.config.capacity import DirectionsConfig, SamplingConfig
from capmap.errors import ConfigError

__all__ = ["AtlasConfig", "angle_label"]


def angle_label(angle_deg: float) -> str:
    """File-name label of a lock angle: -90 -> '-90', 12.5 -> '12.5'."""
    return f"{float(angle_deg):g}"


@dataclass(frozen=True)
class AtlasConfig:
    """``atlas``: one coarse capacity map per (joint in ``joints``, angle in ``angles_deg``), with
    its own sampling, directions and voxel edge; task, limits and robot are the run's."""

    joints: tuple[int, ...]
    angles_deg: tuple[float, ...]
    sampling: SamplingConfig
    directions: DirectionsConfig
    edge_m: float

    @classmethod
    def from_doc(cls, d: dict) -> "AtlasConfig":
        try:
            directions = DirectionsConfig.from_doc(d["directions"])
        except ConfigError as exc:
            raise ConfigError(str(exc).replace("directions.", "atlas.directions.")) from None
        labels = [angle_label(a) for a in d["angles_deg"]]
        if len(set(labels)) != len(labels):
            raise ConfigError(f"atlas.angles_deg has repeated values {labels}")
        return cls(joints=tuple(int(j) for j in d["joints"]), angles_deg=tuple(float(a) for a in d["angles_deg"]),
                   sampling=SamplingConfig.from_doc(d["sampling"]), directions=directions, edge_m=float(d["edge_m"]))

    def check(self, robot: str, lower_deg, upper_deg, source: str = "config") -> None:
        """Every joint exists on ``robot`` (its joints' ranges [lower_deg, upper_deg]) and every angle is
        inside every listed joint's range."""
        for j in self.joints:
            if not 1 <= j <= len(lower_deg):
                raise ConfigError(f"{source}: atlas.joints: joint {j} is out of range: {robot} has joints "
                                  f"1..{len(lower_deg)}")
            lo, hi = float(lower_deg[j - 1]), float(upper_deg[j - 1])
            for a in self.angles_deg:
                if not lo - 1e-9 <= a <= hi + 1e-9:
                    raise ConfigError(f"{source}: atlas.angles_deg: {a:g} is outside joint {j}'s range "
                                      f"[{lo:g}, {hi:g}] deg")

    @property
    def cases(self) -> list[tuple[int, str]]:
        """(joint, angle label) of every map."""
        return [(j, angle_label(a)) for j in self.joints for a in self.angles_deg]
