"""The lattice's own response to uniform stress: what the recovery's micro-structure
correction is measured on.

A uniform stress ``sigma`` is an exact state of a homogeneous continuum: its stress
vector ``sigma n`` on every boundary edge, its displacement ``eps x`` (``eps`` from the
in-plane law) at every prescribed dof. Loaded that way, the lattice answers with its
micro-structure: node-to-node fluctuation, the layers of other cells along boundaries
and supports. Averaged by the recovery, the three unit states (``sxx``, ``syy``,
``sxy``) give every node the matrix that maps a true stress to what the recovery
reports there; its inverse is the correction (the localisation tensor of
homogenisation theory, measured on the very mesh and supports). With several
materials, uniform stress is no continuum state (the strains do not fit at the
interfaces), so each material's nodes are corrected with the responses of a
single-material companion of the model (the same mesh, calibration and bonds); a
damaged lattice (fracture) is corrected with the responses of its intact companion.
"""

from __future__ import annotations

import numpy as np

from .._cache import PerObject
from ..lattice import VoronoiModel
from .boundary import Boundary

__all__ = ["companion", "uniform_states", "invert", "UNIT_STATES"]

#: the unit stress states (sxx, syy, sxy)
UNIT_STATES = (
    np.array([[1.0, 0.0], [0.0, 0.0]]),
    np.array([[0.0, 0.0], [0.0, 1.0]]),
    np.array([[0.0, 1.0], [1.0, 0.0]]),
)

_COMPANIONS = PerObject("single-material companions", lambda model: {})


def companion(model: VoronoiModel, material: int) -> VoronoiModel:
    """``model`` itself with one material and no damage; otherwise a model of the same
    kind on the same mesh made of material ``material`` alone, intact, with that
    material's calibrated micro-parameters (cached). (A cracked lattice under uniform
    traction is not in uniform stress: its cracks concentrate it, which the correction
    must not undo.)"""
    if not model.materials and model.damage is None:
        return model
    cache = _COMPANIONS(model)
    if material not in cache:
        m = model.all_materials[material]
        cache[material] = type(model)(
            model.mesh,
            m.E,
            m.nu,
            # a mesh calibrated class by class: the companion's own classes, of
            # this material alone (the same samples, cached)
            calibration="relaxed" if model.micro_field is not None else model.micros[material],
            bonds=model.bonds,
            plane=model.plane,
            thickness=model.thickness,
            boundary_cells=model.boundary_cells,
            anisotropy=model.anisotropy,
        )
        # the model's regions: averaged within its materials, not the companion's one
        object.__setattr__(cache[material], "region_partition", model.region_partition)
        cache[material].share_calibration_flags(model)
    return cache[material]


def uniform_states(model: VoronoiModel, boundary: Boundary) -> list[tuple[np.ndarray, np.ndarray]]:
    """Nodal forces (2N,) and displacements (2N,) of the three unit stress states.

    The forces are the stress vector ``sigma n`` of every boundary edge times its
    length (and the thickness), half to each end; the displacements are ``eps x``
    with ``eps`` from the model's in-plane law (plane strain: the effective
    constants), to be imposed at the prescribed dofs.
    """
    E, nu = model.material.in_plane
    mesh = model.mesh
    out = []
    for sigma in UNIT_STATES:
        eps = (
            np.array(
                [
                    [sigma[0, 0] - nu * sigma[1, 1], (1 + nu) * sigma[0, 1]],
                    [(1 + nu) * sigma[0, 1], sigma[1, 1] - nu * sigma[0, 0]],
                ]
            )
            / E
        )
        t = boundary.normal @ sigma.T * (model.t * 0.5 * boundary.length)[:, None]
        f = np.zeros((mesh.n_points, 2))
        for end in range(2):
            for c in range(2):
                f[:, c] += np.bincount(boundary.edges[:, end], t[:, c], mesh.n_points)
        out.append((f.reshape(-1), (mesh.points @ eps.T).reshape(-1)))
    return out


def invert(A: np.ndarray, limit: float) -> tuple[np.ndarray, int]:
    """Inverses of the response matrices (n, 3, 3) (rows: reported components,
    columns: unit states); the identity where a matrix is not finite or its
    condition number exceeds ``limit``. Returns the inverses and how many were not
    inverted."""
    ok = np.all(np.isfinite(A), axis=(1, 2))
    cond = np.full(len(A), np.inf)
    cond[ok] = np.linalg.cond(A[ok])
    ok &= cond < limit
    out = np.broadcast_to(np.eye(3), A.shape).copy()
    out[ok] = np.linalg.inv(A[ok])
    return out, int((~ok).sum())
