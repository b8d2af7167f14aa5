"""Crack closure: a face cracked in tension carries normal compression again once it
closes (unilateral contact on its bond), the contact status made consistent inside
every event by an active set.

A closed face's bond carries compression with its whole spring (its triangles' coupling
stays off, as for any cracked bond: its tension is then its spring times its
elongation, and the stiffness stays symmetric positive semi-definite). A face is closed
while its bond's elongation is negative (the faces would overlap: the crack has no gap
left) and open otherwise, so a closed bond never carries tension. Faces that failed in
shear or crushing lost their bond for good and take no part.
"""

from __future__ import annotations

import numpy as np

__all__ = ["Contact", "MAX_ITERATIONS"]

#: active-set passes per event before the last status is kept (and the event flagged)
MAX_ITERATIONS = 25


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

    def update(self, elongation: np.ndarray) -> np.ndarray:
        """Set the status from a state's bond elongations (n_bonds,); returns the bonds
        whose status changed."""
        new = self.cracked & (elongation < 0)
        changed = np.flatnonzero(new != self.closed)
        self.closed = new
        return changed
