"""Loads and prescribed displacements times a factor (the states of a fracture run, a
load step): the same objects with every value scaled, functions of position included."""

from __future__ import annotations

import dataclasses

import numpy as np

from .loads import BodyForce, PointLoad, Pressure, Traction
from .supports import Fix

__all__ = ["scaled"]

#: the fields holding values, per class
_VALUES = {Traction: ("value",), Pressure: ("p",), BodyForce: ("value",), PointLoad: ("value",)}
_VALUES[Fix] = ("x", "y")


def _times(value, factor: float):
    if value is None:
        return None
    if callable(value):
        return _Scaled(value, factor)
    if isinstance(value, tuple):
        return tuple(factor * np.asarray(value, dtype=float))
    return factor * np.asarray(value, dtype=float) if np.ndim(value) else factor * float(value)


@dataclasses.dataclass(frozen=True)
class _Scaled:
    """A function of position times a factor."""

    f: object
    factor: float

    def __call__(self, x):
        return self.factor * np.asarray(self.f(x), dtype=float)


def scaled(items, factor: float) -> list:
    """``items`` (supports or loads, one or a list) with every value times ``factor``.

    Raises
    ------
    TypeError
        An item that is not a ``Fix``, ``Traction``, ``Pressure``, ``BodyForce`` or
        ``PointLoad``.
    """
    if items is None:
        return []
    items = items if isinstance(items, (list, tuple)) else [items]
    out = []
    for item in items:
        names = _VALUES.get(type(item))
        if names is None:
            raise TypeError(f"cannot scale a {type(item).__name__}")
        changes = {n: _times(getattr(item, n), factor) for n in names}
        if hasattr(item, "at"):  # `where`/`nodes` already hold the point (an At)
            changes["at"] = None
        out.append(dataclasses.replace(item, **changes))
    return out
