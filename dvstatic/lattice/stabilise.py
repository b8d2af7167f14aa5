"""Per-triangle stabilisation of the Voronoi coupling.

A triangle's share of the stiffness is ``K_T = B^T (W + g_T M) B`` with ``B`` (3, 6) the
elongation gradients of its bonds, ``W`` the diagonal of its share of their springs
(``tri_weight * spring``), ``g_T`` its coupling stiffness and ``M`` the symmetric 3x3
matrix for which the half-side gradients are ``dr = M B`` (they vanish on rigid motions,
as the rows of ``B`` span the rest). ``K_T`` is positive semi-definite, with the rigid
motions its only null space, iff ``1 + g_T lambda > 0`` for the eigenvalues ``lambda`` of
``W^-1/2 M W^-1/2`` (:func:`triangle_modes`). Where a triangle's coupling would break
that, :func:`clip_coupling` reduces it until ``min(1 + g_T lambda) = MARGIN``: every
triangle then stiffens, so the lattice is stable on any mesh and at any ``nu_m``, and
triangles that are fine keep their coupling. The relaxed calibration applies the same
rule to its sample, so the moduli stay matched.
"""

from __future__ import annotations

import numpy as np

from ..mesh import Mesh
from . import geometry as _geometry
from .kinematics import edge_frames, elongation_gradients, half_sides

__all__ = [
    "MARGIN",
    "triangle_modes",
    "clip_coupling",
    "coupling_matrices",
    "reference_matrices",
    "flat_triangles",
    "eigvalsh3",
    "triangle_tensors",
]

#: smallest eigenvalue left to a triangle's stiffness relative to its springs
MARGIN = 0.05


def triangle_modes(mesh: Mesh, spring: np.ndarray, barycentric: bool) -> np.ndarray:
    """Eigenvalues ``lambda`` (M, 3), ascending, of every triangle's coupling per unit
    coupling stiffness relative to its springs.

    Parameters
    ----------
    mesh : Mesh
    spring : ndarray, shape (n_bonds,)
        Spring stiffness of every bond (> 0).
    barycentric : bool
        DV (True) or RV (False) half sides.
    """
    g = _geometry.of(mesh)
    m = coupling_matrices(mesh, barycentric)
    s = 1.0 / np.sqrt(g.tri_weight * np.asarray(spring)[mesh.topology.tri_bonds])
    m *= s[:, :, None]
    m *= s[:, None, :]
    return eigvalsh3(m)


def eigvalsh3(a: np.ndarray) -> np.ndarray:
    """Eigenvalues (ascending) of symmetric 3x3 matrices ``a`` (M, 3, 3), in closed form
    (the trigonometric solution of the characteristic cubic; to 1e-13 of the matrix's
    norm, twice as fast as ``numpy.linalg.eigvalsh`` at 2e6 matrices)."""
    a00, a11, a22 = a[:, 0, 0], a[:, 1, 1], a[:, 2, 2]
    a01, a02, a12 = a[:, 0, 1], a[:, 0, 2], a[:, 1, 2]
    q = (a00 + a11 + a22) / 3.0
    off = a01**2 + a02**2 + a12**2
    p = np.sqrt(((a00 - q) ** 2 + (a11 - q) ** 2 + (a22 - q) ** 2 + 2.0 * off) / 6.0)
    ps = np.where(p > 0, p, 1.0)
    b00, b11, b22 = (a00 - q) / ps, (a11 - q) / ps, (a22 - q) / ps
    b01, b02, b12 = a01 / ps, a02 / ps, a12 / ps
    det = b00 * (b11 * b22 - b12**2) - b01 * (b01 * b22 - b12 * b02) + b02 * (b01 * b12 - b11 * b02)
    phi = np.arccos(np.clip(0.5 * det, -1.0, 1.0)) / 3.0
    hi = q + 2.0 * p * np.cos(phi)
    lo = q + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0)
    return np.stack([lo, 3.0 * q - hi - lo, hi], axis=1)


def clip_coupling(modes: np.ndarray, coupling, margin: float = MARGIN) -> np.ndarray:
    """Coupling stiffness of every triangle, reduced where it would leave the
    triangle with less than ``margin`` of its spring stiffness, shape (M,).

    Parameters
    ----------
    modes : ndarray, shape (M, 3)
        :func:`triangle_modes`.
    coupling : float or ndarray, shape (M,)
        Requested coupling stiffness ``g_T`` (same units as the springs).
    """
    g = np.broadcast_to(np.asarray(coupling, dtype=float), (len(modes),)).copy()
    lo, hi = modes[:, 0], modes[:, -1]
    neg = (g < 0) & (1 + g * hi < margin)
    g[neg] = -(1 - margin) / hi[neg]
    pos = (g > 0) & (1 + g * lo < margin)
    g[pos] = (1 - margin) / -lo[pos]
    return g


#: triangles whose smallest angle has a sine below this take the general (least-squares)
#: form of ``M`` in :func:`coupling_matrices` (the closed forms divide by the area)
FLAT_SINE = 1e-4


