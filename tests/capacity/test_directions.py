import numpy as np
import pytest

from capmap.capacity.directions import paper_grid, sphere
from capmap.errors import CapmapError


def test_paper_grid_dedup_keeps_every_direction():
    step = 10.0
    d = paper_grid(step)
    a = np.deg2rad(np.arange(0, 360, step))
    A, B = np.meshgrid(a, a, indexing="ij")
    raw = np.stack([np.sin(B) * np.cos(A), np.sin(B) * np.sin(A), np.cos(B)], -1).reshape(-1, 3)
    dist = np.linalg.norm(raw[:, None] - d.u[None], axis=-1)
    assert np.all(dist.min(axis=1) < 1e-9)  # each raw direction is kept
    pair = np.linalg.norm(d.u[:, None] - d.u[None], axis=-1) + 10 * np.eye(len(d))
    assert pair.min() > 1e-6  # no duplicates left
    assert len(d) == 1 + 17 * 36 + 1  # poles once, b in 10..170 x 36 azimuths
    assert np.allclose(np.linalg.norm(d.u, axis=1), 1)


def test_sphere_is_near_uniform():
    d = sphere(500)
    assert np.allclose(np.linalg.norm(d.u, axis=1), 1)
    assert np.linalg.norm(d.u.mean(axis=0)) < 1e-2
    # nearest-neighbour spacing close to the ideal sqrt(4 pi / n)
    ang = np.arccos(np.clip(d.u @ d.u.T, -1, 1)) + 10 * np.eye(500)
    nn = ang.min(axis=1)
    ideal = np.sqrt(4 * np.pi / 500)
    assert 0.6 * ideal < nn.min() and nn.max() < 1.3 * ideal


@pytest.mark.parametrize("bad", [0, -5, 400])
def test_bad_step(bad):
    with pytest.raises(CapmapError, match="step_deg"):
        paper_grid(bad)
