"""Supports and loads: :class:`Fix`, :class:`Traction`, :class:`BodyForce`, :class:`PointLoad`.

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
from .mesh import Mesh

__all__ = ["Fix", "Traction", "BodyForce", "PointLoad", "load_vector", "constraints", "as_list"]


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
            raise ValueError(f"Fix: {label} must be finite, got {value!r}")
        return v
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"Fix: {label} must be a number, an array of numbers or None") from None
    if arr.ndim != 1 or not np.all(np.isfinite(arr)):
        raise ValueError(f"Fix: {label} must be a finite number or a 1-D array (one per node)")
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
    """Node indices from a part name or an index array."""
    if isinstance(where, str):
        return mesh.part_nodes(where)
    arr = np.asarray(where)
    if arr.size == 0:
        raise ValueError(f"{what}: the node selection is empty")
    if not np.issubdtype(arr.dtype, np.integer):
        raise TypeError(f"{what}: node indices must be integers, got dtype {arr.dtype}")
    if arr.ndim != 1:
        raise ValueError(f"{what}: node indices must be a 1-D array, got shape {arr.shape}")
    if arr.min() < 0 or arr.max() >= mesh.n_points:
        raise ValueError(
            f"{what}: node indices must lie in [0, {mesh.n_points}), got [{arr.min()}, {arr.max()}]"
        )
    return np.unique(arr.astype(np.int64))


def select_edges(mesh: Mesh, where, what: str) -> np.ndarray:
    """Boundary edges (m, 2) from a part name or an edge array."""
    if isinstance(where, str):
        return mesh.part_edges(where)
    arr = np.asarray(where)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ValueError(f"{what}: edges must have shape (m, 2), got {arr.shape}")
    if not np.issubdtype(arr.dtype, np.integer):
        raise TypeError(f"{what}: edge indices must be integers, got dtype {arr.dtype}")
    n = mesh.n_points
    be = mesh.boundary_edges
    keys = np.sort(be, axis=1) @ np.array([n, 1])
    want = np.sort(arr.astype(np.int64), axis=1) @ np.array([n, 1])
    if not np.all(np.isin(want, keys)):
        bad = arr[~np.isin(want, keys)][0]
        raise ValueError(f"{what}: {bad.tolist()} is not a boundary edge of the mesh")
    return arr.astype(np.int64)


def load_vector(mesh: Mesh, loads, scale: float = 1.0) -> np.ndarray:
    """External nodal forces, interleaved, shape (2N,).

    Parameters
    ----------
    mesh : Mesh
    loads : Traction, BodyForce, PointLoad or a list of them
    scale : float
        Load factor applied to all loads.
    """
    n = mesh.n_points
    f = np.zeros((n, 2))
    for load in as_list(loads, "Traction, BodyForce or PointLoad"):
        if isinstance(load, Traction):
            e = select_edges(mesh, load.where, "Traction")
            d = mesh.points[e[:, 1]] - mesh.points[e[:, 0]]
            half = 0.5 * np.hypot(d[:, 0], d[:, 1])
            for c in range(2):
                f[:, c] += load.value[c] * (
                    np.bincount(e[:, 0], half, n) + np.bincount(e[:, 1], half, n)
                )
        elif isinstance(load, BodyForce):
            share = np.repeat(mesh.triangle_areas / 3.0, 3)
            w = np.bincount(mesh.triangles.ravel(), share, n)
            f += w[:, None] * np.asarray(load.value)[None, :]
        elif isinstance(load, PointLoad):
            nodes = select_nodes(mesh, load.nodes, "PointLoad")
            f[nodes] += np.asarray(load.value)[None, :]
        elif isinstance(load, Fix):
            raise TypeError("Fix is a support: pass it in `supports`, not in `loads`")
        else:
            raise TypeError(
                f"unknown load type {type(load).__name__}; use Traction, BodyForce or PointLoad"
            )
    return scale * f.reshape(-1)


def constraints(mesh: Mesh, supports) -> tuple[np.ndarray, np.ndarray]:
    """Constrained dofs and their prescribed values.

    Returns
    -------
    dofs : ndarray of int, shape (k,), sorted
    values : ndarray, shape (k,) (length units)

    Raises
    ------
    ValueError
        If the same dof is prescribed twice with different values.
    """
    dof_list, val_list = [], []
    for s in as_list(supports, "Fix"):
        if not isinstance(s, Fix):
            raise TypeError(f"supports must be Fix objects, got {type(s).__name__}")
        nodes = select_nodes(mesh, s.where, "Fix")
        for comp, value in ((0, s.x), (1, s.y)):
            if value is None:
                continue
            v = np.broadcast_to(value, nodes.shape) if np.ndim(value) == 0 else np.asarray(value)
            if v.shape != nodes.shape:
                raise ValueError(f"Fix: {'xy'[comp]} has {v.size} values for {nodes.size} nodes")
            dof_list.append(2 * nodes + comp)
            val_list.append(np.asarray(v, dtype=float))
    if not dof_list:
        return np.zeros(0, np.int64), np.zeros(0)
    dofs = np.concatenate(dof_list)
    vals = np.concatenate(val_list)
    order = np.argsort(dofs, kind="stable")
    dofs, vals = dofs[order], vals[order]
    same = dofs[1:] == dofs[:-1]
    if np.any(same & (vals[1:] != vals[:-1])):
        k = int(np.flatnonzero(same & (vals[1:] != vals[:-1]))[0])
        raise ValueError(
            f"conflicting supports: dof {dofs[k]} (node {dofs[k] // 2}, "
            f"{'xy'[dofs[k] % 2]}) is prescribed as {vals[k]} and {vals[k + 1]}"
        )
    keep = np.concatenate([[True], ~same])
    return dofs[keep], vals[keep]
