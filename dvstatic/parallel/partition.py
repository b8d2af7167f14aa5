"""Partition and patches of distributed solves (``solver="petsc"``; the PETSc engine
itself is :mod:`dvstatic.parallel.petsc`).

Run the same script or scene on P ranks::

    mpiexec -n 4 python -m dvstatic run scene.toml      # scene: solver.kind = "petsc"
    mpiexec -n 4 python my_script.py                     # dv.solve(..., solver="petsc")

How the work is split
---------------------
* The nodes are partitioned by recursive coordinate bisection (:func:`rcb_partition`,
  computed identically on every rank) and renumbered so that rank ``p`` owns the
  contiguous block of nodes ``starts[p]:starts[p+1]`` and their dofs.
* Each rank builds a *patch*: the triangles within two rings of its nodes. On it, the
  half sides, circumcentres and bond tensions of every bond that acts on an owned node
  are exact, so the rank computes its own matrix rows, internal forces and loads with
  the serial model code on the patch, and hands them to PETSc through the COO
  interface. No rank ever builds the global matrix or any global vector.
* The paper's calibration sums (moments) and the relaxed calibration's bond-length
  spread are added up over owned bonds and triangles with one ``allreduce``.
* Linear solve: KSP CG; Newton tangents (not symmetric): KSP GMRES. Both use GAMG
  with the three rigid-body modes of the owned nodes as near null space. Prescribed
  displacements are eliminated symmetrically in each rank's own rows.
* The solution and the reactions are gathered on rank 0 only (for the outputs).

What every rank holds: the mesh (points, triangles, its bond topology and parts), the
node permutation (N integers), and its patch. Use :func:`patch_memory` and
``sol.info.parallel`` for the measured sizes.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from .._env import launched_under_mpi
from ..errors import InputError
from ..lattice import calibration
from ..lattice import geometry as _geometry
from ..lattice.weights import bond_weights
from ..mesh import Mesh
from ..problem import nodal_forces
from ..solvers import backends

__all__ = [
    "available",
    "launched_under_mpi",
    "rcb_partition",
    "Layout",
    "layout",
    "owned_bonds",
    "owned_triangles",
    "micro_parameters",
    "owned_loads",
    "patch_bond_weights",
    "patch_memory",
    "patch_model",
    "patch_triangles",
]

log = logging.getLogger(__name__)


def available() -> bool:
    """True if the PETSc engine's dependency (petsc4py) can be imported."""
    return backends.installed("petsc")


def rcb_partition(points: np.ndarray, nparts: int) -> np.ndarray:
    """Recursive coordinate bisection.

    Parameters
    ----------
    points : ndarray, shape (N, 2)
    nparts : int
        Number of parts, >= 1 (any integer: splits are in proportion).

    Returns
    -------
    ndarray of int, shape (N,)
        Part of every point; parts differ in size by at most one point per level.
    """
    points = np.asarray(points, dtype=float)
    if not isinstance(nparts, (int, np.integer)) or nparts < 1:
        raise InputError(f"nparts must be an integer >= 1, got {nparts!r}", "nparts")
    if nparts > len(points):
        raise InputError(f"cannot split {len(points)} points into {nparts} parts", "nparts")
    part = np.zeros(len(points), dtype=np.int64)
    stack = [(np.arange(len(points)), 0, int(nparts))]
    while stack:
        idx, first, k = stack.pop()
        if k == 1:
            part[idx] = first
            continue
        k1 = k // 2
        n1 = int(round(len(idx) * k1 / k))
        p = points[idx]
        axis = int(np.argmax(np.ptp(p, axis=0)))
        order = np.argsort(p[:, axis], kind="stable")
        stack.append((idx[order[:n1]], first, k1))
        stack.append((idx[order[n1:]], first + k1, k - k1))
    return part


@dataclass(frozen=True, eq=False)
class Layout:
    """One rank's share of a mesh.

    Attributes
    ----------
    rank, size : int
    new_of : ndarray of int, shape (N,)
        New (PETSc) node number of every mesh node; rank ``p`` owns new numbers
        ``starts[p]:starts[p+1]`` and dofs ``2*starts[p]:2*starts[p+1]``.
    starts : ndarray of int, shape (size + 1,)
    local_nodes : ndarray of int, shape (L,)
        Mesh nodes of the patch: the owned ones first (in new-number order), then the
        two rings around them.
    patch : Mesh
        Triangles within two rings of the owned nodes, in local numbering.
    n_owned : int
    """

    rank: int
    size: int
    new_of: np.ndarray
    starts: np.ndarray
    local_nodes: np.ndarray
    patch: Mesh
    n_owned: int

    @property
    def lo(self) -> int:
        return int(self.starts[self.rank])

    @property
    def local_dofs_global(self) -> np.ndarray:
        """PETSc dof number of every patch dof, shape (2L,)."""
        g = 2 * self.new_of[self.local_nodes]
        return np.stack([g, g + 1], axis=1).reshape(-1)