def coupling_matrices(mesh: Mesh, barycentric: bool) -> np.ndarray:
    """The symmetric 3x3 matrices ``M`` of every triangle (``dr = M B``), (M, 3, 3).

    In closed form from the half sides ``r_k = (l_k / 2) cot alpha_k`` (alpha_k the
    angle opposite edge k), the edge lengths and the area ``A``. DV: the half side of
    the affinely moved circumcentre changes by ``r_k t.eps.t = r_k (tr eps - e_k)`` and
    ``tr eps = dA / A = sum_j (l_j r_j / A) e_j``, so ``M = r r^T / A - diag(r / l)``.
    RV: the circumcentre is recomputed, ``dr_k = cot(alpha_k) dl_k / 2 - l_k dalpha_k /
    (2 sin^2 alpha_k)`` with ``dalpha_k / dl_k = l_k / (2 A)`` and ``dalpha_k / dl_j =
    -l_k cos(alpha_i) / (2 A)`` (i the third edge). Both equal the least-squares fit
    ``dr B^T (B B^T)^-1`` of the half-side gradients to round-off (1e-13 on random
    points) at a fraction of its cost; near-flat triangles keep that fit.
    """
    return reference_matrices(_geometry.of(mesh), barycentric)


def reference_matrices(g, barycentric: bool, sl: slice = slice(None)) -> np.ndarray:
    """:func:`coupling_matrices` of the triangles ``sl`` of a :class:`Geometry`."""
    r, length, area = g.tri_r[sl], g.tri_l[sl], g.tri_area[sl]
    if barycentric:  # symmetric by construction
        m = r[:, :, None] * (r / area[:, None])[:, None, :]
        for k in range(3):
            m[:, k, k] -= r[:, k] / length[:, k]
    else:
        m = _rv_matrices(r, length, area)
        m = 0.5 * (m + m.transpose(0, 2, 1))
    flat = flat_triangles(g, sl)
    if flat.size:
        x_tri, bary = g.x_tri[sl][flat], g.bary[sl][flat]
        fit = _fitted_matrices(x_tri, bary if barycentric else None)
        m[flat] = 0.5 * (fit + fit.transpose(0, 2, 1))
    return m


def flat_triangles(g, sl: slice = slice(None)) -> np.ndarray:
    """Indices (within ``sl``) of the near-flat triangles of a :class:`Geometry`: the
    sine of their smallest angle is below :data:`FLAT_SINE`."""
    return np.flatnonzero(_geometry.smallest_sine(g, sl) < FLAT_SINE)


def _rv_matrices(r: np.ndarray, length: np.ndarray, area: np.ndarray) -> np.ndarray:
    """``M`` of RV triangles in closed form (see :func:`coupling_matrices`)."""
    cot = 2.0 * r / length
    sin2 = 1.0 / (1.0 + cot**2)
    cos = cot * np.sqrt(sin2)
    scale = -length / (2.0 * sin2) / (2.0 * area[:, None])  # -l_k / (2 sin^2) / (2 A)
    m = np.empty((len(r), 3, 3))
    for k in range(3):
        for j in range(3):
            dalpha = length[:, k] if j == k else -length[:, k] * cos[:, 3 - k - j]
            m[:, k, j] = scale[:, k] * dalpha
        m[:, k, k] += 0.5 * cot[:, k]
    return m


def _fitted_matrices(x_tri: np.ndarray, bary: np.ndarray | None) -> np.ndarray:
    """``M = dr B^T (B B^T)^-1`` from the half-side gradients (pseudo-inverse where
    ``B B^T`` is singular: a flat triangle), for the triangles ``x_tri`` (m, 3, 2)."""
    _, _, n = edge_frames(x_tri)
    b = elongation_gradients(n)
    _, dr = half_sides(x_tri, bary, grad=True)
    bbt = b @ b.transpose(0, 2, 1)
    flat = np.abs(np.linalg.det(bbt)) < 1e-10
    inv = np.empty_like(bbt)
    inv[~flat] = np.linalg.inv(bbt[~flat])
    inv[flat] = np.linalg.pinv(bbt[flat], hermitian=True)
    return dr @ b.transpose(0, 2, 1) @ inv


def triangle_tensors(mesh: Mesh, spring: np.ndarray, coupling, barycentric: bool) -> np.ndarray:
    """The elasticity tensor of every triangle (Mandel, (M, 3, 3), units of E).

    The linear lattice *is* a P1 finite-element model whose triangle T has the tensor
    ``C_T = N^T L (W + g_T M) L N / A_T``: the three bond elongations of a triangle are
    ``L N eps_T`` for its (constant) P1 strain ``eps_T`` (``L`` the bond lengths, ``N``
    the rows ``(nx^2, ny^2, sqrt(2) nx ny)`` of the bond directions), and its share of
    the stiffness is a quadratic form in them. On equilateral triangles ``C_T`` is
    isotropic; on others it is not, and the spread of ``C_T`` over the mesh is what
    makes irregular lattices relax non-affinely.

    Parameters
    ----------
    mesh : Mesh
    spring : ndarray, shape (n_bonds,)
        Spring stiffness of every bond (split equally between its triangles).
    coupling : float or ndarray, shape (M,)
        Coupling stiffness of every triangle.
    barycentric : bool
        DV (True) or RV (False).
    """
    g = _geometry.of(mesh)
    _, length, n = edge_frames(g.x_tri)
    w = g.tri_weight * np.asarray(spring)[mesh.topology.tri_bonds]
    q = w[:, :, None] * np.eye(3) + np.broadcast_to(
        np.asarray(coupling, dtype=float), (mesh.n_triangles,)
    )[:, None, None] * coupling_matrices(mesh, barycentric)
    nm = np.stack([n[..., 0] ** 2, n[..., 1] ** 2, np.sqrt(2.0) * n[..., 0] * n[..., 1]], -1)
    lnm = length[..., None] * nm  # (M, 3 bonds, 3 strain components)
    return (lnm.transpose(0, 2, 1) @ q @ lnm) / g.tri_area[:, None, None]
