"""The bond-matrix terms a model adds to its triangles: the exact boundary cells
(:mod:`.cells`) and the regional isotropy (:mod:`.isotropy`), as a mixin of
:class:`~dvstatic.lattice.models.VoronoiModel` (which supplies ``mesh``,
``boundary_cells``, ``anisotropy``, ``_intact``, the materials and the thickness)."""

from __future__ import annotations

from functools import cached_property

import numpy as np

from .cells import cell_corrections, exact_cells, isotropic_tensor
from .isotropy import corrected_triangles, regional_anisotropy, regional_corrections
from .stabilise import triangle_tensors

__all__ = ["TriangleTerms"]


class TriangleTerms:
    """The exact cells' and the regional isotropy's bond matrices of a model."""

    def _triangle_terms(self, spring, coupling) -> tuple[np.ndarray | None, np.ndarray | None]:
        """The triangles with a bond-matrix term and their terms (k, 3, 3): the exact
        cells, then the triangles the regional isotropy corrects; (None, None) if none."""
        idx, terms = [], []
        cells = self.cell_triangles
        if len(cells):
            idx.append(cells)
            terms.append(self._cell_dq(spring, coupling))
        if self.anisotropy == "regional":
            take = self.regional_triangles
            idx.append(take)
            terms.append(self._regional_terms(take, spring, coupling))
        if not idx or not sum(len(i) for i in idx):
            return None, None
        return np.concatenate(idx), np.concatenate(terms)

    def _regional_terms(self, take, spring, coupling) -> np.ndarray:
        """The regional isotropy's bond matrices (k, 3, 3) of triangles ``take``; the
        field computed on the way (once: it needs the same tensors) unless set (a
        distributed patch reads the whole mesh's)."""
        tensors = triangle_tensors(self.mesh, spring, coupling, self.barycentric_images)
        if "anisotropy_field" not in self.__dict__:
            field = regional_anisotropy(self.mesh, tensors, take, self.region_partition)
            object.__setattr__(self, "anisotropy_field", field)  # the cached_property
        return regional_corrections(self.mesh, take, self.anisotropy_field[take], tensors[take])

    @cached_property
    def anisotropy_field(self) -> np.ndarray:
        """The anisotropic part of every triangle's regional mean tensor (M, 3, 3,
        Mandel, units of E times the thickness) that ``anisotropy="regional"`` takes
        out (:mod:`dvstatic.lattice.isotropy`; zero on the triangles that take no term:
        exact cells, slivers, random points)."""
        spring, coupling = self._intact
        tensors = triangle_tensors(self.mesh, spring, coupling, self.barycentric_images)
        take, parts = self.regional_triangles, self.region_partition
        return regional_anisotropy(self.mesh, tensors, take, parts)

    @cached_property
    def regional_triangles(self) -> np.ndarray:
        """The triangles that take the regional isotropy's term, shape (k,) int (all but
        the exact cells, slivers and random points: :func:`.isotropy.corrected_triangles`)."""
        return corrected_triangles(self.mesh, self.cell_triangles)

    @cached_property
    def region_partition(self) -> np.ndarray:
        """The parts (M,) int within which the regional isotropy averages: the
        materials (a companion of one material, as the stress recovery builds, takes
        its model's)."""
        return self.material_of_triangle

    @cached_property
    def cell_triangles(self) -> np.ndarray:
        """The exact cells (``boundary_cells="exact"``, :func:`.cells.exact_cells`), shape
        (k,) int; empty with ``"lattice"`` or on periodic meshes."""
        if self.boundary_cells == "lattice":
            return np.zeros(0, dtype=np.int64)
        return exact_cells(self.mesh)

    def _cell_dq(self, spring: np.ndarray, coupling: np.ndarray) -> np.ndarray:
        """The exact cells' bond matrices (k, 3, 3) for the intact springs and couplings."""
        cells = self.cell_triangles
        tensors = np.stack([isotropic_tensor(*m.in_plane) for m in self.all_materials])
        c = self.t * tensors[self.material_of_triangle[cells]]
        return cell_corrections(self.mesh, cells, spring, coupling, self.barycentric_images, c)
