"""Plane-stress finite-element reference (scikit-fem) on the lattice's own triangles.

``solve(mesh, E, nu, supports, loads, order=1 ... 4, refine=0)`` takes the same
:class:`~dvstatic.Fix`, :class:`~dvstatic.Traction`, :class:`~dvstatic.Pressure`,
:class:`~dvstatic.BodyForce` and :class:`~dvstatic.PointLoad` objects as
:func:`dvstatic.solve`, builds P1 to P4 vector elements on the mesh triangles
(uniformly refined ``refine`` times for a reference solution, new boundary nodes on
the domain's true curves, :mod:`.mesh`), and returns the displacement at the lattice
nodes (they stay vertices of the refined mesh) together with a way to evaluate it
anywhere.

Supports and loads on named parts act on the whole boundary segment (every refined
facet on it, every dof of those facets); supports on node index arrays act on those
nodes and on the facets of the boundary edges joining two of them. Prescribed values
given per node are interpolated linearly along each boundary edge; prescribed
functions of position are evaluated at every constrained dof. Tractions and pressures
are integrated along the facets, body forces over the elements.

scikit-fem is imported on first use only.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from .._checks import check_int, check_positive
from ..errors import InputError
from ..lattice import VoronoiModel
from ..material import Elastic, lame_plane_stress
from ..mesh import Mesh
from ..problem import (
    BodyForce,
    PointLoad,
    Pressure,
    Traction,
    as_list,
    evaluate,
    select_edges,
    select_nodes,
    support_components,
)
from .compare import Comparison, compare
from .info import FEInfo, FETimings
from .mesh import FEMesh, build
from .probes import FACET_CHUNK, probe_matrix
from .system import solve_spd

if TYPE_CHECKING:  # annotations only: scipy is imported where it is used
    import scipy.sparse as sp


log = logging.getLogger(__name__)

__all__ = [
    "lame_plane_stress",
    "FESolution",
    "FEInfo",
    "FETimings",
    "solve",
    "Comparison",
    "compare",
]


#: most uniform refinements of the FE reference (the library's and the scene's limit)
MAX_REFINE = 8
#: highest Lagrange element order (P1 to P4)
MAX_ORDER = 4


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
    info : FEInfo
        ``n_dof``, ``n_elements``, ``lame``, ``load_resultant`` (total applied force),
        ``seconds`` per stage (:class:`FETimings`: mesh, assembly, solve, total).
    basis : skfem.Basis
        The vector basis on every element (for your own post-processing with
        scikit-fem; built on first use: its quadrature data are about 250 MB at 7e4 P2
        elements, which the solve does not need).
    x : ndarray
        The dof vector of ``basis``.
    fe_mesh : FEMesh
        The refined mesh and its boundary bookkeeping.
    lame : tuple of ndarray
        In-plane ``lambda``, ``mu`` and out-of-plane ``lambda_zz`` of every element.
    """

    mesh: Mesh
    u: np.ndarray
    order: int
    refine: int
    info: FEInfo
    x: np.ndarray
    fe_mesh: FEMesh
    lame: tuple

    @cached_property
    def basis(self):
        import skfem

        return skfem.Basis(self.fe_mesh.skfem, _vector_element(self.order))

    @cached_property
    def _dofs(self):
        """The vector basis on one element: the dof numbering without quadrature data."""
        return _dof_basis(self.fe_mesh, self.order)

    def evaluate(self, points) -> np.ndarray:
        """Displacement at arbitrary points inside the mesh, shape (n, 2)."""
        p = _points(points)
        v = probe_matrix(self._dofs, self.fe_mesh, p) @ self.x
        n = len(p)
        return np.c_[v[:n], v[n:]]

    @property
    def max_displacement(self) -> float:
        return float(np.max(np.hypot(self.u[:, 0], self.u[:, 1])))

    @cached_property
    def _stress_fields(self):
        """Element stresses (sxx, syy, sxy, szz) L2-projected onto continuous scalar
        elements."""
        import skfem

        lam, mu, lzz = (v[:, None] for v in self.lame)
        sb = skfem.Basis(self.fe_mesh.skfem, _scalar_element(self.order))
        # each displacement component as a scalar field of sb (a quarter of the vector
        # basis's quadrature data): its gradient (2, elements, quadrature points)
        g = [sb.interpolate(_component(self._dofs, sb, self.x, c)).grad for c in range(2)]
        exx, eyy, exy = g[0][0], g[1][1], 0.5 * (g[0][1] + g[1][0])
        tr = exx + eyy
        comps = (lam * tr + 2 * mu * exx, lam * tr + 2 * mu * eyy, 2 * mu * exy, lzz * tr)
        return sb, _l2_project(sb, comps)

    def stress(self, points) -> np.ndarray:
        """Plane-stress Cauchy stress at points, shape (n, 2, 2).

        The element stresses are L2-projected onto continuous scalar elements of the
        same order (smooth nodal stresses), then evaluated at the points. Stress is force
        per area (with a thickness, forces were totals and stresses are not).
        """
        p = _points(points)
        sb, vals = self._stress_fields
        probe = probe_matrix(sb, self.fe_mesh, p)
        sxx, syy, sxy = (probe @ v for v in vals[:3])
        return np.stack([np.stack([sxx, sxy], -1), np.stack([sxy, syy], -1)], -2)

    def out_of_plane_stress(self, points) -> np.ndarray:
        """``szz`` at points, shape (n,): ``lambda (exx + eyy)`` in plane strain (the
        3-D Lame constant), zero in plane stress."""
        p = _points(points)
        sb, vals = self._stress_fields
        return probe_matrix(sb, self.fe_mesh, p) @ vals[3]


