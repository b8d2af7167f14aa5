"""Tabulated relaxed moduli of the built-in generators' micro-structures.

``relaxed_table.json`` (next to this module) holds, for DV and RV and every tabulated
recipe (regular lattice, jittered lattices at several jitters, random points, CVT),
the relaxed ``nu_eff`` and ``E_eff`` (at ``k_n = 1``) on a grid of ``nu_m``, measured
on large periodic samples with the stabilised coupling. It is made by
``validation/calibration_table.py``; :func:`curve` interpolates it (monotone cubic in
``nu_m``, cubic in the jitter).
"""

from __future__ import annotations

import json
from functools import cache
from importlib import resources

import numpy as np

from ..._cache import Bounded
from ...mesh.recipe import Sampling
from ..stabilise import MARGIN

__all__ = ["TABLE_FILE", "WEIGHTINGS", "load", "curve", "TableCurve"]

TABLE_FILE = "relaxed_table.json"
#: spring weightings of the samples in the table: uniform springs (the "surface" and
#: "uniform" schemes) and fabric-corrected ones (the "fabric" scheme; point-set recipes)
WEIGHTINGS = ("uniform", "fabric")
#: interpolated curves by (model, recipe)
_CURVES = Bounded("calibration table curves", maxsize=64)


@cache
def load() -> dict | None:
    """The table (parsed once), or None if the package has none."""
    try:
        text = resources.files(__package__).joinpath(TABLE_FILE).read_text()
    except FileNotFoundError:
        return None
    data = json.loads(text)
    if data.get("margin") != MARGIN:
        return None  # made for another stabilisation: not valid
    return data


class TableCurve:
    """``nu_eff(nu_m)`` and ``E_eff(nu_m)`` interpolated from the table.

    Attributes
    ----------
    nu_range : (float, float)
        The range of nu_eff over the tabulated nu_m.
    """

    def __init__(self, nu_m: np.ndarray, nu: np.ndarray, E: np.ndarray, what: str, data: dict):
        from scipy.interpolate import PchipInterpolator

        self._nu = PchipInterpolator(nu_m, nu)
        self._E = PchipInterpolator(nu_m, E)
        self.nu_m_span = (float(nu_m[0]), float(nu_m[-1]))
        self.nu_range = (float(np.min(nu)), float(np.max(nu)))
        self.what = what
        self.points = int(data["sample_points"])
        self.seeds = len(data["seeds"])

    def __call__(self, nu_m: float) -> tuple[float, float]:
        x = float(np.clip(nu_m, *self.nu_m_span))
        return float(self._nu(x)), float(self._E(x))

    def guess(self, nu: float) -> float:
        """nu_m of the tabulated point nearest to nu."""
        grid = np.linspace(*self.nu_m_span, 129)
        return float(grid[np.argmin(np.abs(self._nu(grid) - nu))])

    def describe(self) -> dict:
        return {
            "source": "table",
            "sample": self.what,
            "sample_points": self.points,
            "samples": self.seeds,
            "evaluations": 0,
            "factorisations": 0,
        }


def curve(kind: str, sampling: Sampling, weighting: str = "uniform") -> TableCurve | None:
    """The tabulated curve for ``kind`` ("DV" or "RV"), a generator recipe and a spring
    weighting (one of :data:`WEIGHTINGS`), or None when it is not in the table
    (perturbed meshes, other CVT iterations, jitter outside the tabulated range, fabric
    corrections of lattice recipes)."""
    if sampling.perturbations or weighting not in WEIGHTINGS:
        return None
    key = (kind, weighting, sampling.key)
    if key not in _CURVES:
        c = _curve(kind, weighting, sampling.kind, sampling.jitter, sampling.iterations)
        _CURVES.put(key, c)
    return _CURVES.get(key)


def _curve(
    kind: str, weighting: str, sampling_kind: str, jitter: float, iterations: int
) -> TableCurve | None:
    data = load()
    if data is None or kind not in data["curves"]:
        return None
    curves = data["curves"][kind]
    if weighting != "uniform":
        curves = curves.get(weighting, {})
    nu_m = np.asarray(data["nu_m"], dtype=float)
    what = str(Sampling(sampling_kind, jitter, iterations))
    if weighting != "uniform":
        what += f", {weighting}-corrected springs"
    if sampling_kind == "cvt" and iterations != data["cvt_iterations"]:
        return None
    if sampling_kind in ("lattice", "random", "cvt"):
        c = curves.get(sampling_kind)
        if c is None:
            return None
        return TableCurve(nu_m, np.asarray(c["nu"]), np.asarray(c["E"]), what, data)
    c = curves.get("jittered")
    if c is None:
        return None
    grid = np.asarray(c["jitter"], dtype=float)
    if not grid[0] <= jitter <= grid[-1]:
        return None
    from scipy.interpolate import CubicSpline

    nu = CubicSpline(grid, np.asarray(c["nu"]), axis=0)(jitter)
    E = CubicSpline(grid, np.asarray(c["E"]), axis=0)(jitter)
    return TableCurve(nu_m, nu, E, what, data)
