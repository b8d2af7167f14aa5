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

import dataclasses
import logging
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from .._checks import as_displacement, check_choice, check_positive
from .._env import launched_under_mpi
from ..errors import CalibrationError, InputError
from ..material import Elastic
from ..mesh import Mesh
from . import calibration
from . import geometry as _geometry
from .cells import BOUNDARY_CELLS, cell_tensors
from .flags import model_flags
from .inputs import METHODS, checked_damage, checked_materials, preset_keywords
from .isotropy import ANISOTROPY, resolve_anisotropy
from .operator import RESIDUAL, LatticeOperator, coupling_factor, term_mask
from .stabilise import clip_coupling, triangle_modes, triangle_tensors
from .terms import TriangleTerms
from .weights import BONDS, bond_weights, mixed_springs, resolve_bonds, voronoi_weights

if TYPE_CHECKING:  # annotations only: scipy is imported where it is used
    import scipy.sparse as sp


log = logging.getLogger(__name__)

__all__ = ["DV", "RV", "VoronoiModel", "voronoi_weights", "BONDS", "METHODS", "check_model"]


@dataclass(frozen=True, eq=False)
class VoronoiModel(TriangleTerms):
    """Common base of :class:`DV` and :class:`RV` (not used directly).

    Parameters
    ----------
    mesh : Mesh
    E : float
        Young's modulus (force per area), > 0.
    nu : float
        Poisson's ratio: -1 < nu < 1 in plane stress, -1 < nu < 0.5 in plane strain
        (within the calibration's admissible range).
    calibration : {"relaxed", "paper"} or MicroParameters
        How ``k_n`` and ``nu_m`` are obtained from E and nu. ``"relaxed"`` (default):
        the lattice *in equilibrium* (non-affinely relaxed) matches E and nu on a
        periodic sample with the micro-structure of the mesh (read from the package's
        table for the built-in generators, measured on a sample made by the mesh's
        recipe or with its bond-length spread otherwise; see
        :func:`dvstatic.lattice.calibration.relaxed`), with the coupling stabilised
        per triangle, so the lattice is stable for any nu it reaches. ``"paper"``: the
        paper's closed form under affine strain (eqs. 9-10 / 19-20), no stabilisation.
        Or given :class:`~dvstatic.lattice.calibration.MicroParameters` (used as they
        are; a sequence of them with ``materials``: the default material's first).
    bonds : {"auto", "surface", "fabric", "uniform", "voronoi"}
        Normal-spring stiffness of each bond. ``"auto"`` (default): ``"fabric"`` on the
        generators' graded meshes (a size field as ``h``) and CVT and random point
        sets, ``"surface"`` on all others
        (:func:`~dvstatic.lattice.weights.default_bonds`; ``model.bonds`` holds the
        scheme chosen, which ``dataclasses.replace`` keeps: pass ``bonds="auto"``
        again with another mesh). ``"surface"``: ``k_n``, and
        ``k_n / 2`` on boundary bonds (one triangle), which carry half a cell (as on the
        surface of a regular lattice) and would otherwise make a stiff surface layer;
        ``"fabric"``: the surface springs times ``1 - 4 n.D.n``, ``D`` the deviator of
        the springs' fabric tensor averaged over
        :data:`~dvstatic.lattice.weights.FABRIC_RINGS` rings of neighbours, which takes
        the local anisotropy of the cells (a graded mesh's stretched cells, the
        patches of a point set) out of the lattice to first order
        (:func:`~dvstatic.lattice.weights.fabric_factors`; calibrated on samples
        corrected alike; better on curved boundaries and on CVT and random points,
        worse in some cases: docs/validation.md); ``"uniform"``: the paper's ``k_n``
        everywhere; ``"voronoi"``: ``k_n w_e`` with ``w_e = sqrt(3) r_e / l_e`` (its
        own Voronoi side). The Voronoi coupling stays per triangle, so the stiffness
        stays symmetric.
        The paper's model is ``method="paper"``.
    plane : {"stress", "strain"}
        Plane stress, or plane strain: the lattice is calibrated with the effective
        constants ``E* = E / (1 - nu^2)``, ``nu* = nu / (1 - nu)``; the stress recovery
        reports ``szz = nu (sxx + syy)``.
    thickness : float, optional
        Out-of-plane thickness (length). Without it everything is per unit thickness;
        with it the stiffness is multiplied by it and forces (loads, reactions, bond
        tensions) are totals: tractions, pressures and body forces stay per unit area
        and volume, point loads are total forces.
    materials : mapping region name -> (E, nu), optional
        Other materials on named regions of the mesh (``mesh.regions``); ``E, nu``
        are the material of the other triangles. Every material is calibrated on its
        own; a bond between two triangles of different materials gets the springs of
        both, each in proportion to its triangle's share of the bond's Voronoi side,
        and every triangle its own coupling, so that the stiffness stays symmetric.
    damage : ndarray, shape (n_bonds,), optional
        Bond stiffness factors in [0, 1] (1 intact, 0 broken) of a cracked lattice, as
        :func:`dvstatic.fracture` leaves it (use :meth:`damaged`): each spring times its
        factor, each triangle's coupling times the smallest factor of its bonds (an
        exact cell's or regionally corrected triangle's dropped at its first damaged
        bond: :func:`~dvstatic.lattice.operator.coupling_factor`).
    closed : ndarray of bool, shape (n_bonds,), optional
        With ``damage``: cracked bonds whose faces are closed (in contact), which carry
        compression with their whole spring (their triangles' coupling stays off).
    boundary_cells : {"exact", "lattice"}
        ``"exact"`` (default): every triangle with a vertex within
        :data:`~dvstatic.lattice.cells.CELL_RINGS` (3) rings of bonds of the boundary
        is an exact cell, a lattice triangle with a 3x3 coupling of its three bonds
        that gives it the isotropic tensor of its material, so the layer cut to fit a
        boundary is exactly P1 (:mod:`dvstatic.lattice.cells`; at Kirsch's hole on the
        default mesh at 2e4 nodes the hoop stress at the top goes from -5.8 % to -1.3 %
        with one layer; imported meshes' disordered boundary zones need the four:
        docs/theory.md 8.2b). ``"lattice"``: the plain lattice everywhere (the paper).
    anisotropy : {"auto", "regional", "keep"}
        ``"regional"``: every lattice triangle gets a term that takes out the
        anisotropy of its region's mean tensor (a window about 2.3 spacings wide),
        which a mesher's graded or front-aligned cells leave in an isotropic material
        (:mod:`dvstatic.lattice.isotropy`; a gmsh ring graded towards its bore, 17,060
        nodes: Lame displacement 0.91 -> 0.24 %); the calibrated isotropic part and the
        triangle-to-triangle fluctuations stay. ``"keep"``: the lattice's tensors as
        they are (the paper). ``"auto"`` (default): ``"regional"`` on meshes without a
        generator recipe (imported) and on the generators' graded CVT meshes (with
        their fabric springs: the tunnel example's wall at h_near = 0.0125, seeds 0-3,
        hoop rms 1.77 -> 0.85 %), ``"keep"`` on the
        package's uniform meshes (isotropic by construction) and graded random points
        (their regions' anisotropy is noise the term amplifies); ``model.anisotropy``
        holds the choice made, which ``dataclasses.replace`` keeps (pass
        ``anisotropy="auto"`` again with another mesh).

    method : {None, "paper"}
        A named preset of the four keywords above. ``"paper"``: the paper's model
        exactly, ``calibration="paper", bonds="uniform", boundary_cells="lattice",
        anisotropy="keep"`` (:data:`METHODS`), which stays the paper's model whatever
        later defaults become; a keyword at its default takes the preset's value, one
        given with another value is refused. None (default): the keywords as given.

    Raises
    ------
    InputError
        E, nu or thickness out of range, unknown calibration, bonds, plane, region or
        method, or a keyword that contradicts ``method``.
    CalibrationError
        nu has no calibration on this mesh (raised at construction, except under
        ``mpiexec``, where the distributed engine calibrates from sums over ranks).
    """

    mesh: Mesh
    E: float
    nu: float
    calibration: object = "relaxed"
    bonds: str = "auto"
    plane: str = "stress"
    thickness: float | None = None
    materials: object = None
    damage: np.ndarray | None = None
    closed: np.ndarray | None = None
    boundary_cells: str = "exact"
    anisotropy: str = "auto"
    method: str | None = None
    kind: ClassVar[str] = ""
    barycentric_images: ClassVar[bool] = True

    def __post_init__(self) -> None:
        if type(self) is VoronoiModel:
            raise TypeError("use dvstatic.DV or dvstatic.RV")
        if not isinstance(self.mesh, Mesh):
            raise TypeError(f"mesh must be a dvstatic Mesh, got {type(self.mesh).__name__}")
        for name, value in preset_keywords(self).items():
            object.__setattr__(self, name, value)
        material = Elastic(self.E, self.nu, self.plane)
        object.__setattr__(self, "E", material.E)
        object.__setattr__(self, "nu", material.nu)
        object.__setattr__(self, "bonds", resolve_bonds(self.bonds, self.mesh))
        check_choice("anisotropy", self.anisotropy, ANISOTROPY)
        object.__setattr__(self, "anisotropy", resolve_anisotropy(self.anisotropy, self.mesh))
        if self.anisotropy == "regional" and self.mesh.is_periodic:
            raise InputError(
                "anisotropy='regional' is for bodies, not periodic samples (the samples "
                "calibrate the lattice as it is): use 'keep' or 'auto'",
                "anisotropy",
            )
        check_choice("boundary_cells", self.boundary_cells, BOUNDARY_CELLS)
        if self.thickness is not None:
            object.__setattr__(self, "thickness", check_positive("thickness", self.thickness))
        object.__setattr__(self, "materials", checked_materials(self.materials, self))
        damage, closed = checked_damage(self.damage, self.closed, self.mesh.n_bonds)
        object.__setattr__(self, "damage", damage)
        object.__setattr__(self, "closed", closed)
        self._check_calibration()
        if not launched_under_mpi():
            _ = self.micro  # calibrate now: an impossible nu fails at construction
        # under mpiexec the calibration waits: solver="petsc" computes it from sums
        # over each rank's own bonds (set_micro), so no rank needs the global geometry

    def damaged(self, stiffness: np.ndarray, closed=None) -> VoronoiModel:
        """This lattice with bond stiffness factors ``stiffness`` (n_bonds,; 1 intact, 0
        broken), as :func:`dvstatic.fracture` leaves it: the same calibration, each
        bond's spring times its factor (a broken bond keeps
        :data:`~dvstatic.lattice.damage.RESIDUAL` of it), and a triangle's coupling
        times the smallest factor of its bonds (a cell's dropped at its first damaged
        bond; :mod:`dvstatic.lattice.damage`); the
        ``closed`` cracks (bool, n_bonds) with their whole spring. A model like any
        other: ``dv.solve``, ``Solution.stress()`` and the writers take it."""
        return self.replaced(damage=stiffness, closed=closed)

    def replaced(self, **changes) -> VoronoiModel:
        """This lattice with ``changes`` (fields of the model other than the material
        and the mesh), keeping its calibration as computed: micro-parameters, the field
        of classes of a mixed mesh, the calibration flags (warned once, by this model)."""
        micros = self.micros
        out = dataclasses.replace(
            self, calibration=micros if len(micros) > 1 else micros[0], **changes
        )
        object.__setattr__(out, "micro_field", self.micro_field)  # the cached_properties
        out.share_calibration_flags(self)
        return out

    def replaced_calibration(self, micros) -> VoronoiModel:
        """This lattice calibrated with ``micros`` (one MicroParameters per material,
        computed elsewhere, as the distributed engine's sums over ranks), keeping the
        field of classes of a mixed mesh."""
        micros = tuple(micros)
        out = dataclasses.replace(self, calibration=micros if len(micros) > 1 else micros[0])
        object.__setattr__(out, "micro_field", self.micro_field)
        return out

    def share_calibration_flags(self, parent: VoronoiModel) -> None:
        """Take ``parent``'s :attr:`calibration_flags` (a companion on the same mesh, as
        the stress recovery and the fracture criteria build: warned once, by the
        parent)."""
        if parent.mesh is not self.mesh:
            raise InputError("calibration flags are shared only on the same mesh", "parent")
        object.__setattr__(self, "calibration_flags", parent.calibration_flags)

    def _check_calibration(self) -> None:
        cal = self.calibration
        if isinstance(cal, calibration.MicroParameters):
            cal = (cal,)
        if isinstance(cal, (tuple, list)):
            if len(cal) != 1 + len(self.materials) or not all(
                isinstance(c, calibration.MicroParameters) for c in cal
            ):
                n = 1 + len(self.materials)
                raise InputError(
                    f"calibration: give one MicroParameters per material ({n})", "calibration"
                )
            object.__setattr__(self, "calibration", tuple(cal) if len(cal) > 1 else cal[0])
            return
        check_choice("calibration", self.calibration, calibration.CALIBRATIONS)

    # ------------------------------------------------------------ parameters
    @cached_property
    def geometry(self) -> _geometry.Geometry:
        """Reference geometry (shared by all models on the same mesh)."""
        return _geometry.of(self.mesh)

    @property
    def material(self) -> Elastic:
        """The material of the triangles outside the ``materials`` regions."""
        return Elastic(self.E, self.nu, self.plane)

    @property
    def all_materials(self) -> tuple[Elastic, ...]:
        """The default material, then those of ``materials`` in their order."""
        return (self.material, *self.materials.values())

    @property
    def t(self) -> float:
        """The thickness (1 when the model is per unit thickness)."""
        return 1.0 if self.thickness is None else float(self.thickness)

    @cached_property
    def material_of_triangle(self) -> np.ndarray:
        """Index of every triangle's material in :attr:`all_materials`, shape (M,)."""
        out = np.zeros(self.mesh.n_triangles, dtype=np.int64)
        for k, name in enumerate(self.materials, start=1):
            out[self.mesh.regions[name]] = k
        out.setflags(write=False)
        return out

    @cached_property
    def micro(self) -> calibration.MicroParameters:
        """Calibrated micro-parameters (of the default material) with the moments they
        came from."""
        return self.micros[0]

    @cached_property
    def micros(self) -> tuple[calibration.MicroParameters, ...]:
        """Calibrated micro-parameters of every material (:attr:`all_materials`)."""
        if "micro" in self.__dict__ and not self.materials:
            return (self.__dict__["micro"],)
        if isinstance(self.calibration, calibration.MicroParameters):
            return (self.calibration,)
        if isinstance(self.calibration, tuple):
            return self.calibration
        field = self.micro_field
        if field is not None:  # the largest class of every material, for the record
            return tuple(self._largest_class(field, k) for k in range(len(self.all_materials)))
        return tuple(self._calibrate(m) for m in self.all_materials)

    def _largest_class(self, field, material: int) -> calibration.MicroParameters:
        mine = field.classes.of_triangle[self.material_of_triangle == material]
        if not len(mine):
            return self._calibrate(self.all_materials[material])
        return field.micros[(material, int(np.bincount(mine).argmax()))]

    def _calibrate(
        self, material: Elastic, spread=None, defects=None
    ) -> calibration.MicroParameters:
        E2, nu2 = material.in_plane
        if self.calibration == "relaxed":
            try:
                return calibration.relaxed(
                    self.kind, self.mesh, E2, nu2, self.bonds, spread=spread, defects=defects
                )
            except CalibrationError as exc:
                if material.plane == "stress":
                    raise
                raise CalibrationError(
                    f"nu = {material.nu} in plane strain (in-plane nu* = nu / (1 - nu) = "
                    f"{nu2:.4g}) cannot be calibrated: {exc}",
                    "nu",
                ) from None
        return calibration.paper(self.kind, self.mesh, self.geometry, E2, nu2, self.bond_weight)

    @cached_property
    def micro_field(self) -> calibration.MicroField | None:
        """Micro-parameters triangle by triangle where the mesh mixes micro-structures
        (a mesh without recipe whose regions differ in local spread, relaxed
        calibration: each class of local spread calibrated on its own sample,
        :mod:`dvstatic.lattice.calibration.classes`); None where :attr:`micros`, one
        per material, serve (the usual case). :attr:`micros` then hold the
        calibration of every material's largest class, for the record."""
        if not (isinstance(self.calibration, str) and self.calibration == "relaxed"):
            return None
        classes = calibration.spread_classes(self.mesh)
        if classes is None:
            return None
        field = calibration.calibrate_classes(
            classes,
            self.material_of_triangle,
            lambda mat, spread, defects: self._calibrate(self.all_materials[mat], spread, defects),
        )
        log.info("%s", field.describe())
        return field

    @cached_property
    def calibration_flags(self) -> tuple[calibration.QualityFlag, ...]:
        """The parts of a mesh without recipe whose micro-structure lies outside what
        their relaxed calibration was measured on (a patch of another local spread, or
        a spread beyond the samples' reach; :mod:`dvstatic.lattice.calibration.quality`),
        each logged once as a warning; empty for meshes with a recipe, periodic meshes
        and given micro-parameters."""
        return model_flags(self)

    def _triangle_constants(self) -> tuple[np.ndarray, np.ndarray]:
        """Every triangle's ``k_n`` and ``nu_m``, shape (M,) each."""
        field = self.micro_field
        if field is not None:
            return field.k_n, field.nu_m
        mat = self.material_of_triangle
        k_n = np.array([m.k_n for m in self.micros])[mat]
        return k_n, np.array([m.nu_m for m in self.micros])[mat]

    def set_micro(self, micro) -> None:
        """Adopt micro-parameters computed elsewhere (the distributed engine sums the
        calibration over ranks): one MicroParameters, or one per material. Allowed
        once, before the model is calibrated."""
        micros = (micro,) if isinstance(micro, calibration.MicroParameters) else tuple(micro)
        if len(micros) != 1 + len(self.materials) or not all(
            isinstance(m, calibration.MicroParameters) for m in micros
        ):
            raise TypeError("micro must be MicroParameters (one per material)")
        if self.is_calibrated:
            if self.micros != micros:
                raise InputError("the model is calibrated already, with other parameters", "micro")
            return
        object.__setattr__(self, "micros", micros)  # the cached_properties, set once
        object.__setattr__(self, "micro", micros[0])

    @property
    def is_calibrated(self) -> bool:
        """True once the micro-parameters have been computed (or set)."""
        return "micro" in self.__dict__ or "micros" in self.__dict__

    @cached_property
    def bond_weight(self) -> np.ndarray:
        """Relative normal-spring stiffness of every bond, shape (n_bonds,) (ones if
        uniform)."""
        return bond_weights(self.bonds, self.mesh)

    @cached_property
    def operator(self) -> LatticeOperator:
        """Forces and matrices of this lattice (its calibrated stiffnesses, times the
        thickness; stabilised couplings clipped per triangle; the exact cells' and the
        regional isotropy's terms)."""
        self.calibration_flags  # noqa: B018 (warned once, where the calibration is used)
        spring, coupling = self._intact
        cells, dq = self._triangle_terms(spring, coupling)
        if self.damage is not None:  # as lattice.damage.TriangleSplit.factors does
            d = self.damage
            spring = spring * np.maximum(d, RESIDUAL)
            if self.closed is not None:
                spring = np.where(self.closed, spring / np.maximum(d, RESIDUAL), spring)
            terms = term_mask(cells, self.mesh.n_triangles)
            low = coupling_factor(d[self.mesh.topology.tri_bonds], terms)
            coupling = coupling * low
            if dq is not None:
                dq = dq * low[cells, None, None]
        return LatticeOperator(
            self.mesh,
            spring,
            coupling,
            barycentric=self.barycentric_images,
            cells=cells,
            cell_dq=dq,
        )

    @cached_property
    def _intact(self) -> tuple[np.ndarray, np.ndarray]:
        """The intact springs (n_bonds,) and stabilised couplings (M,), times the
        thickness (force / length)."""
        mat = self.material_of_triangle
        if len(self.micros) == 1 and self.micro_field is None:
            k_n, nu_m = self.micro.k_n, self.micro.nu_m
            spring = self.t * k_n * self.bond_weight
            coupling = np.full(self.mesh.n_triangles, self.t * k_n * nu_m)
        else:
            k_tri, nu_tri = self._triangle_constants()
            spring = self.t * self.bond_weight * mixed_springs(self.geometry, self.mesh, k_tri)
            coupling = self.t * k_tri * nu_tri
        stab = np.array([m.stabilised for m in self.micros])[mat]
        if stab.any():
            modes = triangle_modes(self.mesh, spring, self.barycentric_images)
            coupling = np.where(stab, clip_coupling(modes, coupling), coupling)
        return spring, coupling

    @cached_property
    def clipped_fraction(self) -> float:
        """Fraction of the triangles whose coupling the stabilisation reduced (0 for
        the paper's calibration)."""
        k_n, nu_m = self._triangle_constants()
        full = self.t * k_n * nu_m
        return float(np.mean(~np.isclose(self.operator.coupling, full, rtol=1e-12, atol=0)))

    @property
    def k_n(self) -> float:
        """Bond stiffness of the default material (units of E: force per unit length per
        unit thickness)."""
        return self.micro.k_n

    @property
    def nu_m(self) -> float:
        """Voronoi coupling coefficient of the default material (dimensionless)."""
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

    def triangle_tensors(self) -> np.ndarray:
        """Elasticity tensor of every triangle, Mandel (M, 3, 3), units of E (times the
        thickness): the linear lattice is the P1 finite-element model with these
        tensors (:func:`dvstatic.lattice.stabilise.triangle_tensors`). Isotropic on
        equilateral triangles; their spread over an irregular mesh is what relaxes."""
        op = self.operator
        out = triangle_tensors(self.mesh, op.spring, op.coupling, self.barycentric_images)
        if op.cells is not None:  # exact cells: diag(w) + g M + dQ
            out[op.cells] += cell_tensors(self.mesh, op.cells, op.cell_dq)
        return out

    def energy(self, u) -> float:
        """Strain energy of the linear model, ``u.K.u / 2`` (energy per unit thickness)."""
        x = as_displacement(u, self.mesh.n_points).reshape(-1)
        return float(0.5 * x @ (self.operator.stiffness_bsr @ x))

    def __repr__(self) -> str:
        extra = "" if self.plane == "stress" else ", plane='strain'"
        cells = "" if self.boundary_cells == "exact" else ", boundary_cells='lattice'"
        cells += f", anisotropy={self.anisotropy!r}"
        if self.damage is not None:
            extra += f", damage: {int(np.sum(self.damage < 1))} bonds cracked"
        extra += "" if self.thickness is None else f", thickness={self.thickness:g}"
        extra += f", materials={list(self.materials)}" if self.materials else ""
        return (
            f"{self.kind}(N={self.mesh.n_points}, E={self.E:g}, nu={self.nu:g}, "
            f"k_n={self.k_n:.6g}, nu_m={self.nu_m:.6g}, calibration={self.micro.calibration!r}, "
            f"bonds={self.bonds!r}{cells}{extra})"
        )


def check_model(model) -> VoronoiModel:
    """``model`` if it is a DV or RV model (TypeError otherwise)."""
    if not isinstance(model, VoronoiModel):
        raise TypeError(f"model must be a dvstatic DV or RV model, got {type(model).__name__}")
    return model


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