#: relative residual of the stress projections' CG solves (mass matrix, Jacobi)
PROJECTION_RTOL = 1e-12


def _l2_project(sb, fields) -> list[np.ndarray]:
    """L2 projections of quadrature-point fields (n_elements, n_points) onto the
    continuous scalar basis ``sb``: one mass matrix, and CG preconditioned by its
    diagonal (a mass matrix is well conditioned: at 2.2e5 P2 dof 0.2 s against 2.5 s
    for a factorisation)."""
    import scipy.sparse.linalg as spla
    import skfem

    mass = skfem.asm(skfem.BilinearForm(lambda u, v, w: u * v), sb).tocsr()
    rhs = skfem.LinearForm(lambda v, w: w.f * v)
    inv_diag = 1.0 / mass.diagonal()
    jacobi = spla.LinearOperator(mass.shape, matvec=lambda r: inv_diag * r.ravel())
    out = []
    for f in fields:
        b = skfem.asm(rhs, sb, f=f)
        x, fail = spla.cg(mass, b, rtol=PROJECTION_RTOL, atol=0.0, M=jacobi, maxiter=2000)
        if fail:  # never seen: fall back to a factorisation
            x = spla.splu(mass.tocsc()).solve(b)
        out.append(x)
    return out


def _points(points) -> np.ndarray:
    p = np.atleast_2d(np.asarray(points, dtype=float))
    if p.ndim != 2 or p.shape[1] != 2:
        raise InputError(f"points must have shape (n, 2), got {p.shape}", "points")
    return p


