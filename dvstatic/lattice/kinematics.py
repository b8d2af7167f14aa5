"""Triangle kinematics shared by the DV and RV models (vectorised over triangles).

For a triangle with vertices ``Y[:, 0..2]`` (counter-clockwise), local edge ``k``
joins vertex ``O = k+1`` to ``A = k+2`` (mod 3) and faces vertex ``k``. Its signed
half side is the signed distance of a point ``H`` (the circumcentre image) from the
edge line, positive towards vertex ``k``::

    r_k = cross(d, H - Y_O) / |d|,    d = Y_A - Y_O.

DV takes ``H = sum_v lambda_v Y_v`` with the reference barycentric coordinates of the
circumcentre; RV takes the circumcentre of the current triangle. Derivatives with
respect to the six vertex coordinates are exact and analytic.
"""

from __future__ import annotations

import numpy as np

from .._planar import circumcentres, cross, perp, rot

__all__ = [
    "O_OF",
    "A_OF",
    "circumcentres",
    "barycentric",
    "edge_frames",
    "half_sides",
    "elongation_gradients",
]

O_OF = np.array([1, 2, 0])  # local start vertex of edge k
A_OF = np.array([2, 0, 1])  # local end vertex of edge k


def barycentric(Y: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Barycentric coordinates (M, 3) of points P (M, 2) in triangles Y (M, 3, 2)."""
    a = Y[:, 1] - Y[:, 0]
    b = Y[:, 2] - Y[:, 0]
    q = P - Y[:, 0]
    det = cross(a, b)
    l1 = cross(q, b) / det
    l2 = cross(a, q) / det
    return np.stack([1.0 - l1 - l2, l1, l2], axis=1)


def edge_frames(Y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Edge vectors, lengths and unit directions of the three local edges.

    Returns
    -------
    d : (M, 3, 2) edge vectors Y_A - Y_O
    length : (M, 3)
    n : (M, 3, 2) unit directions
    """
    d = np.empty_like(Y)
    for k in range(3):
        np.subtract(Y[:, A_OF[k]], Y[:, O_OF[k]], out=d[:, k])
    length = np.hypot(d[..., 0], d[..., 1])
    return d, length, d / length[..., None]


def _circumcentre_jacobian_T(Y: np.ndarray, t: np.ndarray) -> np.ndarray:
    """J_v^T t for the circumcentre H(Y): shape (M, 3 edges, 3 vertices, 2).

    ``t`` has shape (M, 3, 2) (one vector per local edge).
    """
    a = Y[:, 1] - Y[:, 0]
    b = Y[:, 2] - Y[:, 0]
    D = 2.0 * cross(a, b)
    aa = np.einsum("mi,mi->m", a, a)
    bb = np.einsum("mi,mi->m", b, b)
    p = (aa[:, None] * rot(b) - bb[:, None] * rot(a)) / D[:, None]
    rb, ra = rot(b), rot(a)
    # dp/da = (2 rot(b) a^T - |b|^2 R - 2 p rot(b)^T) / D ; R = [[0, 1], [-1, 0]]
    # dp/db = (|a|^2 R - 2 rot(a) b^T + 2 p rot(a)^T) / D
    # (J^T t) = J^T applied to t: (u v^T)^T t = v (u . t);  R^T t = -rot(t)... R^T = -R
    rb_t = np.einsum("mi,mki->mk", rb, t)
    ra_t = np.einsum("mi,mki->mk", ra, t)
    p_t = np.einsum("mi,mki->mk", p, t)
    RTt = -rot(t)  # R^T t
    Da = D[:, None, None]
    ja = (
        2.0 * rb_t[..., None] * a[:, None, :]
        - bb[:, None, None] * RTt
        - 2.0 * p_t[..., None] * rb[:, None, :]
    ) / Da
    jb = (
        aa[:, None, None] * RTt
        - 2.0 * ra_t[..., None] * b[:, None, :]
        + 2.0 * p_t[..., None] * ra[:, None, :]
    ) / Da
    j0 = t - ja - jb
    return np.stack([j0, ja, jb], axis=2)


def half_sides(
    Y: np.ndarray, bary: np.ndarray | None, grad: bool = False
) -> tuple[np.ndarray, np.ndarray | None]:
    """Signed half sides of the three local edges and, optionally, their gradients.

    Parameters
    ----------
    Y : ndarray, shape (M, 3, 2)
        Current (unwrapped) vertex coordinates.
    bary : ndarray, shape (M, 3), or None
        DV: barycentric coordinates of the reference circumcentre (its image is
        ``sum_v bary_v Y_v``). RV: ``None`` (the current circumcentre is used).
    grad : bool
        Also return the derivative of every half side with respect to the six
        vertex coordinates (interleaved x, y per local vertex).

    Returns
    -------
    r : ndarray, shape (M, 3)
    dr : ndarray, shape (M, 3, 6), or None
    """
    d, length, _ = edge_frames(Y)
    if bary is None:
        H = circumcentres(Y)
    else:
        H = np.einsum("mv,mvi->mi", bary, Y)
    w = np.empty_like(d)
    for k in range(3):
        np.subtract(H, Y[:, O_OF[k]], out=w[:, k])
    g = cross(d, w)
    r = g / length
    if not grad:
        return r, None
    inv_l = 1.0 / length
    t = perp(d) * inv_l[..., None]  # current unit normal, dr/dw
    dd = rot(w) * inv_l[..., None] - (g * inv_l**3)[..., None] * d  # dr/dd
    if bary is None:
        jt = _circumcentre_jacobian_T(Y, t)  # (M, 3, 3, 2)
    else:
        jt = bary[:, None, :, None] * t[:, :, None, :]
    for k in range(3):
        jt[:, k, A_OF[k]] += dd[:, k]
        jt[:, k, O_OF[k]] -= dd[:, k] + t[:, k]
    return r, jt.reshape(len(Y), 3, 6)


def elongation_gradients(n: np.ndarray) -> np.ndarray:
    """Elongation gradients b (M, 3, 6) of the three local edges: ``-n`` at O, ``+n`` at A
    (interleaved x, y per local vertex), for unit edge directions ``n`` (M, 3, 2)."""
    m = n.shape[0]
    b = np.zeros((m, 3, 3, 2))
    for k in range(3):
        b[:, k, O_OF[k]] = -n[:, k]
        b[:, k, A_OF[k]] = n[:, k]
    return b.reshape(m, 3, 6)
