"""The deformable (DV) and remeshing (RV) Voronoi lattice models.

Each bond (mesh edge) O-A carries a normal spring whose rest length grows by
``dl = nu_m (r - r')`` when its dual Voronoi side changes from ``r`` to ``r'``. The
tension in the current configuration is::

    T = k_n (l' - l - nu_m (r - r'))

and acts along the current bond on its two particles. ``r'`` is the sum over the
bond's triangles of the signed distance of the circumcentre image from the current
bond line: DV keeps the circumcentre's reference barycentric coordinates in the
deformed triangle, RV takes the circumcentre of the deformed triangle.

``internal_force`` is exact for any displacement (invariant to rigid rotations of
any size); ``tangent`` is its exact Jacobian; ``stiffness`` is the tangent at u = 0.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from . import assembly, calibration
from . import geometry as _geometry
from ._checks import as_displacement, as_strain, check_choice, check_positive, check_real
from .distributed import launched_under_mpi
from .kinematics import A_OF, O_OF, edge_frames, half_sides
from .mesh import Mesh

if TYPE_CHECKING:  # annotations only: scipy is imported where it is used
    import scipy.sparse as sp


log = logging.getLogger(__name__)

__all__ = ["DV", "RV", "VoronoiModel", "voronoi_weights", "BONDS"]

BONDS = ("uniform", "voronoi")
#: floor of the Voronoi bond weight (a bond whose dual side vanishes keeps a spring)
MIN_WEIGHT = 0.05


def voronoi_weights(geom) -> np.ndarray:
    """Bond weights ``sqrt(3) r / l`` (1 on the regular lattice), floored at 0.05."""
    return np.maximum(np.sqrt(3.0) * geom.r / geom.length, MIN_WEIGHT)


CHUNK = 1 << 18  # triangles per assembly chunk (bounds temporary memory)


@dataclass(frozen=True, eq=False)
class VoronoiModel:
    """Common base of :class:`DV` and :class:`RV` (not used directly).

    Parameters
    ----------
    mesh : Mesh
    E : float
        Young's modulus of the plane-stress continuum (force per area), > 0.
    nu : float
        Poisson's ratio, in the calibration's admissible range (within (-1, 1)).
    calibration : {"paper", "relaxed"} or MicroParameters
        How ``k_n`` and ``nu_m`` are obtained from E and nu: ``"paper"`` (closed
        form under affine strain, eqs. 9-10 / 19-20), ``"relaxed"`` (the equilibrium,
        non-affinely relaxed response of a periodic sample with the mesh's bond-length
        spread matches E and nu; see :func:`dvstatic.calibration.relaxed`), or given
        :class:`~dvstatic.calibration.MicroParameters` (used as they are).
    bonds : {"uniform", "voronoi"}
        Normal-spring stiffness of each bond: the paper's uniform ``k_n``, or
        ``k_n w_e`` with ``w_e = sqrt(3) r_e / l_e`` (its own Voronoi side: 1 inside a
        regular lattice, 1/2 on its surface bonds), which removes the stiff surface
        layer. The Voronoi coupling stays uniform, so the stiffness stays symmetric.
    """

    mesh: Mesh
    E: float
    nu: float
    calibration: object = "paper"
    bonds: str = "uniform"
    kind: ClassVar[str] = ""
    barycentric_images: ClassVar[bool] = True

    def __post_init__(self) -> None:
        if type(self) is VoronoiModel:
            raise TypeError("use dvstatic.DV or dvstatic.RV")
        if not isinstance(self.mesh, Mesh):
            raise TypeError(f"mesh must be a dvstatic Mesh, got {type(self.mesh).__name__}")
        E = check_positive("E", self.E)
        nu = check_real("nu", self.nu)
        if not -1.0 < nu < 1.0:
            raise ValueError(f"nu must lie in the plane-stress range -1 < nu < 1, got {nu}")
        if not isinstance(self.calibration, calibration.MicroParameters):
            check_choice("calibration", self.calibration, calibration.CALIBRATIONS)
        check_choice("bonds", self.bonds, BONDS)
        object.__setattr__(self, "E", E)
        object.__setattr__(self, "nu", nu)
        if not launched_under_mpi():
            _ = self.micro  # calibrate now: an impossible nu fails at construction
        # under mpiexec the calibration waits: solver="petsc" computes it from sums
        # over each rank's own bonds, so no rank needs the global geometry

    # ------------------------------------------------------------ parameters
    @cached_property
    def geometry(self) -> _geometry.Geometry:
        """Reference geometry (shared by all models on the same mesh)."""
        return _geometry.of(self.mesh)

    @cached_property
    def micro(self) -> calibration.MicroParameters:
        """Calibrated micro-parameters with the moments they came from."""
        if isinstance(self.calibration, calibration.MicroParameters):
            return self.calibration
        if self.calibration == "relaxed":
            return calibration.relaxed(self.kind, self.mesh, self.E, self.nu, self.bonds)
        return calibration.paper(
            self.kind, self.mesh, self.geometry, self.E, self.nu, self.bond_weight
        )

    @cached_property
    def bond_weight(self) -> np.ndarray:
        """Relative normal-spring stiffness of every bond, shape (E,) (ones if uniform)."""
        if self.bonds == "uniform":
            w = np.ones(self.mesh.n_bonds)
        else:
            w = voronoi_weights(self.geometry)
        w.setflags(write=False)
        return w

    @property
    def k_n(self) -> float:
        """Bond stiffness (units of E: force per unit length per unit thickness)."""
        return self.micro.k_n

    @property
    def nu_m(self) -> float:
        """Voronoi coupling coefficient (dimensionless)."""
        return self.micro.nu_m

    @property
    def n_dof(self) -> int:
        return 2 * self.mesh.n_points

    def _bary(self, sl: slice = slice(None)) -> np.ndarray | None:
        """Barycentric coordinates of the circumcentre images (DV) or None (RV)."""
        return self.geometry.bary[sl] if self.barycentric_images else None

    # ------------------------------------------------------------ configuration
    def _strain(self, strain) -> np.ndarray | None:
        if strain is None:
            return None
        if not self.mesh.is_periodic:
            raise ValueError(
                "strain (a macroscopic strain of the period) applies to periodic meshes only; "
                "for a bounded mesh pass the displacement u = x @ eps.T instead"
            )
        return as_strain(strain, "strain")

    def _triangles_now(
        self, u: np.ndarray, strain: np.ndarray | None, sl=slice(None)
    ) -> np.ndarray:
        tri = self.mesh.triangles[sl]
        y = self.geometry.x_tri[sl] + u[tri]
        if strain is not None:
            y = y + np.einsum("ij,mvj->mvi", strain, self.mesh.images[sl] * self.mesh.period)
        return y

    def _bonds_now(self, u: np.ndarray, strain: np.ndarray | None) -> np.ndarray:
        b = self.mesh.topology.bonds
        d = self.geometry.length[:, None] * self.geometry.direction + u[b[:, 1]] - u[b[:, 0]]
        if strain is not None:
            d = d + (self.mesh.topology.bond_image * self.mesh.period) @ strain.T
        return d

    # ------------------------------------------------------------ forces
    def bond_tension(self, u, strain=None) -> np.ndarray:
        """Bond tensions on the current geometry, shape (E,) (force units).

        Parameters
        ----------
        u : array_like, shape (N, 2) or (2N,)
            Nodal displacements.
        strain : array_like, shape (2, 2), optional
            Periodic meshes only: macroscopic strain carried by the period.
        """
        u = as_displacement(u, self.mesh.n_points)
        strain = self._strain(strain)
        return self._tension(u, strain)[0]

    def _tension(self, u, strain):
        g = self.geometry
        d = self._bonds_now(u, strain)
        length = np.hypot(d[:, 0], d[:, 1])
        if np.any(length <= 0):
            raise ValueError("a bond has collapsed to zero length in this displacement")
        stretch = self.bond_weight * (length - g.length)
        if self.nu_m != 0.0:
            r_now = np.zeros(len(g.length))
            topo = self.mesh.topology
            for sl in _chunks(self.mesh.n_triangles):
                y = self._triangles_now(u, strain, sl)
                rt, _ = half_sides(y, self._bary(sl))
                r_now += np.bincount(topo.tri_bonds[sl].ravel(), rt.ravel(), len(g.length))
            stretch = stretch - self.nu_m * (g.r - r_now)
        return self.k_n * stretch, d, length

    def internal_force(self, u, strain=None) -> np.ndarray:
        """Internal (spring) forces on the nodes, interleaved, shape (2N,).

        In equilibrium ``internal_force(u) = external loads`` at free dofs. Exactly
        invariant to rigid rotations of the displaced configuration.
        """
        u = as_displacement(u, self.mesh.n_points)
        strain = self._strain(strain)
        t, d, length = self._tension(u, strain)
        fb = (t / length)[:, None] * d
        b = self.mesh.topology.bonds
        n = self.mesh.n_points
        f = np.zeros((n, 2))
        for c in range(2):
            f[:, c] = np.bincount(b[:, 1], fb[:, c], n) - np.bincount(b[:, 0], fb[:, c], n)
        return f.reshape(-1)

    # ------------------------------------------------------------ matrices
    def _element_matrices(self, y: np.ndarray, sl: slice, tension: np.ndarray | None) -> np.ndarray:
        """Triangle 6x6 tangent blocks for the current vertex positions ``y``."""
        g = self.geometry
        _, length, n = edge_frames(y)
        m = len(y)
        b = np.zeros((m, 3, 3, 2))
        for k in range(3):
            b[:, k, O_OF[k]] = -n[:, k]
            b[:, k, A_OF[k]] = n[:, k]
        b = b.reshape(m, 3, 6)
        w = g.tri_weight[sl] * self.bond_weight[self.mesh.topology.tri_bonds[sl]]
        q = w[..., None] * b
        if self.nu_m != 0.0:
            _, dr = half_sides(y, self._bary(sl), grad=True)
            q = q + self.nu_m * dr
        ke = self.k_n * np.matmul(b.transpose(0, 2, 1), q)
        if tension is not None:
            s = g.tri_weight[sl] * tension[self.mesh.topology.tri_bonds[sl]] / length
            p = np.eye(2) - n[..., :, None] * n[..., None, :]
            sp_ = s[..., None, None] * p  # (m, 3, 2, 2)
            ke5 = ke.reshape(m, 3, 2, 3, 2)
            for kk in range(3):
                o, a = O_OF[kk], A_OF[kk]
                ke5[:, o, :, o, :] += sp_[:, kk]
                ke5[:, a, :, a, :] += sp_[:, kk]
                ke5[:, o, :, a, :] -= sp_[:, kk]
                ke5[:, a, :, o, :] -= sp_[:, kk]
        return ke

    def _assemble(self, u: np.ndarray | None, strain, tension) -> sp.bsr_matrix:
        import scipy.sparse as sp

        pat = assembly.pattern(self.mesh)
        data = np.zeros((pat.nnzb, 4))
        for sl in _chunks(self.mesh.n_triangles):
            if u is None:
                y = self.geometry.x_tri[sl]
            else:
                y = self._triangles_now(u, strain, sl)
            ke = self._element_matrices(y, sl, tension)
            assembly.accumulate(pat, ke, data, sl)
        n2 = 2 * self.mesh.n_points
        return sp.bsr_matrix((data.reshape(-1, 2, 2), pat.indices, pat.indptr), shape=(n2, n2))

    @cached_property
    def _stiffness_bsr(self) -> sp.bsr_matrix:
        t0 = time.perf_counter()
        k = self._assemble(None, None, None)
        object.__setattr__(self, "_assembly_seconds", time.perf_counter() - t0)
        log.debug(
            "assembled %s stiffness (%d dof) in %.3f s",
            self.kind,
            k.shape[0],
            self._assembly_seconds,
        )
        return k

    def stiffness(self) -> sp.csr_matrix:
        """Linear stiffness K (tangent at u = 0), CSR, shape (2N, 2N), units of E.

        Interleaved dofs ``[ux0, uy0, ux1, uy1, ...]``. Symmetric for the paper's
        uniform ``k_n, nu_m``; same pattern as P1 elements on the mesh; rigid-body
        motions are in its null space. Assembled once per model and cached.
        """
        return self._stiffness_bsr.tocsr()

    def tangent(self, u, strain=None) -> sp.csr_matrix:
        """Exact Jacobian d(internal_force)/du at displacement ``u``, CSR (2N, 2N).

        In general not symmetric. Equals :meth:`stiffness` at ``u = 0``.
        """
        u = as_displacement(u, self.mesh.n_points)
        strain = self._strain(strain)
        t, _, _ = self._tension(u, strain)
        return self._assemble(u, strain, t).tocsr()

    def linear_tension(self, u, strain=None) -> np.ndarray:
        """Bond tensions of the linearised model, shape (E,).

        ``T = k_n (n.(u_A - u_O) + nu_m dr . u)``; with ``strain`` on a periodic mesh the
        period carries that macroscopic strain.
        """
        u = as_displacement(u, self.mesh.n_points)
        strain = self._strain(strain)
        g = self.geometry
        topo = self.mesh.topology
        b = topo.bonds
        du = u[b[:, 1]] - u[b[:, 0]]
        if strain is not None:
            du = du + (topo.bond_image * self.mesh.period) @ strain.T
        t = self.bond_weight * np.einsum("ei,ei->e", g.direction, du)
        if self.nu_m != 0.0:
            dr_sum = np.zeros(len(t))
            for sl in _chunks(self.mesh.n_triangles):
                _, dr = half_sides(g.x_tri[sl], self._bary(sl), grad=True)
                ut = u[self.mesh.triangles[sl]]
                if strain is not None:
                    ut = ut + np.einsum(
                        "ij,mvj->mvi", strain, self.mesh.images[sl] * self.mesh.period
                    )
                rt = np.einsum("mkj,mj->mk", dr, ut.reshape(len(ut), 6))
                dr_sum += np.bincount(topo.tri_bonds[sl].ravel(), rt.ravel(), len(t))
            t = t + self.nu_m * dr_sum
        return self.k_n * t

    def __repr__(self) -> str:
        return (
            f"{self.kind}(N={self.mesh.n_points}, E={self.E:g}, nu={self.nu:g}, "
            f"k_n={self.k_n:.6g}, nu_m={self.nu_m:.6g}, calibration={self.micro.calibration!r}, "
            f"bonds={self.bonds!r})"
        )


@dataclass(frozen=True, eq=False, repr=False)
class DV(VoronoiModel):
    """Deformable Voronoi model: the dual side deforms with the triangles.

    See :class:`VoronoiModel` for the parameters.
    """

    kind: ClassVar[str] = "DV"
    barycentric_images: ClassVar[bool] = True


@dataclass(frozen=True, eq=False, repr=False)
class RV(VoronoiModel):
    """Remeshing Voronoi model: the dual side is rebuilt from current circumcentres.

    See :class:`VoronoiModel` for the parameters.
    """

    kind: ClassVar[str] = "RV"
    barycentric_images: ClassVar[bool] = False


def _chunks(m: int):
    for start in range(0, m, CHUNK):
        yield slice(start, min(m, start + CHUNK))
