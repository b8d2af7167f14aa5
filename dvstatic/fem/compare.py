"""Differences between displacement fields: :func:`compare` and its
:class:`Comparison`."""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

log = logging.getLogger(__name__)

__all__ = ["Comparison", "compare"]


@dataclass(frozen=True)
class Comparison:
    """Difference between two displacement fields on the same nodes.

    Attributes
    ----------
    l2 : float
        ``|u_a - u_b| / |u_b|`` over all nodes (discrete l2).
    max : float
        ``max_i |u_a,i - u_b,i| / max_i |u_b,i|`` (nodal vector magnitudes).
    diff : ndarray, shape (N, 2)
        ``u_a - u_b`` (less the rigid motion where ``rigid`` is set).
    rigid : tuple of float or None
        The rigid motion taken out of the difference with ``compare(..., rigid=True)``:
        translation ``(tx, ty)`` (length) and rotation (radians, small) about the
        centroid of the nodes; None when nothing was taken out.
    """

    l2: float
    max: float
    diff: np.ndarray
    rigid: tuple[float, float, float] | None = None


def compare(a, b, rigid: bool = False) -> Comparison:
    """Relative L2 and max displacement errors of ``a`` against the reference ``b``.

    ``a`` and ``b`` are solutions (anything with ``.u``) or (N, 2) arrays on the same
    nodes. With ``rigid``, the rigid motion that fits the difference best (least
    squares) is taken out first and reported (``Comparison.rigid``, and a log line):
    a body held at points only floats on the lattice's fluctuations at those points,
    which moves it rigidly without straining it.
    """
    nonlinear = [bool(getattr(getattr(x, "info", None), "nonlinear", False)) for x in (a, b)]
    linear_fe = [hasattr(x, "fe_mesh") for x in (a, b)]  # FE solutions are linear
    if (nonlinear[0] and linear_fe[1]) or (nonlinear[1] and linear_fe[0]):
        raise InputError(
            "compare: a nonlinear (large-deformation) solution against the linear FE "
            "reference: their difference is the nonlinearity, not an error; compare with "
            "a nonlinear reference, or pass the arrays (.u) to compare anyway",
            "b",
        )
    ua = np.asarray(getattr(a, "u", a), dtype=float)
    ub = np.asarray(getattr(b, "u", b), dtype=float)
    if ua.shape != ub.shape or ua.ndim != 2 or ua.shape[1] != 2:
        raise InputError(
            f"compare needs two (N, 2) fields on the same nodes, got {ua.shape} and {ub.shape}",
            "b",
        )
    d = ua - ub
    motion = None
    if rigid:
        pts = None
        for obj in (getattr(a, "model", None), a, getattr(b, "model", None), b):
            pts = getattr(getattr(obj, "mesh", None), "points", None)
            if pts is not None:
                break
        if pts is None or len(pts) != len(d):
            raise InputError("compare(rigid=True) needs a solution (its nodes)", "a")
        d, motion = _without_rigid(np.asarray(pts, dtype=float), d)
        log.info(
            "compare: rigid motion taken out: translation (%.4g, %.4g), rotation %.4g rad",
            *motion,
        )
    nb = float(np.linalg.norm(ub))
    mb = float(np.max(np.hypot(ub[:, 0], ub[:, 1])))
    if nb == 0:
        raise InputError("the reference field is zero: relative errors are undefined", "b")
    return Comparison(
        float(np.linalg.norm(d) / nb), float(np.max(np.hypot(d[:, 0], d[:, 1])) / mb), d, motion
    )


def _without_rigid(points: np.ndarray, d: np.ndarray):
    """``d`` less its least-squares rigid motion (translation, rotation about the
    centroid), and that motion."""
    x = points - points.mean(axis=0)
    A = np.zeros((2 * len(x), 3))
    A[0::2, 0] = 1.0
    A[1::2, 1] = 1.0
    A[0::2, 2] = -x[:, 1]
    A[1::2, 2] = x[:, 0]
    c = np.linalg.lstsq(A, d.reshape(-1), rcond=None)[0]
    return d - (A @ c).reshape(-1, 2), (float(c[0]), float(c[1]), float(c[2]))
