"""Crack closure: a face cracked in tension carries normal compression again once it
closes (unilateral contact on its bond), the contact status made consistent inside
every event by an active set.

The status is the solution of a convex problem: the lattice's energy with every cracked
face's missing spring added back where its bond is shortened (a penalty form of
non-penetration), a piecewise quadratic. Setting the status from the signs and solving
is Newton's method on it (semismooth); :func:`line_search` damps the steps so that the
energy falls at every pass, which keeps the active set from cycling.

A closed face's bond carries compression with its whole spring (its triangles' coupling
stays off, as for any cracked bond: its tension is then its spring times its
elongation, and the stiffness stays symmetric positive semi-definite). A face is closed
while its bond's elongation is negative (the faces would overlap: the crack has no gap
left) and open otherwise, so a closed bond never carries tension. Faces that failed in
shear or crushing (broken, or softening with ``gf_shear``) take no part.
"""

from __future__ import annotations

import numpy as np

__all__ = ["Contact", "MAX_ITERATIONS", "TOLERANCE", "line_search"]

#: elongations within this fraction of the state's largest count as zero (a face there
#: keeps its status)
TOLERANCE = 1e-9

#: Newton passes for one contact status before the last one is kept (and a warning
#: given); nearly separated bodies take tens (the energy is flat there)
MAX_ITERATIONS = 100


class Contact:
    """The faces cracked in tension and which of them are closed.

    Parameters
    ----------
    n_bonds : int
    enabled : bool
        False: cracks never close (the faces pass through each other).
    """

    def __init__(self, n_bonds: int, enabled: bool):
        self.enabled = enabled
        self.cracked = np.zeros(n_bonds, dtype=bool)
        self.closed = np.zeros(n_bonds, dtype=bool)

    @property
    def active(self) -> bool:
        """True if a face can close (contact on and some face cracked in tension)."""
        return self.enabled and bool(self.cracked.any())

    def effective(self, d: np.ndarray) -> np.ndarray:
        """Bond factors as the pieces see them: 1 for a closed face, else ``d``."""
        return np.where(self.closed, 1.0, d) if self.closed.any() else d

    def status(self, elongation: np.ndarray) -> np.ndarray:
        """The closed faces (bool, n_bonds) of a state's bond elongations (n_bonds,): the
        cracked faces whose bonds are shortened. A face within :data:`TOLERANCE` of the
        largest elongation of zero keeps its status (a face exactly at the turn carries
        no force either way, and flipping it would stall the Newton passes)."""
        tol = TOLERANCE * (float(np.max(np.abs(elongation))) or 1.0)
        stays = self.closed & (elongation <= tol)
        closes = ~self.closed & (elongation < -tol)
        return self.cracked & (stays | closes)

    def set(self, status: np.ndarray) -> None:
        """Take the closed faces ``status`` (bool, n_bonds)."""
        self.closed = status


def line_search(a0: float, a1: float, delta, step, extra) -> float:
    """The step ``alpha`` in (0, 1] that minimises the energy along a Newton step.

    The energy's derivative along the step ``d`` is ``a0 + alpha a1 + sum_e extra_e
    min(delta_e + alpha step_e, 0) step_e``: ``a0 = (K_open z - F) . d`` and ``a1 = d .
    K_open d`` (the lattice with every cracked face open), ``delta``/``step`` the
    cracked faces' elongations at ``z`` and along ``d``, ``extra`` their missing
    springs. It grows with ``alpha`` (convexity); its root is found by bisection.
    """

    def slope(alpha: float) -> float:
        return a0 + alpha * a1 + float(np.sum(extra * np.minimum(delta + alpha * step, 0.0) * step))

    if slope(1.0) <= 0.0:
        return 1.0
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if slope(mid) > 0.0:
            hi = mid
        else:
            lo = mid
    return max(hi, 1e-12)
