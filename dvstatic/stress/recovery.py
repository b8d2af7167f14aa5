"""The default stress of a linear lattice solution: a continuum stress field at a
stated averaging scale, right at every node.

Three steps, each a linear map (built once per model and set of supports, cached):

1. **Data** at every node: ``ALPHA`` times the lattice's force-based (virial) stress
   of the node's share of its bonds plus ``1 - ALPHA`` times the continuum law of its
   material applied to the P1 strain of its triangles (both per node area). Their
   node-to-node fluctuations (the lattice's micro-structure) are nearly uncorrelated
   (correlation -0.02 to -0.24 on jittered, CVT and random meshes), so the mix
   scatters less than either (random points, 6 spacings: 5.5 % virial, 8.9 % strain,
   4.2 % mixed).
2. **Averaging** over a window of ``RADIUS`` local spacings (:mod:`.fit`): a kernel
   mean inside the body, equilibrated fits (Kolosov-Muskhelishvili fields, Laurent
   fields at holes) that also match the stress vector on the boundary (read from the
   nodal forces, :mod:`.boundary`) where the window meets a boundary or another
   material. At a boundary node the known components of the stress vector are then
   imposed exactly (all of them at a corner between free or loaded pieces).
3. **Micro-structure correction** (:mod:`.response`): the same two steps applied to
   the lattice's own responses to the three uniform stress states (solved on the same
   mesh, with the same supported dofs held at the uniform state's displacement) give
   every node a 3x3 matrix ``A``: what the averaging reports there for a unit
   ``sxx``, ``syy`` or ``sxy``. The recovered stress is ``A^-1`` times the estimate:
   exact for any uniform stress, whatever the mesh, the supports or the node (rows
   next to loaded or supported edges, corners included), and, since a smooth field
   is uniform to first order over the window, right to first order in h where the
   stress varies. The known stress vector at boundary nodes stays exact through it.
"""

from __future__ import annotations

import logging
import weakref

import numpy as np

from .._cache import PerObject
from ..lattice import VoronoiModel
from ..problem import BodyForce, evaluate, load_vector
from .boundary import Boundary
from .fit import Estimator, build_estimator
from .virial import triangle_stress

log = logging.getLogger(__name__)

__all__ = ["Recovery", "recovery_of", "body_forces", "ALPHA", "CONDITION_LIMIT"]

#: share of the force-based (virial) stress in the nodal data (the rest: the strain
#: with the continuum law); 0.6-0.7 gave the least scatter on every mesh kind measured
ALPHA = 0.65
#: a node whose response matrix is worse conditioned than this keeps its estimate
#: uncorrected (and is counted in ``Recovery.uncorrected``)
CONDITION_LIMIT = 1e3

#: the recoveries of a model, by the bytes of its prescribed-dof mask
_RECOVERIES = PerObject("stress recoveries", lambda model: {})


def recovery_of(model: VoronoiModel, fixed: np.ndarray) -> Recovery:
    """The (cached) recovery of ``model`` with the prescribed dofs ``fixed`` (N, 2)."""
    fixed = np.asarray(fixed, dtype=bool).reshape(-1, 2)
    cache = _RECOVERIES(model)
    key = fixed.tobytes()
    if key not in cache:
        if len(cache) >= 4:
            cache.pop(next(iter(cache)))
        cache[key] = Recovery(model, fixed)
    return cache[key]


def body_forces(model: VoronoiModel, loads) -> tuple[np.ndarray, np.ndarray] | None:
    """The body force at every node (force per volume, (N, 2): the region's where a
    node's triangles are in it) and its nodal forces (N, 2), or None without any."""
    forces = [ld for ld in loads or () if isinstance(ld, BodyForce)]
    if not forces:
        return None
    mesh = model.mesh
    at_nodes = np.zeros((mesh.n_points, 2))
    for ld in forces:
        inside = np.ones(mesh.n_points, dtype=bool)
        if ld.region is not None:
            inside = np.zeros(mesh.n_points, dtype=bool)
            inside[mesh.triangles[mesh.regions[ld.region]].ravel()] = True
        if callable(ld.value):
            v = evaluate(ld.value, mesh.points, (2,), "BodyForce")
        else:
            v = np.broadcast_to(np.asarray(ld.value, dtype=float), (mesh.n_points, 2))
        at_nodes += np.where(inside[:, None], v, 0.0)
    nodal = load_vector(mesh, forces, thickness=model.t).reshape(-1, 2)
    return at_nodes, nodal


