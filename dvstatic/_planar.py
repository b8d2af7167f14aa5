"""Small vectorised helpers of plane geometry (shared by meshes and lattice kernels)."""

from __future__ import annotations

import numpy as np

__all__ = ["cross", "rot", "perp", "signed_area2", "circumcentres"]


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """z-component of the cross product of 2-vectors, over the last axis."""
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def rot(v: np.ndarray) -> np.ndarray:
    """Clockwise quarter turn ``(vy, -vx)``."""
    return np.stack([v[..., 1], -v[..., 0]], axis=-1)


def perp(v: np.ndarray) -> np.ndarray:
    """Counter-clockwise quarter turn ``(-vy, vx)``."""
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


def signed_area2(x: np.ndarray) -> np.ndarray:
    """Twice the signed area of triangles ``x`` of shape (M, 3, 2), shape (M,)."""
    return cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])


def circumcentres(Y: np.ndarray) -> np.ndarray:
    """Circumcentres of triangles, shape (M, 2), for vertices Y of shape (M, 3, 2)."""
    a = Y[:, 1] - Y[:, 0]
    b = Y[:, 2] - Y[:, 0]
    D = 2.0 * cross(a, b)
    p = np.einsum("mi,mi->m", a, a)[:, None] * rot(b) - np.einsum("mi,mi->m", b, b)[:, None] * rot(
        a
    )
    return Y[:, 0] + p / D[:, None]