def solve(
    mesh,
    E: float | None = None,
    nu: float | None = None,
    supports=None,
    loads=None,
    order: int = 1,
    refine: int = 0,
    plane: str = "stress",
    thickness: float | None = None,
    materials=None,
) -> FESolution:
    """Plane FE solution with the lattice's supports and loads.

    Parameters
    ----------
    mesh : Mesh, or a DV / RV model
        Bounded mesh; its triangles are the elements (refined ``refine`` times). Given a
        model, ``dv.fem.solve(model, supports, loads, order=2)`` takes its mesh, E, nu,
        plane, thickness and materials (the reference of exactly that problem).
    E, nu : float
        Young's modulus (> 0) and Poisson's ratio (-1 < nu < 1; < 0.5 in plane strain).
    supports, loads
        As for :func:`dvstatic.solve`.
    order : {1, 2, 3, 4}
        Lagrange element order (2 and up: quadratic geometry on curved boundaries).
    refine : int
        Uniform refinements (each splits a triangle into four), >= 0.
    plane, thickness, materials
        As for :class:`dvstatic.DV`: plane strain uses the 3-D Lame constants
        ``lambda = E nu / ((1 + nu)(1 - 2 nu))``; the thickness multiplies the
        stiffness and the distributed loads; ``materials`` maps region names of the
        mesh to ``(E, nu)``.

    Returns
    -------
    FESolution
    """
    import skfem

    if isinstance(mesh, VoronoiModel):
        model = mesh
        if supports is not None or loads is not None:
            raise TypeError("fem.solve(model, supports, loads, ...): E and nu come from the model")
        supports, loads = E, nu
        mesh, E, nu, plane = model.mesh, model.E, model.nu, model.plane
        thickness = model.thickness
        materials = {k: (m.E, m.nu) for k, m in model.materials.items()} or None
    if not isinstance(mesh, Mesh):
        raise TypeError(f"mesh must be a dvstatic Mesh or model, got {type(mesh).__name__}")
    if E is None or nu is None:
        raise TypeError("fem.solve(mesh, E, nu, supports, loads, ...) needs E and nu")
    if mesh.is_periodic:
        raise InputError("the FE reference needs a bounded mesh", "mesh")
    table = _materials(mesh, Elastic(E, nu, plane), materials)
    t = 1.0 if thickness is None else check_positive("thickness", thickness)
    order = check_int("order", order, minimum=1, maximum=MAX_ORDER)
    refine = check_int("refine", refine, minimum=0, maximum=MAX_REFINE)
    t0 = time.perf_counter()
    fe = build(mesh, refine, order)
    elem = _vector_element(order)
    basis = _dof_basis(fe, order)  # the dof bookkeeping without quadrature data
    t1 = time.perf_counter()
    lame = _element_lame(mesh, fe, table)
    K = t * _stiffness(fe, elem, lame[:2], basis.N)
    f = _load_vector(mesh, fe, elem, basis, loads, t)
    D, vals = _prescribed(mesh, fe, basis, supports)
    x = np.zeros(basis.N)
    x[D] = vals
    A, b, x_free, free = skfem.condense(K, f, x=x, D=D)
    del K  # A is a copy
    t2 = time.perf_counter()
    comp = _components(basis)
    x[free], solver, its = solve_spd(A, b, basis.doflocs[:, free].T, comp[free])
    t3 = time.perf_counter()
    nodal = basis.nodal_dofs
    u = np.c_[x[nodal[0, : mesh.n_points]], x[nodal[1, : mesh.n_points]]]
    info = FEInfo(
        n_dof=int(basis.N),
        n_elements=int(fe.triangles.shape[0]),
        lame=(float(lame[0][0]), float(lame[1][0])),
        plane=plane,
        thickness=t,
        load_resultant=_resultant(basis, f),
        seconds=FETimings(t1 - t0, t2 - t1, t3 - t2, t3 - t0),
        solver=solver,
        iterations=its,
    )
    log.info("FE P%d refine=%d: %d dof in %.3f s", order, refine, basis.N, t3 - t0)
    return FESolution(mesh, u, order, refine, info, x, fe, lame)


def _materials(mesh: Mesh, default: Elastic, materials) -> list[Elastic]:
    """The default material, then one per named region (checked against the mesh)."""
    out = [default]
    for name, value in (materials or {}).items():
        if name not in mesh.regions:
            known = ", ".join(repr(k) for k in mesh.regions) or "none"
            raise InputError(
                f"materials: unknown region {name!r}; the mesh's regions: {known}", "materials"
            )
        E, nu = value
        out.append((name, Elastic(E, nu, default.plane)))
    return out


def _element_lame(mesh: Mesh, fe: FEMesh, table) -> tuple[np.ndarray, ...]:
    """In-plane Lame constants (lambda, mu) and the out-of-plane ``lambda_zz`` (0 in
    plane stress) of every FE element, each shape (n_elements,)."""
    default = table[0]
    coarse = np.zeros(mesh.n_triangles, dtype=np.int64)
    for k, (name, _) in enumerate(table[1:], start=1):
        coarse[mesh.regions[name]] = k
    mats = [default] + [m for _, m in table[1:]]
    lam, mu, lzz = (np.array(v) for v in zip(*(_lame(m) for m in mats), strict=True))
    k = coarse[fe.parent_triangle]
    return lam[k], mu[k], lzz[k]


def _lame(m: Elastic) -> tuple[float, float, float]:
    mu = m.E / (2.0 * (1.0 + m.nu))
    if m.plane == "stress":
        return m.E * m.nu / (1.0 - m.nu**2), mu, 0.0
    lam = m.E * m.nu / ((1.0 + m.nu) * (1.0 - 2.0 * m.nu))  # the 3-D constant
    return lam, mu, lam


