"""Primitives and their distances (see :mod:`capmap.dualarm`)."""

__all__ = []
