"""Plane-stress finite-element reference (scikit-fem) on the lattice's own triangles.

``solve(mesh, E, nu, supports, loads, order=1 | 2, refine=0)`` takes the same
:class:`~dvstatic.Fix`, :class:`~dvstatic.Traction`, :class:`~dvstatic.BodyForce` and
:class:`~dvstatic.PointLoad` objects as :func:`dvstatic.solve`, builds P1 or P2
vector elements on the mesh triangles (uniformly refined ``refine`` times for a
reference solution), and returns the displacement at the lattice nodes (they stay
vertices of the refined mesh) together with a way to evaluate it anywhere.

Supports and loads on named parts act on the whole boundary segment (every refined
facet on it); supports and point loads on node index arrays act on those nodes only.
Tractions are integrated exactly along the facets, body forces over the elements.

scikit-fem is imported on first use only.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ._checks import check_int
from .errors import InputError, SingularError
from .linalg import DirectSolver, nested_dissection
from .material import lame_plane_stress
from .mesh import Mesh
from .problem import (
    BodyForce,
    PointLoad,
    Traction,
    as_list,
    select_edges,
    select_nodes,
    support_components,
)

if TYPE_CHECKING:  # annotations only: scipy is imported where it is used
    import scipy.sparse as sp


log = logging.getLogger(__name__)

__all__ = ["lame_plane_stress", "FESolution", "solve", "Comparison", "compare"]


@dataclass(frozen=True, eq=False)
class FESolution:
    """Finite-element solution.

    Attributes
    ----------
    mesh : Mesh
        The lattice mesh the problem was posed on.
    u : ndarray, shape (N, 2)
        Displacement at the lattice nodes.
    order, refine : int
    info : dict
        ``n_dof``, ``n_elements``, ``seconds`` per stage (mesh, assembly, solve).
    """

    mesh: Mesh
    u: np.ndarray
    order: int
    refine: int
    info: dict
    _basis: object
    _x: np.ndarray
    _stress_nodal: object = None

    def evaluate(self, points) -> np.ndarray:
        """Displacement at arbitrary points inside the mesh, shape (n, 2)."""
        p = np.atleast_2d(np.asarray(points, dtype=float))
        if p.ndim != 2 or p.shape[1] != 2:
            raise InputError(f"points must have shape (n, 2), got {p.shape}", "points")
        probe = self._basis.probes(np.ascontiguousarray(p.T))
        v = probe @ self._x
        n = len(p)
        return np.c_[v[:n], v[n:]]

    @property
    def max_displacement(self) -> float:
        return float(np.max(np.hypot(self.u[:, 0], self.u[:, 1])))

    def stress(self, points) -> np.ndarray:
        """Plane-stress Cauchy stress at points, shape (n, 2, 2).

        The element stresses are L2-projected onto continuous scalar elements of the
        same order (smooth nodal stresses), then evaluated at the points.
        """
        import skfem

        p = np.atleast_2d(np.asarray(points, dtype=float))
        if p.ndim != 2 or p.shape[1] != 2:
            raise InputError(f"points must have shape (n, 2), got {p.shape}", "points")
        if self._stress_nodal is None:
            lam, mu = self.info["lame"]
            g = self._basis.interpolate(self._x).grad  # (2, 2, elements, quadrature points)
            exx, eyy, exy = g[0, 0], g[1, 1], 0.5 * (g[0, 1] + g[1, 0])
            tr = exx + eyy
            comps = (lam * tr + 2 * mu * exx, lam * tr + 2 * mu * eyy, 2 * mu * exy)
            el = skfem.ElementTriP1() if self.order == 1 else skfem.ElementTriP2()
            sb = self._basis.with_element(el)
            vals = [sb.project(skfem.DiscreteField(c)) for c in comps]
            object.__setattr__(self, "_stress_nodal", (sb, vals))
        sb, vals = self._stress_nodal
        probe = sb.probes(np.ascontiguousarray(p.T))
        sxx, syy, sxy = (probe @ v for v in vals)
        return np.stack([np.stack([sxx, sxy], -1), np.stack([sxy, syy], -1)], -2)


def _facets_on_edges(fm, coarse_pts: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Boundary facets of the refined skfem mesh lying on the given coarse edges."""
    bf = fm.boundary_facets()
    a = fm.p[:, fm.facets[0, bf]].T
    b = fm.p[:, fm.facets[1, bf]].T
    mid = 0.5 * (a + b)
    p0 = coarse_pts[edges[:, 0]]
    p1 = coarse_pts[edges[:, 1]]
    d = p1 - p0
    dd = np.einsum("ij,ij->i", d, d)
    tol = 1e-9 * np.sqrt(dd.max())
    keep = np.zeros(len(bf), dtype=bool)
    # chunk over coarse edges to bound memory (facets x edges)
    for start in range(0, len(edges), 2048):
        sl = slice(start, start + 2048)
        q = mid[:, None, :] - p0[None, sl, :]
        s = np.einsum("nej,ej->ne", q, d[sl]) / dd[None, sl]
        off = q - s[..., None] * d[None, sl, :]
        on = (np.hypot(off[..., 0], off[..., 1]) <= tol) & (s >= -1e-12) & (s <= 1 + 1e-12)
        keep |= on.any(axis=1)
    return bf[keep]


