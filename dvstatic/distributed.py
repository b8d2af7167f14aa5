"""Distributed solves on PETSc (``solver="petsc"``): petsc4py and MPI.

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
``sol.info["parallel"]`` for the measured sizes.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass

import numpy as np

from . import calibration
from .loads import BodyForce, Fix, PointLoad, Traction, as_list, select_edges, select_nodes
from .mesh import Mesh

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
    "patch_memory",
]

log = logging.getLogger(__name__)


#: KSP options (prefix ``dvstatic_``); any PETSc option given on the command line
#: (``-dvstatic_ksp_monitor``, ``-dvstatic_pc_type hypre``...) overrides them
def available() -> bool:
    """True if petsc4py can be imported."""
    try:
        import petsc4py  # noqa: F401
    except ImportError:
        return False
    return True


def launched_under_mpi() -> bool:
    """True if this process was started by an MPI launcher (``mpiexec``), read from
    the launcher's environment without importing MPI."""
    for key in ("PMI_SIZE", "OMPI_COMM_WORLD_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS"):
        v = os.environ.get(key, "")
        if v.isdigit() and int(v) >= 1:
            return True
    return False


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
        raise ValueError(f"nparts must be an integer >= 1, got {nparts!r}")
    if nparts > len(points):
        raise ValueError(f"cannot split {len(points)} points into {nparts} parts")
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
    patch_tri = tri[ring1[tri].any(axis=1)]
    in_patch = np.zeros(n, dtype=bool)
    in_patch[patch_tri.ravel()] = True
    in_patch[owned] = False
    ghosts = np.flatnonzero(in_patch)
    local_nodes = np.concatenate([owned, ghosts[np.argsort(new_of[ghosts], kind="stable")]])
    local_of = np.full(n, -1, dtype=np.int64)
    local_of[local_nodes] = np.arange(len(local_nodes))
    patch = Mesh(mesh.points[local_nodes], local_of[patch_tri])
    return Layout(rank, size, new_of, starts, local_nodes, patch, len(owned))


# --------------------------------------------------------------------- owned parts
def owned_bonds(lay: Layout) -> np.ndarray:
    """Patch bonds owned by this rank (its node is the lower-numbered end), (E_patch,)."""
    new_local = lay.new_of[lay.local_nodes]
    b = lay.patch.topology.bonds
    first = np.minimum(new_local[b[:, 0]], new_local[b[:, 1]])
    return (first >= lay.lo) & (first < lay.starts[lay.rank + 1])


def owned_triangles(lay: Layout) -> np.ndarray:
    """Patch triangles owned by this rank (its node is the lowest-numbered), (T_patch,)."""
    first = lay.new_of[lay.local_nodes][lay.patch.triangles].min(axis=1)
    return (first >= lay.lo) & (first < lay.starts[lay.rank + 1])


def micro_parameters(model, lay: Layout, allreduce):
    """Calibrated micro-parameters from sums over this rank's own bonds and triangles.

    ``allreduce`` adds a float array over all ranks (``lambda a: a`` on one process).
    Each bond and triangle is owned by the rank that owns its lowest-numbered node, so
    the sums over all ranks are the global ones.
    """
    if isinstance(model.calibration, calibration.MicroParameters):
        return model.calibration
    if "micro" in model.__dict__:
        return model.__dict__["micro"]
    from . import geometry as _geometry
    from .models import voronoi_weights

    geom = _geometry.of(lay.patch)
    b = lay.patch.topology.bonds
    own_b = owned_bonds(lay)
    own_t = owned_triangles(lay)
    if model.calibration == "relaxed":
        bnd = np.zeros(model.mesh.n_points, dtype=bool)
        bnd[model.mesh.boundary_nodes] = True
        glob = lay.local_nodes[b]
        inner = own_b & ~(bnd[glob[:, 0]] | bnd[glob[:, 1]])
        ln = geom.length
        s = allreduce(
            np.array(
                [inner.sum(), ln[inner].sum(), (ln[inner] ** 2).sum()]
                + [own_b.sum(), ln[own_b].sum(), (ln[own_b] ** 2).sum()],
                dtype=float,
            )
        )
        c, s1, s2 = s[:3] if s[0] >= 30 else s[3:]
        mean = s1 / c
        spread = float(np.sqrt(max(s2 / c - mean**2, 0.0)) / mean)
        return calibration.relaxed(
            model.kind, model.mesh, model.E, model.nu, model.bonds, spread=spread
        )
    w = voronoi_weights(geom) if model.bonds == "voronoi" else None
    sums = calibration.moment_sums(model.kind, geom, w, own_b, own_t)
    mom = calibration.moments_from_sums(allreduce(sums), model.mesh.area)
    return calibration.paper_from_moments(model.kind, mom, model.E, model.nu)


def owned_loads(mesh: Mesh, loads, lay: Layout) -> np.ndarray:
    """External forces on the owned dofs, shape (2 n_owned,)."""
    n_own, lo = lay.n_owned, lay.lo
    f = np.zeros((n_own, 2))

    def owned_index(nodes):
        k = lay.new_of[nodes] - lo
        keep = (k >= 0) & (k < n_own)
        return k, keep

    for load in as_list(loads, "Traction, BodyForce or PointLoad"):
        if isinstance(load, Traction):
            e = select_edges(mesh, load.where, "Traction")
            d = mesh.points[e[:, 1]] - mesh.points[e[:, 0]]
            half = 0.5 * np.hypot(d[:, 0], d[:, 1])
            for end in (0, 1):
                k, keep = owned_index(e[:, end])
                for c in range(2):
                    f[:, c] += load.value[c] * np.bincount(k[keep], half[keep], n_own)
        elif isinstance(load, BodyForce):
            t = lay.patch.triangles
            share = np.repeat(lay.patch.triangle_areas / 3.0, 3)
            w = np.bincount(t.ravel(), share, lay.patch.n_points)[:n_own]
            f += w[:, None] * np.asarray(load.value)[None, :]
        elif isinstance(load, PointLoad):
            nodes = select_nodes(mesh, load.nodes, "PointLoad")
            k, keep = owned_index(nodes)
            f[k[keep]] += np.asarray(load.value)[None, :]
        elif isinstance(load, Fix):
            raise TypeError("Fix is a support: pass it in `supports`, not in `loads`")
        else:
            raise TypeError(
                f"unknown load type {type(load).__name__}; use Traction, BodyForce or PointLoad"
            )
    return f.reshape(-1)


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
