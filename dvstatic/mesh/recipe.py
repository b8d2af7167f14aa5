"""How a mesh's points were placed: the generator's recipe, relative to its spacing.

The generators record it on the mesh (:attr:`Mesh.sampling`); :meth:`Mesh.perturbed`
appends its move. The relaxed calibration uses it as a key: a periodic sample made by
the same recipe has the same micro-structure statistics as the mesh's interior, so its
equilibrium moduli are those of the mesh (:func:`dvstatic.mesh.periodic_sample`).
Meshes built from points and triangles (imported, or made by hand) have none.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

__all__ = ["Sampling", "ROW_KINDS"]

#: kinds whose points keep the rows of a triangular lattice
ROW_KINDS = ("lattice", "jittered")


@dataclass(frozen=True)
class Sampling:
    """The point-placement recipe of a generated mesh.

    Attributes
    ----------
    kind : {"lattice", "jittered", "random", "cvt"}
        The generator's kind (``"jittered"`` with zero jitter is ``"lattice"``).
    jitter : float
        Largest node shift of ``"jittered"`` relative to the spacing (0 otherwise).
    iterations : int
        Lloyd iterations of ``"cvt"`` (0 otherwise).
    perturbations : tuple of float
        Amplitudes of later random moves (:meth:`Mesh.perturbed`), relative to the
        spacing, in the order they were applied.
    h : float
        The generator's node spacing (length units): what the relative values refer to
        (a graded mesh's smallest).
    graded : bool
        True if the spacing follows a size field (``h`` callable): the cells keep the
        recipe's statistics but are stretched along the grading, which is why models on
        such meshes take ``bonds="fabric"`` by default. Not part of :attr:`key` (the
        calibration samples are uniform).
    """

    kind: str
    jitter: float = 0.0
    iterations: int = 0
    perturbations: tuple[float, ...] = ()
    h: float = float("nan")
    graded: bool = False

    def __post_init__(self) -> None:
        jitter = float(self.jitter) if self.kind == "jittered" else 0.0
        kind = "lattice" if self.kind == "jittered" and jitter == 0.0 else self.kind
        object.__setattr__(self, "kind", kind)
        object.__setattr__(self, "jitter", jitter)
        object.__setattr__(self, "iterations", int(self.iterations) if kind == "cvt" else 0)
        object.__setattr__(self, "perturbations", tuple(float(a) for a in self.perturbations))
        object.__setattr__(self, "graded", bool(self.graded))

    def perturbed(self, amplitude: float) -> Sampling:
        """The recipe followed by a random move of ``amplitude`` (length units)."""
        if not np.isfinite(self.h) or self.h <= 0:
            return replace(self, perturbations=self.perturbations + (float("nan"),))
        return replace(self, perturbations=self.perturbations + (float(amplitude) / self.h,))

    @property
    def has_rows(self) -> bool:
        """True if the points keep the rows of a triangular lattice (cracks follow them)."""
        return self.kind in ROW_KINDS

    @property
    def reproducible(self) -> bool:
        """True if a periodic sample can be made by this recipe."""
        return bool(np.all(np.isfinite(self.perturbations)))

    @property
    def key(self) -> tuple:
        """Hashable key of the statistics (independent of the spacing)."""
        return (
            self.kind,
            round(self.jitter, 6),
            self.iterations,
            tuple(round(a, 6) for a in self.perturbations),
        )

    def __str__(self) -> str:
        s = ("graded " if self.graded else "") + self.kind
        if self.kind == "jittered":
            s += f" (jitter {self.jitter:g})"
        if self.kind == "cvt":
            s += f" ({self.iterations} Lloyd iterations)"
        for a in self.perturbations:
            s += f", perturbed by {a:.3g} h"
        return s