#: P2 elements per chunk of the FE stiffness assembly (each chunk's basis holds its
#: quadrature data: 12 P2 gradients at 6 points, about 35 MB per 2e4 elements; higher
#: orders take fewer, :func:`_chunk`)
ASSEMBLY_CHUNK = 20_000


def _dof_basis(fe: FEMesh, order: int):
    """The vector basis on one element: global dof numbering, no quadrature data."""
    import skfem

    return skfem.Basis(fe.skfem, _vector_element(order), elements=np.array([0]))


def _component(vector, scalar, x: np.ndarray, c: int) -> np.ndarray:
    """Component ``c`` of the vector dofs ``x`` as dofs of the scalar basis (of the
    same order)."""
    out = np.zeros(scalar.N)
    for kind in ("nodal_dofs", "facet_dofs", "interior_dofs"):
        s, v = getattr(scalar, kind), getattr(vector, kind)
        # a vector element's dofs of each kind come as (x, y) pairs of its scalar dofs
        for k in range(s.shape[0]):
            out[s[k]] = x[v[2 * k + c]]
    return out


def _components(basis) -> np.ndarray:
    """The component (0: x, 1: y) of every dof of a vector ``basis``, shape (N,)."""
    comp = np.zeros(basis.N, dtype=np.int8)
    for kind in ("nodal_dofs", "facet_dofs", "interior_dofs"):
        rows = getattr(basis, kind)
        if rows.size:
            comp[rows[1::2].ravel()] = 1
    return comp


def _scalar_element(order: int):
    import skfem

    return (skfem.ElementTriP1, skfem.ElementTriP2, skfem.ElementTriP3, skfem.ElementTriP4)[
        order - 1
    ]()


def _vector_element(order: int):
    import skfem

    return skfem.ElementVector(_scalar_element(order))


def _stiffness(fe: FEMesh, elem, per_element, n_dof: int) -> sp.csr_matrix:
    """The elasticity stiffness ``int lambda tr(e_u) tr(e_v) + 2 mu e_u : e_v``,
    shape (N, N): the element matrices from each chunk's basis gradients in one
    product (scikit-fem's form assembly calls a kernel per pair of basis functions),
    their upper triangles gathered as one COO array and summed once (plate_with_hole
    refined once, 6.9e4 P2 elements: a peak of 320 MB against 580 MB when each chunk
    was added to the matrix through CSR)."""
    import scipy.sparse as sp
    import skfem

    lam, mu = per_element
    n, nb = fe.skfem.t.shape[1], len(elem.doflocs)
    iu, ju = np.triu_indices(nb)
    rows = np.empty((len(iu), n), dtype=np.int32 if n_dof < 2**31 else np.int64)
    cols, data = np.empty_like(rows), np.empty((len(iu), n))
    dofs = skfem.Dofs(fe.skfem, elem)  # the global numbering, once for every chunk
    chunk = _chunk(fe, elem, dofs)
    for start in range(0, n, chunk):
        idx = np.arange(start, min(n, start + chunk))
        part = skfem.Basis(fe.skfem, elem, elements=idx, dofs=dofs, disable_doflocs=True)
        ke = _element_matrices(part, lam[idx], mu[idx])
        rows[:, idx], cols[:, idx] = part.element_dofs[iu], part.element_dofs[ju]
        data[:, idx] = ke[iu, ju]
    upper = sp.csr_matrix((data.ravel(), (rows.ravel(), cols.ravel())), shape=(n_dof, n_dof))
    del rows, cols, data
    return (upper + upper.T - sp.diags(upper.diagonal())).tocsr()


