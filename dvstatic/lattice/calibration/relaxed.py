"""The relaxed calibration: ``k_n`` and ``nu_m`` for which the lattice *in equilibrium*
(non-affinely relaxed) matches E and nu.

The equilibrium moduli of a lattice depend on its micro-structure, so they are
measured on a periodic sample with the micro-structure of the mesh's interior:

1. meshes from the built-in generators carry their recipe (:attr:`Mesh.sampling`);
   for the tabulated recipes the moduli are read from the package's table
   (:mod:`.table`, no cost);
2. other recipes (other jitters outside the table, perturbed meshes, Voronoi-weighted
   bonds) get a periodic sample made by the same recipe (:func:`periodic_sample`);
3. meshes without a recipe (imported, or built from points) get a perturbed lattice
   with the mesh's *local* bond-length spread (:func:`local_spread`: every bond's
   length over the mean length at its two nodes; :func:`rev_for_spread`). The global
   spread ``sigma_L`` measures the grading of a graded mesh, not the irregularity of
   its cells (0.43 on a gmsh plate graded from 0.04 to 0.24, 0.035 uniform; locally
   0.053 and 0.024), and calibrated such meshes as random points (-9 % in the far
   field). On uniform periodic samples both predict the relaxed moduli alike (within
   1.6 % on jittered, CVT, random and perturbed samples; docs/theory.md).

On a sample, the three unit strains are applied with periodic fluctuations that bring
every node into equilibrium (one factorisation, three solves per ``nu_m``): the mean
stress gives ``nu_eff(nu_m)`` and ``E_eff(nu_m)`` at ``k_n = 1``
(:func:`relaxed_moduli`). A root find on ``nu_eff(nu_m) = nu`` gives ``nu_m``, then
``k_n = E / E_eff(nu_m)``. The couplings are stabilised per triangle
(:mod:`dvstatic.lattice.stabilise`), on the sample and on the mesh alike.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

import numpy as np

from ..._cache import Bounded
from ...errors import CalibrationError
from ...linalg import ConstrainedSystem, DirectSolver
from ...material import to_mandel
from ...mesh import Mesh, mesh_dof_order, periodic_sample, periodic_square
from ...mesh.recipe import Sampling
from .. import geometry as _geometry
from ..operator import LatticeOperator, scatter_bond_forces, virial_sum
from ..stabilise import clip_coupling, triangle_modes
from ..weights import bond_weights, resolve_bonds
from . import table
from .base import MicroParameters
from .descriptors import (  # noqa: F401 (re-exported: the relaxed calibration's descriptors)
    DEFECT_RINGS,
    MIXED_SPREAD,
    deep_nodes,
    defect_fraction,
    interior_spread,
    local_spread,
    node_degrees,
    relative_lengths,
    spread_field,
)

__all__ = [
    "FAMILY_STEP",
    "REV_POINTS",
    "SPREAD_STEP",
    "NU_M_LIMIT",
    "deep_nodes",
    "defect_fraction",
    "interior_spread",
    "local_spread",
    "node_degrees",
    "rev_for_spread",
    "sample_for",
    "relaxed_moduli",
    "relaxed",
    "moduli_curve",
]

log = logging.getLogger(__name__)

#: points of the periodic samples made on the fly
REV_POINTS = 10_000
#: resolution of the bond-length spread used to match samples (meshes without recipe)
SPREAD_STEP = 0.005
#: the weight of the CVT family in a mesh's curve is rounded to this (0.05 of the 1.1 %
#: between the families moves the moduli by 0.06 %)
FAMILY_STEP = 0.05
#: the root find searches nu_m in [-NU_M_LIMIT, NU_M_LIMIT]
NU_M_LIMIT = 3.0
#: typical d nu_eff / d nu_m (first secant step)
_SLOPE = 0.6
#: periodic samples (a few; each holds a mesh of REV_POINTS points)
_SAMPLES = Bounded("calibration samples", maxsize=8)
#: relaxed calibrations by (model, bonds, sample key, nu, sample size, seed)
_RESULTS = Bounded("relaxed calibrations", maxsize=256)
#: moduli curves measured on samples (their evaluations are kept)
_CURVES = Bounded("calibration sample curves", maxsize=16)
#: per-triangle coupling modes of the samples (springs of unit stiffness)
_MODES = Bounded("calibration sample modes", maxsize=16)

_PROBES = (
    np.array([[1.0, 0.0], [0.0, 0.0]]),
    np.array([[0.0, 0.0], [0.0, 1.0]]),
    np.array([[0.0, 1.0], [1.0, 0.0]]) / np.sqrt(2.0),
)

#: interior bonds of a periodic sample are full bonds: "surface" is "uniform" there (a
#: "fabric" sample is corrected for its own fabric, as the mesh is)
_SAMPLE_BONDS = {
    "surface": "uniform",
    "uniform": "uniform",
    "voronoi": "voronoi",
    "fabric": "fabric",
}


def rev_for_spread(sigma_l: float, n_points: int = REV_POINTS, seed: int = 0) -> Mesh:
    """Periodic sample with local bond-length spread ``sigma_l`` (:func:`local_spread`;
    cached).

    A periodic triangular lattice whose nodes are moved at random (the paper's way to
    raise sigma_L), the amplitude found by bisection; a random periodic point set when
    the spread exceeds what moves can reach.
    """
    key = ("local spread", round(sigma_l, 4), n_points, seed)
    best = _SAMPLES.get(key)
    if best is not None:
        return best
    lat = periodic_sample(Sampling("lattice"), n_points, seed)
    best = lat
    if sigma_l > local_spread(lat) + 1e-3:
        rnd = periodic_square(n_points, kind="random", seed=seed)
        if sigma_l >= local_spread(rnd):
            best = rnd
        else:
            lo, hi = 0.0, 0.9
            for _ in range(30):
                amp = 0.5 * (lo + hi)
                m = periodic_sample(Sampling("lattice", perturbations=(amp,)), n_points, seed)
                s = local_spread(m)
                best = m
                if abs(s / sigma_l - 1) < 0.01:
                    break
                lo, hi = (amp, hi) if s < sigma_l else (lo, amp)
    _SAMPLES.put(key, best)
    return best


def sample_for(mesh: Mesh, n_points: int = REV_POINTS, seed: int = 0, spread=None):
    """The periodic sample of ``mesh``'s micro-structure and how it was made.

    Returns
    -------
    sample : Mesh
    source : str
        ``"recipe"`` (made by the mesh's generator recipe) or ``"local spread"`` (a
        perturbed lattice with the mesh's local bond-length spread).
    key : tuple
        What identifies the sample (for caches).
    """
    s = mesh.sampling
    if s is not None and s.reproducible:
        key = ("recipe", s.key, n_points, seed)
        rev = _SAMPLES.get(key)
        if rev is None:
            rev = periodic_sample(s, n_points, seed)
            _SAMPLES.put(key, rev)
        return rev, "recipe", key
    raw = local_spread(mesh) if spread is None else float(spread)
    # quantised to 0.005 (nu_eff moves by < 1e-3): meshes of the same statistics share
    sig = round(raw / SPREAD_STEP) * SPREAD_STEP
    key = ("local spread", round(sig, 4), n_points, seed)
    return rev_for_spread(sig, n_points, seed), "local spread", key


def relaxed_moduli(
    kind: str, rev: Mesh, nu_m: float, bonds: str = "uniform", stabilise: bool = True
) -> dict:
    """Equilibrium (relaxed) moduli of a periodic sample for ``k_n = 1`` and ``nu_m``.

    For each unit macroscopic strain the periodic fluctuation that brings every node
    into equilibrium is solved for; the mean stress gives the effective tensor, whose
    isotropic part gives E and nu.

    Parameters
    ----------
    kind : {"DV", "RV"}
    rev : Mesh
        A periodic sample.
    nu_m : float
    bonds : {"uniform", "surface", "fabric", "voronoi"}
        The mesh's scheme ("surface" is "uniform" on a sample).
    stabilise : bool
        Clip the coupling per triangle (:mod:`dvstatic.lattice.stabilise`).

    Returns
    -------
    dict
        ``C`` (3x3 Mandel), ``E``, ``nu`` (for k_n = 1), ``stable`` (False if the
        sample's stiffness is not positive definite), ``clipped`` (fraction of
        triangles whose coupling was reduced), ``seconds``.
    """
    t0 = time.perf_counter()
    geom = _geometry.of(rev)
    spring = bond_weights(_SAMPLE_BONDS[bonds], rev)
    coupling = np.full(rev.n_triangles, float(nu_m))
    if stabilise:
        key = (id(rev), kind, bonds)
        modes = _MODES.get(key)
        if modes is None or modes[0] is not rev:
            modes = (rev, triangle_modes(rev, spring, kind == "DV"))
            _MODES.put(key, modes)
        coupling = clip_coupling(modes[1], coupling)
    op = LatticeOperator(rev, spring, coupling, barycentric=kind == "DV")
    # the fluctuation is periodic: pin one node against the two translations
    system = ConstrainedSystem(op.stiffness_bsr, np.array([0, 1]))
    lu = DirectSolver(system.A, order=mesh_dof_order(rev))
    bonds_ref = geom.length[:, None] * geom.direction
    cols = []
    for eps in _PROBES:
        u_aff = rev.points @ eps.T  # with the period carrying eps: u = eps x + fluctuation
        t_aff = op.linear_tension(u_aff, strain=eps)
        f = scatter_bond_forces(rev.topology.bonds, t_aff[:, None] * geom.direction, rev.n_points)
        x, _ = lu.solve(system.rhs(-f, np.zeros(2)))
        t = op.linear_tension(u_aff + x.reshape(-1, 2), strain=eps)
        cols.append(to_mandel(virial_sum(t, bonds_ref) / rev.area))
    return {
        **isotropic_part(np.stack(cols, axis=1)),
        "stable": lu.negative_pivots == 0,
        "clipped": float(np.mean(coupling != nu_m)),
        "seconds": time.perf_counter() - t0,
    }


def isotropic_part(C: np.ndarray) -> dict:
    """E and nu of the isotropic part of a 3x3 Mandel stiffness (plane), and C."""
    C = 0.5 * (C + C.T)
    k2 = 0.25 * (C[0, 0] + C[1, 1] + 2 * C[0, 1])  # E / (2 (1 - nu))
    g = 0.25 * (0.5 * (C[0, 0] + C[1, 1]) - C[0, 1] + C[2, 2])  # E / (2 (1 + nu))
    return {"C": C, "E": 4 * k2 * g / (k2 + g), "nu": (k2 - g) / (k2 + g)}


def relaxed(
    kind: str,
    mesh: Mesh,
    E: float,
    nu: float,
    bonds: str = "surface",
    rev_points: int = REV_POINTS,
    seed: int = 0,
    spread: float | None = None,
    defects: float | None = None,
) -> MicroParameters:
    """Micro-parameters for which the *relaxed* lattice matches E and nu.

    Parameters
    ----------
    kind : {"DV", "RV"}
    mesh : Mesh
    E, nu : float
        In-plane constants to match (plane strain: the effective ones).
    bonds : {"auto", "surface", "fabric", "uniform", "voronoi"}
        The model's bond scheme (``"auto"``: the one a model takes on ``mesh`` by
        default).
    rev_points, seed : int
        Size and seed of a sample made on the fly.
    spread : float, optional
        Overrides the local spread (:func:`local_spread`) of a mesh without recipe.
    defects : float, optional
        Overrides its defect fraction (:func:`defect_fraction`).

    Returns
    -------
    MicroParameters
        ``stabilised=True``; ``details["source"]`` is ``"table"``, ``"recipe"`` or
        ``"local spread"`` (``details["local_spread"]`` the spread asked for: the
        mesh's descriptor, or ``spread`` where given (a class's, :mod:`.classes`);
        ``details["local_spread_sample"]`` its sample's),
        ``details["seconds"]`` the time it took (0 for a cached result).

    Raises
    ------
    CalibrationError
        If nu lies outside the range of nu_eff that the lattice reaches (the message
        gives the range).
    """
    for name, value, hi in (("spread", spread, np.inf), ("defects", defects, 1.0)):
        if value is not None and not (np.isfinite(float(value)) and 0.0 <= float(value) <= hi):
            raise CalibrationError(f"{name} must be finite in [0, {hi:g}], got {value!r}", name)
    t0 = time.perf_counter()
    bonds = resolve_bonds(bonds, mesh)
    curve, ckey = moduli_curve(kind, mesh, bonds, rev_points, seed, spread, defects)
    key = (ckey, round(float(nu), 12))
    hit = _RESULTS.get(key)
    if hit is None:
        nu_m, e_eff, details = _solve_nu(curve, float(nu), kind, mesh)
        hit = (nu_m, e_eff, {**details, "seconds": time.perf_counter() - t0})
        _RESULTS.put(key, hit)
    else:
        hit = (hit[0], hit[1], {**hit[2], "seconds": 0.0, "cached": True})
    nu_m, e_eff, details = hit
    if details["source"] == "local spread":  # what this mesh asked for (the sample: near)
        raw = local_spread(mesh) if spread is None else float(spread)
        d = defect_fraction(mesh) if defects is None else float(defects)
        details = {**details, "local_spread": raw, "defect_fraction": d}
    log.debug(
        "relaxed %s calibration (%s): nu_m %.5f, k_n/E %.5f in %.3f s",
        kind,
        details["source"],
        nu_m,
        1 / e_eff,
        details["seconds"],
    )
    return MicroParameters(
        E / e_eff, nu_m, "relaxed", None, details["nu_range"], details, stabilised=True
    )


def moduli_curve(
    kind: str,
    mesh: Mesh,
    bonds: str = "surface",
    rev_points: int = REV_POINTS,
    seed: int = 0,
    spread: float | None = None,
    defects: float | None = None,
):
    """The relaxed ``(nu_eff, E_eff)(nu_m)`` of ``mesh``'s micro-structure: the table's
    curve, or one measured on a sample (each value once, kept for later calibrations).

    A mesh without recipe gets the curve of a perturbed lattice of its local spread,
    blended with the table's CVT family at that spread by :func:`.table.family_weight`
    of its defect fraction (uniform and fabric-corrected springs; in steps of
    :data:`FAMILY_STEP`): a
    CVT-like mesh (gmsh's graded meshes, Lloyd-relaxed points) relaxes less than a
    perturbed lattice of the same local spread (a CVT mesh stripped of its recipe came
    out 1.2 % stiff at a Lame bore).

    Returns
    -------
    curve : callable
        ``curve(nu_m) -> (nu_eff, E_eff)``, with ``describe()``.
    key : tuple
        Identifies the curve.
    """
    bonds = resolve_bonds(bonds, mesh)
    if _SAMPLE_BONDS[bonds] in table.WEIGHTINGS and mesh.sampling is not None:
        c = table.curve(kind, mesh.sampling, _SAMPLE_BONDS[bonds])
        if c is not None:
            return c, (kind, "table", _SAMPLE_BONDS[bonds], mesh.sampling.key)
    rev, source, skey = sample_for(mesh, rev_points, seed, spread)
    key = (kind, _SAMPLE_BONDS[bonds], skey)
    c = _CURVES.get(key)
    if c is None or c.rev is not rev:
        c = _SampleCurve(kind, rev, bonds, source)
        _CURVES.put(key, c)
    if source != "local spread" or _SAMPLE_BONDS[bonds] not in table.WEIGHTINGS:
        return c, key
    raw = local_spread(mesh) if spread is None else float(spread)
    d = defect_fraction(mesh) if defects is None else float(defects)
    w = round(round(table.family_weight(raw, d) / FAMILY_STEP) * FAMILY_STEP, 4)
    family = table.family_curve(kind, skey[1], _SAMPLE_BONDS[bonds]) if w > 0 else None
    if family is None:
        return c, key
    bkey = (*key, "cvt family", round(w, 4))
    b = _CURVES.get(bkey)
    if b is None or b.a is not c:
        b = _BlendCurve(c, family, w)
        _CURVES.put(bkey, b)
    return b, bkey


class _BlendCurve:
    """``(1 - w)`` times a perturbed lattice's curve plus ``w`` times the CVT family's
    (:func:`moduli_curve`)."""

    def __init__(self, a, b, w: float):
        self.a, self.b, self.w = a, b, float(w)

    def __call__(self, nu_m: float) -> tuple[float, float]:
        (nu_a, e_a), (nu_b, e_b) = self.a(nu_m), self.b(nu_m)
        return (1 - self.w) * nu_a + self.w * nu_b, (1 - self.w) * e_a + self.w * e_b

    def guess(self, nu: float) -> float:
        return self.b.guess(nu) if self.w > 0.5 else self.a.guess(nu)

    def describe(self) -> dict:
        d = self.a.describe()
        d["sample"] = f"{d['sample']}, {self.w:.2f} of it replaced by {self.b.what}"
        d["cvt_family_weight"] = self.w
        return d


class _SampleCurve:
    """``nu_eff(nu_m)`` and ``E_eff(nu_m)`` measured on a sample (each value once)."""

    def __init__(self, kind: str, rev: Mesh, bonds: str, source: str):
        self.kind, self.rev, self.bonds, self.source = kind, rev, bonds, source
        self.evals: dict[float, dict] = {}

    def __call__(self, nu_m: float) -> tuple[float, float]:
        x = float(nu_m)
        if x not in self.evals:
            self.evals[x] = relaxed_moduli(self.kind, self.rev, x, self.bonds)
        r = self.evals[x]
        return float(r["nu"]), float(r["E"])

    def guess(self, nu: float) -> float:
        """The paper's closed-form nu_m on the sample (0 where it has none)."""
        from .paper import paper

        try:
            w = bond_weights(_SAMPLE_BONDS[self.bonds], self.rev)
            return paper(self.kind, self.rev, _geometry.of(self.rev), 1.0, nu, w).nu_m
        except CalibrationError:
            return 0.0

    def describe(self) -> dict:
        return {
            "source": self.source,
            "sample": str(self.rev.sampling) if self.rev.sampling else "perturbed lattice",
            "sample_points": self.rev.n_points,
            "sigma_L_sample": self.rev.edge_length_spread(),
            "local_spread_sample": local_spread(self.rev),
            "evaluations": len(self.evals),
            "factorisations": len(self.evals),
        }


def _solve_nu(curve: Callable, nu: float, kind: str, mesh: Mesh) -> tuple[float, float, dict]:
    """The root of ``nu_eff(nu_m) = nu``: secant steps from the curve's first guess
    until the root is bracketed, then Brent's method. nu_eff grows with nu_m (and
    saturates where every triangle's coupling is clipped)."""
    from scipy.optimize import brentq

    def g(x):
        return curve(x)[0] - nu

    x0 = float(np.clip(curve.guess(nu), -NU_M_LIMIT, NU_M_LIMIT))
    g0 = g(x0)
    seen = [g0 + nu]
    step = -g0 / _SLOPE
    step = step if abs(step) > 0.005 else 0.005 * np.sign(step or 1.0)
    x1 = float(np.clip(x0 + step, -NU_M_LIMIT, NU_M_LIMIT))
    root = x0 if abs(g0) < 1e-9 else None
    for _ in range(30):
        if root is not None or x1 == x0:
            break
        g1 = g(x1)
        seen.append(g1 + nu)
        if g1 == 0 or np.sign(g1) != np.sign(g0):
            a, b = sorted((x0, x1))
            root = x1 if g1 == 0 else float(brentq(g, a, b, xtol=1e-6, rtol=1e-9, maxiter=50))
            break
        if abs(g1 - g0) < 1e-7 or abs(g1) >= abs(g0) and abs(x1) >= NU_M_LIMIT:
            break  # saturated (every coupling clipped) or at the end of the search
        slope = (g1 - g0) / (x1 - x0)
        step = -g1 / slope if slope > 0 else np.sign(-g1) * 2 * abs(x1 - x0)
        step = float(np.clip(step, -4 * abs(x1 - x0), 4 * abs(x1 - x0)))
        step = step if abs(step) > 0.01 else 0.01 * np.sign(-g1)
        x0, g0, x1 = x1, g1, float(np.clip(x1 + 1.2 * step, -NU_M_LIMIT, NU_M_LIMIT))
    if root is None:
        where = "this mesh" if mesh.sampling is None else f"a {mesh.sampling} mesh"
        span = getattr(curve, "nu_range", None)
        if span is not None:
            reach = f"its nu_eff lies in [{span[0]:.3f}, {span[1]:.3f}]"
        elif nu > max(seen):
            reach = f"its nu_eff saturates at {max(seen):.3f}"
        else:
            reach = f"its nu_eff saturates at {min(seen):.3f}"
        raise CalibrationError(
            f"nu = {nu} cannot be reached by the relaxed {kind} lattice of {where}: {reach}"
            " (plane strain: the in-plane nu / (1 - nu) must lie there)",
            "nu",
        )
    nu_eff, e_eff = curve(root)
    info = curve.describe()
    info.update(
        nu_range=getattr(curve, "nu_range", (np.nan, np.nan)), nu_eff=nu_eff, E_eff_per_k_n=e_eff
    )
    return root, e_eff, info
