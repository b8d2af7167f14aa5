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

from ._checks import check_real, check_vector2
from .errors import InputError
from .linalg import check_restrained
from .mesh import Mesh

__all__ = [
    "Fix",
    "Traction",
    "Pressure",
    "BodyForce",
    "PointLoad",
    "LOADS",
    "evaluate",
    "as_list",
    "select_nodes",
    "select_edges",
    "SupportComponent",
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
    if value is None or callable(value):
        return value
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        v = float(value)
        if not np.isfinite(v):
            raise InputError(f"Fix: {label} must be finite, got {value!r}", label)
        return v
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(
            f"Fix: {label} must be a number, an array of numbers, a callable or None"
        ) from None
    if arr.ndim != 1 or not np.all(np.isfinite(arr)):
        raise InputError(
            f"Fix: {label} must be a finite number or a 1-D array (one per node)", label
        )
    return arr


def _vector_or_callable(value, what: str):
    """A constant 2-vector as a tuple, or a callable kept as it is."""
    return value if callable(value) else tuple(check_vector2(what, value))


def evaluate(fn, points: np.ndarray, tail: tuple[int, ...], what: str) -> np.ndarray:
    """``fn(points)`` checked: a finite float array of shape ``(m,) + tail``.

    Raises
    ------
    InputError
        The callable returned another shape, or non-finite values.
    """
    m = len(points)
    try:
        out = np.asarray(fn(np.array(points, dtype=float)), dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(
            f"{what}: the callable failed on points of shape {(m, 2)}: {exc}", "value"
        ) from exc
    if out.shape != (m,) + tail:
        if tail == () and out.shape == ():
            out = np.full(m, float(out))
        elif tail == (2,) and out.shape == (2,):
            out = np.broadcast_to(out, (m, 2)).copy()
        else:
            raise InputError(
                f"{what}: the callable returned shape {out.shape} for {m} points; expected "
                f"{(m,) + tail}",
                "value",
            )
    if not np.all(np.isfinite(out)):
        raise InputError(f"{what}: the callable returned non-finite values", "value")
    return out


@dataclass(frozen=True, eq=False)
class Fix:
    """Prescribed displacement components on a set of nodes.

    Parameters
    ----------
    where : str or array_like of int
        Part name or node indices.
    x, y : float, array_like, callable or None
        Prescribed ``u_x`` / ``u_y`` (length units): one value, one value per
        selected node (in the order of ``where``: node ``where[i]`` gets value ``i``;
        for a part name, in the order of ``mesh.part_nodes(name)``), or a function of
        position ``g(x) -> (m,)`` for points ``x`` of shape (m, 2) (a prescribed
        displacement field); ``None`` leaves the component free. ``Fix(where)`` with
        neither given clamps both components to zero.
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
    value : (tx, ty) or callable
        Force per unit length (force / length; stress units for unit thickness), or
        a function of position ``t(x) -> (m, 2)``. Constant values are lumped half to
        each end node of every edge; functions are integrated with the linear shape
        functions of each edge and two Gauss points (exact resultant and moment for
        linearly varying tractions).
    """

    where: object
    value: object

    def __post_init__(self) -> None:
        _where_ok(self.where, "Traction")
        object.__setattr__(self, "value", _vector_or_callable(self.value, "Traction value"))


@dataclass(frozen=True, eq=False)
class Pressure:
    """Normal pressure on boundary edges; positive pushes into the body.

    Parameters
    ----------
    where : str or array_like of int, shape (m, 2)
        Part name or boundary edges.
    p : float or callable
        Pressure (force per unit length for unit thickness, i.e. stress units), or a
        function of position ``p(x) -> (m,)`` (e.g. hydrostatic). The force on an
        edge is ``-p n`` per unit length, ``n`` its outward normal, lumped with the
        edge's linear shape functions (exact resultant on any polygonal boundary).
    follower : bool
        Nonlinear solves: the pressure stays normal to the deformed edges and scales
        with their current length (its derivative enters the Newton tangent, which is
        then not symmetric). Linear solves use the reference edges either way.
    """

    where: object
    p: object
    follower: bool = False

    def __post_init__(self) -> None:
        _where_ok(self.where, "Pressure")
        if not callable(self.p):
            object.__setattr__(self, "p", check_real("Pressure p", self.p))
        if not isinstance(self.follower, (bool, np.bool_)):
            raise TypeError(f"Pressure follower must be True or False, got {self.follower!r}")
        object.__setattr__(self, "follower", bool(self.follower))


@dataclass(frozen=True, eq=False)
class BodyForce:
    """Force per unit area, e.g. ``BodyForce((0, -rho g))``.

    Parameters
    ----------
    value : (bx, by) or callable
        Constant, lumped to the nodes with one third of the area of each neighbouring
        triangle (the consistent lumping of P1 elements; the nodal forces sum to
        ``value * area``), or a function of position ``b(x) -> (m, 2)`` integrated
        over each triangle with the edge-midpoint rule (exact for linear variation).
    """

    value: object

    def __post_init__(self) -> None:
        object.__setattr__(self, "value", _vector_or_callable(self.value, "BodyForce value"))


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


LOADS = (Traction, Pressure, BodyForce, PointLoad)


def as_list(items, cls_names: str) -> list:
    """Accept a single object, None or a sequence of objects."""
    if items is None:
        return []
    if isinstance(items, (Fix, *LOADS)):
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
    """Boundary edges (m, 2) from a part name or an edge array, oriented
    counter-clockwise around the body (the body lies to the left of a -> b)."""
    if isinstance(where, str):
        return mesh.part_edges(where)
    arr = np.asarray(where)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InputError(f"{what}: edges must have shape (m, 2), got {arr.shape}", "where")
    if not np.issubdtype(arr.dtype, np.integer):
        raise TypeError(f"{what}: edge indices must be integers, got dtype {arr.dtype}")
    n = mesh.n_points
    be = mesh.boundary_edges
    arr = arr.astype(np.int64)
    fwd = be @ np.array([n, 1])
    key = arr @ np.array([n, 1])
    back = arr[:, ::-1] @ np.array([n, 1])
    ok_fwd, ok_back = np.isin(key, fwd), np.isin(back, fwd)
    if not np.all(ok_fwd | ok_back):
        bad = arr[~(ok_fwd | ok_back)][0]
        raise InputError(f"{what}: {bad.tolist()} is not a boundary edge of the mesh", "where")
    return np.where(ok_fwd[:, None], arr, arr[:, ::-1])


#: two-point Gauss rule on [0, 1]: abscissae and weights
_GAUSS_S = 0.5 + np.array([-0.5, 0.5]) / np.sqrt(3.0)
_GAUSS_W = np.array([0.5, 0.5])


def _edge_forces(mesh: Mesh, e: np.ndarray, density) -> tuple[np.ndarray, np.ndarray]:
    """Nodal forces of a force density along edges ``e``: ``density(x, n) -> (k, 2)``
    evaluated at two Gauss points of every edge (``n``: outward unit normals), lumped
    with the edges' linear shape functions."""
    xa, xb = mesh.points[e[:, 0]], mesh.points[e[:, 1]]
    d = xb - xa
    length = np.hypot(d[:, 0], d[:, 1])
    normal = np.c_[d[:, 1], -d[:, 0]] / length[:, None]
    m = len(e)
    xq = (xa[None] + _GAUSS_S[:, None, None] * d[None]).reshape(-1, 2)
    tq = density(xq, np.tile(normal, (2, 1))).reshape(2, m, 2)
    fa = np.einsum("q,q,qmc->mc", _GAUSS_W, 1.0 - _GAUSS_S, tq) * length[:, None]
    fb = np.einsum("q,q,qmc->mc", _GAUSS_W, _GAUSS_S, tq) * length[:, None]
    return np.concatenate([e[:, 0], e[:, 1]]), np.concatenate([fa, fb])


def _load_terms(mesh: Mesh, load):
    """Nodal contributions of one load: node indices (k,) and forces (k, 2)."""
    if isinstance(load, Traction):
        e = select_edges(mesh, load.where, "Traction")
        if callable(load.value):
            what = f"Traction on {_label(load.where)}"
            return _edge_forces(mesh, e, lambda x, n: evaluate(load.value, x, (2,), what))
        d = mesh.points[e[:, 1]] - mesh.points[e[:, 0]]
        half = 0.5 * np.hypot(d[:, 0], d[:, 1])
        nodes = np.concatenate([e[:, 0], e[:, 1]])
        return nodes, np.concatenate([half, half])[:, None] * np.asarray(load.value)[None, :]
    if isinstance(load, Pressure):
        e = select_edges(mesh, load.where, "Pressure")
        what = f"Pressure on {_label(load.where)}"
        if callable(load.p):
            return _edge_forces(mesh, e, lambda x, n: -evaluate(load.p, x, (), what)[:, None] * n)
        return _edge_forces(mesh, e, lambda x, n: -load.p * n)
    if isinstance(load, BodyForce):
        return _body_terms(mesh, load)
    if isinstance(load, PointLoad):
        nodes = select_nodes(mesh, load.nodes, "PointLoad")
        return nodes, np.broadcast_to(np.asarray(load.value), (nodes.size, 2))
    if isinstance(load, Fix):
        raise TypeError("Fix is a support: pass it in `supports`, not in `loads`")
    raise TypeError(
        f"unknown load type {type(load).__name__}; use Traction, Pressure, BodyForce or PointLoad"
    )


def _body_terms(mesh: Mesh, load: BodyForce):
    """Constant: a third of every triangle to each vertex; a function: the edge-midpoint
    rule with the linear shape functions (exact for linear variation)."""
    tri = mesh.triangles
    area = mesh.triangle_areas
    if not callable(load.value):
        share = np.repeat(area / 3.0, 3)
        return tri.ravel(), share[:, None] * np.asarray(load.value)[None, :]
    x = mesh.triangle_coordinates()
    mid = 0.5 * (x[:, [1, 2, 0]] + x[:, [2, 0, 1]])  # midpoint of the edge opposite vertex k
    b = evaluate(load.value, mid.reshape(-1, 2), (2,), "BodyForce").reshape(-1, 3, 2)
    # vertex v gets A/6 (b at the midpoints of its two edges)
    f = (area / 6.0)[:, None, None] * (b.sum(axis=1, keepdims=True) - b)
    return tri.ravel(), f.reshape(-1, 2)


def _label(where) -> str:
    return repr(where) if isinstance(where, str) else f"{len(np.asarray(where))} edges"


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


@dataclass(frozen=True, eq=False)
class SupportComponent:
    """One prescribed displacement component of a :class:`Fix`.

    Attributes
    ----------
    where : str or ndarray
        The Fix's selection.
    component : int
        0 (x) or 1 (y).
    nodes : ndarray of int
        The selected nodes (sorted).
    value : float or ndarray
        One value, or one per node of ``nodes`` (a field evaluated at the nodes).
    field : callable or None
        The prescribed function of position, if one was given.
    """

    where: object
    component: int
    nodes: np.ndarray
    value: object
    field: object = None


def support_components(mesh: Mesh, supports) -> list[SupportComponent]:
    """Every prescribed component of ``supports`` (:class:`SupportComponent`)."""
    out = []
    for s in as_list(supports, "Fix"):
        if not isinstance(s, Fix):
            raise TypeError(f"supports must be Fix objects, got {type(s).__name__}")
        nodes = select_nodes(mesh, s.where, "Fix")
        for comp, value in ((0, s.x), (1, s.y)):
            if value is None:
                continue
            field = value if callable(value) else None
            if field is not None:
                what = f"Fix on {_label(s.where)}: {'xy'[comp]}"
                value = evaluate(field, mesh.points[nodes], (), what)
            elif np.ndim(value) != 0:
                value = _per_node(s.where, nodes, np.asarray(value, dtype=float), "xy"[comp])
            out.append(SupportComponent(s.where, comp, nodes, value, field))
    return out


def _per_node(where, nodes: np.ndarray, value: np.ndarray, label: str) -> np.ndarray:
    """Per-node values given in the order of ``where`` (a node listed twice must get the
    same value), returned in the sorted order of ``nodes``."""
    given = nodes if isinstance(where, str) else np.asarray(where).reshape(-1)
    if value.shape != given.shape:
        raise InputError(f"Fix: {label} has {value.size} values for {given.size} nodes", label)
    if given is nodes:
        return value
    _, first, inv = np.unique(given, return_index=True, return_inverse=True)
    out = value[first]
    if np.any(out[inv] != value):
        k = int(np.flatnonzero(out[inv] != value)[0])
        raise InputError(
            f"Fix: node {int(given[k])} is listed twice with different {label} values "
            f"({out[inv][k]} and {value[k]})",
            label,
        )
    return out


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
    for c in support_components(mesh, supports):
        dof_list.append(2 * c.nodes + c.component)
        val_list.append(np.broadcast_to(np.asarray(c.value, dtype=float), c.nodes.shape))
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