class Recovery:
    """The recovery of one model with one set of prescribed dofs.

    Parameters
    ----------
    model : DV or RV
    fixed : ndarray of bool, shape (N, 2)
        The prescribed dofs of the solutions to recover.

    Attributes
    ----------
    estimator : Estimator
    boundary : Boundary or None
    correction : ndarray, shape (N, 3, 3) or None
        ``A^-1`` per node once the responses are in (:meth:`set_responses`).
    uncorrected : int
        Nodes whose response matrix was too ill-conditioned to invert.
    """

    def __init__(self, model: VoronoiModel, fixed: np.ndarray):
        mesh = model.mesh
        # weakly: the recovery is cached per model (recovery_of), and a strong reference
        # from the cached value to its key would keep every model that was ever
        # recovered alive, with its factorisation (a long sweep ran out of memory)
        self._model = weakref.ref(model)
        self.fixed = fixed
        self.node_mat = node_material(model)
        self.consts = np.array([m.in_plane for m in model.all_materials])
        self.area = model.geometry.dual_area
        self.boundary = None if mesh.is_periodic else Boundary.of(mesh)
        self.edge_mat = (
            np.zeros(0, dtype=np.int64) if self.boundary is None else _edge_material(model)
        )
        self.estimator: Estimator = build_estimator(
            mesh,
            self.node_mat,
            model.material_of_triangle,
            self.consts,
            self.area,
            self.boundary,
            fixed,
            self.edge_mat,
        )
        self.correction: np.ndarray | None = None
        self.uncorrected = 0
        self._pending = set(range(len(self.consts))) if self.boundary is not None else set()
        self._responses: dict[int, np.ndarray] = {}

    @property
    def model(self) -> VoronoiModel:
        """The model this recovery was built for."""
        model = self._model()
        if model is None:  # only reachable through a recovery kept past its model
            raise ReferenceError("the model of this stress recovery no longer exists")
        return model

    # -- the estimate ----------------------------------------------------------------
    def estimate(self, model: VoronoiModel, u: np.ndarray, body=None) -> np.ndarray:
        """Averaged and boundary-projected stress (..., N, 3) of displacements u
        (..., N, 2) of ``model`` (this recovery's model, or one with the same mesh and
        materials: a damaged state of it, a single-material companion), before the
        micro-structure correction."""
        u = np.asarray(u, dtype=float)
        lead = u.shape[:-2]
        us = u.reshape(-1, *u.shape[-2:])
        out = np.empty(us.shape[:-1] + (3,))
        for k, uk in enumerate(us):
            out[k] = self._estimate_one(model, uk, body)
        return out.reshape(*lead, -1, 3)

    def _estimate_one(self, model, u, body) -> np.ndarray:
        nodal = nodal_data(model, u)
        if self.boundary is None:
            return self.estimator.interior @ nodal
        b = self.boundary
        fext = (model.stiffness("bsr") @ u.reshape(-1)).reshape(-1, 2)
        if body is not None:
            fext = fext - body[1]
        slot_t, edge_t = b.tractions(fext, model.t, self.estimator.radius, self.fixed)
        du = u[b.edges[:, 1]] - u[b.edges[:, 0]]
        stretch = self.consts[self.edge_mat, 0] * np.einsum("ij,ij->i", du, b.tangent) / b.length
        est = self.estimator.apply(nodal, edge_t, stretch)
        if body is not None:
            est -= np.einsum("ncd,nd->nc", self.estimator.body, body[0])
        return self._project(est, slot_t)

    def _project(self, est: np.ndarray, slot_t: np.ndarray) -> np.ndarray:
        """The nearest stress (sxy counted twice) whose stress vector at every boundary
        node has the known (not reaction) components of its slots' stress vectors."""
        b = self.boundary
        nodes, first = np.unique(b.slot_node, return_index=True)
        second = np.full(len(nodes), -1)
        slots_of = np.searchsorted(nodes, b.slot_node)
        dup = np.ones(len(b.slot_node), dtype=bool)
        dup[first] = False
        second[slots_of[dup]] = np.flatnonzero(dup)
        C = np.zeros((len(nodes), 4, 3))
        d = np.zeros((len(nodes), 4))
        for k, slot in enumerate((first, second)):
            ok = slot >= 0
            s = np.where(ok, slot, 0)
            nrm = b.slot_normal[s]
            known = ~self.fixed[nodes] & ok[:, None]  # (n, 2)
            C[:, 2 * k, :] = np.c_[nrm[:, 0], np.zeros(len(s)), nrm[:, 1]] * known[:, :1]
            C[:, 2 * k + 1, :] = np.c_[np.zeros(len(s)), nrm[:, 1], nrm[:, 0]] * known[:, 1:]
            d[:, 2 * k : 2 * k + 2] = slot_t[s] * known
        v = est[nodes]
        winv = np.array([1.0, 1.0, 0.5])
        CW = C * winv
        M = np.einsum("nij,nkj->nik", CW, C)
        lam = np.einsum(
            "nij,nj->ni", np.linalg.pinv(M, rcond=1e-10), np.einsum("nij,nj->ni", C, v) - d
        )
        out = est.copy()
        out[nodes] = v - np.einsum("nij,ni->nj", CW, lam)
        return out

    # -- the micro-structure correction ------------------------------------------------
    @property
    def needs_responses(self) -> bool:
        """True until the responses of every material are in."""
        return bool(self._pending)

    @property
    def pending(self) -> list[int]:
        """The materials whose responses are still to be set."""
        return sorted(self._pending)

    def uniform_states(self, material: int):
        """The model whose responses material ``material`` needs and its three uniform
        stress states: ``(model, [(f, values), ...])`` with the nodal forces (2N,) of
        the state's stress vector on every boundary edge and the prescribed values
        (2N,) of its displacement (read at the prescribed dofs)."""
        from .response import companion, uniform_states

        model = companion(self.model, material)
        return model, uniform_states(model, self.boundary)

    def set_responses(self, material: int, responses: np.ndarray) -> None:
        """Adopt the displacements (3, N, 2) of ``uniform_states(material)``."""
        from .response import companion, invert

        model = companion(self.model, material)
        est = self.estimate(model, np.asarray(responses))  # (3, N, 3)
        if self.correction is None:
            self.correction = np.broadcast_to(np.eye(3), (self.model.mesh.n_points, 3, 3)).copy()
        sel = self.node_mat == material
        inv, bad = invert(np.moveaxis(est[:, sel, :], 0, -1), CONDITION_LIMIT)
        self.correction[sel] = inv
        self.uncorrected += int(bad)
        self._pending.discard(material)
        if bad:
            log.warning(
                "stress recovery: %d node(s) with an ill-conditioned response kept their "
                "uncorrected estimate",
                bad,
            )

    def stress(self, u: np.ndarray, loads=()) -> np.ndarray:
        """The recovered stress (N, 2, 2) of a state u (N, 2) of this model."""
        est = self.estimate(self.model, u, body_forces(self.model, loads))
        if self.correction is not None:
            est = np.einsum("nij,nj->ni", self.correction, est)
        return as_tensors(est)


