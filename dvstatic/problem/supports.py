"""Supports: :class:`Fix` (prescribed displacement components, values or fields) and
the constrained dofs they give."""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..linalg import check_restrained
from ..mesh import Mesh
from .fields import evaluate
from .select import At, as_list, label, select_nodes, where_ok

__all__ = ["Fix", "SupportComponent", "support_components", "constraints", "check_restrained"]


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


@dataclass(frozen=True, eq=False)
class Fix:
    """Prescribed displacement components on a set of nodes.

    Parameters
    ----------
    where : str, array_like of int or At
        Part name, node indices, or :class:`At` (the node nearest to a point).
    x, y : float, array_like, callable or None
        Prescribed ``u_x`` / ``u_y`` (length units): one value, one value per
        selected node (in the order of ``where``: node ``where[i]`` gets value ``i``;
        for a part name, in the order of ``mesh.part_nodes(name)``), or a function of
        position ``g(x) -> (m,)`` for points ``x`` of shape (m, 2) (a prescribed
        displacement field); ``None`` leaves the component free. ``Fix(where)`` with
        neither given clamps both components to zero.
    at : (x, y), optional
        Instead of ``where``: the node nearest to this point (length), which must lie
        within the local spacing of it (``Fix(at=(1.0, 0.0), y=0.0)``).
    """

    where: object = None
    x: object = None
    y: object = None
    at: object = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "where", _at_where(self.where, self.at, "Fix"))
        where_ok(self.where, "Fix")
        x, y = _component(self.x, "x"), _component(self.y, "y")
        if x is None and y is None:
            x, y = 0.0, 0.0
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "y", y)


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
                what = f"Fix on {label(s.where)}: {'xy'[comp]}"
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


def _at_where(where, at, name: str, key: str = "where"):
    """``where``, or ``At(*at)`` when only ``at`` is given (exactly one is needed)."""
    if at is None:
        if where is None:
            raise TypeError(f"{name}: give `{key}` (a part, node indices) or `at=(x, y)`")
        return where
    if where is not None:
        raise TypeError(f"{name}: give `{key}` or `at`, not both")
    try:
        a = np.asarray(at, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name}: at must be a point (x, y) of numbers, got {at!r}") from None
    if a.shape != (2,):
        raise InputError(f"{name}: at must be a point (x, y), got shape {a.shape}", "at")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name}: at must be finite, got {a.tolist()}", "at")
    return At(float(a[0]), float(a[1]))
