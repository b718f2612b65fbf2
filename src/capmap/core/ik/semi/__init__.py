"""The semi-analytical IK method (chains with two parallel axes left): :mod:`.resultant` (the method: a
resultant polynomial in q0 per pose), :mod:`.search` (the 1-D search around roots known only
approximately) and :mod:`.kernels` (their compiled kernels)."""

__all__ = []
