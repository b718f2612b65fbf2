"""The exception hierarchy: every error a user can see is a :class:`CapmapError` of one line.

Numerics raise errors in their own terms; a message may name an input by its *role* in
braces (``"{q_ini} is 9.97 deg from ..."`` with ``q_ini="the start configuration"``),
so that a stage or a config check can re-word it with the config key that holds that
input (``exc.in_terms(q_ini="task.q_ini_deg")``) without a second copy of the text.
Entry points (the Snakemake scripts through :func:`capmap.io.logs.one_line_errors`, the
Snakefile's validation) print ``capmap: <message>`` instead of a traceback.

    CapmapError
    ├── ConfigError       a config or robot file is wrong (names the key or file)
    ├── DataError         an intermediate file is missing or corrupt (names the file)
    ├── NoPath            the planner found no path at a payload (a result, not a failure)
    ├── TrackingLost      inverse kinematics cannot follow a branch along a path
    ├── LimitInfeasible   a limit cannot be met at all (e.g. holding a path at rest)
    └── SolverFailed      an iterative method did not converge or arrive
"""

from __future__ import annotations

__all__ = ["CapmapError", "ConfigError", "DataError", "NoPath", "TrackingLost", "LimitInfeasible", "SolverFailed"]


class CapmapError(ValueError):
    """One-line error. ``message`` may hold ``{role}`` placeholders; ``roles`` give their own-terms
    names (``str(exc)``); :meth:`in_terms` renames them, e.g. to config keys."""

    def __init__(self, message: str, **roles: str):
        self.template = message
        self.roles = roles
        super().__init__(message.format(**roles) if roles else message)

    def in_terms(self, **names: str) -> str:
        """The message with roles renamed (unnamed roles keep their own-terms name)."""
        if not self.roles:
            return str(self)
        return self.template.format(**{**self.roles, **{k: v for k, v in names.items() if k in self.roles}})


class ConfigError(CapmapError):
    """A config or robot file is wrong; the message names the key or the file."""


class DataError(CapmapError):
    """An intermediate file is missing or corrupt; the message names the file and how to rebuild it."""


class NoPath(CapmapError):
    """No path at this payload (start or goal voxel too weak, or no connection): a result that the
    pipeline records (the direct line is still verified), not a configuration error."""


class TrackingLost(CapmapError):
    """Inverse kinematics cannot follow a branch along a path (singularity, workspace boundary)."""


class LimitInfeasible(CapmapError):
    """A limit cannot be met at all, e.g. the torques that hold a path at rest exceed it."""


class SolverFailed(CapmapError):
    """An iterative method did not converge, or a follower did not arrive in time."""
