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

__all__ = ["MARGIN", "triangle_modes", "clip_coupling", "coupling_matrices", "triangle_tensors"]

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
    return np.linalg.eigvalsh(s[:, :, None] * m * s[:, None, :])


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


def coupling_matrices(mesh: Mesh, barycentric: bool) -> np.ndarray:
    """The symmetric 3x3 matrices ``M`` of every triangle (``dr = M B``), (M, 3, 3)."""
    g = _geometry.of(mesh)
    _, _, n = edge_frames(g.x_tri)
    b = elongation_gradients(n)
    _, dr = half_sides(g.x_tri, g.bary if barycentric else None, grad=True)
    bbt = b @ b.transpose(0, 2, 1)
    # B B^T (unit directions: entries <= 1) is singular only for a flat triangle (a
    # sliver): the pseudo-inverse there
    flat = np.abs(np.linalg.det(bbt)) < 1e-10
    inv = np.empty_like(bbt)
    inv[~flat] = np.linalg.inv(bbt[~flat])
    inv[flat] = np.linalg.pinv(bbt[flat], hermitian=True)
    m = dr @ b.transpose(0, 2, 1) @ inv
    return 0.5 * (m + m.transpose(0, 2, 1))


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
    return np.einsum("mki,mkj,mjl->mil", lnm, q, lnm) / g.tri_area[:, None, None]
