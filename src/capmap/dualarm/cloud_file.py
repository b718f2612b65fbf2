"""A user's cloud file (CSV or Parquet) -> points and the viewpoint that saw each; one-line errors naming the
config key and the file. The file's check before any job: :func:`capmap.config.inputs.check_cloud_file`."""

from __future__ import annotations

import numpy as np
import pandas as pd

from capmap.errors import ConfigError

__all__ = ["XYZ", "read_cloud"]

XYZ = ["x_m", "y_m", "z_m"]


def read_cloud(path: str, viewpoints: int) -> tuple[np.ndarray, np.ndarray]:
    """A user's cloud file: CSV or Parquet with columns x_m, y_m, z_m (base frame) and, with several
    viewpoints, the index of the one that saw each point (``viewpoint``): (points (P, 3) m, index (P,))."""
    try:
        df = pd.read_parquet(path) if str(path).lower().endswith(".parquet") else pd.read_csv(path)
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        raise ConfigError(f"dualarm.cloud.file = {path!r}: cannot be read ({str(exc).splitlines()[0]})") from None
    missing = [c for c in XYZ if c not in df.columns]
    if missing:
        raise ConfigError(f"dualarm.cloud.file = {path!r}: no column {missing[0]} (need x_m, y_m, z_m)")
    try:
        pts = df[XYZ].to_numpy(dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"dualarm.cloud.file = {path!r}: columns x_m, y_m, z_m must hold numbers only") from None
    if len(pts) == 0:
        raise ConfigError(f"dualarm.cloud.file = {path!r}: no points")
    if not np.isfinite(pts).all():
        raise ConfigError(f"dualarm.cloud.file = {path!r}: {int((~np.isfinite(pts)).any(axis=1).sum())} points are "
                          "not finite")
    if "viewpoint" not in df.columns:
        return pts, np.zeros(len(pts), dtype=int)  # one viewpoint (checked before the run)
    view = pd.to_numeric(df["viewpoint"], errors="coerce").to_numpy()
    bad = ~((view >= 0) & (view < viewpoints) & (view == np.round(view)))
    if bad.any():
        raise ConfigError(f"dualarm.cloud.file = {path!r}: column viewpoint must index dualarm.cloud.viewpoints_m "
                          f"(0..{viewpoints - 1}); {int(bad.sum())} rows do not")
    return pts, view.astype(int)
