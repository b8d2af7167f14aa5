"""The bond lattice as an operator: tensions, internal forces and matrices for given
micro-parameters (the kernels that the DV/RV models, the calibration, the stability
analysis and the distributed engine share).

Each bond (mesh edge) O-A carries a normal spring whose rest length grows with the
change of its dual Voronoi side. With a spring stiffness ``k_e`` per bond and a coupling
stiffness ``g_T`` per triangle (the paper: ``k_e = k_n``, ``g_T = k_n nu_m``), the
tension in the current configuration is::

    T_e = k_e (l'_e - l_e) - sum_{T at e} g_T (r_eT - r'_eT)

and acts along the current bond on its two particles. ``r'_eT`` is the signed distance
of the circumcentre image of triangle T from the current bond line: DV keeps the
circumcentre's reference barycentric coordinates in the deformed triangle
(``barycentric=True``), RV takes the circumcentre of the deformed triangle.

``internal_force`` is exact for any displacement (invariant to rigid rotations of
any size); ``tangent`` is its exact Jacobian; ``stiffness`` is the tangent at u = 0.
A coupling coefficient per triangle keeps the stiffness symmetric.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from .._checks import as_displacement, as_strain
from .._planar import signed_area2
from ..errors import InputError
from ..mesh import Mesh
from . import assembly
from . import geometry as _geometry
from .kinematics import A_OF, O_OF, edge_frames, elongation_gradients, half_sides
from .stabilise import flat_triangles, reference_matrices

if TYPE_CHECKING:  # annotations only: scipy is imported where it is used
    import scipy.sparse as sp


log = logging.getLogger(__name__)

__all__ = [
    "LatticeOperator",
    "scatter_bond_forces",
    "virial_sum",
    "coupling_factor",
    "term_mask",
    "CHUNK",
]

CHUNK = 1 << 18  # triangles per assembly chunk (bounds temporary memory)


#: stiffness fraction a broken bond keeps (numerical only: no tension is ever read from
#: it; :mod:`dvstatic.lattice.damage`)
RESIDUAL = 1e-9


def scatter_bond_forces(bonds: np.ndarray, fb: np.ndarray, n: int) -> np.ndarray:
    """Nodal forces of bond forces: ``+fb`` on end A, ``-fb`` on end O, interleaved (2n,).

    Parameters
    ----------
    bonds : ndarray of int, shape (n_bonds, 2)
        End nodes (O, A).
    fb : ndarray, shape (n_bonds, 2)
        Force of every bond on its end A.
    n : int
        Number of nodes.
    """
    f = np.zeros((n, 2))
    for c in range(2):
        f[:, c] = np.bincount(bonds[:, 1], fb[:, c], n) - np.bincount(bonds[:, 0], fb[:, c], n)
    return f.reshape(-1)


def virial_sum(t: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``sum_e T_e l_e n_e (x) n_e = sum_e (T_e / l_e) d_e (x) d_e``, shape (2, 2), for
    tensions ``t`` (n_bonds,) and bond vectors ``d`` (n_bonds, 2); divided by an area it
    is the mean (virial) stress."""
    ln = np.hypot(d[:, 0], d[:, 1])
    return np.einsum("e,ei,ej->ij", t / ln, d, d)


def _chunks(m: int):
    for start in range(0, m, CHUNK):
        yield slice(start, min(m, start + CHUNK))


