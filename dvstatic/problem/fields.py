"""Values given as functions of position: evaluated and checked."""

from __future__ import annotations

import numpy as np

from .._checks import check_vector2
from ..errors import InputError

__all__ = ["evaluate", "vector_or_callable"]


def vector_or_callable(value, what: str):
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
