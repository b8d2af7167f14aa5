"""Micro-parameters ``k_n`` and ``nu_m`` from the macroscopic E and nu.

``"paper"`` calibration (Chaiko & Konovalov 2021): every bond is assumed to follow
the macroscopic (affine) strain; the energy of the bonds is matched to plane stress.
Under an affine strain eps a bond stretches by ``l n.eps.n`` and its dual side by
``R_e : eps``; averaging the resulting stiffness over bond directions gives::

    C1111 = 3 alpha k_n + M1 k_n nu_m,      C1122 = alpha k_n + M2 k_n nu_m,
    alpha = sum(l^2) / (8 A),
    M1 = sum l (tau + 2 rho) / (8 A),        M2 = sum l (3 tau - 2 rho) / (8 A),

with ``tau = tr R_e`` and ``rho = n.R_e.n``. DV: ``R_e = r t t`` (the side is carried
affinely), so ``tau = r``, ``rho = 0``: M1 = beta, M2 = 3 beta, beta = sum(l r) / (8 A),
the paper's eqs. (7), (9), (10). RV: ``R_e`` follows from the derivative of the
circumcentre (see docs/theory.md); ``tau = r`` still holds, ``rho != 0`` (on an
equilateral lattice ``rho = -r``, so M1 = -beta, M2 = 5 beta). Matching to plane stress
gives the paper's eqs. (19), (20), which contain (9), (10) as the DV case::

    k_n  = E (M2 - nu M1) / (alpha (1 - nu^2) (3 M2 - M1)),
    nu_m = alpha (1 - 3 nu) / (nu M1 - M2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .geometry import Geometry
from .kinematics import half_sides
from .mesh import Mesh

__all__ = [
    "MicroParameters",
    "Moments",
    "moments",
    "moment_sums",
    "moments_from_sums",
    "paper",
    "paper_from_moments",
    "relaxed",
    "admissible_nu",
    "relaxed_moduli",
    "CALIBRATIONS",
]

CALIBRATIONS = ("paper", "relaxed")


@dataclass(frozen=True)
class Moments:
    """Lattice moments of a mesh for one model (dimensionless)."""

    alpha: float
    beta: float
    m1: float
    m2: float


@dataclass(frozen=True)
class MicroParameters:
    """Calibrated micro-parameters.

    Attributes
    ----------
    k_n : float
        Bond stiffness (force per length per unit thickness, i.e. units of E).
    nu_m : float
        Voronoi coupling coefficient (dimensionless).
    calibration : str
    moments : Moments
    nu_range : tuple of float
        Open interval of nu for which this calibration has a solution on this mesh.
    """

    k_n: float
    nu_m: float
    calibration: str
    moments: Moments | None = None
    nu_range: tuple[float, float] = (float("nan"), float("nan"))
    details: dict | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.k_n) and self.k_n > 0):
            raise ValueError(f"k_n must be finite and > 0, got {self.k_n}")
        if not np.isfinite(self.nu_m):
            raise ValueError(f"nu_m must be finite, got {self.nu_m}")


def moment_sums(kind: str, geom: Geometry, weights=None, bond_mask=None, tri_mask=None):
    """Raw sums behind :func:`moments` over the selected bonds and triangles.

    Returns ``[sum w l^2, sum l r, S1, S2]`` (length^2), where ``S1 = M1 * 8A`` and
    ``S2 = M2 * 8A`` (for DV ``S1 = sum l r``, ``S2 = 3 sum l r``). With masks, sums
    over disjoint sets of bonds and triangles add up: that is how the distributed
    solver calibrates across ranks.
    """
    length, r = geom.length, geom.r
    w = np.ones(len(length)) if weights is None else np.asarray(weights)
    bm = slice(None) if bond_mask is None else bond_mask
    s_alpha = float(np.sum(w[bm] * length[bm] ** 2))
    s_beta = float(np.sum(length[bm] * r[bm]))
    if kind == "DV":
        return np.array([s_alpha, s_beta, s_beta, 3 * s_beta])
    x = geom.x_tri if tri_mask is None else geom.x_tri[tri_mask]
    _, dr = half_sides(x, None, grad=True)
    m = len(x)
    # R_Tk = sym(sum_v dr_v (x) x_v): linear map from a homogeneous strain to delta r_Tk
    R = np.einsum("mkvi,mvj->mkij", dr.reshape(m, 3, 3, 2), x)
    tau = R[..., 0, 0] + R[..., 1, 1]
    d = x[:, [2, 0, 1]] - x[:, [1, 2, 0]]
    ll = np.hypot(d[..., 0], d[..., 1])
    n = d / ll[..., None]
    rho = np.einsum("mki,mkij,mkj->mk", n, R, n)
    return np.array(
        [
            s_alpha,
            s_beta,
            float(np.sum(ll * (tau + 2 * rho))),
            float(np.sum(ll * (3 * tau - 2 * rho))),
        ]
    )


def moments_from_sums(sums, area: float) -> Moments:
    """:class:`Moments` from :func:`moment_sums` (added over all parts) and the area."""
    s = np.asarray(sums, dtype=float) / (8.0 * area)
    return Moments(float(s[0]), float(s[1]), float(s[2]), float(s[3]))


def paper_from_moments(kind: str, mom: Moments, E: float, nu: float) -> MicroParameters:
    """The paper's closed form (eqs. 9-10 / 19-20) for given lattice moments.

    Raises
    ------
    ValueError
        If nu lies outside the interval where the calibration has a solution.
    """
    lo, hi = admissible_nu(mom)
    if not (lo < nu < hi):
        raise ValueError(
            f"nu = {nu} has no {kind} calibration on this mesh: the accepted range is "
            f"{lo:.4g} < nu < {hi:.4g}"
        )
    k_n = E * (mom.m2 - nu * mom.m1) / (mom.alpha * (1 - nu**2) * (3 * mom.m2 - mom.m1))
    nu_m = mom.alpha * (1 - 3 * nu) / (nu * mom.m1 - mom.m2)
    return MicroParameters(float(k_n), float(nu_m), "paper", mom, (lo, hi))


def moments(kind: str, mesh: Mesh, geom: Geometry, weights=None) -> Moments:
    """alpha, beta, M1, M2 of ``mesh`` for model ``kind`` ("DV" or "RV").

    ``weights`` (E,) are the relative normal-spring stiffnesses (``bonds="voronoi"``);
    they enter alpha = sum w l^2 / (8 A) only, since the coupling is not weighted.
    """
    return moments_from_sums(moment_sums(kind, geom, weights), mesh.area)


def admissible_nu(mom: Moments) -> tuple[float, float]:
    """Open nu interval in (-1, 1) where the closed-form calibration gives k_n > 0.

    Returns ``(nan, nan)`` if there is none.
    """
    lo, hi = -1.0, 1.0
    den = 3 * mom.m2 - mom.m1
    if den <= 0:
        return (float("nan"), float("nan"))
    # need M2 - nu M1 > 0
    if mom.m1 > 0:
        hi = min(hi, mom.m2 / mom.m1)
    elif mom.m1 < 0:
        lo = max(lo, mom.m2 / mom.m1)
    elif mom.m2 <= 0:
        return (float("nan"), float("nan"))
    if not lo < hi:
        return (float("nan"), float("nan"))
    return (lo, hi)


def paper(
    kind: str, mesh: Mesh, geom: Geometry, E: float, nu: float, weights=None
) -> MicroParameters:
    """Closed-form calibration of the paper (eqs. 9-10 for DV, 19-20 for RV).

    Raises
    ------
    ValueError
        If nu lies outside the interval where the calibration has a solution.
    """
    return paper_from_moments(kind, moments(kind, mesh, geom, weights), E, nu)


# --------------------------------------------------------------------- relaxed
#: points of the periodic sample used by the relaxed calibration
REV_POINTS = 20_000
#: resolution of the bond-length spread used to match samples
SPREAD_STEP = 0.005
_REV_CACHE: dict = {}
_RELAXED_CACHE: dict = {}


def interior_spread(mesh: Mesh) -> float:
    """sigma_L over the bonds whose end nodes are both off the boundary."""
    lengths = mesh.bond_lengths()
    if not mesh.is_periodic:
        bnd = np.zeros(mesh.n_points, dtype=bool)
        bnd[mesh.boundary_nodes] = True
        b = mesh.topology.bonds
        inner = ~(bnd[b[:, 0]] | bnd[b[:, 1]])
        if inner.sum() >= 30:
            lengths = lengths[inner]
    return float(np.std(lengths) / np.mean(lengths))


def rev_for_spread(sigma_l: float, n_points: int = REV_POINTS, seed: int = 0) -> Mesh:
    """Periodic sample with bond-length spread ``sigma_l`` (cached).

    A periodic triangular lattice whose nodes are moved at random (the paper's way to
    raise sigma_L), the amplitude found by bisection; a random periodic point set when
    the spread exceeds what moves can reach.
    """
    from .periodic import periodic_square

    key = (round(sigma_l, 4), n_points, seed)
    if key in _REV_CACHE:
        return _REV_CACHE[key]
    lat = periodic_square(n_points, kind="lattice", seed=seed)
    best = lat
    if sigma_l > lat.edge_length_spread() + 1e-3:
        rnd = periodic_square(n_points, kind="random", seed=seed)
        if sigma_l >= rnd.edge_length_spread():
            best = rnd
        else:
            lo, hi = 0.0, 0.9 * lat.h
            for _ in range(30):
                amp = 0.5 * (lo + hi)
                m = lat.perturbed(amp, seed=seed)
                s = m.edge_length_spread()
                best = m
                if abs(s / sigma_l - 1) < 0.01:
                    break
                lo, hi = (amp, hi) if s < sigma_l else (lo, amp)
    _REV_CACHE[key] = best
    return best


def relaxed_moduli(kind: str, rev: Mesh, nu_m: float, bonds: str = "uniform") -> dict:
    """Equilibrium (relaxed) moduli of a periodic sample for ``k_n = 1`` and ``nu_m``.

    For each unit macroscopic strain the periodic fluctuation that brings every node
    into equilibrium is solved for; the mean stress gives the effective tensor, whose
    isotropic part gives E and nu.

    Returns
    -------
    dict
        ``C`` (3x3 Mandel), ``E``, ``nu`` (for k_n = 1), ``stable`` (False if the
        sample's stiffness is not positive definite), ``seconds``.
    """
    import time

    from . import linalg
    from .models import DV, RV
    from .post import to_mandel, virial_stress

    t0 = time.perf_counter()
    cls = DV if kind == "DV" else RV
    micro = MicroParameters(1.0, float(nu_m), "probe")
    model = cls(rev, 1.0, 0.0, calibration=micro, bonds=bonds)
    K = model._stiffness_bsr
    # the fluctuation is periodic: pin one node against the two translations
    system = linalg.ConstrainedSystem(K, np.array([0, 1]))
    from .ordering import mesh_dof_order

    lu = linalg.DirectSolver(system.A, order=mesh_dof_order(rev))
    stable = lu.negative_pivots == 0
    probes = [
        np.array([[1.0, 0.0], [0.0, 0.0]]),
        np.array([[0.0, 0.0], [0.0, 1.0]]),
        np.array([[0.0, 1.0], [1.0, 0.0]]) / np.sqrt(2.0),
    ]
    cols = []
    for eps in probes:
        u_aff = rev.points @ eps.T  # with the period carrying eps: u = eps x + fluctuation
        f = _macro_force(model, u_aff, eps)
        b = system.rhs(-f, np.zeros(2))
        x, _ = lu.solve(b)
        u = u_aff + x.reshape(-1, 2)
        cols.append(to_mandel(virial_stress(model, u, eps, linear=True)))
    C = np.stack(cols, axis=1)
    C = 0.5 * (C + C.T)
    k2 = 0.25 * (C[0, 0] + C[1, 1] + 2 * C[0, 1])  # E / (2 (1 - nu))
    g = 0.25 * (0.5 * (C[0, 0] + C[1, 1]) - C[0, 1] + C[2, 2])  # E / (2 (1 + nu))
    return {
        "C": C,
        "E": 4 * k2 * g / (k2 + g),
        "nu": (k2 - g) / (k2 + g),
        "stable": stable,
        "seconds": time.perf_counter() - t0,
    }


def _macro_force(model, u_aff: np.ndarray, eps: np.ndarray) -> np.ndarray:
    """Nodal forces of the linear model under the affine field ``u_aff = eps x``."""
    t = model.linear_tension(u_aff, strain=eps)
    d = model.geometry.direction
    b = model.mesh.topology.bonds
    n = model.mesh.n_points
    f = np.zeros((n, 2))
    for c in range(2):
        f[:, c] = np.bincount(b[:, 1], t * d[:, c], n) - np.bincount(b[:, 0], t * d[:, c], n)
    return f.reshape(-1)


def relaxed(
    kind: str,
    mesh: Mesh,
    E: float,
    nu: float,
    bonds: str = "uniform",
    rev_points: int = REV_POINTS,
    seed: int = 0,
    spread: float | None = None,
) -> MicroParameters:
    """Micro-parameters for which the *relaxed* lattice matches E and nu.

    Method: a periodic sample with the interior bond-length spread of ``mesh``
    (:func:`rev_for_spread`) is probed with three unit strains; the fluctuations that
    equilibrate it are solved for (one LU factorisation, three solves), giving the
    relaxed Poisson's ratio ``nu_eff(nu_m)`` and modulus ``E_eff(nu_m)`` at ``k_n = 1``.
    A secant root find on ``nu_eff(nu_m) = nu``, started from the paper's ``nu_m``,
    gives ``nu_m``; then ``k_n = E / E_eff(nu_m)``. Typically 3-6 evaluations. Results
    are cached per (model, bonds, spread, nu). ``spread`` overrides the interior
    sigma_L of ``mesh`` (the distributed solver computes it across ranks).

    Raises
    ------
    ValueError
        If nu cannot be reached with a stable sample (the message gives the range of
        nu_eff found).
    """
    from . import geometry as _geometry

    # the spread is quantised to 0.005 (nu_eff moves by < 1e-3): meshes of the same
    # statistics share one calibration
    raw = interior_spread(mesh) if spread is None else float(spread)
    sig = round(raw / SPREAD_STEP) * SPREAD_STEP
    key = (kind, bonds, round(sig, 4), round(float(nu), 12), rev_points, seed)
    hit = _RELAXED_CACHE.get(key)
    if hit is not None:
        nu_m, e_eff, details = hit
        return MicroParameters(E / e_eff, nu_m, "relaxed", None, details["nu_range"], details)
    rev = rev_for_spread(sig, rev_points, seed)
    geom = _geometry.of(rev)
    from .models import voronoi_weights

    w = voronoi_weights(geom) if bonds == "voronoi" else None
    start = paper(kind, rev, geom, 1.0, nu, w).nu_m if -1 < nu < 1 else 0.0
    evals: dict[float, dict] = {}

    def g(x):
        x = float(x)
        if x not in evals:
            evals[x] = relaxed_moduli(kind, rev, x, bonds)
        r = evals[x]
        return r["nu"] - nu if r["stable"] else np.nan

    def fail(reason):
        ok = [r["nu"] for r in evals.values() if r["stable"]]
        span = f"[{min(ok):.3f}, {max(ok):.3f}]" if ok else "none (every sample unstable)"
        raise ValueError(
            f"nu = {nu} has no relaxed {kind} calibration for a mesh of sigma_L = {sig:.3f}: "
            f"{reason}; stable samples reached nu_eff in {span} ({len(evals)} evaluations)"
        )

    # bracket the root: nu_eff grows with nu_m; unstable samples are walls
    x0, g0 = start, g(start)
    if not np.isfinite(g0):
        # move towards nu_m = 0 (the plain spring network is always stable)
        lo, hi = (start, 0.0) if start < 0 else (0.0, start)
        for _ in range(12):
            mid = 0.5 * (lo + hi)
            if np.isfinite(g(mid)):
                x0, g0 = mid, g(mid)
                if start < 0:
                    hi = mid
                else:
                    lo = mid
            elif start < 0:
                lo = mid
            else:
                hi = mid
        if not np.isfinite(g0):
            g0 = g(0.0)
            x0 = 0.0
    step = 0.05 * (1.0 + abs(x0))
    direction = 1.0 if g0 < 0 else -1.0
    x1, g1 = x0, g0
    for _ in range(10):
        if abs(g1) < 1e-5:
            break
        x2 = x1 + direction * step
        g2 = g(x2)
        if not np.isfinite(g2):
            # a stability wall between x1 and x2: approach it by bisection; the root may
            # lie before it
            stable_x, wall_x = x1, x2
            for _ in range(8):
                xm = 0.5 * (stable_x + wall_x)
                gm = g(xm)
                if not np.isfinite(gm):
                    wall_x = xm
                elif np.sign(gm) != np.sign(g1):
                    x2, g2 = xm, gm
                    break
                else:
                    stable_x = xm
            if not np.isfinite(g2):
                fail("it would need nu_m beyond the stability limit of the sample")
        if np.sign(g2) != np.sign(g1):
            from scipy.optimize import brentq

            a_, b_ = sorted((x1, x2))
            x1 = float(brentq(lambda t: g(t), a_, b_, xtol=1e-6, rtol=1e-9, maxiter=30))
            g1 = g(x1)
            break
        x1, g1 = x2, g2
        step *= 2.0
    if not (np.isfinite(g1) and abs(g1) < 1e-4):
        fail("no nu_m found")
    r = evals[float(x1)]
    ok = [e["nu"] for e in evals.values() if e["stable"]]
    rng = (min(ok), max(ok))
    details = {
        "sigma_L_mesh": sig,
        "sigma_L_sample": rev.edge_length_spread(),
        "sample_points": rev.n_points,
        "evaluations": len(evals),
        "solves": 3 * len(evals),
        "factorisations": len(evals),
        "seconds": float(sum(e["seconds"] for e in evals.values())),
        "E_eff_per_k_n": r["E"],
        "nu_range": rng,
        "paper_nu_m": start,
    }
    _RELAXED_CACHE[key] = (x1, r["E"], details)
    return MicroParameters(E / r["E"], x1, "relaxed", None, rng, details)
