"""A problem resolved once: supports and loads on a model's mesh, turned into the
constrained dofs, their prescribed values and the load vector, validated on the way.
``dv.solve`` and ``dv.fracture`` build one and carry it (on ``Solution.problem``), so no
later step works the supports and loads out again."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..linalg import check_restrained
from .loads import load_vector
from .scale import scaled
from .select import as_list
from .supports import constraints

__all__ = ["Problem"]


@dataclass(frozen=True, eq=False)
class Problem:
    """Supports and loads resolved on a mesh.

    Attributes
    ----------
    supports, loads : tuple
        As given (``Fix``; ``Traction``, ``Pressure``, ``BodyForce``, ``PointLoad``).
    dofs : ndarray of int, shape (k,)
        The constrained dofs (sorted; interleaved ``2 node + component``).
    values : ndarray, shape (k,)
        Their prescribed values (length).
    f : ndarray, shape (2N,)
        The nodal load vector (force; times the model's thickness).
    """

    supports: tuple
    loads: tuple
    dofs: np.ndarray
    values: np.ndarray
    f: np.ndarray

    @classmethod
    def build(cls, model, supports=None, loads=None, restrained: bool = True) -> Problem:
        """Resolve ``supports`` and ``loads`` (one or a list; None: none) on ``model``.

        Raises
        ------
        InputError
            Bad supports or loads, or (``restrained``) supports that leave a rigid-body
            motion free.
        """
        mesh = model.mesh
        sup = tuple(as_list(supports, "Fix"))
        lds = tuple(as_list(loads, "Traction, Pressure, BodyForce or PointLoad"))
        dofs, values = constraints(mesh, list(sup))
        if restrained:
            check_restrained(mesh.points, dofs)
        f = load_vector(mesh, list(lds), thickness=model.t) if lds else np.zeros(2 * mesh.n_points)
        return cls(sup, lds, dofs, values, f)

    @cached_property
    def fixed(self) -> np.ndarray:
        """True at the constrained dofs, shape (2N,)."""
        out = np.zeros(len(self.f), dtype=bool)
        out[self.dofs] = True
        return out

    def scaled(self, factor: float) -> Problem:
        """The same problem with every load and prescribed value times ``factor``."""
        return Problem(
            tuple(scaled(list(self.supports), factor)),
            tuple(scaled(list(self.loads), factor)),
            self.dofs,
            factor * self.values,
            factor * self.f,
        )