def nodal_data(model: VoronoiModel, u: np.ndarray, alpha=ALPHA) -> np.ndarray:
    """``alpha`` x virial + ``(1 - alpha)`` x strain-law stress per node (N, 3)
    (``alpha`` a number or one per node)."""
    mesh = model.mesh
    n = mesh.n_points
    area = model.geometry.dual_area
    t = model.linear_tension(u)
    g = model.geometry
    d = g.direction
    half = 0.5 * (t * g.length)[:, None] * np.c_[d[:, 0] ** 2, d[:, 1] ** 2, d[:, 0] * d[:, 1]]
    b = mesh.topology.bonds
    virial = np.empty((n, 3))
    strain = np.empty((n, 3))
    s_tri = triangle_stress(model, u)
    s_tri = np.c_[s_tri[:, 0, 0], s_tri[:, 1, 1], s_tri[:, 0, 1]] * (g.tri_area / 3.0)[:, None]
    for c in range(3):
        virial[:, c] = np.bincount(b[:, 0], half[:, c], n) + np.bincount(b[:, 1], half[:, c], n)
        strain[:, c] = sum(np.bincount(mesh.triangles[:, v], s_tri[:, c], n) for v in range(3))
    alpha = np.reshape(alpha, (-1, 1))
    return (alpha * virial / model.t + (1.0 - alpha) * strain) / area[:, None]


def node_material(model: VoronoiModel) -> np.ndarray:
    """Material index of every node: the one covering most of its triangles' area."""
    mesh = model.mesh
    n_mat = 1 + len(model.materials)
    if n_mat == 1:
        return np.zeros(mesh.n_points, dtype=np.int64)
    share = np.zeros((mesh.n_points, n_mat))
    for v in range(3):
        np.add.at(share, (mesh.triangles[:, v], model.material_of_triangle), mesh.triangle_areas)
    return np.argmax(share, axis=1)


def _edge_material(model: VoronoiModel) -> np.ndarray:
    """Material of the triangle of every boundary edge."""
    mesh = model.mesh
    bonds = mesh.topology.bonds
    n = mesh.n_points
    keys = bonds[:, 0] * n + bonds[:, 1]
    e = mesh.boundary_edges
    lo, hi = np.minimum(e[:, 0], e[:, 1]), np.maximum(e[:, 0], e[:, 1])
    order = np.argsort(keys)
    bond = order[np.searchsorted(keys[order], lo * n + hi)]
    return model.material_of_triangle[mesh.topology.bond_tris[bond, 0]]


def as_tensors(s: np.ndarray) -> np.ndarray:
    """(..., 3) ``(sxx, syy, sxy)`` as (..., 2, 2) tensors."""
    return np.stack(
        [np.stack([s[..., 0], s[..., 2]], -1), np.stack([s[..., 2], s[..., 1]], -1)], -2
    )