def layout(mesh: Mesh, rank: int, size: int) -> Layout:
    """Partition ``mesh`` over ``size`` ranks and build rank ``rank``'s patch."""
    n = mesh.n_points
    part = rcb_partition(mesh.points, size)
    old_of_new = np.argsort(part, kind="stable")
    new_of = np.empty(n, dtype=np.int64)
    new_of[old_of_new] = np.arange(n)
    counts = np.bincount(part, minlength=size)
    starts = np.concatenate([[0], np.cumsum(counts)])
    owned = old_of_new[starts[rank] : starts[rank + 1]]
    tri = mesh.triangles
    mask = np.zeros(n, dtype=bool)
    mask[owned] = True
    ring1 = np.zeros(n, dtype=bool)
    ring1[tri[mask[tri].any(axis=1)].ravel()] = True
    patch_idx = np.flatnonzero(ring1[tri].any(axis=1))
    patch_tri = tri[patch_idx]
    in_patch = np.zeros(n, dtype=bool)
    in_patch[patch_tri.ravel()] = True
    in_patch[owned] = False
    ghosts = np.flatnonzero(in_patch)
    local_nodes = np.concatenate([owned, ghosts[np.argsort(new_of[ghosts], kind="stable")]])
    local_of = np.full(n, -1, dtype=np.int64)
    local_of[local_nodes] = np.arange(len(local_nodes))
    regions = {k: np.flatnonzero(np.isin(patch_idx, v)) for k, v in mesh.regions.items()}
    patch = Mesh(mesh.points[local_nodes], local_of[patch_tri], regions=regions)
    return Layout(rank, size, new_of, starts, local_nodes, patch, len(owned))


# --------------------------------------------------------------------- owned parts
def owned_bonds(lay: Layout) -> np.ndarray:
    """Patch bonds owned by this rank (its node is the lower-numbered end), shape
    (n_patch_bonds,) bool."""
    new_local = lay.new_of[lay.local_nodes]
    b = lay.patch.topology.bonds
    first = np.minimum(new_local[b[:, 0]], new_local[b[:, 1]])
    return (first >= lay.lo) & (first < lay.starts[lay.rank + 1])


def owned_triangles(lay: Layout) -> np.ndarray:
    """Patch triangles owned by this rank (its node is the lowest-numbered), (T_patch,)."""
    first = lay.new_of[lay.local_nodes][lay.patch.triangles].min(axis=1)
    return (first >= lay.lo) & (first < lay.starts[lay.rank + 1])


def micro_parameters(model, lay: Layout, allreduce) -> tuple:
    """Calibrated micro-parameters of every material of ``model`` from sums over this
    rank's own bonds and triangles.

    ``allreduce`` adds a float array over all ranks (``lambda a: a`` on one process).
    Each bond and triangle is owned by the rank that owns its lowest-numbered node, so
    the sums over all ranks are the global ones. Collective: every rank computes them
    (unless every rank's model is calibrated already), so that all ranks use the same.
    """
    if allreduce(np.array([0.0 if model.is_calibrated else 1.0]))[0] == 0.0:
        return model.micros
    if not isinstance(model.calibration, str) or model.micro_field is not None:
        return model.micros  # given, or a mesh calibrated class by class (replicated)
    geom = _geometry.of(lay.patch)
    own_b = owned_bonds(lay)
    constants = [m.in_plane for m in model.all_materials]
    if model.calibration == "relaxed":
        # the recipe (or the table) is the same on every rank; without one, the
        # sample matches the local spread of the (replicated) mesh, the same everywhere
        return tuple(
            calibration.relaxed(model.kind, model.mesh, E2, nu2, model.bonds)
            for E2, nu2 in constants
        )
    w = patch_bond_weights(model, lay)
    sums = calibration.moment_sums(model.kind, geom, w, own_b, owned_triangles(lay))
    mom = calibration.moments_from_sums(allreduce(sums), model.mesh.area)
    return tuple(calibration.paper_from_moments(model.kind, mom, E2, nu2) for E2, nu2 in constants)


