"""Stresses of lattice states (layer 3, beside the problem: imports the lattice and the
problem; the solvers import it).

* :mod:`.virial`: the lattice's own stresses: bond states, the force-based (virial)
  stress per Voronoi cell, the P1 strain and stress of every triangle.
* :mod:`.recovery`: the default stress of a linear solution, a continuum field at a
  stated averaging scale (``RADIUS`` local spacings) that is exact for every uniform
  stress at every node and right to first order where the stress varies:
  :class:`~.recovery.Recovery`, built once per model and set of supports from
  :mod:`.boundary` (the stress vector read from the nodal forces), :mod:`.fit` (the
  averaging as sparse operators, equilibrated fits by the fields of :mod:`.kolosov`)
  and :mod:`.response` (the micro-structure correction).
"""

from .fit import RADIUS
from .recovery import ALPHA, Recovery, as_tensors, body_forces, recovery_of
from .virial import (
    bond_state,
    node_stress,
    out_of_plane_stress,
    strain_stress,
    triangle_strains,
    triangle_stress,
)

__all__ = [
    "RADIUS",
    "ALPHA",
    "Recovery",
    "recovery_of",
    "body_forces",
    "as_tensors",
    "bond_state",
    "node_stress",
    "out_of_plane_stress",
    "strain_stress",
    "triangle_strains",
    "triangle_stress",
]
