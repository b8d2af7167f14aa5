"""The problem: supports and loads (:class:`Fix`, :class:`Traction`, :class:`BodyForce`,
:class:`PointLoad`), the constrained dofs and the load vector (layer 3).

``where`` selects nodes or boundary edges: a part name of the mesh (``"left"``,
``"right"``, ``"bottom"``, ``"top"`` for rectangles), an index array of nodes
(:class:`Fix`, :class:`PointLoad`), or an (m, 2) array of boundary edges
(:class:`Traction`). All loads are dead loads given per unit thickness.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ._checks import check_vector2
from .errors import InputError
from .linalg import check_restrained
from .mesh import Mesh

__all__ = [
    "Fix",
    "Traction",
    "BodyForce",
    "PointLoad",
    "as_list",
    "select_nodes",
    "select_edges",
    "support_components",
    "constraints",
    "check_restrained",
    "load_vector",
    "nodal_forces",
]


def _where_ok(where, name: str) -> None:
    if isinstance(where, str):
        return
    if isinstance(where, (np.ndarray, Sequence)) and not isinstance(where, (bytes, bytearray)):
        return
    raise TypeError(
        f"{name}: `where` must be a boundary part name or an index array, "
        f"got {type(where).__name__}"
    )


def _component(value, label: str):
    if value is None:
        return None
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        v = float(value)
        if not np.isfinite(v):
            raise InputError(f"Fix: {label} must be finite, got {value!r}", label)
        return v
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"Fix: {label} must be a number, an array of numbers or None") from None
    if arr.ndim != 1 or not np.all(np.isfinite(arr)):
        raise InputError(
            f"Fix: {label} must be a finite number or a 1-D array (one per node)", label
        )
    return arr


@dataclass(frozen=True, eq=False)
class Fix:
    """Prescribed displacement components on a set of nodes.

    Parameters
    ----------
    where : str or array_like of int
        Part name or node indices.
    x, y : float, array_like or None
        Prescribed ``u_x`` / ``u_y`` (length units; one value or one per selected
        node); ``None`` leaves the component free. ``Fix(where)`` with neither
        given clamps both components to zero.
    """

    where: object
    x: object = None
    y: object = None

    def __post_init__(self) -> None:
        _where_ok(self.where, "Fix")
        x, y = _component(self.x, "x"), _component(self.y, "y")
        if x is None and y is None:
            x, y = 0.0, 0.0
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "y", y)


@dataclass(frozen=True, eq=False)
class Traction:
    """Distributed force per unit boundary length on boundary edges.

    Parameters
    ----------
    where : str or array_like of int, shape (m, 2)
        Part name or boundary edges.
    value : (tx, ty)
        Force per unit length (force / length; stress units for unit thickness),
        constant along the edges and lumped half to each end node of every edge
        (exact for the resultant and the moment about each edge's midpoint).
    """

    where: object
    value: tuple[float, float]

    def __post_init__(self) -> None:
        _where_ok(self.where, "Traction")
        object.__setattr__(self, "value", tuple(check_vector2("Traction value", self.value)))


@dataclass(frozen=True, eq=False)
class BodyForce:
    """Force per unit area, e.g. ``BodyForce((0, -rho g))``.

    Lumped to the nodes with one third of the area of each neighbouring triangle
    (the consistent lumping of P1 elements; the nodal forces sum to ``value * area``).
    """

    value: tuple[float, float]

    def __post_init__(self) -> None:
        object.__setattr__(self, "value", tuple(check_vector2("BodyForce value", self.value)))


@dataclass(frozen=True, eq=False)
class PointLoad:
    """Concentrated force ``value`` applied to each of the selected nodes.

    Parameters
    ----------
    nodes : str or array_like of int
        Part name or node indices (every node receives the full ``value``).
    value : (fx, fy)
        Force per node (force per unit thickness).
    """

    nodes: object
    value: tuple[float, float]

    def __post_init__(self) -> None:
        _where_ok(self.nodes, "PointLoad")
        object.__setattr__(self, "value", tuple(check_vector2("PointLoad value", self.value)))


def as_list(items, cls_names: str) -> list:
    """Accept a single object, None or a sequence of objects."""
    if items is None:
        return []
    if isinstance(items, (Fix, Traction, BodyForce, PointLoad)):
        return [items]
    if isinstance(items, (list, tuple)):
        return list(items)
    raise TypeError(f"expected {cls_names} or a list of them, got {type(items).__name__}")


def select_nodes(mesh: Mesh, where, what: str) -> np.ndarray:
    """Node indices (sorted, unique) from a part name or an index array."""
    if isinstance(where, str):
        return mesh.part_nodes(where)
    arr = np.asarray(where)
    if arr.size == 0:
        raise InputError(f"{what}: the node selection is empty", "where")
    if not np.issubdtype(arr.dtype, np.integer):
        raise TypeError(f"{what}: node indices must be integers, got dtype {arr.dtype}")
    if arr.ndim != 1:
        raise InputError(
            f"{what}: node indices must be a 1-D array, got shape {arr.shape}", "where"
        )
    if arr.min() < 0 or arr.max() >= mesh.n_points:
        raise InputError(
            f"{what}: node indices must lie in [0, {mesh.n_points}), "
            f"got [{arr.min()}, {arr.max()}]",
            "where",
        )
    return np.unique(arr.astype(np.int64))


def select_edges(mesh: Mesh, where, what: str) -> np.ndarray:
    """Boundary edges (m, 2) from a part name or an edge array."""
    if isinstance(where, str):
        return mesh.part_edges(where)
    arr = np.asarray(where)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InputError(f"{what}: edges must have shape (m, 2), got {arr.shape}", "where")
    if not np.issubdtype(arr.dtype, np.integer):
        raise TypeError(f"{what}: edge indices must be integers, got dtype {arr.dtype}")
    n = mesh.n_points
    be = mesh.boundary_edges
    keys = np.sort(be, axis=1) @ np.array([n, 1])
    want = np.sort(arr.astype(np.int64), axis=1) @ np.array([n, 1])
    if not np.all(np.isin(want, keys)):
        bad = arr[~np.isin(want, keys)][0]
        raise InputError(f"{what}: {bad.tolist()} is not a boundary edge of the mesh", "where")
    return arr.astype(np.int64)


def _load_terms(mesh: Mesh, load):
    """Nodal contributions of one load: node indices (k,) and forces (k, 2)."""
    if isinstance(load, Traction):
        e = select_edges(mesh, load.where, "Traction")
        d = mesh.points[e[:, 1]] - mesh.points[e[:, 0]]
        half = 0.5 * np.hypot(d[:, 0], d[:, 1])
        nodes = np.concatenate([e[:, 0], e[:, 1]])
        return nodes, np.concatenate([half, half])[:, None] * np.asarray(load.value)[None, :]
    if isinstance(load, BodyForce):
        share = np.repeat(mesh.triangle_areas / 3.0, 3)
        return mesh.triangles.ravel(), share[:, None] * np.asarray(load.value)[None, :]
    if isinstance(load, PointLoad):
        nodes = select_nodes(mesh, load.nodes, "PointLoad")
        return nodes, np.broadcast_to(np.asarray(load.value), (nodes.size, 2))
    if isinstance(load, Fix):
        raise TypeError("Fix is a support: pass it in `supports`, not in `loads`")
    raise TypeError(
        f"unknown load type {type(load).__name__}; use Traction, BodyForce or PointLoad"
    )


def nodal_forces(mesh: Mesh, loads, nodes: np.ndarray | None = None) -> np.ndarray:
    """External forces on ``nodes`` (all nodes if None), interleaved, shape (2 len(nodes),).

    Tractions are lumped half to each end node of every edge (exact for the resultant
    and the moment about each edge's midpoint); body forces with one third of the area
    of each neighbouring triangle (the consistent lumping of P1 elements); point loads
    go to their nodes. The distributed engine asks for its own nodes only.
    """
    n = mesh.n_points
    if nodes is None:
        local = np.arange(n)
        m = n
    else:
        local = np.full(n, -1, dtype=np.int64)
        local[nodes] = np.arange(len(nodes))
        m = len(nodes)
    f = np.zeros((m, 2))
    for load in as_list(loads, "Traction, BodyForce or PointLoad"):
        where, values = _load_terms(mesh, load)
        k = local[where]
        keep = k >= 0
        for c in range(2):
            f[:, c] += np.bincount(k[keep], values[keep, c], m)
    return f.reshape(-1)


def load_vector(mesh: Mesh, loads, scale: float = 1.0) -> np.ndarray:
    """External nodal forces, interleaved, shape (2N,).

    Parameters
    ----------
    mesh : Mesh
    loads : Traction, BodyForce, PointLoad or a list of them
    scale : float
        Load factor applied to all loads.
    """
    return scale * nodal_forces(mesh, loads)


def support_components(mesh: Mesh, supports) -> list[tuple[object, int, np.ndarray, object]]:
    """Every prescribed component: ``(where, component, nodes, value)``.

    ``component`` is 0 (x) or 1 (y); ``nodes`` the selected node indices; ``value`` a
    float or an array with one value per node (checked against ``nodes``).
    """
    out = []
    for s in as_list(supports, "Fix"):
        if not isinstance(s, Fix):
            raise TypeError(f"supports must be Fix objects, got {type(s).__name__}")
        nodes = select_nodes(mesh, s.where, "Fix")
        for comp, value in ((0, s.x), (1, s.y)):
            if value is None:
                continue
            if np.ndim(value) != 0:
                value = _per_node(s.where, nodes, np.asarray(value, dtype=float), "xy"[comp])
            out.append((s.where, comp, nodes, value))
    return out


def _per_node(where, nodes: np.ndarray, value: np.ndarray, label: str) -> np.ndarray:
    """Per-node values given in the order of ``where``, in the (sorted) order of ``nodes``."""
    given = nodes if isinstance(where, str) else np.asarray(where).reshape(-1)
    if value.shape != given.shape:
        raise InputError(f"Fix: {label} has {value.size} values for {given.size} nodes", label)
    if given is nodes:
        return value
    _, first = np.unique(given, return_index=True)
    return value[first]


def constraints(mesh: Mesh, supports) -> tuple[np.ndarray, np.ndarray]:
    """Constrained dofs and their prescribed values.

    Returns
    -------
    dofs : ndarray of int, shape (k,), sorted
    values : ndarray, shape (k,) (length units)

    Raises
    ------
    InputError
        If the same dof is prescribed twice with different values.
    """
    dof_list, val_list = [], []
    for _, comp, nodes, value in support_components(mesh, supports):
        dof_list.append(2 * nodes + comp)
        val_list.append(np.broadcast_to(np.asarray(value, dtype=float), nodes.shape))
    if not dof_list:
        return np.zeros(0, np.int64), np.zeros(0)
    dofs = np.concatenate(dof_list)
    vals = np.concatenate(val_list)
    order = np.argsort(dofs, kind="stable")
    dofs, vals = dofs[order], vals[order]
    same = dofs[1:] == dofs[:-1]
    if np.any(same & (vals[1:] != vals[:-1])):
        k = int(np.flatnonzero(same & (vals[1:] != vals[:-1]))[0])
        raise InputError(
            f"conflicting supports: dof {dofs[k]} (node {dofs[k] // 2}, "
            f"{'xy'[dofs[k] % 2]}) is prescribed as {vals[k]} and {vals[k + 1]}",
            "supports",
        )
    keep = np.concatenate([[True], ~same])
    return dofs[keep], vals[keep]
