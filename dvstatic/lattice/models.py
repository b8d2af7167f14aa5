"""The deformable (DV) and remeshing (RV) Voronoi lattice models.

Each bond (mesh edge) O-A carries a normal spring whose rest length grows by
``dl = nu_m (r - r')`` when its dual Voronoi side changes from ``r`` to ``r'``. The
tension in the current configuration is::

    T = k_n (l' - l - nu_m (r - r'))

and acts along the current bond on its two particles. ``r'`` is the sum over the
bond's triangles of the signed distance of the circumcentre image from the current
bond line: DV keeps the circumcentre's reference barycentric coordinates in the
deformed triangle, RV takes the circumcentre of the deformed triangle.

A model is its calibration (:attr:`VoronoiModel.micro`) plus the
:class:`~dvstatic.lattice.operator.LatticeOperator` that computes forces and matrices.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from .._checks import as_displacement, check_choice, check_positive
from .._env import launched_under_mpi
from ..errors import InputError
from ..material import check_poisson
from ..mesh import Mesh
from . import calibration
from . import geometry as _geometry
from .operator import LatticeOperator
from .weights import BONDS, bond_weights, voronoi_weights

if TYPE_CHECKING:  # annotations only: scipy is imported where it is used
    import scipy.sparse as sp


log = logging.getLogger(__name__)

__all__ = ["DV", "RV", "VoronoiModel", "voronoi_weights", "BONDS"]


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
        spread matches E and nu; see :func:`dvstatic.lattice.calibration.relaxed`), or
        given :class:`~dvstatic.lattice.calibration.MicroParameters` (used as they are).
    bonds : {"uniform", "voronoi"}
        Normal-spring stiffness of each bond: the paper's uniform ``k_n``, or
        ``k_n w_e`` with ``w_e = sqrt(3) r_e / l_e`` (its own Voronoi side: 1 inside a
        regular lattice, 1/2 on its surface bonds), which removes the stiff surface
        layer. The Voronoi coupling stays uniform, so the stiffness stays symmetric.

    Raises
    ------
    InputError
        E or nu out of range, unknown calibration or bonds.
    CalibrationError
        nu has no calibration on this mesh (raised at construction, except under
        ``mpiexec``, where the distributed engine calibrates from sums over ranks).
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
        nu = check_poisson(self.nu)
        if not isinstance(self.calibration, calibration.MicroParameters):
            check_choice("calibration", self.calibration, calibration.CALIBRATIONS)
        check_choice("bonds", self.bonds, BONDS)
        object.__setattr__(self, "E", E)
        object.__setattr__(self, "nu", nu)
        if not launched_under_mpi():
            _ = self.micro  # calibrate now: an impossible nu fails at construction
        # under mpiexec the calibration waits: solver="petsc" computes it from sums
        # over each rank's own bonds (set_micro), so no rank needs the global geometry

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

    def set_micro(self, micro: calibration.MicroParameters) -> None:
        """Adopt micro-parameters computed elsewhere (the distributed engine sums the
        calibration over ranks). Allowed once, before the model is calibrated."""
        if not isinstance(micro, calibration.MicroParameters):
            raise TypeError(f"micro must be MicroParameters, got {type(micro).__name__}")
        if self.is_calibrated:
            if self.micro != micro:
                raise InputError("the model is calibrated already, with other parameters", "micro")
            return
        self.__dict__["micro"] = micro  # the cached_property's slot

    @property
    def is_calibrated(self) -> bool:
        """True once :attr:`micro` has been computed (or set)."""
        return "micro" in self.__dict__

    @cached_property
    def bond_weight(self) -> np.ndarray:
        """Relative normal-spring stiffness of every bond, shape (n_bonds,) (ones if
        uniform)."""
        return bond_weights(self.bonds, self.geometry)

    @cached_property
    def operator(self) -> LatticeOperator:
        """Forces and matrices of this lattice (its calibrated stiffnesses)."""
        k_n, nu_m = self.micro.k_n, self.micro.nu_m
        return LatticeOperator(
            self.mesh, k_n * self.bond_weight, k_n * nu_m, barycentric=self.barycentric_images
        )

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

    # ------------------------------------------------------------ forces
    def bond_tension(self, u, strain=None) -> np.ndarray:
        """Bond tensions on the current geometry, shape (n_bonds,) (force units).

        Parameters
        ----------
        u : array_like, shape (N, 2) or (2N,)
            Nodal displacements.
        strain : array_like, shape (2, 2), optional
            Periodic meshes only: macroscopic strain carried by the period.
        """
        return self.operator.bond_tension(u, strain)

    def internal_force(self, u, strain=None) -> np.ndarray:
        """Internal (spring) forces on the nodes, interleaved, shape (2N,).

        In equilibrium ``internal_force(u) = external loads`` at free dofs. Exactly
        invariant to rigid rotations of the displaced configuration.
        """
        return self.operator.internal_force(u, strain)

    def linear_tension(self, u, strain=None) -> np.ndarray:
        """Bond tensions of the linearised model, shape (n_bonds,).

        ``T = k_n (n.(u_A - u_O) + nu_m dr . u)``; with ``strain`` on a periodic mesh the
        period carries that macroscopic strain.
        """
        return self.operator.linear_tension(u, strain)

    # ------------------------------------------------------------ matrices
    def stiffness(self, fmt: str = "csr") -> sp.spmatrix:
        """Linear stiffness K (tangent at u = 0), shape (2N, 2N), units of E.

        Interleaved dofs ``[ux0, uy0, ux1, uy1, ...]``. Symmetric for the paper's
        uniform ``k_n, nu_m``; same pattern as P1 elements on the mesh; rigid-body
        motions are in its null space. Assembled once per model and cached.

        Parameters
        ----------
        fmt : {"csr", "bsr"}
            ``bsr`` returns the cached 2x2-block matrix itself (do not modify it).
        """
        check_choice("fmt", fmt, ("csr", "bsr"))
        K = self.operator.stiffness_bsr
        return K if fmt == "bsr" else K.tocsr()

    @property
    def is_assembled(self) -> bool:
        """True once the linear stiffness has been assembled (and cached)."""
        return self.is_calibrated and self.operator.is_assembled

    def tangent(self, u, strain=None, fmt: str = "csr") -> sp.spmatrix:
        """Exact Jacobian d(internal_force)/du at displacement ``u``, shape (2N, 2N).

        In general not symmetric. Equals :meth:`stiffness` at ``u = 0``.
        """
        check_choice("fmt", fmt, ("csr", "bsr"))
        K = self.operator.tangent(u, strain)
        return K if fmt == "bsr" else K.tocsr()

    def energy(self, u) -> float:
        """Strain energy of the linear model, ``u.K.u / 2`` (energy per unit thickness)."""
        x = as_displacement(u, self.mesh.n_points).reshape(-1)
        return float(0.5 * x @ (self.operator.stiffness_bsr @ x))

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
