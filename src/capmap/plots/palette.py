"""The planned paths' colours, the same on the summary map, the verification figures and the 3D page:
light (no plotting library), so that the workflow can name a verification figure's colour in its params."""

from __future__ import annotations

__all__ = ["PATH_COLOURS", "path_colour"]

PATH_COLOURS = ("darkorange", "magenta", "saddlebrown", "deepskyblue", "olive", "orchid")  # not in viridis, not red


def path_colour(payloads_kg, payload_kg: float, further_task: int | None = None) -> str:
    """A planned path's colour: the main task's payload's by its place among ``payloads_kg``; the
    ``further_task``-th further task's (0-based) after them."""
    payloads = list(payloads_kg)
    n = len(payloads) + further_task if further_task is not None else (
        payloads.index(payload_kg) if payload_kg in payloads else 0)
    return PATH_COLOURS[n % len(PATH_COLOURS)]
