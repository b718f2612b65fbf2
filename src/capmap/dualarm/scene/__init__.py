"""The scene, its scan and envelopes, the unobserved space and the robot (see :mod:`capmap.dualarm`)."""

__all__ = []
