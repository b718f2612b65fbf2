"""Figures, one module per family (:mod:`~capmap.plots.capacity`, :mod:`~capmap.plots.following`),
shared helpers in :mod:`~capmap.plots.common`."""

__all__ = ["capacity", "common", "following"]
