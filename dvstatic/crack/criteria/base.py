"""The breaking-criterion protocol and its registry.

A criterion says, per unit load factor, what every intact bond compares with its
threshold, how its thresholds follow from the material's strengths, and what a cracked
bond softens by. The event loop (:mod:`dvstatic.crack.sla`) only calls
:meth:`Criterion.prepare` once and :meth:`Criterion.critical` at every event. A new
criterion is a module in this package with a :func:`register`-ed subclass (and a test);
its name is then accepted by ``dv.fracture(criterion=...)`` and the scene.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from typing import ClassVar

import numpy as np

from ..strength import bond_strength, principal_response, weibull_factors
from .responses import per_bond, responses

__all__ = ["Criterion", "REGISTRY", "register", "criterion_for"]

#: criterion name -> class, in the order they were registered
REGISTRY: dict[str, type[Criterion]] = {}


def register(cls: type[Criterion]) -> type[Criterion]:
    """Class decorator: make ``cls`` available under ``cls.name``."""
    REGISTRY[cls.name] = cls
    return cls


def criterion_for(name: str, model, sp_) -> Criterion:
    """The registered criterion ``name`` for ``model`` and its split stiffness."""
    return REGISTRY[name](model, sp_)


class Criterion(ABC):
    """Base of the breaking criteria (abstract: a criterion defines :meth:`thresholds`
    and :meth:`__call__`).

    Parameters
    ----------
    model : DV or RV
    sp_ : SplitStiffness
        The per-triangle parts of the stiffness (:func:`dvstatic.lattice.damage.split`).
    """

    #: the name ``dv.fracture(criterion=...)`` takes
    name: ClassVar[str] = ""

    def __init__(self, model, sp_):
        self.sp = sp_
        geo = model.geometry
        self.length = geo.tri_l
        self.area = geo.tri_area * model.t
        self.n = geo.direction
        self.bonds = model.mesh.topology.bonds
        self.h = None  # (n_bonds, 3): tension per unit xx, yy and xy stress

    # ------------------------------------------------------------------ to override
    def set_response(self, h: np.ndarray, patches) -> None:
        """Keep the bonds' tensions ``h`` (n_bonds, 3) and patch stresses (3 x (stress,
        covered)) under the unit uniform stresses xx, yy, xy."""
        self.h = h

    @abstractmethod
    def thresholds(self, s_tension, ftb, factors) -> np.ndarray:
        """First-crack threshold of every bond in the criterion's units, from the
        tension-based strengths ``s_tension`` (force), the tensile strength per bond
        ``ftb`` and the random-field ``factors`` (None: uniform)."""

    @abstractmethod
    def __call__(self, x, w, g, intact=None) -> np.ndarray:
        """What every intact bond compares with its threshold, shape (n_bonds,), in the
        state ``x`` (per unit load factor) of the damaged stiffness ``w, g``."""

    # ------------------------------------------------------------------ shared
    def prepare(self, model, ft, weibull, timings: dict, dofs=None):
        """Thresholds (n_bonds,) in the criterion's units and the tension-based
        strengths (n_bonds,; force, for the fracture energies), from ``ft`` (a number
        or ``{region: ft}``) and the random field; ``dofs``: the problem's prescribed
        dofs (the uniform-stress responses hold them)."""
        t0 = time.perf_counter()
        mesh = model.mesh
        tens, patches = responses(model, self.length, self.area, dofs)
        self.set_response(np.stack(tens, axis=1), patches)
        factors = None
        if weibull is not None:
            factors = weibull_factors(mesh.points[mesh.topology.bonds].mean(axis=1), weibull)
        ftb = per_bond(model, ft, "ft")
        s_t = bond_strength(principal_response(tens), ftb, factors)
        s = self.thresholds(s_t, ftb, factors)
        timings["strength"] = time.perf_counter() - t0
        return s, s_t

    def softening(self, x) -> np.ndarray:
        """What a cracked bond softens by: its elongation (length) per unit load factor,
        shape (n_bonds,)."""
        u = x.reshape(-1, 2)
        return np.einsum("ei,ei->e", self.n, u[self.bonds[:, 1]] - u[self.bonds[:, 0]])

    def critical(self, x, w, g, intact, d: np.ndarray, threshold: np.ndarray):
        """The bond closest to its threshold, the load factor that brings it there, and
        every bond's softening variable: ``(bond, load factor, softening)``. Intact bonds
        (``d >= 1``) answer by the criterion, cracked ones by their softening variable;
        the load factor is ``inf`` when no bond is loaded towards its threshold."""
        softening = self.softening(x)
        value = np.where(d >= 1.0, self(x, w, g, intact), softening)
        ratio = np.where(d > 0, value / threshold, 0.0)
        ratio[~(ratio > 0)] = 0.0
        e = int(np.argmax(ratio))
        return e, (1.0 / ratio[e] if ratio[e] > 0 else np.inf), softening
