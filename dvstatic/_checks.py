"""Argument checks shared by the public functions (clear errors at the boundary)."""

from __future__ import annotations

import numbers

import numpy as np

from .errors import InputError


def check_real(name: str, value) -> float:
    """A finite real number (bool is refused)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__} {value!r}")
    v = float(value)
    if not np.isfinite(v):
        raise InputError(f"{name} must be finite, got {value!r}", name)
    return v


def check_positive(name: str, value, allow_zero: bool = False) -> float:
    """A finite number > 0 (or >= 0)."""
    v = check_real(name, value)
    if v < 0 or (v == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise InputError(f"{name} must be {bound}, got {value!r}", name)
    return v


def check_int(name: str, value, minimum: int | None = None, maximum: int | None = None) -> int:
    """An integer within [minimum, maximum]."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an integer, got {type(value).__name__} {value!r}")
    v = int(value)
    if minimum is not None and v < minimum:
        raise InputError(f"{name} must be >= {minimum}, got {v}", name)
    if maximum is not None and v > maximum:
        raise InputError(f"{name} must be <= {maximum}, got {v}", name)
    return v


def check_seed(seed) -> int | None:
    """A random seed: None or a non-negative integer."""
    if seed is None:
        return None
    return check_int("seed", seed, minimum=0)


def check_choice(name: str, value, choices, param: str | None = None) -> str:
    """One of a fixed set of strings (``param``: the argument name, default ``name``)."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a string, one of {tuple(choices)}, got {value!r}")
    if value not in choices:
        raise InputError(
            f"unknown {name} {value!r}; accepted: {', '.join(map(str, choices))}", param or name
        )
    return value


def check_vector2(name: str, value) -> np.ndarray:
    """Two finite numbers, returned as a float array of shape (2,)."""
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be two numbers (x, y), got {value!r}") from None
    if v.shape != (2,):
        raise InputError(f"{name} must be two numbers (x, y), got shape {v.shape}", name)
    if not np.all(np.isfinite(v)):
        raise InputError(f"{name} must be finite, got {value!r}", name)
    return v


def as_displacement(u, n: int, name: str = "u") -> np.ndarray:
    """Displacement as an (n, 2) float array; accepts (n, 2) or interleaved (2n,)."""
    try:
        a = np.asarray(u, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a numeric array of shape ({n}, 2) or ({2 * n},)") from None
    if a.shape == (2 * n,):
        a = a.reshape(n, 2)
    if a.shape != (n, 2):
        raise InputError(f"{name} must have shape ({n}, 2) or ({2 * n},), got {a.shape}", name)
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name} contains non-finite values", name)
    return a


def as_strain(eps, name: str = "eps") -> np.ndarray:
    """A 2x2 strain matrix (finite); symmetric part is not enforced."""
    try:
        e = np.asarray(eps, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a 2x2 numeric matrix") from None
    if e.shape != (2, 2):
        raise InputError(f"{name} must have shape (2, 2), got {e.shape}", name)
    if not np.all(np.isfinite(e)):
        raise InputError(f"{name} must be finite", name)
    return e
