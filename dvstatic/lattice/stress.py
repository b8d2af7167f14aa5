"""Stress of a lattice state: bond states, the virial (force-based) stress per Voronoi
cell, and the kinematic (strain-based) recovery.

Stress conventions: 2x2 Cauchy stress (force per length for unit thickness, i.e.
units of E).
"""

from __future__ import annotations

import numpy as np

from .._checks import as_displacement
from .models import VoronoiModel

__all__ = ["bond_state", "node_stress", "strain_stress", "out_of_plane_stress", "check_model"]


def check_model(model) -> VoronoiModel:
    """``model`` if it is a DV or RV model (TypeError otherwise)."""
    if not isinstance(model, VoronoiModel):
        raise TypeError(f"model must be a dvstatic DV or RV model, got {type(model).__name__}")
    return model


def bond_state(model: VoronoiModel, u, strain=None, linear: bool = True):
    """Tensions (n_bonds,) and bond vectors (n_bonds, 2) of a state.

    ``linear``: linearised tensions on the reference bonds; otherwise the exact
    tensions on the current bonds.
    """
    if linear:
        t = model.linear_tension(u, strain)
        g = model.geometry
        return t, g.length[:, None] * g.direction
    op = model.operator
    u = as_displacement(u, model.mesh.n_points)
    t, d, _ = op.bond_state(u, op.check_strain(strain))
    return t, d


def node_stress(model: VoronoiModel, u, linear: bool = True) -> np.ndarray:
    """Virial stress of every particle over its Voronoi cell, shape (N, 2, 2).

    ``sigma_i = (1 / A_i) sum_{bonds at i} (1/2) T l n (x) n``, with ``A_i`` the Voronoi
    cell area (the one-third-of-triangles area where the Voronoi cell of a boundary
    node degenerates). Cell averages weighted by area reproduce the lattice's mean
    (virial) stress exactly; on boundary nodes the value is the mean over the
    truncated cell.
    """
    model = check_model(model)
    t, d = bond_state(model, u, None, linear)
    ln = np.hypot(d[:, 0], d[:, 1])
    half = 0.5 * (t / ln)[:, None, None] * d[:, :, None] * d[:, None, :]
    b = model.mesh.topology.bonds
    n = model.mesh.n_points
    out = np.zeros((n, 4))
    hv = half.reshape(-1, 4)
    for c in range(4):
        out[:, c] = np.bincount(b[:, 0], hv[:, c], n) + np.bincount(b[:, 1], hv[:, c], n)
    g = model.geometry
    area = np.where(g.cell_area > 0.25 * g.dual_area, g.cell_area, g.dual_area)
    return (out / (model.t * area[:, None])).reshape(n, 2, 2)


def strain_stress(model: VoronoiModel, u) -> np.ndarray:
    """Kinematic stress recovery: plane-stress law applied to the lattice strain.

    The displacement is interpolated linearly on each triangle, the triangle strains
    are averaged to the nodes (weighted by triangle area) and mapped through the
    plane-stress law of the model's E and nu (each triangle's own material, and the
    effective constants in plane strain). Unlike the virial (force-based) stress,
    this does not see the extra force the paper's uniform ``k_n`` puts into the
    surface bonds (about 1.7x the true stress parallel to a free edge of a lattice), so
    it is the better estimate of surface stresses such as stress concentrations.

    Returns
    -------
    ndarray, shape (N, 2, 2)
    """
    model = check_model(model)
    mesh = model.mesh
    u = as_displacement(u, mesh.n_points)
    x = model.geometry.x_tri
    ut = u[mesh.triangles]
    a, b = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    det = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    # gradients of the barycentric functions 1 and 2
    g1 = np.c_[b[:, 1], -b[:, 0]] / det[:, None]
    g2 = np.c_[-a[:, 1], a[:, 0]] / det[:, None]
    du1, du2 = ut[:, 1] - ut[:, 0], ut[:, 2] - ut[:, 0]
    grad = du1[:, :, None] * g1[:, None, :] + du2[:, :, None] * g2[:, None, :]  # (M, 2, 2)
    eps = 0.5 * (grad + grad.transpose(0, 2, 1))
    sig = np.empty_like(eps)
    for k, material in enumerate(model.all_materials):
        sel = model.material_of_triangle == k
        sig[sel] = material.stress(eps[sel])
    return _to_nodes(mesh, model.geometry.tri_area, sig.reshape(-1, 4)).reshape(-1, 2, 2)


def _to_nodes(mesh, area: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Area-weighted average of triangle values (M, k) at the nodes, (N, k)."""
    n = mesh.n_points
    acc = np.zeros((n, values.shape[1]))
    w = np.zeros(n)
    for v in range(3):
        idx = mesh.triangles[:, v]
        w += np.bincount(idx, area, n)
        for c in range(values.shape[1]):
            acc[:, c] += np.bincount(idx, area * values[:, c], n)
    return acc / w[:, None]


def out_of_plane_stress(model: VoronoiModel, sigma: np.ndarray) -> np.ndarray:
    """``szz`` at the nodes for in-plane nodal stresses ``sigma`` (N, 2, 2): zero in plane
    stress, ``nu (sxx + syy)`` in plane strain (``nu`` area-averaged over the node's
    triangles where materials meet), shape (N,)."""
    if model.plane == "stress":
        return np.zeros(model.mesh.n_points)
    nus = np.array([m.nu for m in model.all_materials])[model.material_of_triangle]
    nu = _to_nodes(model.mesh, model.geometry.tri_area, nus[:, None])[:, 0]
    return nu * (sigma[:, 0, 0] + sigma[:, 1, 1])