def solve(
    mesh: Mesh,
    E: float,
    nu: float,
    supports=None,
    loads=None,
    order: int = 1,
    refine: int = 0,
) -> FESolution:
    """Plane-stress FE solution with the lattice's supports and loads.

    Parameters
    ----------
    mesh : Mesh
        Bounded mesh; its triangles are the elements (refined ``refine`` times).
    E, nu : float
        Young's modulus (> 0) and Poisson's ratio (-1 < nu < 1).
    supports, loads
        As for :func:`dvstatic.solve`.
    order : {1, 2}
        Lagrange element order.
    refine : int
        Uniform refinements (each splits a triangle into four), >= 0.

    Returns
    -------
    FESolution
    """
    import skfem
    from skfem.models.elasticity import linear_elasticity

    if not isinstance(mesh, Mesh):
        raise TypeError(f"mesh must be a dvstatic Mesh, got {type(mesh).__name__}")
    if mesh.is_periodic:
        raise InputError("the FE reference needs a bounded mesh", "mesh")
    lam, mu = lame_plane_stress(E, nu)
    order = check_int("order", order, minimum=1, maximum=2)
    refine = check_int("refine", refine, minimum=0, maximum=8)
    t0 = time.perf_counter()
    fm = skfem.MeshTri(np.ascontiguousarray(mesh.points.T), np.ascontiguousarray(mesh.triangles.T))
    if refine:
        fm = fm.refined(refine)
    elem = skfem.ElementVector(skfem.ElementTriP1() if order == 1 else skfem.ElementTriP2())
    basis = skfem.Basis(fm, elem)
    t1 = time.perf_counter()
    K = skfem.asm(linear_elasticity(lam, mu), basis)
    f = _load_vector(mesh, fm, elem, basis, loads)
    D, vals = _prescribed(mesh, fm, basis, supports)
    x = np.zeros(basis.N)
    x[D] = vals
    A, b, x_free, free = skfem.condense(K, f, x=x, D=D)
    t2 = time.perf_counter()
    x[free] = _solve_spd(A, b, basis.doflocs[:, free].T)
    t3 = time.perf_counter()
    nodal = basis.nodal_dofs
    u = np.c_[x[nodal[0, : mesh.n_points]], x[nodal[1, : mesh.n_points]]]
    info = {
        "n_dof": int(basis.N),
        "n_elements": int(fm.t.shape[1]),
        "lame": (lam, mu),
        "seconds": {"mesh": t1 - t0, "assembly": t2 - t1, "solve": t3 - t2, "total": t3 - t0},
    }
    log.info("FE P%d refine=%d: %d dof in %.3f s", order, refine, basis.N, t3 - t0)
    return FESolution(mesh, u, order, refine, info, basis, x)


def _load_vector(mesh: Mesh, fm, elem, basis, loads) -> np.ndarray:
    """Consistent load vector: tractions integrated along the facets of their edges,
    body forces over the elements, point loads on the lattice nodes."""
    import skfem

    f = np.zeros(basis.N)
    for load in as_list(loads, "Traction, BodyForce or PointLoad"):
        if isinstance(load, Traction):
            edges = select_edges(mesh, load.where, "Traction")
            fb = skfem.FacetBasis(fm, elem, facets=_facets_on_edges(fm, mesh.points, edges))
            f += skfem.asm(_constant_form(np.asarray(load.value, dtype=float)), fb)
        elif isinstance(load, BodyForce):
            f += skfem.asm(_constant_form(np.asarray(load.value, dtype=float)), basis)
        elif isinstance(load, PointLoad):
            nodes = select_nodes(mesh, load.nodes, "PointLoad")
            for c in range(2):
                np.add.at(f, basis.nodal_dofs[c, nodes], load.value[c])
        else:
            raise TypeError(f"unknown load type {type(load).__name__}")
    return f