@dataclass(frozen=True, eq=False)
class LatticeOperator:
    """Forces and matrices of a DV/RV bond lattice with given stiffnesses.

    Parameters
    ----------
    mesh : Mesh
    spring : ndarray, shape (n_bonds,)
        Normal-spring stiffness ``k_e`` of every bond (units of E: force per length per
        unit thickness).
    coupling : ndarray, shape (M,)
        Coupling stiffness ``g_T`` of every triangle (the paper: ``k_n nu_m``).
    barycentric : bool
        True for DV (circumcentre images with reference barycentric coordinates),
        False for RV (current circumcentres).
    cells : ndarray of int, shape (k,), optional
        Triangles with an exact-cell term (:mod:`dvstatic.lattice.cells`).
    cell_dq : ndarray, shape (k, 3, 3), optional
        Their bond matrices ``dQ_T`` (force / length): tensions ``dQ_T e_T`` of the
        triangle's three bond elongations ``e_T = l' - l`` add to the bonds'.
    """

    mesh: Mesh
    spring: np.ndarray
    coupling: np.ndarray
    barycentric: bool = True
    cells: np.ndarray | None = None
    cell_dq: np.ndarray | None = None
    assembly_seconds: float = field(default=0.0, init=False)

    def __post_init__(self) -> None:
        spring = np.broadcast_to(np.asarray(self.spring, dtype=float), (self.mesh.n_bonds,))
        coupling = np.broadcast_to(np.asarray(self.coupling, dtype=float), (self.mesh.n_triangles,))
        object.__setattr__(self, "spring", spring)
        object.__setattr__(self, "coupling", coupling)
        if (self.cells is None) != (self.cell_dq is None):
            raise InputError("cells and cell_dq go together", "cells")
        if self.cells is not None:
            cells = np.asarray(self.cells, dtype=np.int64)
            dq = np.asarray(self.cell_dq, dtype=float)
            if dq.shape != (len(cells), 3, 3):
                raise InputError(
                    f"cell_dq must have shape ({len(cells)}, 3, 3), got {dq.shape}", "cell_dq"
                )
            object.__setattr__(self, "cells", cells if len(cells) else None)
            object.__setattr__(self, "cell_dq", dq if len(cells) else None)

    @cached_property
    def _cell_of(self) -> np.ndarray:
        """Position of every triangle in :attr:`cells` (-1 if not a cell), shape (M,)."""
        out = np.full(self.mesh.n_triangles, -1, dtype=np.int64)
        out[self.cells] = np.arange(len(self.cells))
        return out

    @cached_property
    def _cell_b(self) -> np.ndarray:
        """Reference elongation gradients (k, 3, 6) of the cells."""
        return elongation_gradients(edge_frames(self.geometry.x_tri[self.cells])[2])

    def _cell_tension(self, elong: np.ndarray) -> np.ndarray:
        """The cells' share of the bond tensions (n_bonds,) for their bonds'
        elongations ``elong`` (k, 3)."""
        f = np.einsum("mkl,ml->mk", self.cell_dq, elong)
        tb = self.mesh.topology.tri_bonds[self.cells]
        return np.bincount(tb.ravel(), f.ravel(), self.mesh.n_bonds)

    @cached_property
    def geometry(self) -> _geometry.Geometry:
        """Reference geometry of the mesh (shared through the geometry cache)."""
        return _geometry.of(self.mesh)

    @cached_property
    def has_coupling(self) -> bool:
        """True if any triangle carries a Voronoi coupling."""
        return bool(np.any(self.coupling != 0.0))

    def _bary(self, sl: slice = slice(None)) -> np.ndarray | None:
        return self.geometry.bary[sl] if self.barycentric else None

    # ------------------------------------------------------------ configuration
    def check_strain(self, strain) -> np.ndarray | None:
        """A macroscopic strain of the period (periodic meshes), checked, or None."""
        if strain is None:
            return None
        if not self.mesh.is_periodic:
            raise InputError(
                "strain (a macroscopic strain of the period) applies to periodic meshes only; "
                "for a bounded mesh pass the displacement u = x @ eps.T instead",
                "strain",
            )
        return as_strain(strain, "strain")

    def deformed_triangles(self, u: np.ndarray, strain=None, sl=slice(None)) -> np.ndarray:
        """Current vertex positions of triangles ``sl``, unwrapped, shape (m, 3, 2)."""
        tri = self.mesh.triangles[sl]
        y = self.geometry.x_tri[sl] + u[tri]
        if strain is not None:
            y = y + np.einsum("ij,mvj->mvi", strain, self.mesh.images[sl] * self.mesh.period)
        return y

    def deformed_bonds(self, u: np.ndarray, strain=None) -> np.ndarray:
        """Current bond vectors A - O, shape (n_bonds, 2)."""
        g = self.geometry
        b = self.mesh.topology.bonds
        d = g.length[:, None] * g.direction + u[b[:, 1]] - u[b[:, 0]]
        if strain is not None:
            d = d + (self.mesh.topology.bond_image * self.mesh.period) @ strain.T
        return d

    def inverted(self, u: np.ndarray, strain=None) -> bool:
        """True if a triangle is flat or inverted in the displaced configuration."""
        return not bool(np.all(signed_area2(self.deformed_triangles(u, strain)) > 0))

    # ------------------------------------------------------------ forces
    def bond_state(self, u: np.ndarray, strain=None):
        """Tensions (n_bonds,), current bond vectors (n_bonds, 2) and lengths (n_bonds,).

        ``u`` of shape (N, 2) and ``strain`` are taken as checked.

        Raises
        ------
        InputError
            If a bond has collapsed to zero length.
        """
        g = self.geometry
        d = self.deformed_bonds(u, strain)
        length = np.hypot(d[:, 0], d[:, 1])
        if np.any(length <= 0):
            raise InputError("a bond has collapsed to zero length in this displacement", "u")
        t = self.spring * (length - g.length)
        if self.has_coupling:
            topo = self.mesh.topology
            change = np.zeros(len(g.length))
            for sl in _chunks(self.mesh.n_triangles):
                rt, _ = half_sides(self.deformed_triangles(u, strain, sl), self._bary(sl))
                dr = self.coupling[sl, None] * (g.tri_r[sl] - rt)
                change += np.bincount(topo.tri_bonds[sl].ravel(), dr.ravel(), len(g.length))
            t = t - change
        if self.cells is not None:
            tb = self.mesh.topology.tri_bonds[self.cells]
            t = t + self._cell_tension(length[tb] - g.length[tb])
        return t, d, length

    def bond_tension(self, u, strain=None) -> np.ndarray:
        """Bond tensions on the current geometry, shape (n_bonds,) (force units)."""
        u = as_displacement(u, self.mesh.n_points)
        return self.bond_state(u, self.check_strain(strain))[0]

    def internal_force(self, u, strain=None) -> np.ndarray:
        """Internal (spring) forces on the nodes, interleaved, shape (2N,)."""
        u = as_displacement(u, self.mesh.n_points)
        t, d, length = self.bond_state(u, self.check_strain(strain))
        return scatter_bond_forces(
            self.mesh.topology.bonds, (t / length)[:, None] * d, self.mesh.n_points
        )

    def linear_tension(self, u, strain=None) -> np.ndarray:
        """Bond tensions of the linearised model, shape (n_bonds,).

        ``T = k_e n.(u_A - u_O) + sum_T g_T dr_T . u``; with ``strain`` on a periodic mesh
        the period carries that macroscopic strain.
        """
        u = as_displacement(u, self.mesh.n_points)
        strain = self.check_strain(strain)
        g = self.geometry
        topo = self.mesh.topology
        b = topo.bonds
        du = u[b[:, 1]] - u[b[:, 0]]
        if strain is not None:
            du = du + (topo.bond_image * self.mesh.period) @ strain.T
        t = self.spring * np.einsum("ei,ei->e", g.direction, du)
        if self.has_coupling:
            for sl in _chunks(self.mesh.n_triangles):
                _, dr = half_sides(g.x_tri[sl], self._bary(sl), grad=True)
                ut = u[self.mesh.triangles[sl]]
                if strain is not None:
                    ut = ut + np.einsum(
                        "ij,mvj->mvi", strain, self.mesh.images[sl] * self.mesh.period
                    )
                rt = self.coupling[sl, None] * np.einsum("mkj,mj->mk", dr, ut.reshape(len(ut), 6))
                t = t + np.bincount(topo.tri_bonds[sl].ravel(), rt.ravel(), len(t))
        if self.cells is not None:  # no cells on periodic meshes: no strain term
            ut = u[self.mesh.triangles[self.cells]].reshape(len(self.cells), 6)
            t = t + self._cell_tension(np.einsum("mkj,mj->mk", self._cell_b, ut))
        return t

    # ------------------------------------------------------------ matrices
    def element_matrices(
        self, y: np.ndarray, sl: slice, tension=None, reference: bool = False
    ) -> np.ndarray:
        """Triangle 6x6 tangent blocks for current vertex positions ``y`` (m, 3, 2) of
        triangles ``sl``; with ``tension`` (n_bonds,) the geometric (initial-stress) part
        is added; ``reference``: ``y`` is the reference configuration (the half sides'
        gradients in closed form)."""
        g = self.geometry
        tri_bonds = self.mesh.topology.tri_bonds[sl]
        _, length, n = edge_frames(y)
        m = len(y)
        b = elongation_gradients(n)
        q = (g.tri_weight[sl] * self.spring[tri_bonds])[..., None] * b
        if self.has_coupling:
            if reference:  # dr = M b in closed form (lattice.stabilise), but slivers
                dr = np.matmul(reference_matrices(g, self.barycentric, sl), b)
                flat = flat_triangles(g, sl)
                if flat.size:
                    dr[flat] = half_sides(
                        y[flat], self._bary(sl)[flat] if self.barycentric else None, grad=True
                    )[1]
            else:
                _, dr = half_sides(y, self._bary(sl), grad=True)
            q = q + self.coupling[sl, None, None] * dr
        if self.cells is not None:  # the cells' bond matrices on the elongations
            loc = self._cell_of[sl]
            at = np.flatnonzero(loc >= 0)
            q[at] += np.matmul(self.cell_dq[loc[at]], b[at])
        ke = np.matmul(b.transpose(0, 2, 1), q)
        if tension is not None:
            s = g.tri_weight[sl] * tension[tri_bonds] / length
            proj = np.eye(2) - n[..., :, None] * n[..., None, :]
            sp_ = s[..., None, None] * proj  # (m, 3, 2, 2)
            ke5 = ke.reshape(m, 3, 2, 3, 2)
            for kk in range(3):
                o, a = O_OF[kk], A_OF[kk]
                ke5[:, o, :, o, :] += sp_[:, kk]
                ke5[:, a, :, a, :] += sp_[:, kk]
                ke5[:, o, :, a, :] -= sp_[:, kk]
                ke5[:, a, :, o, :] -= sp_[:, kk]
        return ke

    def assemble(self, u: np.ndarray | None = None, strain=None, tension=None) -> sp.bsr_matrix:
        """Tangent at ``u`` (N, 2) (stiffness when None), BSR (2N, 2N) with 2x2 blocks."""
        pat = assembly.pattern(self.mesh)
        data = np.zeros((pat.nnzb, 4))
        for sl in _chunks(self.mesh.n_triangles):
            if u is None:
                ke = self.element_matrices(self.geometry.x_tri[sl], sl, tension, reference=True)
            else:
                ke = self.element_matrices(self.deformed_triangles(u, strain, sl), sl, tension)
            assembly.accumulate(pat, ke, data, sl)
        return assembly.to_bsr(pat, data)

    @cached_property
    def stiffness_bsr(self) -> sp.bsr_matrix:
        """Linear stiffness (tangent at u = 0), BSR, assembled once."""
        t0 = time.perf_counter()
        k = self.assemble()
        object.__setattr__(self, "assembly_seconds", time.perf_counter() - t0)
        log.debug("assembled stiffness (%d dof) in %.3f s", k.shape[0], self.assembly_seconds)
        return k

    @property
    def is_assembled(self) -> bool:
        """True once the linear stiffness has been assembled (and cached)."""
        return "stiffness_bsr" in self.__dict__

    def tangent(self, u, strain=None) -> sp.bsr_matrix:
        """Exact Jacobian of :meth:`internal_force` at ``u``, BSR (2N, 2N)."""
        u = as_displacement(u, self.mesh.n_points)
        strain = self.check_strain(strain)
        t, _, _ = self.bond_state(u, strain)
        return self.assemble(u, strain, t)


def coupling_factor(d_tri: np.ndarray, terms=None, sl=slice(None)) -> np.ndarray:
    """The factor (k,) on the coupling of triangles whose bonds have stiffness factors
    ``d_tri`` (k, 3): their weakest bond's factor, and 0 from the first damaged bond on
    where the coupling holds an exact cell's or the regional isotropy's term (``terms``,
    (M,) bool, rows ``sl``): those terms make the intact triangle exactly P1 and have no
    softening law, so a damaged one is a set of plain springs (kept in proportion to the
    weakest bond, a cell carried the face across the crack while the bond's saw-tooth
    released it: Petersson's beam 1.244 kN at h = 14 mm against the cohesive 0.853)."""
    low = np.min(d_tri, axis=1)
    if terms is None:
        return low
    return np.where(terms[sl] & (low < 1.0), 0.0, low)


def term_mask(cells, n_triangles: int) -> np.ndarray | None:
    """(M,) bool: the triangles ``cells`` (int array, or None: no term) whose coupling
    holds a term with no softening law, for :func:`coupling_factor`."""
    if cells is None:
        return None
    out = np.zeros(n_triangles, dtype=bool)
    out[cells] = True
    return out