def _chunk(fe: FEMesh, elem, dofs) -> int:
    """Elements per assembly chunk: :data:`ASSEMBLY_CHUNK` for P2 (12 basis functions
    at 6 quadrature points), fewer in proportion for higher orders (P3: 20 at 12, so a
    chunk of 6,000; plate_with_hole, 1.7e4 P3 elements in one chunk: a peak of 516 MB
    against 261 MB in chunks of 4,000, measured before the chunk took this size)."""
    import skfem

    one = skfem.Basis(fe.skfem, elem, elements=np.array([0]), dofs=dofs, disable_doflocs=True)
    return max(1, ASSEMBLY_CHUNK * 72 // (one.Nbfun * one.X.shape[1]))


def _element_matrices(part, lam: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """Element stiffness matrices of a basis chunk, shape (nb, nb, n_elements): at each
    quadrature point ``B^T C B dx`` with the strain-displacement matrix ``B`` (strain
    components xx, yy, sqrt(2) xy, so that ``e_u : e_v`` is a dot product) from the
    chunk's basis gradients."""
    g = np.stack([b[0].grad for b in part.basis], axis=-1)  # (2, 2, e, q, nb)
    ke = np.zeros((g.shape[2], g.shape[4], g.shape[4]))
    for q in range(g.shape[3]):
        B = np.stack(
            [g[0, 0, :, q], g[1, 1, :, q], np.sqrt(0.5) * (g[0, 1, :, q] + g[1, 0, :, q])], 1
        )
        w = part.dx[:, q]
        CB = 2.0 * (mu * w)[:, None, None] * B
        CB[:, :2] += ((lam * w)[:, None] * (B[:, 0] + B[:, 1]))[:, None, :]
        ke += np.matmul(B.transpose(0, 2, 1), CB)
    return ke.transpose(1, 2, 0)


def _resultant(basis, f: np.ndarray) -> tuple[float, float]:
    """Total applied force (the load vector summed per component)."""
    comp = _components(basis)
    return tuple(float(f[comp == c].sum()) for c in range(2))


def _facets_of(mesh: Mesh, fe: FEMesh, edges: np.ndarray) -> np.ndarray:
    """skfem boundary facets lying on the coarse boundary edges ``edges`` (m, 2)."""
    n = mesh.n_points
    be = mesh.boundary_edges
    key_be = be[:, 0] * n + be[:, 1]
    order = np.argsort(key_be)
    idx = order[np.searchsorted(key_be[order], edges[:, 0] * n + edges[:, 1])]
    chosen = np.zeros(len(be), dtype=bool)
    chosen[idx] = True
    bf = fe.skfem.boundary_facets()
    return bf[chosen[fe.parent[fe.facet_index(bf)]]]


def _load_vector(mesh: Mesh, fe: FEMesh, elem, basis, loads, t: float = 1.0) -> np.ndarray:
    """Consistent load vector: tractions and pressures integrated along the facets of
    their edges, body forces over the elements (times the thickness ``t``), point loads
    on the lattice nodes."""
    import skfem

    f = np.zeros(basis.N)
    for load in as_list(loads, "Traction, Pressure, BodyForce or PointLoad"):
        if isinstance(load, (Traction, Pressure)):
            what = type(load).__name__
            edges = select_edges(mesh, load.where, what)
            facets = _facets_of(mesh, fe, edges)
            # in chunks: scikit-fem's inverse isoparametric map (quadratic geometry)
            # tests convergence on the sum over all points, which a long list never meets
            for start in range(0, len(facets), FACET_CHUNK):
                fb = skfem.FacetBasis(fe.skfem, elem, facets=facets[start : start + FACET_CHUNK])
                f += t * skfem.asm(_boundary_form(load), fb)
        elif isinstance(load, BodyForce):
            f += t * skfem.asm(
                _vector_form(load.value, "BodyForce"), _body_basis(mesh, fe, basis, load)
            )
        elif isinstance(load, PointLoad):
            nodes = select_nodes(mesh, load.nodes, "PointLoad")
            for c in range(2):
                np.add.at(f, basis.nodal_dofs[c, nodes], load.value[c])
        else:
            raise TypeError(f"unknown load type {type(load).__name__}")
    return f


def _body_basis(mesh: Mesh, fe: FEMesh, basis, load: BodyForce):
    """The basis of the body force's elements (all, or those of its region)."""
    import skfem

    if load.region is None:
        return skfem.Basis(fe.skfem, basis.elem)
    if load.region not in mesh.regions:
        known = ", ".join(repr(k) for k in mesh.regions) or "none"
        raise InputError(
            f"BodyForce: unknown region {load.region!r}; the mesh's regions: {known}", "region"
        )
    inside = np.isin(fe.parent_triangle, mesh.regions[load.region])
    return skfem.Basis(fe.skfem, basis.elem, elements=np.flatnonzero(inside))


def _at(w) -> np.ndarray:
    """Quadrature points of a form as an (m, 2) array."""
    return np.stack([w.x[0].ravel(), w.x[1].ravel()], axis=1)


def _vector_form(value, what: str):
    """Linear form of a constant or position-dependent force density (2 components)."""
    import skfem

    @skfem.LinearForm
    def form(v, w):
        if callable(value):
            shape = w.x[0].shape
            b = evaluate(value, _at(w), (2,), what)
            return b[:, 0].reshape(shape) * v[0] + b[:, 1].reshape(shape) * v[1]
        return value[0] * v[0] + value[1] * v[1]

    return form


def _boundary_form(load):
    """Linear form of a traction, or of a pressure ``-p n`` with the outward normal."""
    import skfem

    if isinstance(load, Traction):
        return _vector_form(load.value, "Traction")

    @skfem.LinearForm
    def pressure(v, w):
        shape = w.x[0].shape
        p = evaluate(load.p, _at(w), (), "Pressure").reshape(shape) if callable(load.p) else load.p
        return -p * (w.n[0] * v[0] + w.n[1] * v[1])

    return pressure


def _prescribed(mesh: Mesh, fe: FEMesh, basis, supports) -> tuple[np.ndarray, np.ndarray]:
    """Prescribed FE dofs and values.

    Every dof on the facets of the selected boundary edges (a named part; the
    boundary edges joining two selected nodes) and the vertex dofs of the selected
    nodes. A function of position is evaluated at each dof; per-node values are
    interpolated linearly along their coarse edge.
    """
    dof_list, val_list = [], []
    be = mesh.boundary_edges
    for c in support_components(mesh, supports):
        dof_list.append(basis.nodal_dofs[c.component, c.nodes])
        val_list.append(np.broadcast_to(np.asarray(c.value, dtype=float), c.nodes.shape))
        chosen = np.zeros(mesh.n_points, dtype=bool)
        chosen[c.nodes] = True
        on = chosen[be[:, 0]] & chosen[be[:, 1]]
        if on.any():
            dofs, edge, s = _facet_dofs(mesh, fe, basis, be[on], c.component)
            dof_list.append(dofs)
            val_list.append(_values(mesh, basis, c, dofs, edge, s))
    if not dof_list:
        raise InputError("no supports: the FE problem is singular", "supports")
    D, first = np.unique(np.concatenate(dof_list), return_index=True)
    return D, np.concatenate(val_list)[first]


def _facet_dofs(mesh: Mesh, fe: FEMesh, basis, edges: np.ndarray, comp: int):
    """Dofs of component ``comp`` on the facets of coarse boundary ``edges``, with the
    coarse edge and the parameter along it of every dof."""
    bf = _facets_of(mesh, fe, edges)
    rows = fe.facet_index(bf)
    edge, s = fe.parent[rows], fe.s[rows]
    dofs = [basis.nodal_dofs[comp, fe.facets[rows, 0]], basis.nodal_dofs[comp, fe.facets[rows, 1]]]
    edges_, params = [edge, edge], [s[:, 0], s[:, 1]]
    ends = fe.points[fe.facets[rows]]  # (k, 2, 2)
    along = ends[:, 1] - ends[:, 0]
    for k in range(comp, basis.facet_dofs.shape[0], 2):  # P2 and up: dofs inside facets
        d = basis.facet_dofs[k, bf]
        # where the dof lies between the facet's ends (on the chord; a curved facet's
        # mid-nodes project onto it), mapped onto the facet's stretch of its coarse edge
        t = np.einsum("ij,ij->i", basis.doflocs[:, d].T - ends[:, 0], along)
        t /= np.einsum("ij,ij->i", along, along)
        dofs.append(d)
        edges_.append(edge)
        params.append((1.0 - t) * s[:, 0] + t * s[:, 1])
    return np.concatenate(dofs), np.concatenate(edges_), np.concatenate(params)


def _values(mesh: Mesh, basis, c, dofs, edge, s) -> np.ndarray:
    """Prescribed values at ``dofs``: the field at their locations, the constant, or
    the per-node values interpolated along the coarse edge."""
    if c.field is not None:
        return evaluate(c.field, basis.doflocs[:, dofs].T, (), f"Fix {'xy'[c.component]}")
    if np.ndim(c.value) == 0:
        return np.full(dofs.size, float(c.value))
    full = np.zeros(mesh.n_points)
    full[c.nodes] = c.value
    a, b = mesh.boundary_edges[edge, 0], mesh.boundary_edges[edge, 1]
    return (1.0 - s) * full[a] + s * full[b]