def _constant_form(value: np.ndarray):
    import skfem

    @skfem.LinearForm
    def form(v, w):
        return value[0] * v[0] + value[1] * v[1]

    return form


def _prescribed(mesh: Mesh, fm, basis, supports) -> tuple[np.ndarray, np.ndarray]:
    """Prescribed FE dofs and values: every dof on the facets of a named part, the
    vertex dofs of supports on node index arrays."""
    dof_list, val_list = [], []
    for where, comp, nodes, value in support_components(mesh, supports):
        if isinstance(where, str):
            if np.ndim(value) != 0:
                raise InputError(
                    "FE reference: a prescribed value on a named part must be a scalar "
                    "(per-node values are supported on node index arrays)",
                    "xy"[comp],
                )
            facets = _facets_on_edges(fm, mesh.points, mesh.part_edges(where))
            idx = np.asarray(basis.get_dofs(facets=facets).all(f"u^{comp + 1}"), dtype=np.int64)
            dof_list.append(idx)
            val_list.append(np.full(idx.size, float(value)))
        else:
            dof_list.append(basis.nodal_dofs[comp, nodes])
            val_list.append(np.broadcast_to(np.asarray(value, dtype=float), nodes.shape))
    if not dof_list:
        raise InputError("no supports: the FE problem is singular", "supports")
    D, first = np.unique(np.concatenate(dof_list), return_index=True)
    return D, np.concatenate(val_list)[first]


def _solve_spd(A: sp.spmatrix, b: np.ndarray, locs: np.ndarray) -> np.ndarray:
    """Direct solve with a nested-dissection ordering on the dof locations."""
    import scipy.sparse as sp

    A = sp.csr_matrix(A)
    coo = sp.triu(A, k=1).tocoo()
    order = nested_dissection(locs + 1e-12 * np.arange(len(locs))[:, None], np.c_[coo.row, coo.col])
    lu = DirectSolver(A, order=order)
    if lu.negative_pivots:
        raise SingularError("the FE stiffness is not positive definite: check the supports")
    x, info = lu.solve(b)
    if not np.all(np.isfinite(x)) or info["residuals"][-1] > 1e-8:
        raise SingularError(f"FE solve failed (relative residual {info['residuals'][-1]:.2e})")
    return x


@dataclass(frozen=True)
class Comparison:
    """Difference between two displacement fields on the same nodes.

    Attributes
    ----------
    l2 : float
        ``|u_a - u_b| / |u_b|`` over all nodes (discrete l2).
    max : float
        ``max_i |u_a,i - u_b,i| / max_i |u_b,i|`` (nodal vector magnitudes).
    diff : ndarray, shape (N, 2)
        ``u_a - u_b``.
    """

    l2: float
    max: float
    diff: np.ndarray


def compare(a, b) -> Comparison:
    """Relative L2 and max displacement errors of ``a`` against the reference ``b``.

    ``a`` and ``b`` are solutions (anything with ``.u``) or (N, 2) arrays on the same
    nodes.
    """
    ua = np.asarray(getattr(a, "u", a), dtype=float)
    ub = np.asarray(getattr(b, "u", b), dtype=float)
    if ua.shape != ub.shape or ua.ndim != 2 or ua.shape[1] != 2:
        raise InputError(
            f"compare needs two (N, 2) fields on the same nodes, got {ua.shape} and {ub.shape}",
            "b",
        )
    d = ua - ub
    nb = float(np.linalg.norm(ub))
    mb = float(np.max(np.hypot(ub[:, 0], ub[:, 1])))
    if nb == 0:
        raise InputError("the reference field is zero: relative errors are undefined", "b")
    return Comparison(
        float(np.linalg.norm(d) / nb), float(np.max(np.hypot(d[:, 0], d[:, 1])) / mb), d
    )
