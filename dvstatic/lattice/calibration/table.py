"""Tabulated relaxed moduli of the built-in generators' micro-structures.

``relaxed_table.json`` (next to this module) holds, for DV and RV and every tabulated
recipe (regular lattice, jittered lattices at several jitters, random points, CVT),
the relaxed ``nu_eff`` and ``E_eff`` (at ``k_n = 1``) on a grid of ``nu_m``, measured
on large periodic samples with the stabilised coupling. It is made by
``validation/calibration_table.py``; :func:`curve` interpolates it (monotone cubic in
``nu_m``, cubic in the jitter).

It also holds the *CVT family* (``calibration_table.py --cvt-family``): random points
Lloyd-relaxed 0 to 480 times, from local spread 0.366 (random) down to 0.052, with
every member's local spread and defect fraction (interior nodes with other than six
neighbours: 0.71 down to 0.14), and the defect fractions of perturbed lattices (none up
to a local spread of 0.13). A mesh without recipe lies between the two families
(gmsh's graded meshes near the CVT one, its uniform meshes near the perturbed
lattices): :func:`family_weight` says where, :func:`family_curve` gives the CVT
family's curve at a local spread.
"""

from __future__ import annotations

import json
from functools import cache
from importlib import resources

import numpy as np

from ..._cache import Bounded
from ...mesh.recipe import Sampling
from ..stabilise import MARGIN

__all__ = [
    "TABLE_FILE",
    "WEIGHTINGS",
    "load",
    "curve",
    "FAMILY_GAP",
    "family_curve",
    "family_defects",
    "family_weight",
    "TableCurve",
]

TABLE_FILE = "relaxed_table.json"
#: spring weightings of the samples in the table: uniform springs (the "surface" and
#: "uniform" schemes) and fabric-corrected ones (the "fabric" scheme; point-set recipes)
WEIGHTINGS = ("uniform", "fabric")
#: below this difference of the two families' defect fractions the CVT weight tapers
#: to 0 (they meet at random points)
FAMILY_GAP = 0.05
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


def _family() -> dict | None:
    data = load()
    return None if data is None else data.get("cvt_family")


def family_curve(kind: str, spread: float, weighting: str = "uniform") -> TableCurve | None:
    """The CVT family's relaxed curve at local spread ``spread`` (linear in the spread
    between the two members around it; clamped to the family's range, 0.052 to
    0.366) for a spring weighting of :data:`WEIGHTINGS`, or None without it in the
    table."""
    fam = _family()
    curves = None if fam is None else fam if weighting == "uniform" else fam.get(weighting)
    if curves is None or kind not in curves:
        return None
    s = np.asarray(fam["spread"], dtype=float)
    order = np.argsort(s)
    s = s[order]
    nu = np.asarray(curves[kind]["nu"], dtype=float)[order]
    E = np.asarray(curves[kind]["E"], dtype=float)[order]
    x = float(np.clip(spread, s[0], s[-1]))
    j = int(np.clip(np.searchsorted(s, x), 1, len(s) - 1))
    t = (x - s[j - 1]) / (s[j] - s[j - 1])
    what = f"the CVT family at local spread {x:.3f}"
    if weighting != "uniform":
        what += f", {weighting}-corrected springs"
    nu_m = np.asarray(fam["nu_m"], dtype=float)
    nu_x, e_x = (1 - t) * nu[j - 1] + t * nu[j], (1 - t) * E[j - 1] + t * E[j]
    return TableCurve(nu_m, nu_x, e_x, what, fam)


def family_weight(spread: float, defects: float) -> float:
    """Where a micro-structure of local spread ``spread`` and defect fraction
    ``defects`` lies between the perturbed lattices (0) and the CVT family (1) of the
    same local spread: ``(d - d_perturbed(s)) / (d_cvt(s) - d_perturbed(s))``, clipped
    to [0, 1] and tapered linearly to 0 where the two families' defect fractions differ
    by less than :data:`FAMILY_GAP` (towards random points, where both meet); 0
    without the family in the table."""
    fam = _family()
    if fam is None:
        return 0.0

    def at(s, d) -> float:
        s, d = np.asarray(s, dtype=float), np.asarray(d, dtype=float)
        order = np.argsort(s)
        return float(np.interp(spread, s[order], d[order]))

    # the perturbed lattices end in random points (:func:`.relaxed.rev_for_spread`),
    # the CVT family's first member
    rnd = int(np.argmax(fam["spread"]))
    pert = fam["perturbed"]
    d_cvt = family_defects(spread)
    d_pert = at([*pert["spread"], fam["spread"][rnd]], [*pert["defects"], fam["defects"][rnd]])
    gap = d_cvt - d_pert
    if gap <= 0:
        return 0.0
    # tapered to 0 where the families meet (a gap below FAMILY_GAP), without a jump
    taper = min(gap / FAMILY_GAP, 1.0)
    return float(np.clip((defects - d_pert) / gap, 0.0, 1.0) * taper)


def family_defects(spread: float) -> float:
    """The CVT family's defect fraction at local spread ``spread`` (interpolated,
    clamped to the family's ends; NaN without the family in the table)."""
    fam = _family()
    if fam is None:
        return float("nan")
    s = np.asarray(fam["spread"], dtype=float)
    order = np.argsort(s)
    return float(np.interp(spread, s[order], np.asarray(fam["defects"], dtype=float)[order]))
