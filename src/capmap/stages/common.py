"""What every stage does first: read its config slice (its canonical JSON from the rule's params)."""

from __future__ import annotations

import json

__all__ = ["parse_slice"]


def parse_slice(slice_json: str) -> dict:
    """A stage's config slice (see :func:`capmap.config.slices.stage_slices`) from its canonical JSON."""
    return json.loads(slice_json)