def patch_bond_weights(model, lay: Layout) -> np.ndarray:
    """The model's relative spring weights on the patch's bonds, shape (n_patch_bonds,):
    computed on the whole (replicated) mesh, since a scheme may read the mesh beyond
    the patch's two rings (``"fabric"`` averages over
    :data:`~dvstatic.lattice.weights.FABRIC_RINGS`)."""
    w = bond_weights(model.bonds, model.mesh)
    n = model.mesh.n_points
    gb = np.sort(model.mesh.topology.bonds, axis=1).astype(np.int64)
    key = gb[:, 0] * n + gb[:, 1]
    order = np.argsort(key)
    pb = np.sort(lay.local_nodes[lay.patch.topology.bonds], axis=1).astype(np.int64)
    pos = np.searchsorted(key, pb[:, 0] * n + pb[:, 1], sorter=order)
    return w[order[pos]]


def patch_triangles(mesh: Mesh, lay: Layout) -> np.ndarray:
    """The global index of every triangle of the patch, shape (n_patch_triangles,): found
    through the bond of its two lowest nodes and the node opposite it."""
    n = mesh.n_points
    topo = mesh.topology
    gb = np.sort(topo.bonds, axis=1).astype(np.int64)
    key = gb[:, 0] * n + gb[:, 1]
    order = np.argsort(key)
    pt = np.sort(lay.local_nodes[lay.patch.triangles], axis=1).astype(np.int64)
    bond = order[np.searchsorted(key, pt[:, 0] * n + pt[:, 1], sorter=order)]
    first, second = topo.bond_tris[bond, 0], topo.bond_tris[bond, 1]
    has = np.any(mesh.triangles[first] == pt[:, 2:3], axis=1)
    return np.where(has, first, second)


def patch_model(model, lay: Layout, micros: tuple | None = None):
    """``model`` on the rank's patch, with what reaches beyond the patch's two rings
    read from the whole (replicated) mesh: the spring weights
    (:func:`patch_bond_weights`), the exact cells (the whole mesh's boundary triangles
    :data:`~dvstatic.lattice.cells.CELL_RINGS` rings deep, not the patch's cut), a
    class-by-class calibration's micro-parameters and the regional isotropy's field
    (:mod:`dvstatic.lattice.isotropy`: a region reaches 12 passes of neighbours).
    ``micros``: one MicroParameters per material (default: the model's)."""
    micros = model.micros if micros is None else tuple(micros)
    pm = type(model)(
        lay.patch,
        model.E,
        model.nu,
        calibration=micros if len(micros) > 1 else micros[0],
        bonds=model.bonds,
        plane=model.plane,
        thickness=model.thickness,
        materials={k: (m.E, m.nu) for k, m in model.materials.items()},
        boundary_cells=model.boundary_cells,
        anisotropy=model.anisotropy,
    )
    object.__setattr__(pm, "bond_weight", patch_bond_weights(model, lay))  # cached
    tri_global = patch_triangles(model.mesh, lay)
    is_cell = np.zeros(model.mesh.n_triangles, dtype=bool)
    is_cell[model.cell_triangles] = True
    object.__setattr__(pm, "cell_triangles", np.flatnonzero(is_cell[tri_global]))
    if model.micro_field is not None:  # a mesh calibrated class by class
        object.__setattr__(pm, "micro_field", model.micro_field.restricted(tri_global))
    if model.anisotropy == "regional":  # regions reach beyond the patch: the whole's
        whole = model if model.is_calibrated else model.replaced_calibration(micros)
        object.__setattr__(pm, "anisotropy_field", whole.anisotropy_field[tri_global])
        takes = np.zeros(model.mesh.n_triangles, dtype=bool)
        takes[whole.regional_triangles] = True  # read over 4 rings: the whole's too
        object.__setattr__(pm, "regional_triangles", np.flatnonzero(takes[tri_global]))
    return pm


def owned_loads(mesh: Mesh, loads, lay: Layout, thickness: float = 1.0) -> np.ndarray:
    """External forces on the owned dofs, shape (2 n_owned,)."""
    return nodal_forces(mesh, loads, nodes=lay.local_nodes[: lay.n_owned], thickness=thickness)


def patch_memory(lay: Layout) -> dict:
    """Sizes (MB) of what this rank holds: replicated mesh, permutation, patch."""
    mesh = lay.patch

    def mb(*arrs):
        return float(sum(a.nbytes for a in arrs)) / 2**20

    return {
        "patch_nodes": int(mesh.n_points),
        "patch_triangles": int(mesh.n_triangles),
        "owned_nodes": int(lay.n_owned),
        "permutation_MB": mb(lay.new_of),
        "patch_mesh_MB": mb(mesh.points, mesh.triangles),
    }
