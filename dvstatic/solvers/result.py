"""What a solve returns: :class:`Solution` (its report, :class:`SolveInfo`, and the
records in it are in :mod:`.info`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..lattice import VoronoiModel
from ..mesh.locate import interpolate, snap_point
from ..problem import Problem
from ..stress import node_stress, out_of_plane_stress, strain_stress, triangle_stress
from .info import LinearSolve, NewtonStep, ParallelInfo, SolveInfo, StabilityCheck, Timings
from .responses import recovered_stress

__all__ = [
    "Solution",
    "SolveInfo",
    "NewtonStep",
    "StabilityCheck",
    "Timings",
    "LinearSolve",
    "ParallelInfo",
    "STRESS_METHODS",
]

#: stress recoveries of :meth:`Solution.stress`
STRESS_METHODS = ("recovered", "virial", "strain")


@dataclass(frozen=True, eq=False)
class Solution:
    """Result of :func:`dvstatic.solve`.

    Attributes
    ----------
    model : DV or RV
    u : ndarray, shape (N, 2)
        Nodal displacements (length units). ``None`` on MPI ranks other than 0 with
        ``solver="petsc"`` (rank 0 gathers the solution; so are ``reactions``).
    reactions : ndarray, shape (N, 2)
        Support reactions (force per unit thickness), non-zero at constrained dofs:
        the force the supports exert on the body.
    info : SolveInfo
        What ran and how it went.
    supports, loads : list
        What was solved.
    """

    model: VoronoiModel
    u: np.ndarray
    reactions: np.ndarray
    info: SolveInfo
    supports: list = field(default_factory=list)
    loads: list = field(default_factory=list)
    #: the supports and loads resolved (dofs, values, load vector) by the solve
    problem: Problem | None = field(default=None, repr=False)
    #: stresses computed so far, one per method
    _stresses: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def max_displacement(self) -> float:
        """Largest nodal displacement magnitude."""
        return float(np.max(np.hypot(self.u[:, 0], self.u[:, 1])))

    def tension(self) -> np.ndarray:
        """Bond tensions, shape (n_bonds,) (linearised for a linear solve)."""
        if self.info.nonlinear:
            return self.model.bond_tension(self.u)
        return self.model.linear_tension(self.u)

    def stress(self, method: str | None = None) -> np.ndarray:
        """Per-node stress, shape (N, 2, 2) (force per area).

        Parameters
        ----------
        method : {"recovered", "virial", "strain"}, optional
            ``recovered`` (the default for linear solutions): the continuum stress at an
            averaging scale of ``dvstatic.stress.RADIUS`` (4) local spacings
            (:mod:`dvstatic.stress.recovery`): force- and strain-based data averaged by
            equilibrated fits that match the stress vector on the boundary (read from
            the nodal forces, however the loads were written), then corrected by the
            lattice's own response to uniform stress, so that it is exact for any
            uniform stress at every node (boundary rows and corners included). The
            first call also solves those three responses (with this solution's
            engine); later solutions of the model with the same supports reuse them.
            ``virial`` (the default for nonlinear solutions: the Cauchy stress of the
            deformed lattice): the lattice's own force-based stress over each Voronoi
            cell (:func:`dvstatic.post.node_stress`). ``strain``: the continuum law
            applied to the area-averaged lattice strain
            (:func:`dvstatic.post.strain_stress`). Both keep the lattice's
            micro-structure (node-to-node scatter of 5-50 % on irregular meshes);
            :meth:`triangle_stress` has it per triangle.

        Each method is computed once per solution (a copy is returned); ``u`` is not
        meant to be changed in place.
        """
        if method is None:
            method = "virial" if self.info.nonlinear else "recovered"
        if method not in self._stresses:
            self._stresses[method] = self._compute_stress(method)
        return self._stresses[method].copy()

    def _compute_stress(self, method: str) -> np.ndarray:
        if method == "recovered":
            if self.info.nonlinear:
                raise InputError(
                    "the recovered stress applies the linear law to small strains; use "
                    "method='virial' for a nonlinear solution",
                    "method",
                )
            return recovered_stress(
                self.model, self.u, self.supports, self.loads, self.info.solver, self.problem
            )
        if method == "virial":
            return node_stress(self.model, self.u, linear=not self.info.nonlinear)
        if method == "strain":
            return strain_stress(self.model, self.u)
        raise InputError(
            f"unknown stress method {method!r}; accepted: {', '.join(STRESS_METHODS)}", "method"
        )

    def triangle_stress(self) -> np.ndarray:
        """The continuum law applied to every triangle's P1 strain, shape (M, 2, 2): the
        lattice's stress at the scale of one cell (micro-structure and all)."""
        return triangle_stress(self.model, self.u)

    def stress_at(self, points, method: str | None = None) -> np.ndarray:
        """Stress at arbitrary points, shape (n, 2, 2) (force per area): the nodal stress
        of ``method`` (see :meth:`stress`) interpolated linearly; a point just outside
        the mesh (on a curved boundary, within half the local spacing of a node) takes that
        node's value.

        Parameters
        ----------
        points : array_like, shape (n, 2) or (2,)

        Raises
        ------
        InputError
            A point outside the mesh.
        """
        mesh = self.model.mesh
        p = np.atleast_2d(np.asarray(points, dtype=float))
        if p.ndim != 2 or p.shape[1] != 2:
            raise InputError(f"points must have shape (n, 2), got {p.shape}", "points")
        s = self.stress(method).reshape(-1, 4)
        if len(p) == 0:
            return np.zeros((0, 2, 2))
        try:  # one search for all points; point by point only if one misses
            return interpolate(mesh, s, p).reshape(-1, 2, 2)
        except InputError:
            p = np.concatenate([snap_point(mesh, q) for q in p])
            return interpolate(mesh, s, p).reshape(-1, 2, 2)

    def mean_stress(self, region: str | None = None, method: str | None = None) -> np.ndarray:
        """Area-weighted mean stress over a region of the mesh (None: the whole body),
        shape (2, 2): the nodal stress of ``method`` integrated with linear shape
        functions over the region's triangles, divided by their area.

        Raises
        ------
        InputError
            An unknown region name (the known ones are listed).
        """
        mesh = self.model.mesh
        if region is None:
            tris = np.arange(mesh.n_triangles)
        elif region in mesh.regions:
            tris = np.asarray(mesh.regions[region])
        else:
            known = ", ".join(repr(k) for k in mesh.regions) or "none"
            raise InputError(f"unknown region {region!r}; known regions: {known}", "region")
        s = self.stress(method)[mesh.triangles[tris]].mean(axis=1)  # (m, 2, 2)
        a = np.asarray(mesh.triangle_areas)[tris]
        return np.einsum("m,mij->ij", a, s) / a.sum()

    def out_of_plane_stress(self, method: str | None = None) -> np.ndarray:
        """``szz`` per node, shape (N,): ``nu (sxx + syy)`` in plane strain (of the
        in-plane stress of ``method``, see :meth:`stress`), zero in plane stress."""
        return out_of_plane_stress(self.model, self.stress(method))

    def energy(self) -> float:
        """Strain energy ``u.K.u / 2`` of the linear model (energy per unit thickness, or
        the total with a ``thickness``)."""
        return self.model.energy(self.u)
