"""Shared figure helpers (matplotlib, Agg backend). Plotting lives in :mod:`capmap.plots`,
never in the numerics; each function takes DataFrames and writes one PNG."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

__all__ = ["plt", "save"]


def save(fig, out_png: str | Path) -> None:
    """Lay out, write (110 dpi, parents created) and close a figure."""
    fig.tight_layout()
    Path(out_png).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_png, dpi=110)
    plt.close(fig)
