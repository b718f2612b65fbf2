"""The general 6R IK method (Raghavan-Roth / Manocha-Canny elimination, up to 16 solutions, complete):
:mod:`.elimination` (the 12 x 12 eliminant and its polynomial), :mod:`.matrices` and :mod:`.kernels`
(its compiled arithmetic), :mod:`.back` (the back-substitution), :mod:`.select` (the method: the
candidates polished and selected). One method, split by the module size cap."""

__all__ = []
