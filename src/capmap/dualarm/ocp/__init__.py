"""The optimal-control problem of the assembly and its solver (see :mod:`capmap.dualarm`)."""

__all__ = []
