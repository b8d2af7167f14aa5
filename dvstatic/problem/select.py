"""Selections of nodes and boundary edges by part name or index array."""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..mesh import Mesh

__all__ = ["At", "as_list", "nearest_node", "select_nodes", "select_edges", "where_ok", "label"]


log = logging.getLogger(__name__)


@dataclass(frozen=True)
class At:
    """Selects the mesh node nearest to the point ``(x, y)`` (length); it must lie
    within half the local spacing (the mean length of its bonds) of the point.
    ``Fix(at=(x, y))`` and ``PointLoad(at=(x, y), value=...)`` build one."""

    x: float
    y: float

    def __post_init__(self) -> None:
        for name in ("x", "y"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.number)):
                raise TypeError(f"At.{name} must be a number, got {type(v).__name__}")
            if not np.isfinite(v):
                raise InputError(f"At.{name} must be finite, got {v}", "at")


#: how far (in local spacings) a support's ``at=`` may be from the node it selects
SNAP_TOLERANCE = 0.5
#: the same for a point load (a force between two nodes goes to the nearer one)
LOAD_SNAP_TOLERANCE = 1.0


def nearest_node(mesh: Mesh, point, tolerance: float = SNAP_TOLERANCE) -> int:
    """Index of the node nearest to ``point``; :class:`InputError` if it is farther
    than ``tolerance`` local spacings (the mean length of that node's bonds; default
    half a spacing). A node more than a tenth of the spacing away is reported (a
    warning): a support moved off a symmetry line adds a rigid motion."""
    from ..mesh.locate import local_spacing

    p = np.asarray(point, dtype=float).reshape(2)
    if not np.all(np.isfinite(p)):
        raise InputError(f"at must be a finite point (x, y), got {p.tolist()}", "at")
    d = np.hypot(*(mesh.points - p).T)
    i = int(np.argmin(d))
    h = local_spacing(mesh, i)
    if d[i] > tolerance * h:
        raise InputError(
            f"no node at {p.tolist()}: the nearest, {mesh.points[i].tolist()}, is "
            f"{d[i]:.3g} away, more than {tolerance:g} x the local spacing ({h:.3g}); put "
            "a node there (a mesh whose boundary nodes include it) or choose a node",
            "at",
        )
    if d[i] > 0.1 * h:
        log.warning(
            "at=%s selects node %d at %s, %.3g away (%.0f %% of the local spacing)",
            p.tolist(),
            i,
            mesh.points[i].tolist(),
            d[i],
            100 * d[i] / h,
        )
    return i


def where_ok(where, name: str, nodes: bool = True) -> None:
    """Check a selection's type: a part name or an index array; ``At`` for node
    selections only (``nodes``)."""
    if isinstance(where, str) or (nodes and isinstance(where, At)):
        return
    if isinstance(where, At):
        raise TypeError(
            f"{name}: `where` must be a boundary part name or an array of boundary edges "
            "(At selects a node: use PointLoad for a force at a point)"
        )
    if isinstance(where, (np.ndarray, Sequence)) and not isinstance(where, (bytes, bytearray)):
        return
    raise TypeError(
        f"{name}: `where` must be a boundary part name, an index array or At(x, y), "
        f"got {type(where).__name__}"
    )


def as_list(items, cls_names: str) -> list:
    """Accept a single object, None or a sequence of objects (their types are checked
    where they are used)."""
    if items is None:
        return []
    if isinstance(items, (list, tuple)):
        return list(items)
    if isinstance(items, (str, bytes, np.ndarray, int, float, dict)):
        raise TypeError(f"expected {cls_names} or a list of them, got {type(items).__name__}")
    return [items]


def select_nodes(mesh: Mesh, where, what: str) -> np.ndarray:
    """Node indices (sorted, unique) from a part name or an index array."""
    if isinstance(where, str):
        return mesh.part_nodes(where)
    if isinstance(where, At):
        tol = LOAD_SNAP_TOLERANCE if what == "PointLoad" else SNAP_TOLERANCE
        return np.array([nearest_node(mesh, (where.x, where.y), tol)])
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


def label(where) -> str:
    """A short description of a selection for messages."""
    if isinstance(where, At):
        return f"the node at ({where.x:g}, {where.y:g})"
    return repr(where) if isinstance(where, str) else f"{len(np.asarray(where))} edges"
