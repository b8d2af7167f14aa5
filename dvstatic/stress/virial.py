"""The lattice's own stresses: bond states, the virial (force-based) stress per
Voronoi cell, the P1 strain of every triangle and the continuum law applied to it.

Stress conventions: 2x2 Cauchy stress (force per length for unit thickness, i.e.
units of E).
"""

from __future__ import annotations

import numpy as np

from .._checks import as_displacement
from ..lattice import VoronoiModel, check_model
from ..mesh import Mesh

__all__ = [
    "bond_state",
    "node_stress",
    "strain_stress",
    "triangle_strains",
    "strain_operator",
    "continuum_stress",
    "triangle_stress",
    "out_of_plane_stress",
]


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


def triangle_strains(mesh: Mesh, u) -> np.ndarray:
    """P1 strain ``(exx, eyy, exy)`` of every triangle, shape (M, 3) (tensor shear)."""
    x = mesh.triangle_coordinates()
    ut = np.asarray(u).reshape(-1, 2)[mesh.triangles]
    d1, d2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    det = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    inv = (
        np.stack([np.c_[d2[:, 1], -d2[:, 0]], np.c_[-d1[:, 1], d1[:, 0]]], axis=1)
        / det[:, None, None]
    )
    du = np.stack([ut[:, 1] - ut[:, 0], ut[:, 2] - ut[:, 0]], axis=1)  # (M, 2 edges, 2 comps)
    grad = np.einsum("mej,mei->mij", inv, du)  # grad[m, i, j] = d u_i / d x_j
    return np.c_[grad[:, 0, 0], grad[:, 1, 1], 0.5 * (grad[:, 0, 1] + grad[:, 1, 0])]


def triangle_stress(model: VoronoiModel, u) -> np.ndarray:
    """The continuum law of each triangle's material applied to its P1 strain, shape
    (M, 2, 2) (in-plane stress; plane strain: the effective constants): the lattice's
    stress at the scale of one triangle, micro-structure and all."""
    model = check_model(model)
    mesh = model.mesh
    eps = triangle_strains(mesh, as_displacement(u, mesh.n_points))
    return continuum_stress(model, eps)


def continuum_stress(model: VoronoiModel, eps: np.ndarray) -> np.ndarray:
    """The continuum law of each triangle's material applied to strains ``eps`` (M, 3;
    xx, yy and the tensor shear xy), shape (M, 2, 2) (in-plane; plane strain: the
    effective constants)."""
    consts = np.array([m.in_plane for m in model.all_materials])[model.material_of_triangle]
    E, nu = consts[:, 0], consts[:, 1]
    c = E / (1 - nu**2)
    sxx = c * (eps[:, 0] + nu * eps[:, 1])
    syy = c * (eps[:, 1] + nu * eps[:, 0])
    sxy = E / (1 + nu) * eps[:, 2]
    return np.stack([np.stack([sxx, sxy], -1), np.stack([sxy, syy], -1)], -2)


def strain_operator(mesh: Mesh):
    """(3M, 2N) CSR: the P1 strain ``(exx, eyy, exy)`` of every triangle (the rows of
    :func:`triangle_strains`, tensor shear) as a linear map of the displacement."""
    import scipy.sparse as sp

    x = mesh.triangle_coordinates()
    d1, d2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    det = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    g1 = np.c_[d2[:, 1], -d2[:, 0]] / det[:, None]  # grad of vertex 1's shape function
    g2 = np.c_[-d1[:, 1], d1[:, 0]] / det[:, None]
    g = np.stack([-g1 - g2, g1, g2], axis=1)  # (M, 3 vertices, 2)
    m = len(x)
    dof = 2 * mesh.triangles  # (M, 3): the x dof of every vertex
    rows, cols, vals = [], [], []
    for k, (cx, cy) in enumerate(((0, None), (None, 1), (1, 0))):
        for comp, along in ((0, cx), (1, cy)):  # d u_comp / d x_along
            if along is None:
                continue
            rows.append(np.repeat(3 * np.arange(m) + k, 3))
            cols.append((dof + comp).ravel())
            vals.append((0.5 if k == 2 else 1.0) * g[:, :, along].ravel())
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(3 * m, 2 * mesh.n_points),
    )


def strain_stress(model: VoronoiModel, u) -> np.ndarray:
    """Kinematic stress: :func:`triangle_stress` averaged to the nodes (weighted by
    triangle area), shape (N, 2, 2).

    Unlike the virial (force-based) stress, this does not see the extra force the
    paper's uniform ``k_n`` puts into the surface bonds (about 1.7x the true stress
    parallel to a free edge of a lattice).
    """
    model = check_model(model)
    sig = triangle_stress(model, u)
    return _to_nodes(model.mesh, model.geometry.tri_area, sig.reshape(-1, 4)).reshape(-1, 2, 2)


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
